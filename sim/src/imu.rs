//! The pen's IMU at 100 Hz: accelerometer (specific force, gravity included), gyroscope (bias, bias random walk,
//! noise) and magnetometer (Earth field, hard and soft iron, noise), quantised through the board's scale factors
//! and clamped to the sensors' ranges, sampled on the pen's own (drifting) clock.
//!
//! The IMU sits on the pen axis at `lever_arm_m` in the pen frame with its axes aligned to the pen frame. The
//! specific force is `f = R^T (a_imu - g)` where `a_imu` is the acceleration of the IMU point (so rotation adds
//! centripetal and tangential terms) and `g` the gravity vector in the world; at rest it reads `-R^T g`.

use crate::motion::Trajectory;
use crate::objects::V3;
use crate::rng::SimRng;
use fires_protocol::{ScaleFactors, SensorPacket};
use nalgebra::{Matrix3, UnitQuaternion};

/// IMU error model and environment.
#[derive(Clone, Debug, PartialEq)]
pub struct ImuConfig {
    /// Position of the IMU in the pen frame, metres.
    pub lever_arm_m: V3,
    /// Gravity in the world frame, m/s^2.
    pub gravity_world: V3,
    /// Earth magnetic field in the world frame, tesla.
    pub earth_field_world: V3,
    /// Accelerometer constant bias, m/s^2.
    pub accel_bias: V3,
    /// Accelerometer white noise per sample, m/s^2.
    pub accel_noise: f64,
    /// Gyro initial bias, rad/s.
    pub gyro_bias: V3,
    /// Gyro bias random walk, rad/s per sqrt(second).
    pub gyro_bias_walk: f64,
    /// Gyro white noise per sample, rad/s.
    pub gyro_noise: f64,
    /// Magnetometer hard-iron offset, tesla.
    pub hard_iron: V3,
    /// Magnetometer soft-iron matrix.
    pub soft_iron: Matrix3<f64>,
    /// Magnetometer white noise per sample, tesla.
    pub mag_noise: f64,
    /// Board scale factors.
    pub scale: ScaleFactors,
}

impl ImuConfig {
    /// The same configuration with every noise, bias and distortion removed (for closed-form tests).
    pub fn ideal(&self) -> Self {
        ImuConfig {
            accel_bias: V3::zeros(),
            accel_noise: 0.0,
            gyro_bias: V3::zeros(),
            gyro_bias_walk: 0.0,
            gyro_noise: 0.0,
            hard_iron: V3::zeros(),
            soft_iron: Matrix3::identity(),
            mag_noise: 0.0,
            ..self.clone()
        }
    }
}

/// Sensor full-scale limits in counts: LIS3LV02DL +-2 g 12-bit, L3G4200D 16-bit, MAG3110 +-1000 uT.
pub const ACCEL_RANGE_COUNTS: (i16, i16) = (-2048, 2047);
/// Gyroscope count limits.
pub const GYRO_RANGE_COUNTS: (i16, i16) = (i16::MIN, i16::MAX);
/// Magnetometer count limits.
pub const MAG_RANGE_COUNTS: (i16, i16) = (-10000, 10000);

/// The ideal (error-free) kinematic quantities at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kinematics {
    /// Specific force at the IMU in the pen frame, m/s^2.
    pub specific_force: V3,
    /// Angular velocity in the pen frame, rad/s.
    pub angular_velocity: V3,
    /// Earth field in the pen frame, tesla.
    pub earth_field: V3,
}

/// Differentiation step for the kinematics, seconds.
const H: f64 = 1e-3;
/// Averaging window of the sensors' output filter: one sample period, seconds.
pub const FILTER_WINDOW_S: f64 = 0.01;

