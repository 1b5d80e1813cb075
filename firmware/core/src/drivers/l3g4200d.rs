//! ST L3G4200D 3-axis gyroscope (datasheet Rev 3, December 2010, §7 "Register mapping", §8 "Register description",
//! Table 4 "Mechanical characteristics").
//!
//! Configuration used by FIRES:
//! - `CTRL_REG4` (0x23) = `0xB0`: BDU = 1, BLE = 0 (little endian), FS1..0 = 11 (**±2000 dps**, 70 mdps/digit, the
//!   gyroscope factor of [`fires_protocol::ScaleFactors::FIRES_PEN`]), ST1..0 = 00 (normal), SIM = 0.
//! - `CTRL_REG1` (0x20) = `0x1F`: DR1..0 = 00 (**100 Hz** output rate), BW1..0 = 01 (25 Hz cut-off), PD = 1
//!   (normal mode), Zen = Xen = Yen = 1.
//!
//! Self-test: ST1..0 = 01 ("self-test 0") displaces the proof masses; Table 4 gives a typical output change of
//! 530 dps at ±2000 dps. FIRES accepts 50 %..150 % of that per axis (no min/max is specified).
//!
//! I2C address 0x69 (SDO tied high; 0x68 with SDO low); sub-address bit 7 requests auto-increment.

use super::{Part, SelfTest, SelfTesting, Sensor};

/// 7-bit I2C address with SDO high (the FIRES board).
pub const I2C_ADDRESS: u8 = 0x69;
/// 7-bit I2C address with SDO low.
pub const I2C_ADDRESS_SDO_LOW: u8 = 0x68;
/// Value of WHO_AM_I.
pub const WHO_AM_I_VALUE: u8 = 0xD3;
/// Degrees per second per count at ±2000 dps.
pub const DPS_PER_COUNT: f64 = 0.070;
/// Output data rate configured, Hz.
pub const OUTPUT_RATE_HZ: u32 = 100;

/// Register addresses.
pub mod reg {
    /// Identity register.
    pub const WHO_AM_I: u8 = 0x0F;
    /// Data rate, bandwidth, power, axis enables.
    pub const CTRL_REG1: u8 = 0x20;
    /// BDU, endianness, full scale, self-test.
    pub const CTRL_REG4: u8 = 0x23;
    /// Data status.
    pub const STATUS_REG: u8 = 0x27;
    /// First output register (X low byte).
    pub const OUT_X_L: u8 = 0x28;
}

/// `CTRL_REG1`: 100 Hz, 25 Hz cut-off, normal mode, XYZ on.
pub const CTRL_REG1_VALUE: u8 = 0x1F;
/// `CTRL_REG4`: BDU, little endian, ±2000 dps, self-test off.
pub const CTRL_REG4_RUN: u8 = 0xB0;
/// `CTRL_REG4` with ST1..0 = 01 (self-test 0).
pub const CTRL_REG4_SELF_TEST: u8 = CTRL_REG4_RUN | 0x02;

/// Typical self-test output change at ±2000 dps, counts (530 dps / 70 mdps).
pub const SELF_TEST_TYPICAL_COUNTS: i16 = 7571;
/// Smallest accepted self-test change per axis, counts (50 % of typical).
pub const SELF_TEST_MIN_COUNTS: i16 = SELF_TEST_TYPICAL_COUNTS / 2;
/// Largest accepted self-test change per axis, counts (150 % of typical).
pub const SELF_TEST_MAX_COUNTS: i16 = SELF_TEST_TYPICAL_COUNTS / 2 * 3;
const SETTLE_MS: u32 = 60;

/// The L3G4200D register map.
#[derive(Debug)]
pub struct Gyroscope;

impl Part for Gyroscope {
    const WHO_AM_I: u8 = reg::WHO_AM_I;
    const WHO_AM_I_VALUE: u8 = WHO_AM_I_VALUE;
    const CONFIGURATION: &'static [(u8, u8)] = &[
        (reg::CTRL_REG4, CTRL_REG4_RUN),
        (reg::CTRL_REG1, CTRL_REG1_VALUE),
    ];
    const OUTPUT: u8 = reg::OUT_X_L;
    const BIG_ENDIAN: bool = false;
}

/// The gyroscope.
pub type L3g4200d<B> = Sensor<B, Gyroscope>;

