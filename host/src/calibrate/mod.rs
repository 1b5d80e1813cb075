//! Calibration: the stereo rig from chessboard views (Zhang's method through OpenCV, as the thesis, seed 002
//! digest §1.2).

#[cfg(feature = "opencv")]
pub mod chessboard;
