//! The tracker's configuration ([`TrackerConfig`]) and the choice of pen axis for the tip
//! ([`DirectionSource`]).

use crate::stereo::{CorrespondenceConfig, TriangulationMethod};
use crate::track::frame_clock::FrameTiming;
use crate::track::fusion::{
    DeadReckonConfig, FusionKind, MagCalibrationConfig, OrientationConfig, ThesisKalmanConfig,
    TipFilterConfig, WorldEstimateConfig, WorldReference,
};
use crate::track::identify::IdentifyConfig;
use crate::track::pen::PenGeometry;

/// Which axis eq. 4.13 uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum DirectionSource {
    /// The least-squares axis of the identified LEDs (the thesis's eq. 4.13 as printed).
    Vision,
    /// The fused direction when the filter has seen vision recently, else the vision axis.
    #[default]
    Fused,
}

/// Everything the tracker needs to know.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TrackerConfig {
    /// Pen LED layout and tip offset.
    pub pen: PenGeometry,
    /// Triangulation method (eqs. 4.1-4.10).
    pub method: TriangulationMethod,
    /// Stereo gates.
    pub correspondence: CorrespondenceConfig,
    /// Identification tolerances.
    pub identify: IdentifyConfig,
    /// Direction filter.
    pub fusion: FusionKind,
    /// Gains of the default filter.
    pub orientation: OrientationConfig,
    /// Noise of the thesis filter.
    pub thesis_kalman: ThesisKalmanConfig,
    /// Gravity and magnetic directions in the world (left camera) frame; `None` (the default):
    /// estimated during the session ([`crate::track::fusion::world_estimate`]), and until then the
    /// fusion gives no prior, no fused axis and no inertial dead reckoning.
    pub world: Option<WorldReference>,
    /// When the online world estimate is accepted.
    pub world_estimate: WorldEstimateConfig,
    /// Online hard-iron calibration of the magnetometer.
    pub mag_calibration: MagCalibrationConfig,
    /// Occlusion handling.
    pub dead_reckon: DeadReckonConfig,
    /// Tip position filter (constant velocity + IMU acceleration).
    pub tip_filter: TipFilterConfig,
    /// Position of the tip relative to the IMU in the pen frame, metres (lever arm for the
    /// tip filter's acceleration input).
    pub imu_to_tip: [f64; 3],
    /// Axis used for the tip (the one shown live, dead-reckoned and filtered for the display).
    pub direction_source: DirectionSource,
    /// Axis of the tips strokes are drawn from ([`TrackSample::stroke_tip`]): the end-of-stroke
    /// spline smooths the vision axis's frame-to-frame noise away, where the fused axis's slowly
    /// varying error (a fraction of a degree from three LEDs, a millimetre at the tip) stays in
    /// the stroke; the display, which nothing smooths afterwards, is steadier on the fused axis.
    ///
    /// [`TrackSample::stroke_tip`]: super::TrackSample::stroke_tip
    pub stroke_direction_source: DirectionSource,
    /// Frames of the two cameras further apart than this are not paired, nanoseconds.
    pub max_pair_dt_ns: u64,
    /// Added to right-camera timestamps to express them on the left camera's clock, nanoseconds.
    pub right_clock_offset_ns: i64,
    /// Move the other camera's blobs to the frame time using their image velocity.
    pub time_align: bool,
    /// Rolling shutter of each camera (left, right): the delay of one pixel row after the previous,
    /// nanoseconds (0: a global shutter). A blob on row `y` was exposed `y` rows after the frame time;
    /// with `time_align` every blob is moved to the pair's time with its image velocity.
    pub row_time_ns: [f64; 2],
    /// How each camera's frames are timed (left, right): with a known period and stamp noise the frame
    /// times come from [`crate::track::frame_clock::FrameClock`] instead of the raw stamps.
    pub frame_timing: [FrameTiming; 2],
    /// A labelling is refused when two of the pen's LEDs image closer than this in either camera,
    /// pixels: the spots overlap (pen pointing at a camera), so which blob is which LED is a guess.
    pub min_image_separation_px: f64,
    /// Estimate the residual right-camera clock offset online from the epipolar residuals of
    /// moving labelled LEDs (needs `time_align`), and add it to `right_clock_offset_ns`.
    pub estimate_clock_offset: bool,
    /// Fastest pen motion expected, metres per second: with the time between a pair's two
    /// exposures it bounds the triangulation's scale error (`1 + v Δt / baseline`), which decides
    /// whether two three-LED patterns that differ only in scale can be confused.
    pub max_pen_speed_mps: f64,
    /// With a measured pen speed `v` (the fastest LED between the last two labelled frames), the
    /// scale-error bound uses `min(max_pen_speed_mps, measured_speed_factor v +
    /// measured_speed_floor_mps)` instead (speed-bounded twin test): the factor allows the pen to
    /// speed up between frames...
    pub measured_speed_factor: f64,
    /// ...and the floor the speed's noise (two frames' depth noise over a frame period) plus a
    /// hand accelerating at 3 m/s^2 for `continuity_ns`, metres per second.
    pub measured_speed_floor_mps: f64,
    /// Labelled frames per clock-offset update.
    pub clock_window: usize,
    /// Required precision of one clock-offset update, nanoseconds (else the window is discarded).
    pub clock_precision_ns: f64,
    /// Largest image motion between consecutive frames of one camera used for velocity, pixels,
    /// per 60 Hz frame period (frames further apart may be that many pixels per period apart:
    /// a 15 Hz camera's blobs of a quickly drawn stroke move 50-60 px between frames).
    pub max_blob_motion_px: f64,
    /// Previous labels serve as a prior for this long, nanoseconds.
    pub continuity_ns: u64,
    /// The fused direction counts as vision-corrected for this long, nanoseconds.
    pub fused_fresh_ns: u64,
    /// After that, the filter's direction still serves identification as a prior whose
    /// expected error grows by this much per second (gyro drift against the gravity and
    /// heading corrections), radians per second...
    pub stale_prior_growth: f64,
    /// ...up to this error, radians (the IMU-only orientation's error bound with a calibrated
    /// world reference); a value of 0 disables the stale prior.
    pub stale_prior_max: f64,
}

