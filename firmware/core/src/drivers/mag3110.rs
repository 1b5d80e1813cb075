//! Freescale MAG3110 3-axis magnetometer (datasheet Rev 9.2, §14 "Register descriptions").
//!
//! Configuration used by FIRES:
//! - `CTRL_REG1` (0x10) = `0x00` first (standby: `CTRL_REG2` may only be changed in standby).
//! - `CTRL_REG2` (0x11) = `0x80`: AUTO_MRST_EN = 1 (magnetic sensor reset before each acquisition), RAW = 0
//!   (user offset registers applied).
//! - `CTRL_REG1` (0x10) = `0x01`: DR2..0 = 000 and OS1..0 = 00 (**80 Hz**, the fastest rate; the part has no
//!   100 Hz setting, so one packet in five repeats the previous reading), FR = 0 (16-bit reads), TM = 0, AC = 1.
//!
//! Output registers are **big endian** (X MSB at 0x01). Sensitivity 0.1 µT/count, the magnetometer factor of
//! [`fires_protocol::ScaleFactors::FIRES_PEN`]. I2C address 0x0E; the part auto-increments by itself.
//!
//! The MAG3110 has **no self-test**. [`Mag3110::plausibility_check`] stands in for it: data must become ready,
//! no axis may sit outside the ±1000 µT full scale, and the field magnitude must be at least 10 µT (the Earth's
//! field alone is 25..65 µT everywhere; all zeros means a dead part).

use embedded_hal_async::delay::DelayNs;

use super::bus::RegisterBus;
use super::{Axes, Part, Sensor, SensorError};

/// 7-bit I2C address.
pub const I2C_ADDRESS: u8 = 0x0E;
/// Value of WHO_AM_I.
pub const WHO_AM_I_VALUE: u8 = 0xC4;
/// Microtesla per count.
pub const MICROTESLA_PER_COUNT: f64 = 0.1;
/// Output data rate configured, Hz.
pub const OUTPUT_RATE_HZ: u32 = 80;

/// Register addresses.
pub mod reg {
    /// Data-ready status.
    pub const DR_STATUS: u8 = 0x00;
    /// First output register (X MSB).
    pub const OUT_X_MSB: u8 = 0x01;
    /// Identity register.
    pub const WHO_AM_I: u8 = 0x07;
    /// Rate, oversampling, mode.
    pub const CTRL_REG1: u8 = 0x10;
    /// Reset and offset options.
    pub const CTRL_REG2: u8 = 0x11;
}

/// `CTRL_REG1` standby.
pub const CTRL_REG1_STANDBY: u8 = 0x00;
/// `CTRL_REG1` active at 80 Hz.
pub const CTRL_REG1_ACTIVE: u8 = 0x01;
/// `CTRL_REG2`: automatic magnetic reset.
pub const CTRL_REG2_VALUE: u8 = 0x80;
/// `DR_STATUS` bit: new X, Y and Z data.
pub const ZYXDR: u8 = 0x08;
/// Largest plausible magnitude of one axis, counts (±1000 µT full scale).
pub const FULL_SCALE_COUNTS: i16 = 10_000;
/// Smallest plausible field magnitude, counts (10 µT).
pub const MIN_FIELD_COUNTS: i32 = 100;
/// Data-ready polls before giving up (10 ms apart).
const READY_POLLS: usize = 10;

/// The MAG3110 register map.
#[derive(Debug)]
pub struct Magnetometer;

impl Part for Magnetometer {
    const WHO_AM_I: u8 = reg::WHO_AM_I;
    const WHO_AM_I_VALUE: u8 = WHO_AM_I_VALUE;
    const CONFIGURATION: &'static [(u8, u8)] = &[
        (reg::CTRL_REG1, CTRL_REG1_STANDBY),
        (reg::CTRL_REG2, CTRL_REG2_VALUE),
        (reg::CTRL_REG1, CTRL_REG1_ACTIVE),
    ];
    const OUTPUT: u8 = reg::OUT_X_MSB;
    const BIG_ENDIAN: bool = true;
}

/// The magnetometer.
pub type Mag3110<B> = Sensor<B, Magnetometer>;

