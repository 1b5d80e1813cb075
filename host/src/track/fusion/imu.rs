//! IMU samples in SI units, the raw-count scale factors, and the world reference directions.

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

/// One IMU sample in SI units, pen frame.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ImuSample {
    /// Sample time, nanoseconds (same clock as the camera timestamps).
    pub t_ns: u64,
    /// Specific force, m/s^2 (reads +g "up" at rest).
    pub accel: [f64; 3],
    /// Angular rate, rad/s.
    pub gyro: [f64; 3],
    /// Magnetic field (any unit; only its direction is used), e.g. microtesla.
    pub mag: [f64; 3],
}

/// Raw-count to SI conversion (the smart-pen's 16-bit sensor values).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ImuScale {
    /// m/s^2 per accelerometer count.
    pub accel_per_count: f64,
    /// rad/s per gyroscope count.
    pub gyro_per_count: f64,
    /// Microtesla per magnetometer count.
    pub mag_per_count: f64,
    /// Rotation from the sensor axes to the pen frame (identity when aligned).
    pub pen_from_sensor: [[f64; 3]; 3],
}

impl Default for ImuScale {
    fn default() -> Self {
        Self {
            accel_per_count: 9.80665 / 1024.0,
            gyro_per_count: 0.070f64.to_radians(),
            mag_per_count: 0.1,
            pen_from_sensor: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        }
    }
}

impl ImuScale {
    /// Converts raw counts to an SI sample in the pen frame.
    pub fn to_si(&self, t_ns: u64, accel: [i16; 3], gyro: [i16; 3], mag: [i16; 3]) -> ImuSample {
        let m = Matrix3::from_row_slice(&self.pen_from_sensor.concat());
        let conv = |v: [i16; 3], k: f64| {
            let s = m * Vector3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2])) * k;
            [s.x, s.y, s.z]
        };
        ImuSample {
            t_ns,
            accel: conv(accel, self.accel_per_count),
            gyro: conv(gyro, self.gyro_per_count),
            mag: conv(mag, self.mag_per_count),
        }
    }
}

/// Directions of gravity ("up", opposite to gravity) and of the magnetic field in the world
/// (left camera) frame, plus the gravity magnitude.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WorldReference {
    /// Unit "up" vector in the world frame (OpenCV camera held level: `(0, -1, 0)`).
    pub up: [f64; 3],
    /// Magnetic field direction in the world frame (need not be unit, must not be vertical).
    pub magnetic: [f64; 3],
    /// Gravity magnitude, m/s^2.
    pub gravity: f64,
}

impl Default for WorldReference {
    fn default() -> Self {
        // Level camera looking north-ish with 60 degrees of magnetic dip.
        Self {
            up: [0.0, -1.0, 0.0],
            magnetic: [0.0, 0.866, 0.5],
            gravity: 9.80665,
        }
    }
}

impl WorldReference {
    /// Unit up vector.
    pub fn up(&self) -> Vector3<f64> {
        Vector3::from(self.up)
            .try_normalize(1e-12)
            .unwrap_or_else(|| -Vector3::y())
    }

    /// Unit magnetic direction.
    pub fn magnetic(&self) -> Vector3<f64> {
        Vector3::from(self.magnetic)
            .try_normalize(1e-12)
            .unwrap_or_else(Vector3::z)
    }

    /// World-from-pen orientation from one accelerometer + magnetometer pair (TRIAD), or None
    /// when the readings are degenerate (zero, or field parallel to gravity).
    pub fn triad(&self, accel: &Vector3<f64>, mag: &Vector3<f64>) -> Option<UnitQuaternion<f64>> {
        let body = triad_basis(accel, mag)?;
        let world = triad_basis(&self.up(), &self.magnetic())?;
        let r = world * body.transpose();
        Some(UnitQuaternion::from_rotation_matrix(
            &Rotation3::from_matrix(&r),
        ))
    }
}

/// Orthonormal basis [up, north, east] from an up-like and a field-like vector.
fn triad_basis(up: &Vector3<f64>, field: &Vector3<f64>) -> Option<Matrix3<f64>> {
    let u = up.try_normalize(1e-9)?;
    let n = (field - u * field.dot(&u)).try_normalize(1e-9)?;
    let e = u.cross(&n);
    Some(Matrix3::from_columns(&[u, n, e]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triad_recovers_orientation_and_counts_convert() {
        let world = WorldReference::default();
        let q = UnitQuaternion::from_euler_angles(0.3, -0.7, 2.0);
        let accel = q.inverse() * world.up() * 9.8;
        let mag = q.inverse() * world.magnetic() * 48.0;
        let est = world.triad(&accel, &mag).unwrap();
        assert!(est.angle_to(&q) < 1e-9);
        let s = ImuScale::default().to_si(5, [0, 0, 1024], [1000, 0, 0], [0, 480, 0]);
        assert!((s.accel[2] - 9.80665).abs() < 1e-12);
        assert!((s.gyro[0] - 70f64.to_radians()).abs() < 1e-12);
        assert!((s.mag[1] - 48.0).abs() < 1e-12);
    }
}
