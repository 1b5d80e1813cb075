//! Stereo geometry for the two tracking cameras (FIRES thesis, §4.1.1).
//!
//! Conventions (shared with `fires-record` so a later `From` is a few lines): OpenCV camera frame
//! (x right, y down, z forward), world frame = left camera frame, SI units (metres, radians),
//! right-camera extrinsics as `X_right = R * X_left + t`.
//!
//! - [`camera`]: pinhole intrinsics + OpenCV distortion, projection and iterative undistortion.
//! - [`rig`]: the calibrated pair, its projection and essential/fundamental matrices.
//! - [`triangulate`]: the thesis's three triangulation methods (eqs. 4.1-4.10) with the ray gap.
//! - [`correspond`]: all left/right blob pairs, gated by epipolar distance and ray gap.

pub mod camera;
pub mod correspond;
pub mod rig;
pub mod triangulate;

pub use camera::{project, CameraModel, ProjectionError};
pub use correspond::{Candidate, CorrespondenceConfig, Correspondences};
pub use rig::{CameraId, StereoRig};
pub use triangulate::{Triangulated, TriangulationError, TriangulationMethod, Triangulator};
