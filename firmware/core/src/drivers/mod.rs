//! Register-level drivers for the pen's three inertial sensors, generic over an `embedded-hal-async` I2C bus or
//! SPI device through [`bus::RegisterBus`].
//!
//! Every driver offers the same four steps: `identify` (WHO_AM_I), `configure` (the ranges and rates the FIRES
//! board description promises, see [`crate::board`]), `read` (all three axes in one burst, raw counts) and a
//! self-test (the MAG3110 has none: it gets a plausibility check instead). Register addresses and values are taken
//! from the datasheets named in each module; the tests in each module check them at register level against
//! `embedded-hal-mock`.

pub mod bus;
pub mod l3g4200d;
pub mod lis3lv02dl;
pub mod mag3110;
pub mod sensor;

pub use sensor::{Part, SelfTesting, Sensor};

/// Raw counts of one 3-axis reading: x, y, z.
pub type Axes = [i16; 3];

/// What can go wrong talking to a sensor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SensorError<E> {
    /// The bus transfer failed.
    Bus(E),
    /// WHO_AM_I returned something else than the part's identity.
    WrongId {
        /// The value the datasheet gives.
        expected: u8,
        /// The value read.
        found: u8,
    },
    /// The self-test (or plausibility check) response was outside its window.
    SelfTestFailed {
        /// The per-axis response (counts) that was judged.
        response: Axes,
    },
    /// The part never reported fresh data.
    NotReady,
}

impl<E> From<E> for SensorError<E> {
    fn from(e: E) -> Self {
        SensorError::Bus(e)
    }
}

/// Little-endian x, y, z from six bytes (ST parts with BLE = 0).
pub(crate) fn axes_le(b: &[u8; 6]) -> Axes {
    [
        i16::from_le_bytes([b[0], b[1]]),
        i16::from_le_bytes([b[2], b[3]]),
        i16::from_le_bytes([b[4], b[5]]),
    ]
}

/// Big-endian x, y, z from six bytes (MAG3110: MSB register first).
pub(crate) fn axes_be(b: &[u8; 6]) -> Axes {
    [
        i16::from_be_bytes([b[0], b[1]]),
        i16::from_be_bytes([b[2], b[3]]),
        i16::from_be_bytes([b[4], b[5]]),
    ]
}

/// Per-axis difference `a - b`, saturating.
pub(crate) fn axes_sub(a: Axes, b: Axes) -> Axes {
    [
        a[0].saturating_sub(b[0]),
        a[1].saturating_sub(b[1]),
        a[2].saturating_sub(b[2]),
    ]
}

/// Per-axis mean of a few readings (the self-tests average to beat the noise).
pub(crate) fn axes_mean(samples: &[Axes]) -> Axes {
    let mut sum = [0i32; 3];
    for s in samples {
        for (acc, v) in sum.iter_mut().zip(s) {
            *acc += i32::from(*v);
        }
    }
    let n = samples.len().max(1) as i32;
    sum.map(|v| (v / n) as i16)
}

/// Reads a part's WHO_AM_I register and checks it against the datasheet value (every driver's identity check).
pub(crate) async fn check_identity<B: bus::RegisterBus>(
    bus: &mut B,
    register: u8,
    expected: u8,
) -> Result<(), SensorError<B::Error>> {
    let found = bus.read_register(register).await?;
    if found == expected {
        Ok(())
    } else {
        Err(SensorError::WrongId { expected, found })
    }
}

/// Samples averaged per self-test phase (both parts with a self-test use the same count).
pub(crate) const SELF_TEST_SAMPLES: usize = 2;

/// Mean of [`SELF_TEST_SAMPLES`] little-endian x, y, z readings from the six output registers at `first`,
/// 10 ms apart (one output period): the baseline and excited phases of a self-test.
pub(crate) async fn mean_le_axes<B: bus::RegisterBus, D: embedded_hal_async::delay::DelayNs>(
    bus: &mut B,
    first: u8,
    delay: &mut D,
) -> Result<Axes, SensorError<B::Error>> {
    let mut s = [[0i16; 3]; SELF_TEST_SAMPLES];
    for slot in s.iter_mut() {
        let mut b = [0u8; 6];
        bus.read_registers(first, &mut b).await?;
        *slot = axes_le(&b);
        delay.delay_ms(10).await;
    }
    Ok(axes_mean(&s))
}

/// The self-test both ST parts run (their datasheets' procedure): configure, wait, average the output, switch the
/// self-test bit on in `register`, wait, average again, switch back to the running value, wait, and judge the
/// per-axis change against `min..=max` counts in magnitude. Leaves the part running.
pub struct SelfTest {
    /// The control register holding the self-test bits.
    pub register: u8,
    /// Its value with the self-test on.
    pub excited: u8,
    /// Its running value.
    pub running: u8,
    /// The first of the six output registers (little-endian x, y, z).
    pub output: u8,
    /// Settling time after each change, milliseconds.
    pub settle_ms: u32,
    /// Smallest acceptable change, counts.
    pub min: i16,
    /// Largest acceptable change, counts.
    pub max: i16,
}

impl SelfTest {
    /// Runs the test on a part already configured for running; returns the per-axis change.
    pub async fn run<B: bus::RegisterBus, D: embedded_hal_async::delay::DelayNs>(
        &self,
        bus: &mut B,
        delay: &mut D,
    ) -> Result<Axes, SensorError<B::Error>> {
        delay.delay_ms(self.settle_ms).await;
        let base = mean_le_axes(bus, self.output, delay).await?;
        bus.write_register(self.register, self.excited).await?;
        delay.delay_ms(self.settle_ms).await;
        let excited = mean_le_axes(bus, self.output, delay).await?;
        bus.write_register(self.register, self.running).await?;
        delay.delay_ms(self.settle_ms).await;
        let response = axes_sub(excited, base);
        if response
            .iter()
            .all(|d| (self.min..=self.max).contains(&d.saturating_abs()))
        {
            Ok(response)
        } else {
            Err(SensorError::SelfTestFailed { response })
        }
    }
}
