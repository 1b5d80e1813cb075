//! The part of every driver that only differs by its register map: wrap a bus, check WHO_AM_I, write the FIRES
//! configuration, read x, y, z in one burst. Each driver module describes its part with a [`Part`] and adds
//! what is its own (a self-test, a plausibility check).

use core::marker::PhantomData;

use super::bus::RegisterBus;
use embedded_hal_async::delay::DelayNs;

use super::{axes_be, axes_le, check_identity, Axes, SelfTest, SensorError};

/// A sensor's register map, as far as the common steps need it.
pub trait Part {
    /// The identity register.
    const WHO_AM_I: u8;
    /// Its value (datasheet).
    const WHO_AM_I_VALUE: u8;
    /// The FIRES configuration: `(register, value)` writes, in order.
    const CONFIGURATION: &'static [(u8, u8)];
    /// The first of the six output registers.
    const OUTPUT: u8;
    /// Whether the outputs are big endian (most significant byte first).
    const BIG_ENDIAN: bool;
}

/// A part with the ST self-test (the datasheets' procedure, [`SelfTest`]).
pub trait SelfTesting: Part {
    /// Its registers, timing and acceptance window.
    const SELF_TEST: SelfTest;
}

/// A register-level driver of part `P` on bus `B`.
#[derive(Debug)]
pub struct Sensor<B, P> {
    pub(crate) bus: B,
    part: PhantomData<P>,
}

impl<B: RegisterBus, P: Part> Sensor<B, P> {
    /// Wraps a register bus (see [`super::bus`]).
    pub fn new(bus: B) -> Self {
        Sensor {
            bus,
            part: PhantomData,
        }
    }

    /// Gives the bus back.
    pub fn release(self) -> B {
        self.bus
    }

    /// Checks WHO_AM_I.
    pub async fn identify(&mut self) -> Result<(), SensorError<B::Error>> {
        check_identity(&mut self.bus, P::WHO_AM_I, P::WHO_AM_I_VALUE).await
    }

    /// Writes the FIRES configuration (the part's module docs).
    pub async fn configure(&mut self) -> Result<(), SensorError<B::Error>> {
        for &(register, value) in P::CONFIGURATION {
            self.bus.write_register(register, value).await?;
        }
        Ok(())
    }

    /// Reads x, y, z in one burst (raw counts).
    pub async fn read(&mut self) -> Result<Axes, SensorError<B::Error>> {
        let mut b = [0u8; 6];
        self.bus.read_registers(P::OUTPUT, &mut b).await?;
        Ok(if P::BIG_ENDIAN {
            axes_be(&b)
        } else {
            axes_le(&b)
        })
    }
}

impl<B: RegisterBus, P: SelfTesting> Sensor<B, P> {
    /// Configures the part and runs its self-test: the mean output with the self-test on minus the mean
    /// output with it off must lie within the part's window in magnitude on every axis. The pen must be held
    /// still. Leaves the part running and returns the per-axis change.
    pub async fn self_test<D: DelayNs>(
        &mut self,
        delay: &mut D,
    ) -> Result<Axes, SensorError<B::Error>> {
        self.configure().await?;
        P::SELF_TEST.run(&mut self.bus, delay).await
    }
}
