//! Deterministic synthetic data for the tracker's tests and benches: a pen-in-front-of-the-rig scene projected
//! into both cameras, and IMU samples of a moving pen (random numbers from [`crate::rng`]).

use crate::stereo::{CameraId, StereoRig};
use crate::track::pen::{PenGeometry, LED_COUNT};
use nalgebra::{UnitQuaternion, Vector3};

pub use crate::rng::SplitMix64;

/// A pen pose: LED 1 position and world-from-pen rotation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PenPose {
    /// World position of LED 1.
    pub led1: Vector3<f64>,
    /// World-from-pen rotation (pen +x = towards the tip).
    pub rotation: UnitQuaternion<f64>,
}

impl PenPose {
    /// A random pose with LED 1 at depth `[z_min, z_max]` and the pen pointing roughly away from the
    /// cameras' view direction (tilted at most `max_tilt` radians from the image plane), so all LEDs
    /// stay in front of the rig.
    pub fn random(rng: &mut SplitMix64, z_min: f64, z_max: f64, max_tilt: f64) -> Self {
        let z = rng.uniform(z_min, z_max);
        let led1 = Vector3::new(rng.uniform(-0.25, 0.25) * z, rng.uniform(-0.2, 0.2) * z, z);
        let yaw = rng.uniform(-std::f64::consts::PI, std::f64::consts::PI);
        let tilt = rng.uniform(-max_tilt, max_tilt);
        let dir = Vector3::new(yaw.cos() * tilt.cos(), yaw.sin() * tilt.cos(), tilt.sin());
        let roll = rng.uniform(-std::f64::consts::PI, std::f64::consts::PI);
        let align = UnitQuaternion::rotation_between(&Vector3::x(), &dir)
            .unwrap_or_else(UnitQuaternion::identity);
        Self {
            led1,
            rotation: align * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), roll),
        }
    }

    /// Unit pen direction (towards the tip).
    pub fn direction(&self) -> Vector3<f64> {
        self.rotation * Vector3::x()
    }
}

/// Pixel projections of the four LEDs in both cameras, with Gaussian pixel noise `sigma_px`;
/// `None` where the LED falls outside the image or behind the camera.
pub fn project_leds(
    rig: &StereoRig,
    pen: &PenGeometry,
    pose: &PenPose,
    sigma_px: f64,
    rng: &mut SplitMix64,
) -> [[Option<[f64; 2]>; LED_COUNT]; 2] {
    let leds = pen.led_positions(&pose.led1, &pose.rotation);
    let mut out = [[None; LED_COUNT]; 2];
    for (c, cam) in [CameraId::Left, CameraId::Right].into_iter().enumerate() {
        let intr = rig.camera(cam);
        for (i, p) in leds.iter().enumerate() {
            if let Ok(px) = rig.project(cam, p) {
                let q = [
                    px[0] + sigma_px * rng.gaussian(),
                    px[1] + sigma_px * rng.gaussian(),
                ];
                if q[0] >= 0.0
                    && q[1] >= 0.0
                    && q[0] < f64::from(intr.width)
                    && q[1] < f64::from(intr.height)
                {
                    out[c][i] = Some(q);
                }
            }
        }
    }
    out
}

/// A smooth hand-like pen motion: the pen wobbles (sinusoids on three Euler angles) around a base
/// orientation while LED 1 moves on a small Lissajous curve. Used to generate IMU and camera data.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PenMotion {
    /// Centre of the LED 1 trajectory, world frame.
    pub center: Vector3<f64>,
    /// Amplitude of the LED 1 trajectory, metres.
    pub radius: f64,
    /// Base orientation (world from pen).
    pub base: UnitQuaternion<f64>,
    /// Wobble amplitudes (yaw, pitch, roll), radians.
    pub amplitude: [f64; 3],
    /// Wobble frequencies (yaw, pitch, roll), Hz.
    pub frequency: [f64; 3],
}

impl PenMotion {
    /// A typical drawing motion 0.8 m in front of a 0.25 m-baseline rig (centred between the
    /// cameras), pen pointing down-forward.
    pub fn drawing() -> Self {
        let dir = Vector3::new(0.35, 0.8, 0.45).normalize();
        let base = UnitQuaternion::rotation_between(&Vector3::x(), &dir)
            .unwrap_or_else(UnitQuaternion::identity);
        Self {
            center: Vector3::new(0.125, -0.05, 0.8),
            radius: 0.06,
            base,
            amplitude: [0.5, 0.35, 0.8],
            frequency: [0.31, 0.47, 0.23],
        }
    }

    /// Pose at time `t` seconds.
    pub fn pose(&self, t: f64) -> PenPose {
        let w = |k: usize, phase: f64| {
            self.amplitude[k] * (std::f64::consts::TAU * self.frequency[k] * t + phase).sin()
        };
        let wobble = UnitQuaternion::from_euler_angles(w(2, 0.3), w(1, 1.1), w(0, 0.0));
        let s = std::f64::consts::TAU * 0.4 * t;
        let led1 = self.center
            + Vector3::new(s.sin(), 0.5 * (1.3 * s).cos(), 0.3 * (0.7 * s).sin()) * self.radius;
        PenPose {
            led1,
            rotation: self.base * wobble,
        }
    }

    /// Angular velocity in the pen frame at `t` (central difference), rad/s.
    pub fn angular_velocity(&self, t: f64) -> Vector3<f64> {
        let h = 1e-4;
        (self.pose(t - h).rotation.inverse() * self.pose(t + h).rotation).scaled_axis() / (2.0 * h)
    }

    /// Acceleration of LED 1 in the world frame at `t` (central difference), m/s^2.
    pub fn acceleration(&self, t: f64) -> Vector3<f64> {
        let h = 1e-3;
        (self.pose(t + h).led1 - 2.0 * self.pose(t).led1 + self.pose(t - h).led1) / (h * h)
    }
}

/// IMU error model for synthetic samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuNoise {
    /// Gyro white noise per sample, rad/s.
    pub gyro_sigma: f64,
    /// Constant gyro bias, rad/s.
    pub gyro_bias: Vector3<f64>,
    /// Accelerometer white noise per sample, m/s^2.
    pub accel_sigma: f64,
    /// Magnetometer white noise per sample, as a fraction of the field.
    pub mag_sigma: f64,
}

impl Default for ImuNoise {
    fn default() -> Self {
        Self {
            gyro_sigma: 0.01,
            gyro_bias: Vector3::new(0.02, -0.015, 0.01),
            accel_sigma: 0.08,
            mag_sigma: 0.02,
        }
    }
}

/// A synthetic IMU sample of `motion` at time `t_ns`.
pub fn imu_sample(
    motion: &PenMotion,
    t_ns: u64,
    world: &crate::track::fusion::WorldReference,
    noise: &ImuNoise,
    rng: &mut SplitMix64,
) -> crate::track::fusion::ImuSample {
    let t = t_ns as f64 * 1e-9;
    let q = motion.pose(t).rotation;
    let mut n3 = |s: f64| Vector3::new(rng.gaussian(), rng.gaussian(), rng.gaussian()) * s;
    let gyro = motion.angular_velocity(t) + noise.gyro_bias + n3(noise.gyro_sigma);
    let specific = motion.acceleration(t) + world.up() * world.gravity;
    let accel = q.inverse() * specific + n3(noise.accel_sigma);
    let mag = q.inverse() * world.magnetic() + n3(noise.mag_sigma);
    crate::track::fusion::ImuSample {
        t_ns,
        accel: accel.into(),
        gyro: gyro.into(),
        mag: mag.into(),
    }
}
