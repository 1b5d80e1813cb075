//! ST LIS3LV02DL 3-axis accelerometer (datasheet Rev 2, January 2008, §7 "Register mapping" and §8 "Register
//! description").
//!
//! Configuration used by FIRES:
//! - `CTRL_REG1` (0x20) = `0xD7`: PD1..0 = 11 (device on), DF1..0 = 01 (decimation 128: **160 Hz** output rate),
//!   ST = 0, Zen = Yen = Xen = 1. The part has no 100 Hz rate (40/160/640/2560 Hz); the 100 Hz sampler reads the
//!   newest 160 Hz sample, so a packet's accelerometer value is at most 6.25 ms old.
//! - `CTRL_REG2` (0x21) = `0x40`: FS = 0 (**±2 g**), BDU = 1 (the high and low bytes of one reading always belong
//!   together), BLE = 0 (little endian), DAS = 0 (**12-bit right-justified**): 1024 counts/g typical, the
//!   accelerometer factor of [`fires_protocol::ScaleFactors::FIRES_PEN`].
//!
//! I2C address 0x1D (SAD 0011101b); the sub-address bit 7 requests auto-increment (see [`super::bus`]).

use super::{Part, SelfTest, SelfTesting, Sensor};

/// 7-bit I2C address.
pub const I2C_ADDRESS: u8 = 0x1D;
/// Value of WHO_AM_I.
pub const WHO_AM_I_VALUE: u8 = 0x3A;
/// Counts per g at ±2 g, 12-bit right-justified (datasheet typical sensitivity).
pub const COUNTS_PER_G: f64 = 1024.0;
/// Output data rate configured, Hz.
pub const OUTPUT_RATE_HZ: u32 = 160;

/// Register addresses.
pub mod reg {
    /// Identity register.
    pub const WHO_AM_I: u8 = 0x0F;
    /// Power, decimation, self-test, axis enables.
    pub const CTRL_REG1: u8 = 0x20;
    /// Full scale, BDU, endianness, data alignment.
    pub const CTRL_REG2: u8 = 0x21;
    /// Data status.
    pub const STATUS_REG: u8 = 0x27;
    /// First output register (X low byte); X, Y, Z low/high follow.
    pub const OUTX_L: u8 = 0x28;
}

/// `CTRL_REG1` for normal operation (on, 160 Hz, XYZ).
pub const CTRL_REG1_RUN: u8 = 0xD7;
/// `CTRL_REG1` with the self-test bit (ST, bit 3) set.
pub const CTRL_REG1_SELF_TEST: u8 = CTRL_REG1_RUN | 0x08;
/// `CTRL_REG2`: ±2 g, BDU, little endian, 12-bit right-justified.
pub const CTRL_REG2_VALUE: u8 = 0x40;

/// Smallest accepted self-test change per axis, counts (about 0.1 g).
///
/// The FIRES acceptance window is deliberately wider than the datasheet's self-test output change at ±2 g; the
/// exact min/max of the electrical characteristics table must be confirmed on real parts (hardware-docs/board.md).
pub const SELF_TEST_MIN_COUNTS: i16 = 100;
/// Largest accepted self-test change per axis, counts (about 1.2 g).
pub const SELF_TEST_MAX_COUNTS: i16 = 1200;
/// Readings averaged in each self-test phase.
/// Settling time after a mode change, ms (several 160 Hz periods).
const SETTLE_MS: u32 = 50;

/// The LIS3LV02DL register map.
#[derive(Debug)]
pub struct Accelerometer;

impl Part for Accelerometer {
    const WHO_AM_I: u8 = reg::WHO_AM_I;
    const WHO_AM_I_VALUE: u8 = WHO_AM_I_VALUE;
    const CONFIGURATION: &'static [(u8, u8)] = &[
        (reg::CTRL_REG2, CTRL_REG2_VALUE),
        (reg::CTRL_REG1, CTRL_REG1_RUN),
    ];
    const OUTPUT: u8 = reg::OUTX_L;
    const BIG_ENDIAN: bool = false;
}

/// The accelerometer.
pub type Lis3lv02dl<B> = Sensor<B, Accelerometer>;

impl SelfTesting for Accelerometer {
    /// The electrostatic self-test: mean output with ST = 1 minus mean output with ST = 0, each axis within
    /// [`SELF_TEST_MIN_COUNTS`]..=[`SELF_TEST_MAX_COUNTS`] in magnitude. Leaves the part configured for running.
    /// The pen must be held still. Returns the per-axis change.
    const SELF_TEST: SelfTest = SelfTest {
        register: reg::CTRL_REG1,
        excited: CTRL_REG1_SELF_TEST,
        running: CTRL_REG1_RUN,
        output: reg::OUTX_L,
        settle_ms: SETTLE_MS,
        min: SELF_TEST_MIN_COUNTS,
        max: SELF_TEST_MAX_COUNTS,
    };
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::drivers::bus::RegisterBus;
    use crate::drivers::bus::{I2cRegisters, SpiRegisters};
    use crate::drivers::SensorError;
    use embassy_futures::block_on;
    use embedded_hal::i2c::ErrorKind;
    use embedded_hal_mock::eh1::delay::NoopDelay;
    use embedded_hal_mock::eh1::i2c::{Mock as I2cMock, Transaction as I2cT};
    use embedded_hal_mock::eh1::spi::{Mock as SpiMock, Transaction as SpiT};
    use std::vec;
    use std::vec::Vec;

