//! The board description the host needs: scale factors and rates (hardware-docs/board.md).
//!
//! Scale factors live here and in the recording metadata, never in the packets (hardware-docs/protocol.md).

use fires_protocol::ScaleFactors;

use crate::drivers::{l3g4200d, lis3lv02dl, mag3110};

/// Firmware version reported in status packets (major, minor).
pub const FIRMWARE_VERSION: (u8, u8) = (0, 1);

/// Scale factors of the FIRES board at the ranges the drivers configure, derived from the drivers' datasheet
/// constants (the tests check they equal [`ScaleFactors::FIRES_PEN`]).
pub fn scale_factors() -> ScaleFactors {
    ScaleFactors {
        accel_mps2_per_count: fires_protocol::scale::STANDARD_GRAVITY / lis3lv02dl::COUNTS_PER_G,
        gyro_radps_per_count: l3g4200d::DPS_PER_COUNT.to_radians(),
        mag_tesla_per_count: mag3110::MICROTESLA_PER_COUNT * 1e-6,
    }
}

/// Output data rates the sensors run at, Hz: accelerometer, gyroscope, magnetometer. The packet rate is
/// [`fires_protocol::SAMPLE_RATE_HZ`]; each packet carries the newest reading of each sensor.
pub const SENSOR_RATES_HZ: [u32; 3] = [
    lis3lv02dl::OUTPUT_RATE_HZ,
    l3g4200d::OUTPUT_RATE_HZ,
    mag3110::OUTPUT_RATE_HZ,
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drivers_agree_with_protocol_defaults() {
        let a = scale_factors();
        let b = ScaleFactors::FIRES_PEN;
        assert!((a.accel_mps2_per_count - b.accel_mps2_per_count).abs() < 1e-12);
        assert!((a.gyro_radps_per_count - b.gyro_radps_per_count).abs() < 1e-12);
        assert!((a.mag_tesla_per_count - b.mag_tesla_per_count).abs() < 1e-18);
    }
}
