//! Calibration algorithms that need no OpenCV (issue 5 item 2, pivot part). Camera intrinsics and
//! stereo extrinsics (Zhang's method) are not implemented here.

pub mod pivot;

pub use pivot::{pivot_axis, pivot_full, PivotAxisFit, PivotError, PivotFullFit};