impl<B: RegisterBus> Mag3110<B> {
    /// The stand-in for a self-test (module docs). Returns the reading it judged.
    pub async fn plausibility_check<D: DelayNs>(
        &mut self,
        delay: &mut D,
    ) -> Result<Axes, SensorError<B::Error>> {
        let mut ready = false;
        for _ in 0..READY_POLLS {
            if self.bus.read_register(reg::DR_STATUS).await? & ZYXDR != 0 {
                ready = true;
                break;
            }
            delay.delay_ms(10).await;
        }
        if !ready {
            return Err(SensorError::NotReady);
        }
        let v = self.read().await?;
        let in_range = v.iter().all(|a| a.saturating_abs() <= FULL_SCALE_COUNTS);
        let mag2: i64 = v.iter().map(|a| i64::from(*a) * i64::from(*a)).sum();
        let min2 = i64::from(MIN_FIELD_COUNTS) * i64::from(MIN_FIELD_COUNTS);
        if in_range && mag2 >= min2 {
            Ok(v)
        } else {
            Err(SensorError::SelfTestFailed { response: v })
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::drivers::bus::I2cRegisters;
    use embassy_futures::block_on;
    use embedded_hal_mock::eh1::delay::NoopDelay;
    use embedded_hal_mock::eh1::i2c::{Mock as I2cMock, Transaction as I2cT};
    use std::vec;
    use std::vec::Vec;

    const A: u8 = I2C_ADDRESS;

    fn be(x: i16, y: i16, z: i16) -> Vec<u8> {
        [x, y, z].iter().flat_map(|v| v.to_be_bytes()).collect()
    }

    #[test]
    fn identify_configure_read_big_endian() {
        let mut i2c = I2cMock::new(&[
            I2cT::write_read(A, vec![0x07], vec![0xC4]),
            I2cT::write(A, vec![0x10, 0x00]),
            I2cT::write(A, vec![0x11, 0x80]),
            I2cT::write(A, vec![0x10, 0x01]),
            // no auto-increment bit: the MAG3110 increments by itself
            I2cT::write_read(A, vec![0x01], vec![0x01, 0x2C, 0xFF, 0x38, 0x00, 0x05]),
        ]);
        let mut dev = Mag3110::new(I2cRegisters::plain(i2c.clone(), A));
        block_on(dev.identify()).unwrap();
        block_on(dev.configure()).unwrap();
        assert_eq!(block_on(dev.read()).unwrap(), [300, -200, 5]);
        i2c.done();
    }

    #[test]
    fn plausibility_check_accepts_earth_field() {
        let mut i2c = I2cMock::new(&[
            I2cT::write_read(A, vec![0x00], vec![0x00]),
            I2cT::write_read(A, vec![0x00], vec![0x0F]),
            I2cT::write_read(A, vec![0x01], be(200, -150, 400)),
        ]);
        let mut dev = Mag3110::new(I2cRegisters::plain(i2c.clone(), A));
        assert_eq!(
            block_on(dev.plausibility_check(&mut NoopDelay)).unwrap(),
            [200, -150, 400]
        );
        i2c.done();
    }

    #[test]
    fn plausibility_check_rejects_dead_or_saturated_or_silent_part() {
        for bad in [be(0, 0, 0), be(200, 12_000, 0)] {
            let mut i2c = I2cMock::new(&[
                I2cT::write_read(A, vec![0x00], vec![0x08]),
                I2cT::write_read(A, vec![0x01], bad),
            ]);
            let mut dev = Mag3110::new(I2cRegisters::plain(i2c.clone(), A));
            assert!(matches!(
                block_on(dev.plausibility_check(&mut NoopDelay)),
                Err(SensorError::SelfTestFailed { .. })
            ));
            i2c.done();
        }
        let script: Vec<I2cT> = (0..10)
            .map(|_| I2cT::write_read(A, vec![0x00], vec![0x00]))
            .collect();
        let mut i2c = I2cMock::new(&script);
        let mut dev = Mag3110::new(I2cRegisters::plain(i2c.clone(), A));
        assert_eq!(
            block_on(dev.plausibility_check(&mut NoopDelay)),
            Err(SensorError::NotReady)
        );
        i2c.done();
    }

    #[test]
    fn scale_matches_board_description() {
        let f = fires_protocol::ScaleFactors::FIRES_PEN.mag_tesla_per_count;
        assert!((MICROTESLA_PER_COUNT * 1e-6 - f).abs() < 1e-15);
    }
}
