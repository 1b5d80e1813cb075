//! Pen motion: curve-network planning on the target object and the time-parametrised pen pose.

pub mod network;
pub mod trajectory;

pub use network::{plan_network, Curve, PlannedStroke, Scene, MAX_PLANNED_STROKES};
pub use trajectory::{min_jerk, FreeMotion, Pose, Trajectory};