impl SelfTesting for Gyroscope {
    /// Self-test 0: the change of the mean output with ST = 01 against normal mode must be within
    /// [`SELF_TEST_MIN_COUNTS`]..=[`SELF_TEST_MAX_COUNTS`] in magnitude on every axis. Leaves the part running.
    const SELF_TEST: SelfTest = SelfTest {
        register: reg::CTRL_REG4,
        excited: CTRL_REG4_SELF_TEST,
        running: CTRL_REG4_RUN,
        output: reg::OUT_X_L,
        settle_ms: SETTLE_MS,
        min: SELF_TEST_MIN_COUNTS,
        max: SELF_TEST_MAX_COUNTS,
    };
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::drivers::bus::I2cRegisters;
    use crate::drivers::SensorError;
    use embassy_futures::block_on;
    use embedded_hal_mock::eh1::delay::NoopDelay;
    use embedded_hal_mock::eh1::i2c::{Mock as I2cMock, Transaction as I2cT};
    use std::vec;
    use std::vec::Vec;

    const A: u8 = I2C_ADDRESS;

    fn sample(x: i16, y: i16, z: i16) -> Vec<u8> {
        [x, y, z].iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    #[test]
    fn identify_configure_read() {
        let mut i2c = I2cMock::new(&[
            I2cT::write_read(A, vec![0x0F], vec![0xD3]),
            I2cT::write(A, vec![0x23, 0xB0]),
            I2cT::write(A, vec![0x20, 0x1F]),
            I2cT::write_read(A, vec![0xA8], sample(-5, 7, 14286)),
            I2cT::write_read(A, vec![0x0F], vec![0xD4]),
        ]);
        let mut dev = L3g4200d::new(I2cRegisters::st(i2c.clone(), A));
        block_on(dev.identify()).unwrap();
        block_on(dev.configure()).unwrap();
        assert_eq!(block_on(dev.read()).unwrap(), [-5, 7, 14286]);
        assert!(matches!(
            block_on(dev.identify()),
            Err(SensorError::WrongId { found: 0xD4, .. })
        ));
        i2c.done();
    }

    fn script(delta: (i16, i16, i16)) -> Vec<I2cT> {
        let base = (3, -4, 5);
        let ex = (base.0 + delta.0, base.1 + delta.1, base.2 + delta.2);
        vec![
            I2cT::write(A, vec![0x23, 0xB0]),
            I2cT::write(A, vec![0x20, 0x1F]),
            I2cT::write_read(A, vec![0xA8], sample(base.0, base.1, base.2)),
            I2cT::write_read(A, vec![0xA8], sample(base.0, base.1, base.2)),
            I2cT::write(A, vec![0x23, 0xB2]),
            I2cT::write_read(A, vec![0xA8], sample(ex.0, ex.1, ex.2)),
            I2cT::write_read(A, vec![0xA8], sample(ex.0, ex.1, ex.2)),
            I2cT::write(A, vec![0x23, 0xB0]),
        ]
    }

    #[test]
    fn self_test_window() {
        let mut i2c = I2cMock::new(&script((7500, -7600, 7000)));
        let mut dev = L3g4200d::new(I2cRegisters::st(i2c.clone(), A));
        assert_eq!(
            block_on(dev.self_test(&mut NoopDelay)).unwrap(),
            [7500, -7600, 7000]
        );
        i2c.done();

        let mut i2c = I2cMock::new(&script((7500, 200, 7000)));
        let mut dev = L3g4200d::new(I2cRegisters::st(i2c.clone(), A));
        assert!(matches!(
            block_on(dev.self_test(&mut NoopDelay)),
            Err(SensorError::SelfTestFailed { .. })
        ));
        i2c.done();
    }

    #[test]
    fn works_over_spi_too() {
        use crate::drivers::bus::SpiRegisters;
        use embedded_hal_mock::eh1::spi::{Mock as SpiMock, Transaction as SpiT};
        let mut spi = SpiMock::new(&[
            SpiT::transaction_start(),
            SpiT::write(0x8F), // read WHO_AM_I
            SpiT::read(0xD3),
            SpiT::transaction_end(),
            SpiT::transaction_start(),
            SpiT::write_vec(vec![0x23, 0xB0]),
            SpiT::transaction_end(),
            SpiT::transaction_start(),
            SpiT::write_vec(vec![0x20, 0x1F]),
            SpiT::transaction_end(),
            SpiT::transaction_start(),
            SpiT::write(0xE8), // read | auto-increment | OUT_X_L
            SpiT::read_vec(sample(100, -100, 0)),
            SpiT::transaction_end(),
        ]);
        let mut dev = L3g4200d::new(SpiRegisters::new(spi.clone()));
        block_on(dev.identify()).unwrap();
        block_on(dev.configure()).unwrap();
        assert_eq!(block_on(dev.read()).unwrap(), [100, -100, 0]);
        spi.done();
    }

    #[test]
    fn scale_matches_board_description() {
        let f = fires_protocol::ScaleFactors::FIRES_PEN.gyro_radps_per_count;
        assert!((DPS_PER_COUNT.to_radians() - f).abs() < 1e-12);
    }
}
