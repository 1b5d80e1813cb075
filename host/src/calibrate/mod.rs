//! Calibration: the stereo rig from chessboard views (Zhang's method through OpenCV, as the FIRES thesis,
//! §4.1; feature `opencv`) and the pen tip by pivoting (no OpenCV needed).

#[cfg(feature = "opencv")]
pub mod chessboard;
pub mod pivot;

pub use pivot::{pivot_axis, pivot_full, PivotAxisFit, PivotError, PivotFullFit};
