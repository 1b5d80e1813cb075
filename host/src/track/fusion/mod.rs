//! Vision-inertial fusion of the pen direction (thesis §4.1.4) and tip dead reckoning.
//!
//! - [`thesis_kalman`]: the thesis's 4-state Kalman filter exactly as eqs. 4.18-4.21 (selectable).
//! - [`orientation`]: the default, a Mahony-style complementary filter on SO(3) with gyro-bias
//!   estimation, gravity and magnetic-heading corrections at the IMU rate, and time-stamped
//!   vision pen-direction corrections applied through a short state history.
//! - [`dead_reckon`]: tip extrapolation through short occlusions, stopped after a time limit.
//! - [`tip_filter`]: constant-velocity Kalman filter on the tip with the IMU acceleration as input.
//!
//! Frames: world = left camera frame; the pen (body) frame has +x along the axis towards the tip
//! and is assumed to coincide with the IMU axes (a fixed mounting rotation can be applied with
//! [`imu::ImuScale::pen_from_sensor`]). The world "up" and magnetic-field directions are inputs
//! ([`imu::WorldReference`]); the thesis leaves this camera-to-world alignment to calibration;
//! [`world_estimate`] estimates it from the session.

pub mod dead_reckon;
pub mod imu;
pub mod mag_calibration;
pub mod orientation;
#[cfg(test)]
mod orientation_tests;
pub mod thesis_kalman;
pub mod tip_filter;
pub mod world_estimate;

pub use dead_reckon::{DeadReckonConfig, TipDeadReckoner};
pub use imu::{ImuSample, ImuScale, WorldReference};
pub use mag_calibration::{MagCalibrationConfig, MagCalibrator, MagOffset};
pub use orientation::{OrientationConfig, OrientationFilter};
pub use thesis_kalman::{ThesisKalman, ThesisKalmanConfig};
pub use tip_filter::{TipFilter, TipFilterConfig};
pub use world_estimate::{WorldEstimateConfig, WorldEstimator, WorldFit};

use nalgebra::Vector3;

/// Which direction filter the tracker runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum FusionKind {
    /// The thesis's 4-state angle Kalman filter (eqs. 4.18-4.21).
    ThesisKalman,
    /// The SO(3) complementary filter with gyro bias and vision corrections (default).
    #[default]
    Orientation,
}

/// Common interface of the two direction filters.
pub trait DirectionFilter {
    /// Processes one IMU sample (time-ordered).
    fn imu(&mut self, sample: &ImuSample);
    /// Processes a vision pen direction (unit, world frame, towards the tip) observed at `t_ns`,
    /// with its variance per perpendicular axis in rad^2 (`None`: the filter's configured value).
    fn vision(&mut self, t_ns: u64, direction: &Vector3<f64>, variance: Option<f64>);
    /// Best estimate of the unit pen direction at `t_ns`, if initialised.
    fn direction_at(&self, t_ns: u64) -> Option<Vector3<f64>>;
    /// World-from-pen orientation at `t_ns` if the filter has one (the thesis filter has none).
    fn orientation_at(&self, t_ns: u64) -> Option<nalgebra::UnitQuaternion<f64>>;
    /// Moves the filter to a new world frame: `new_from_old` rotates its state, `world` is the
    /// reference in the new frame ([`world_estimate`] finds both during a session).
    fn rebase(&mut self, new_from_old: &nalgebra::UnitQuaternion<f64>, world: WorldReference);
}
