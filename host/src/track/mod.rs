//! Pen tracking after blob detection (FIRES thesis, §4.1): LED identification (§4.1.2), tip
//! estimation (eqs. 4.11-4.13), sensor fusion (§4.1.4) and the per-frame [`pipeline::Tracker`];
//! the axis fit both identification and tip use is [`line_fit`].
//!
//! Feeding the tracker (timestamps in nanoseconds on one clock; right-camera clock offset in
//! [`pipeline::TrackerConfig::right_clock_offset_ns`], refined online):
//!
//! ```
//! use fires_host::stereo::{CameraId, StereoRig};
//! use fires_host::track::fusion::ImuSample;
//! use fires_host::track::pipeline::{CameraFrame, TrackQuality, Tracker, TrackerConfig};
//!
//! let rig = StereoRig::parallel(1024, 768, 45f64.to_radians(), 0.25);
//! let mut tracker = Tracker::new(rig, TrackerConfig::default()).expect("identifiable pen");
//! // IMU samples in SI units (pen frame) as they arrive...
//! let imu = ImuSample { t_ns: 1_000_000, accel: [0.0, 0.0, 9.81], gyro: [0.0; 3], mag: [0.0, 30.0, 20.0] };
//! let _ = tracker.push_imu(&imu); // Some(sample) only while the tip is occluded
//! // ...and blob centres (pixels) per camera frame with the exposure time.
//! let left = CameraFrame::new(CameraId::Left, 2_000_000, vec![[500.0, 300.0]]);
//! assert!(tracker.push_frame(left).is_none()); // no right frame to pair with yet
//! let right = CameraFrame::new(CameraId::Right, 2_100_000, vec![[300.0, 300.0]]);
//! let sample = tracker.push_frame(right).expect("paired");
//! assert_eq!(sample.quality, TrackQuality::Lost); // one blob is not a pen
//! ```

pub mod frame_clock;
pub mod fusion;
pub mod identify;
pub mod line_fit;
pub mod pen;
pub mod pipeline;

#[cfg(test)]
mod stress_tests;
pub mod synth;
pub mod tip;

pub use identify::{
    Identification, Identifier, IdentifyConfig, IdentifyError, IdentifyPrior, RefusedBy,
};
pub use pen::{PenGeometry, LED_COUNT};
pub use pipeline::{CameraFrame, TrackQuality, TrackSample, Tracker, TrackerConfig};
pub use tip::{TipError, TipEstimate, TipEstimator};
