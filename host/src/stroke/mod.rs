//! Stroke processing (thesis §4.1.3): real-time smoothing of the tip for display (the One Euro filter by
//! default, the thesis's Gaussian as an option), stroke segmentation by the pen button, and the end-of-stroke post-processing
//! (distance-threshold sampling, constrained weighted least-squares cubic B-spline, resampling).

pub mod imu_bridge;
pub mod imu_smooth;
pub mod one_euro;
pub mod postprocess;
pub mod record;
pub mod segment;
pub mod smooth;

pub use imu_bridge::{imu_bridge, ImuBridgeOptions};
pub use imu_smooth::{imu_smooth, ImuSmoothOptions};
pub use one_euro::{OneEuroConfig, OneEuroFilter};
pub use postprocess::{postprocess, BSpline, PostprocessConfig, StrokeError};
pub use record::{stroke_record, StrokeRecordConfig};
pub use segment::{Stroke, StrokeEvent, StrokeSegmenter, TimedAccel, TimedPoint};
pub use smooth::{smooth_centred, CausalSmoother, GaussianConfig};