    const A: u8 = I2C_ADDRESS;

    fn sample(x: i16, y: i16, z: i16) -> Vec<u8> {
        [x, y, z].iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    #[test]
    fn identifies_over_i2c() {
        let mut i2c = I2cMock::new(&[
            I2cT::write_read(A, vec![0x0F], vec![0x3A]),
            I2cT::write_read(A, vec![0x0F], vec![0x33]),
        ]);
        let mut dev = Lis3lv02dl::new(I2cRegisters::st(i2c.clone(), A));
        assert_eq!(block_on(dev.identify()), Ok(()));
        assert_eq!(
            block_on(dev.identify()),
            Err(SensorError::WrongId {
                expected: 0x3A,
                found: 0x33
            })
        );
        i2c.done();
    }

    #[test]
    fn configures_and_reads_with_auto_increment() {
        let mut i2c = I2cMock::new(&[
            I2cT::write(A, vec![0x21, 0x40]),
            I2cT::write(A, vec![0x20, 0xD7]),
            // 0x28 | 0x80: auto-increment over OUTX_L..OUTZ_H
            I2cT::write_read(A, vec![0xA8], sample(12, -1024, 1000)),
        ]);
        let mut dev = Lis3lv02dl::new(I2cRegisters::st(i2c.clone(), A));
        block_on(dev.configure()).unwrap();
        assert_eq!(block_on(dev.read()).unwrap(), [12, -1024, 1000]);
        i2c.done();
    }

    #[test]
    fn reads_over_spi_with_read_and_ms_bits() {
        let mut spi = SpiMock::new(&[
            SpiT::transaction_start(),
            SpiT::write(0x8F),
            SpiT::read(0x3A),
            SpiT::transaction_end(),
            SpiT::transaction_start(),
            SpiT::write_vec(vec![0x20, 0xD7]),
            SpiT::transaction_end(),
            SpiT::transaction_start(),
            SpiT::write(0xE8), // read | MS | 0x28
            SpiT::read_vec(sample(1, 2, 3)),
            SpiT::transaction_end(),
        ]);
        let mut bus = SpiRegisters::new(spi.clone());
        block_on(bus.read_register(reg::WHO_AM_I)).unwrap();
        block_on(bus.write_register(reg::CTRL_REG1, CTRL_REG1_RUN)).unwrap();
        let mut dev = Lis3lv02dl::new(bus);
        assert_eq!(block_on(dev.read()).unwrap(), [1, 2, 3]);
        spi.done();
    }

    fn self_test_script(excited: (i16, i16, i16)) -> Vec<I2cT> {
        let mut t = vec![
            I2cT::write(A, vec![0x21, 0x40]),
            I2cT::write(A, vec![0x20, 0xD7]),
            I2cT::write_read(A, vec![0xA8], sample(10, -20, 1024)),
            I2cT::write_read(A, vec![0xA8], sample(10, -20, 1024)),
            I2cT::write(A, vec![0x20, 0xDF]),
        ];
        let (x, y, z) = excited;
        t.push(I2cT::write_read(A, vec![0xA8], sample(x, y, z)));
        t.push(I2cT::write_read(A, vec![0xA8], sample(x, y, z)));
        t.push(I2cT::write(A, vec![0x20, 0xD7]));
        t
    }

    #[test]
    fn self_test_passes_inside_window() {
        let mut i2c = I2cMock::new(&self_test_script((10 + 400, -20 - 400, 1024 + 600)));
        let mut dev = Lis3lv02dl::new(I2cRegisters::st(i2c.clone(), A));
        assert_eq!(
            block_on(dev.self_test(&mut NoopDelay)).unwrap(),
            [400, -400, 600]
        );
        i2c.done();
    }

    #[test]
    fn self_test_fails_on_dead_axis() {
        let mut i2c = I2cMock::new(&self_test_script((410, -420, 1024)));
        let mut dev = Lis3lv02dl::new(I2cRegisters::st(i2c.clone(), A));
        assert_eq!(
            block_on(dev.self_test(&mut NoopDelay)),
            Err(SensorError::SelfTestFailed {
                response: [400, -400, 0]
            })
        );
        i2c.done();
    }

    #[test]
    fn bus_errors_are_reported() {
        let mut i2c = I2cMock::new(&[
            I2cT::write_read(A, vec![0xA8], sample(0, 0, 0)).with_error(ErrorKind::Other)
        ]);
        let mut dev = Lis3lv02dl::new(I2cRegisters::st(i2c.clone(), A));
        assert_eq!(
            block_on(dev.read()),
            Err(SensorError::Bus(ErrorKind::Other))
        );
        i2c.done();
    }
}