/// Ideal kinematics of the trajectory at time `t`, as seen through the sensors' output filter: the mean specific
/// force and angular velocity over the window `[t - W/2, t + W/2]` (W = 10 ms, one sample period), i.e.
/// `(v(t + W/2) - v(t - W/2)) / W` with velocities from central differences (1 ms step), and the rotation from
/// `q(t - W/2)` to `q(t + W/2)` divided by W. Without this filter a curvature discontinuity of the surface (the
/// rounded box) would show up as single-sample spikes. The Earth field is taken at `t`.
pub fn kinematics(traj: &Trajectory, cfg: &ImuConfig, t: f64) -> Kinematics {
    let p = |t: f64| {
        let pose = traj.pose(t);
        (pose.tip + pose.q * cfg.lever_arm_m, pose.q)
    };
    let half = FILTER_WINDOW_S / 2.0;
    let (a0, qa) = p(t - half - H);
    let (a1, _) = p(t - half + H);
    let (b0, _) = p(t + half - H);
    let (b1, qb) = p(t + half + H);
    let (_, q0) = p(t);
    let v_a = (a1 - a0) / (2.0 * H);
    let v_b = (b1 - b0) / (2.0 * H);
    let acc = (v_b - v_a) / FILTER_WINDOW_S;
    // Mean body rate: rotation between the window ends (the H offsets cancel to first order).
    let dq: UnitQuaternion<f64> = qa.inverse() * qb;
    let omega = dq.scaled_axis() / (FILTER_WINDOW_S + 2.0 * H);
    let inv = q0.inverse();
    Kinematics {
        specific_force: inv * (acc - cfg.gravity_world),
        angular_velocity: omega,
        earth_field: inv * cfg.earth_field_world,
    }
}

/// Quantises one axis value through a scale factor, rounding to nearest and clamping to the range.
pub fn quantise(value: f64, per_count: f64, range: (i16, i16)) -> i16 {
    let c = (value / per_count).round();
    c.clamp(f64::from(range.0), f64::from(range.1)) as i16
}

/// Stateful IMU sampler (holds the drifting gyro bias and the noise stream).
#[derive(Clone, Debug)]
pub struct Imu {
    cfg: ImuConfig,
    gyro_bias: V3,
    rng: SimRng,
}

impl Imu {
    /// A new IMU.
    pub fn new(cfg: ImuConfig, rng: SimRng) -> Self {
        Imu {
            gyro_bias: cfg.gyro_bias,
            cfg,
            rng,
        }
    }

    /// The configuration.
    pub fn config(&self) -> &ImuConfig {
        &self.cfg
    }

    /// Current gyro bias, rad/s.
    pub fn gyro_bias(&self) -> V3 {
        self.gyro_bias
    }

    /// Measures the given ideal kinematics: adds errors, quantises, and advances the bias walk by `dt` seconds.
    pub fn measure(&mut self, k: &Kinematics, counter: u8, dt: f64) -> SensorPacket {
        let c = &self.cfg;
        let s = c.scale;
        let n3 = |rng: &mut SimRng, sigma: f64| {
            V3::new(rng.gauss(sigma), rng.gauss(sigma), rng.gauss(sigma))
        };
        let acc = k.specific_force + c.accel_bias + n3(&mut self.rng, c.accel_noise);
        let gyr = k.angular_velocity + self.gyro_bias + n3(&mut self.rng, c.gyro_noise);
        let mag = c.soft_iron * k.earth_field + c.hard_iron + n3(&mut self.rng, c.mag_noise);
        let walk = c.gyro_bias_walk * dt.max(0.0).sqrt();
        self.gyro_bias += n3(&mut self.rng, walk);
        let q = |v: V3, per: f64, r: (i16, i16)| {
            [
                quantise(v.x, per, r),
                quantise(v.y, per, r),
                quantise(v.z, per, r),
            ]
        };
        SensorPacket {
            counter,
            accel: q(acc, s.accel_mps2_per_count, ACCEL_RANGE_COUNTS),
            gyro: q(gyr, s.gyro_radps_per_count, GYRO_RANGE_COUNTS),
            mag: q(mag, s.mag_tesla_per_count, MAG_RANGE_COUNTS),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantisation_rounds_and_saturates() {
        assert_eq!(quantise(0.0, 0.1, ACCEL_RANGE_COUNTS), 0);
        assert_eq!(quantise(0.149, 0.1, ACCEL_RANGE_COUNTS), 1);
        assert_eq!(quantise(-0.151, 0.1, ACCEL_RANGE_COUNTS), -2);
        assert_eq!(quantise(1e9, 0.1, ACCEL_RANGE_COUNTS), 2047);
        assert_eq!(quantise(-1e9, 0.1, MAG_RANGE_COUNTS), -10000);
        assert_eq!(quantise(f64::NAN, 0.1, GYRO_RANGE_COUNTS), 0);
    }
}