impl TrackerConfig {
    /// The pen speed that bounds a pair's scale error: `max_pen_speed_mps`, or with a `measured`
    /// speed (m/s) `measured_speed_factor measured + measured_speed_floor_mps` when smaller.
    pub fn twin_speed_bound(&self, measured: Option<f64>) -> f64 {
        measured
            .filter(|v| v.is_finite() && *v >= 0.0)
            .map_or(self.max_pen_speed_mps, |v| {
                (self.measured_speed_factor * v + self.measured_speed_floor_mps)
                    .min(self.max_pen_speed_mps)
            })
    }
}

impl Default for TrackerConfig {
    fn default() -> Self {
        Self {
            pen: PenGeometry::thesis(),
            method: TriangulationMethod::Midpoint,
            correspondence: CorrespondenceConfig::default(),
            identify: IdentifyConfig::default(),
            fusion: FusionKind::Orientation,
            orientation: OrientationConfig::default(),
            thesis_kalman: ThesisKalmanConfig::default(),
            world: None,
            world_estimate: WorldEstimateConfig::default(),
            mag_calibration: MagCalibrationConfig::default(),
            dead_reckon: DeadReckonConfig::default(),
            tip_filter: TipFilterConfig::default(),
            imu_to_tip: [0.0; 3],
            direction_source: DirectionSource::Fused,
            stroke_direction_source: DirectionSource::Vision,
            max_pair_dt_ns: 40_000_000,
            right_clock_offset_ns: 0,
            time_align: true,
            row_time_ns: [0.0; 2],
            frame_timing: [FrameTiming::default(); 2],
            min_image_separation_px: 4.0,
            max_pen_speed_mps: 1.5,
            measured_speed_factor: 2.0,
            measured_speed_floor_mps: 0.3,
            estimate_clock_offset: true,
            clock_window: 30,
            clock_precision_ns: 1_000_000.0,
            max_blob_motion_px: 40.0,
            continuity_ns: 100_000_000,
            fused_fresh_ns: 200_000_000,
            stale_prior_growth: 0.05,
            stale_prior_max: 0.07,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_twin_speed_bound_follows_the_measured_speed_up_to_the_maximum() {
        let c = TrackerConfig::default();
        assert_eq!(c.twin_speed_bound(None), c.max_pen_speed_mps);
        assert_eq!(c.twin_speed_bound(Some(f64::NAN)), c.max_pen_speed_mps);
        assert!((c.twin_speed_bound(Some(0.0)) - c.measured_speed_floor_mps).abs() < 1e-15);
        assert!((c.twin_speed_bound(Some(0.2)) - 0.7).abs() < 1e-12);
        assert_eq!(c.twin_speed_bound(Some(5.0)), c.max_pen_speed_mps);
    }
}
