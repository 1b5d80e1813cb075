//! Physical scale factors of the pen's sensors: part of the board description, never of the packet
//! (hardware-docs/protocol.md). The host reads them from a recording's metadata; these are the defaults for the FIRES
//! board (hardware-docs/board.md) at the ranges the firmware configures.

/// Multipliers from raw packet counts to SI units.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ScaleFactors {
    /// Accelerometer: metres per second squared per count.
    pub accel_mps2_per_count: f64,
    /// Gyroscope: radians per second per count.
    pub gyro_radps_per_count: f64,
    /// Magnetometer: tesla per count.
    pub mag_tesla_per_count: f64,
}

/// Standard gravity, m/s^2, used to convert datasheet milli-g figures.
pub const STANDARD_GRAVITY: f64 = 9.806_65;

impl ScaleFactors {
    /// The FIRES pen: LIS3LV02DL at ±2 g, 12-bit right-justified (1024 counts/g),
    /// L3G4200D at ±2000 dps (70 mdps/count), MAG3110 (0.1 µT/count).
    pub const FIRES_PEN: ScaleFactors = ScaleFactors {
        accel_mps2_per_count: STANDARD_GRAVITY / 1024.0,
        gyro_radps_per_count: 0.070 * core::f64::consts::PI / 180.0,
        mag_tesla_per_count: 0.1e-6,
    };
}

impl Default for ScaleFactors {
    fn default() -> Self {
        Self::FIRES_PEN
    }
}
