//! The per-frame tracker: camera frames (blobs with exposure timestamps, from either camera,
//! asynchronously) and IMU samples in, [`TrackSample`]s out, in the order of the thesis's
//! acquisition pipeline (FIRES thesis, §4.1 and Fig. 4.1; data flow: docs/architecture.md §1).
//!
//! One camera frame, top-down ([`Tracker::push_frame`] → `process_pair`):
//! 1. *Pairing*: the other camera's latest frame is paired with it if close enough in time
//!    (after the right-camera clock offset, configured plus estimated online,
//!    `pipeline/clock_offset.rs`).
//! 2. *Points*: the other camera's blobs are moved to this frame's time with their image velocity
//!    (the cameras are not synchronised, FIRES thesis, §4.1.3; `pipeline/align.rs`), then both are
//!    undistorted.
//! 3. *Stereo*: epipolar and ray-gap gates and triangulation ([`crate::stereo::correspond`]).
//! 4. *Identification* ([`super::identify`]) with the fused direction and the previous labels as
//!    priors (`pipeline/prior.rs`); a pair refused with two LED spots merged in one camera can
//!    still be labelled from the other camera and the pen's rigid line (`pipeline/merged.rs`), and
//!    one refused as ambiguous or by a strayed fused direction by both frames' own LED identities
//!    (`pipeline/frame_labels.rs`).
//! 5. *Safety*: the tracker's own checks of the labelling, on the labelled pen's eq. 4.13 model
//!    along the vision axis (`pipeline/safety.rs`); the first pair after a loss whose frames are
//!    far apart in time keeps its labels but gives no tip (its blobs could not be moved).
//! 6. *Tip* with eq. 4.13 ([`super::tip`]) along the fused axis or the vision axis.
//! 7. *Fusion*: the vision axis corrects the direction filter at the frame time and may complete
//!    the online world estimate; the tip filter smooths the tip.
//!
//! Frames that cannot be labelled give no vision tip; the tip is then dead-reckoned from the IMU
//! for at most `dead_reckon.max_duration_ns`.
//!
//! Inputs are plain (pixel blobs + timestamps, SI IMU samples) so recordings and live capture feed
//! it the same way. Push everything in arrival order; each stream must be time-ordered. Units,
//! frames and clocks: docs/architecture.md §2 and §3.

mod align;
mod clock_offset;
mod config;
mod frame_labels;
mod labelling;
mod line_order;
mod merged;
mod pattern;
mod pen_fit;
mod pen_image;
mod pen_line;
#[cfg(test)]
mod pen_line_tests;
mod pen_mono;
mod pen_motion;
mod pen_ray;
mod pixel_noise;
mod prior;
mod refusal;
mod safety;
#[cfg(test)]
mod tests;

pub use config::{DirectionSource, TrackerConfig};
pub use refusal::{Refusal, UNALIGNED_MAX_DT_NS};
pub use safety::Unsafe;

use super::frame_clock::FrameClock;
use super::fusion::{ImuSample, MagOffset, TipDeadReckoner, TipFilter, WorldFit, WorldReference};
use super::identify::{
    Identification, Identifier, IdentifyError, IdentifyPrior, RefusedBy, Resolution,
};
use super::pen::{PenError, LED_COUNT};
use super::tip::{TipEstimate, TipEstimator};
use crate::stereo::{CameraId, Correspondences, StereoRig, Triangulator};
use crate::vision::Rect;
use align::{AlignOptions, PairPoints, TimeAlignment};
use clock_offset::{ClockOffsetEstimator, ClockOptions};
use nalgebra::Vector3;
use pixel_noise::PixelNoise;
use prior::DirectionPrior;
use safety::LabelGuard;

/// How old the last vision tip may be to place the pen for labelling a frame by its pattern,
/// nanoseconds: drawing moves the pen a few centimetres in depth over this, within the pattern's
/// scale bound.
const PATTERN_GUESS_MAX_AGE_NS: u64 = 3_000_000_000;

/// The blobs of one camera image, in distorted pixel coordinates.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CameraFrame {
    /// Which camera.
    pub camera: CameraId,
    /// Exposure timestamp on that camera's clock, nanoseconds.
    pub t_ns: u64,
    /// Blob centres, pixels.
    pub blobs: Vec<[f64; 2]>,
    /// Radius of each blob's thresholded area, pixels (`sqrt(area / pi)`); empty when unknown.
    /// Two spots closer than their radii merge into one blob, so the radii set how far apart
    /// the pen's LED images must be for a labelling to be trusted.
    #[serde(default)]
    pub radii: Vec<f64>,
    /// Central second moments `[cxx, cxy, cyy]` of each blob's thresholded area, pixels²
    /// ([`crate::vision::Blob::shape`]); empty when unknown. A streak of merged LED spots gives
    /// the pen's image line by its axis.
    #[serde(default)]
    pub shapes: Vec<[f64; 3]>,
}

impl CameraFrame {
    /// A frame of blob centres whose sizes are unknown.
    pub fn new(camera: CameraId, t_ns: u64, blobs: Vec<[f64; 2]>) -> Self {
        Self {
            camera,
            t_ns,
            blobs,
            radii: Vec::new(),
            shapes: Vec::new(),
        }
    }

    /// A frame from detected blobs (their sub-pixel centres and areas, in the detector's order).
    pub fn from_blobs(camera: CameraId, t_ns: u64, blobs: &[crate::vision::Blob]) -> Self {
        Self {
            camera,
            t_ns,
            blobs: blobs.iter().map(|b| [b.x, b.y]).collect(),
            radii: blobs
                .iter()
                .map(|b| area_radius(f64::from(b.area)))
                .collect(),
            shapes: blobs.iter().map(|b| b.shape).collect(),
        }
    }
}

/// Radius of a disc of `area` square pixels.
pub fn area_radius(area: f64) -> f64 {
    (area.max(0.0) / std::f64::consts::PI).sqrt()
}

/// How a sample's tip was obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum TrackQuality {
    /// Vision tip from this many identified LEDs.
    Vision {
        /// Number of identified LEDs (2-4).
        leds: u8,
    },
    /// Extrapolated through an occlusion.
    DeadReckoned,
    /// No tip: too few blobs, no consistent labelling, ambiguity, or occlusion too long.
    Lost,
}

/// One tracker output.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TrackSample {
    /// Time on the left camera's clock, nanoseconds.
    pub t_ns: u64,
    /// Tip position, world frame, metres (filtered when the tip filter is enabled).
    pub tip: Option<[f64; 3]>,
    /// The unfiltered eq. 4.13 tip of this frame (vision samples only).
    pub raw_tip: Option<[f64; 3]>,
    /// Unit pen direction towards the tip (the one used for the tip, or the fused one).
    pub direction: Option<[f64; 3]>,
    /// Identified LED positions (index 0 = LED 1).
    pub leds: [Option<[f64; 3]>; LED_COUNT],
    /// `(left blob, right blob)` indices of each identified LED in the frames used: its own image
    /// in each camera (None for an LED located inside a merged blob by pen-line stereo).
    pub labels: [Option<(usize, usize)>; LED_COUNT],
    /// How the tip was obtained.
    pub quality: TrackQuality,
    /// Labelling confidence in [0, 1] (0 when not from vision).
    pub confidence: f64,
    /// Number of interference points rejected.
    pub interference: usize,
    /// Expected per-axis noise (one sigma) of `raw_tip`, metres: the labelled LEDs' triangulation
    /// covariances through eq. 4.13, scaled to the rig's measured centroid noise (vision samples
    /// only; None when unknown).
    #[serde(default)]
    pub tip_sigma_m: Option<f64>,
    /// The tip strokes are drawn from (vision samples only): along
    /// [`TrackerConfig::stroke_direction_source`], filtered as `tip` is; `tip` itself when both
    /// use one axis.
    #[serde(default)]
    pub stroke_tip: Option<[f64; 3]>,
    /// Expected per-axis noise of `stroke_tip`'s unfiltered tip, metres (as `tip_sigma_m`).
    #[serde(default)]
    pub stroke_tip_sigma_m: Option<f64>,
}

impl TrackSample {
    fn lost(t_ns: u64, direction: Option<Vector3<f64>>) -> Self {
        Self {
            t_ns,
            tip: None,
            raw_tip: None,
            direction: direction.map(Into::into),
            leds: [None; LED_COUNT],
            labels: [None; LED_COUNT],
            quality: TrackQuality::Lost,
            confidence: 0.0,
            interference: 0,
            tip_sigma_m: None,
            stroke_tip: None,
            stroke_tip_sigma_m: None,
        }
    }
}

/// The tracker: stereo, identification, tip, fusion, dead reckoning.
pub struct Tracker {
    config: TrackerConfig,
    rig: StereoRig,
    triangulator: Triangulator,
    correspondences: Correspondences,
    identifier: Identifier,
    tip: TipEstimator,
    /// Camera histories and pen poses (time alignment).
    align: TimeAlignment,
    /// The current pair's aligned and undistorted points.
    points: PairPoints,
    clock: ClockOffsetEstimator,
    /// Each camera's frame times from its stamps (left, right).
    frame_clocks: [FrameClock; 2],
    /// Direction filter, world reference and identification prior.
    direction: DirectionPrior,
    /// Accepted labels and the labelling checks.
    labels: LabelGuard,
    reckoner: TipDeadReckoner,
    tip_filter: TipFilter,
    /// The filter of the stroke axis's tips, when strokes and display use different axes.
    stroke_filter: Option<TipFilter>,
    /// The rig's measured blob-centroid noise, which scales the tip's expected noise.
    pixel_noise: PixelNoise,
    last_gyro: Option<(u64, Vector3<f64>)>,
    /// The tip's world acceleration from the last IMU sample, when orientation and world were known.
    tip_accel: Option<(u64, Vector3<f64>)>,
    occluded: bool,
    /// The last vision tip and its time: where the pen is believed to be for labelling a frame
    /// by its pattern after a loss (`pipeline/pattern.rs`).
    last_vision_tip: Option<(u64, Vector3<f64>)>,
    /// Why the last pair gave no vision tip (None when it gave one).
    last_refusal: Option<Refusal>,
}

impl Tracker {
    /// A tracker for a calibrated rig; fails if the pen is not identifiable at the tolerance.
    pub fn new(rig: StereoRig, config: TrackerConfig) -> Result<Self, PenError> {
        let identifier = Identifier::new(config.pen, config.identify)?
            .with_rig(&rig, config.correspondence.pixel_sigma);
        Ok(Self {
            triangulator: Triangulator::new(&rig, config.method),
            correspondences: Correspondences::default(),
            identifier,
            tip: TipEstimator::new(&config.pen),
            align: TimeAlignment::new(AlignOptions::from_config(&config)),
            points: PairPoints::default(),
            clock: ClockOffsetEstimator::new(ClockOptions::from_config(&config)),
            frame_clocks: config.frame_timing.map(FrameClock::new),
            direction: DirectionPrior::new(&config),
            labels: LabelGuard::new(&config),
            // Until a reference is known the dead reckoner runs in the default frame.
            reckoner: TipDeadReckoner::new(config.dead_reckon, config.world.unwrap_or_default()),
            tip_filter: TipFilter::new(config.tip_filter),
            stroke_filter: (config.stroke_direction_source != config.direction_source)
                .then(|| TipFilter::new(config.tip_filter)),
            pixel_noise: PixelNoise::new(config.correspondence.pixel_sigma),
            last_gyro: None,
            tip_accel: None,
            occluded: false,
            last_vision_tip: None,
            last_refusal: None,
            rig,
            config,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &TrackerConfig {
        &self.config
    }

    /// The rig.
    pub fn rig(&self) -> &StereoRig {
        &self.rig
    }

    /// The world reference in use (configured or estimated), None while still being estimated.
    pub fn world(&self) -> Option<&WorldReference> {
        self.direction.world()
    }

    /// The latest online world estimate with the time it was accepted, nanoseconds.
    pub fn world_fit(&self) -> Option<&(u64, WorldFit)> {
        self.direction.world_fit()
    }

    /// The magnetometer's hard-iron offset, once calibrated.
    pub fn mag_offset(&self) -> Option<&MagOffset> {
        self.direction.mag_offset()
    }

    /// The right-camera clock offset in use: configured plus estimated, nanoseconds.
    pub fn clock_offset_ns(&self) -> i64 {
        self.config
            .right_clock_offset_ns
            .saturating_add(self.clock.offset_ns())
    }

    /// Why the last stereo pair (the last sample [`Self::push_frame`] returned) gave no vision
    /// tip; None when it gave one.
    pub fn last_refusal(&self) -> Option<Refusal> {
        self.last_refusal
    }

    /// The tip's world-frame acceleration (gravity removed, the lever [`TrackerConfig::imu_to_tip`]
    /// included) from the last IMU sample: time and m/s^2; None before orientation and world are known.
    pub fn tip_acceleration(&self) -> Option<(u64, [f64; 3])> {
        self.tip_accel.map(|(t, a)| (t, a.into()))
    }

    /// Feeds one IMU sample. While the tip is occluded this returns a dead-reckoned (or, after the
    /// time limit, lost) sample; otherwise None (frames produce the samples).
    pub fn push_imu(&mut self, sample: &ImuSample) -> Option<TrackSample> {
        let sample = &self.direction.calibrated_mag(sample);
        self.direction.imu(sample);
        self.tip_accel = None;
        if let (Some(q), Some(world)) = (
            self.direction.orientation_at(sample.t_ns),
            self.direction.world().copied(),
        ) {
            let linear = q * self.tip_specific_force(sample) - world.up() * world.gravity;
            self.tip_filter.push_accel(sample.t_ns, linear);
            if let Some(f) = &mut self.stroke_filter {
                f.push_accel(sample.t_ns, linear);
            }
            self.align.push_accel(sample.t_ns, linear);
            self.tip_accel = Some((sample.t_ns, linear));
        }
        self.last_gyro = Some((sample.t_ns, Vector3::from(sample.gyro)));
        self.align
            .push_gyro(sample.t_ns, Vector3::from(sample.gyro));
        if !self.occluded {
            return None;
        }
        let direction = self.direction.direction_at(sample.t_ns);
        // The tip's own acceleration (the lever from the accelerometer included): a pen turning
        // as it stops moves its accelerometer, 12 cm behind the tip, differently from the tip.
        let linear = self.tip_accel.map(|(_, a)| a);
        Some(match self.reckoner.propagate_linear(sample.t_ns, linear) {
            Some(tip) => TrackSample {
                tip: Some(tip.into()),
                quality: TrackQuality::DeadReckoned,
                ..TrackSample::lost(sample.t_ns, direction)
            },
            None => TrackSample::lost(sample.t_ns, direction),
        })
    }

    /// Feeds one camera frame; returns a sample when it could be paired with the other camera.
    pub fn push_frame(&mut self, frame: CameraFrame) -> Option<TrackSample> {
        let (this, other) = match frame.camera {
            CameraId::Left => (0, 1),
            CameraId::Right => (1, 0),
        };
        // The exposure time from the camera's clock model, not the stamp's arrival jitter.
        let stamp = self.frame_clocks[this].time(frame.t_ns);
        let t = match frame.camera {
            CameraId::Left => stamp,
            CameraId::Right => stamp.saturating_add_signed(self.clock_offset_ns()),
        };
        // With a rolling shutter the frame's time becomes that of the rows its blobs lie on.
        let t = self.align.push(this, t, frame.blobs, frame.radii);
        self.align.set_shapes(this, frame.shapes);
        let guess = self.pen_guess(t);
        self.align.set_guess(this, guess);
        let t_other = self.align.current(other)?.t_ns;
        if t.abs_diff(t_other) > self.config.max_pair_dt_ns {
            return None;
        }
        Some(self.process_pair(this, t))
    }

    /// Points → stereo → identification → safety → tip → fusion for the newest frame of camera
    /// `this` at time `t` (left clock).
    fn process_pair(&mut self, this: usize, t: u64) -> TrackSample {
        // Points: this frame's blobs and the other camera's moved to `t`, undistorted.
        self.align.set_noise_scale(self.pixel_noise.scale());
        self.align.prepare(&self.rig, this, t, &mut self.points);
        // Priors: the fused direction, the previous labels, and the scale error that the time
        // between the pair's two exposures allows.
        let (direction, direction_sigma) = self.direction.prior(t).unzip();
        let pair_dt = self
            .align
            .current(1 - this)
            .map_or(0, |f| f.t_ns.abs_diff(t));
        // Speed-bounded twin test: the pen's measured speed, not the fastest conceivable one.
        let speed = self.config.twin_speed_bound(self.labels.recent_speed(t));
        let scale_error_max = 1.0 + speed * pair_dt as f64 * 1e-9 / self.rig.baseline().max(1e-6);
        let prior = IdentifyPrior {
            direction,
            direction_sigma,
            scale_error_max: Some(scale_error_max),
            previous: self
                .labels
                .recent_leds(t)
                .copied()
                .unwrap_or([None; LED_COUNT]),
        };
        // Stereo candidates.
        let (left, right) = (&self.points.left_norm, &self.points.right_norm);
        self.correspondences.compute(
            &self.rig,
            &self.triangulator,
            &self.config.correspondence,
            left,
            right,
        );
        let cands = &self.correspondences.candidates;
        let stale = direction_sigma.is_some_and(|s| s > self.config.identify.prior_sigma);
        // Identification.
        self.last_refusal = None;
        let id = match self
            .identifier
            .identify_with_images(cands, &prior, left, right)
        {
            Ok(id) => id,
            Err(e) => {
                let by = self.identifier.refused_by().unwrap_or(match e {
                    IdentifyError::TooFewCandidates => RefusedBy::TooFewCandidates,
                    IdentifyError::NoConsistentSet => RefusedBy::Distances,
                    IdentifyError::ContradictedByImage => RefusedBy::ImageEvidence,
                    IdentifyError::Ambiguous => RefusedBy::Rival,
                });
                let completed = self
                    .complete_merged_pair(t, by)
                    .or_else(|| {
                        (!merged::is_conflict(by))
                            .then(|| self.complete_pen_line(t))
                            .flatten()
                    })
                    .or_else(|| self.complete_from_frame_labels(by));
                match completed {
                    Some(id) => id,
                    None => return self.refused(t, Refusal::Identify(by)),
                }
            }
        };
        let (id, vision) = match self.checked_or_pen_line(t, id, stale) {
            Ok(checked) => checked,
            Err(r) => return self.refused(t, r),
        };
        // The first pair after a loss has no image velocities: if its frames are far apart in
        // time, the labels are kept (the next pair moves the blobs with them) but not the tip.
        if !self.other_blobs_aligned(this, t, &id) {
            self.remember_labels(this, t, &id, &vision);
            return self.refused(t, Refusal::Unaligned);
        }
        // Fusion and the sample.
        self.vision_sample(this, t, &id, vision)
    }

    /// True when the labelled blobs of the other camera were moved to the pair's time `t`, or
    /// its frame was exposed within [`UNALIGNED_MAX_DT_NS`] of `t` (or alignment is off).
    fn other_blobs_aligned(&self, this: usize, t: u64, id: &Identification) -> bool {
        let cands = &self.correspondences.candidates;
        let blobs = id.assignment.iter().flatten().map(|&k| {
            if this == 0 {
                cands[k].right
            } else {
                cands[k].left
            }
        });
        !self.config.time_align
            || self
                .align
                .other_moved(&self.points, this, t, UNALIGNED_MAX_DT_NS, blobs)
    }

    /// Fusion and output of a labelled pair: world estimate, clock offset, direction filter, the
    /// tip along the chosen axis, dead reckoner and tip filter.
    fn vision_sample(
        &mut self,
        this: usize,
        t: u64,
        id: &Identification,
        vision: TipEstimate,
    ) -> TrackSample {
        if let Some(world) = self.direction.observe_labelled(t, id, &vision.direction) {
            self.reckoner.set_world(world);
        }
        // Without a world reference there is no direction prior. Safe to report are the
        // four-LED pattern (cross-ratio, no mirror image) and three LEDs that the geometry alone
        // labelled (their spacing is not mirror-symmetric, a scaled twin needed continuity, and
        // no rival fits). Other labellings (two LEDs, or resolved by a prior) are kept for time
        // alignment and continuity (a mirrored chain still tracks each blob consistently) but
        // give no tip.
        if self.direction.world().is_none()
            && id.located() < LED_COUNT
            && (id.count() < 3 || id.resolution != Resolution::Geometry)
        {
            self.remember_labels(this, t, id, &vision);
            return self.refused(t, Refusal::NoWorld);
        }
        // The labelled pen's uncertainty, not the identification's gates (which keep the
        // pixel noise's: a wider band would let a mismatched labelling pass), includes the
        // error of moving the other camera's blobs to the pair's time. A pen-line fit has
        // included it already.
        if !id.from_pen_line {
            self.widen_for_extrapolation();
        }
        let cands = &self.correspondences.candidates;
        if !id.from_pen_line {
            self.clock.observe(t, &self.rig, &self.points, cands, id);
            let residuals = id
                .assignment
                .iter()
                .flatten()
                .map(|&k| cands[k].epipolar_px);
            self.pixel_noise.observe(residuals);
        }
        let variance =
            prior::direction_variance(&self.config.pen.led_offsets, cands, id, &vision.direction);
        self.direction.correct(t, &vision.direction, variance);
        let estimate = self.estimate_along(self.config.direction_source, t, id, vision);
        self.direction.mark_vision(t);
        self.remember_labels(this, t, id, &estimate);
        self.last_vision_tip = Some((t, estimate.tip));
        self.occluded = false;
        let sigma = self.scaled_tip_sigma(self.config.direction_source, t, id, &estimate, variance);
        let filtered = self.tip_filter.update(t, &estimate.tip, sigma);
        // Occlusions are extrapolated from the Kalman filter's state, whose velocity weighs each
        // tip by its noise and the time since the last one (an alpha-beta gain does not know an
        // occlusion happened: fires-v1 seed 7's pen, seen once every 80 ms while it was lifted,
        // made it swing ±0.4 m/s and the display 47 mm off a pen come to rest).
        let velocity = self.tip_filter.velocity().unwrap_or_default();
        self.reckoner.observe_with_velocity(t, &filtered, &velocity);
        let tip = if self.config.tip_filter.enabled {
            filtered
        } else {
            estimate.tip
        };
        let (stroke_tip, stroke_sigma) = self
            .stroke_tip(t, id, vision, variance)
            .unwrap_or((tip, sigma));
        let cands = &self.correspondences.candidates;
        TrackSample {
            t_ns: t,
            tip: Some(tip.into()),
            raw_tip: Some(estimate.tip.into()),
            direction: Some(estimate.direction.into()),
            leds: id.points.map(|p| p.map(Into::into)),
            labels: pen_image::own_images(id, cands),
            quality: TrackQuality::Vision {
                leds: id.count() as u8,
            },
            confidence: id.confidence,
            interference: id.interference,
            tip_sigma_m: sigma,
            stroke_tip: Some(stroke_tip.into()),
            stroke_tip_sigma_m: stroke_sigma,
        }
    }

    /// The eq. 4.13 tip of a labelled pair along `source`'s axis: the fused direction when the
    /// filter has one, else the vision axis (`vision`).
    fn estimate_along(
        &self,
        source: DirectionSource,
        t: u64,
        id: &Identification,
        vision: TipEstimate,
    ) -> TipEstimate {
        match (source, self.direction.fused(t)) {
            (DirectionSource::Fused, Some(d)) => self
                .tip
                .estimate_with_direction(&id.points, &d)
                .unwrap_or(vision),
            _ => vision,
        }
    }

    /// [`Self::tip_sigma`] of a tip along `source`'s axis, scaled to the rig's measured centroid
    /// noise.
    fn scaled_tip_sigma(
        &self,
        source: DirectionSource,
        t: u64,
        id: &Identification,
        estimate: &TipEstimate,
        axis_variance: Option<f64>,
    ) -> Option<f64> {
        let fused_axis = source == DirectionSource::Fused && self.direction.fused(t).is_some();
        self.tip_sigma(id, estimate, axis_variance, fused_axis)
            .map(|s| s * self.pixel_noise.scale())
    }

    /// The stroke axis's tip and its noise when strokes and display use different axes
    /// ([`TrackerConfig::stroke_direction_source`]), through its own filter; None when they
    /// share the display's tip.
    fn stroke_tip(
        &mut self,
        t: u64,
        id: &Identification,
        vision: TipEstimate,
        axis_variance: Option<f64>,
    ) -> Option<(Vector3<f64>, Option<f64>)> {
        self.stroke_filter.as_ref()?;
        let source = self.config.stroke_direction_source;
        let estimate = self.estimate_along(source, t, id, vision);
        let sigma = self.scaled_tip_sigma(source, t, id, &estimate, axis_variance);
        let filter = self.stroke_filter.as_mut()?;
        let filtered = filter.update(t, &estimate.tip, sigma);
        let tip = if self.config.tip_filter.enabled {
            filtered
        } else {
            estimate.tip
        };
        Some((tip, sigma))
    }

    /// Where the pen is believed to be at `t` for labelling a frame by its pattern: the last
    /// vision tip (at most [`PATTERN_GUESS_MAX_AGE_NS`] old) along the orientation filter's
    /// direction (None without a world reference).
    fn pen_guess(&self, t: u64) -> Option<pattern::PenGuess> {
        let (tv, tip) = self.last_vision_tip?;
        if t.abs_diff(tv) > PATTERN_GUESS_MAX_AGE_NS {
            return None;
        }
        // The inertial orientation itself, not the identification prior (which times out a
        // second into a loss): the pattern's turn bound refuses a direction that has drifted.
        let orientation = self.direction.orientation_at(t)?;
        Some(pattern::PenGuess { tip, orientation })
    }

    /// Keeps a labelled frame for the next frames ([`LabelGuard::remember`]).
    fn remember_labels(
        &mut self,
        this: usize,
        t: u64,
        id: &Identification,
        estimate: &TipEstimate,
    ) {
        self.labels.remember(
            &mut self.align,
            &self.tip,
            &self.correspondences.candidates,
            this,
            t,
            id,
            estimate,
        );
    }

    /// A pair refused at `stage`: the reason is attributed ([`refusal::attribute`]) and kept for
    /// [`Self::last_refusal`].
    fn refused(&mut self, t: u64, stage: Refusal) -> TrackSample {
        let blobs = [self.points.left_norm.len(), self.points.right_norm.len()];
        let cands = self.correspondences.candidates.len();
        self.last_refusal = Some(refusal::attribute(blobs, cands, stage));
        self.no_vision_sample(t)
    }

    /// A pair without a vision tip: occluded from now, dead-reckoned while the reckoner can.
    fn no_vision_sample(&mut self, t: u64) -> TrackSample {
        self.occluded = true;
        let direction = self.direction.direction_at(t);
        match self.reckoner.current(t) {
            Some(tip) => TrackSample {
                tip: Some(tip.into()),
                quality: TrackQuality::DeadReckoned,
                ..TrackSample::lost(t, direction)
            },
            None => TrackSample::lost(t, direction),
        }
    }

    /// Expected per-axis noise of the eq. 4.13 tip: the centroid's variance from the candidates'
    /// covariances plus the lever `C + T` times the axis noise (the fused axis is taken as about
    /// three times steadier than one frame's vision axis).
    fn tip_sigma(
        &self,
        id: &Identification,
        estimate: &TipEstimate,
        axis_variance: Option<f64>,
        fused_axis: bool,
    ) -> Option<f64> {
        let cands = &self.correspondences.candidates;
        let n = id.count() as f64;
        let centroid_var: f64 = id
            .assignment
            .iter()
            .flatten()
            .map(|&k| cands[k].covariance.trace() / 3.0)
            .sum::<f64>()
            / (n * n);
        let lever = self.tip.pattern_centroid(estimate.pattern)? + self.config.pen.tip_offset;
        let axis_var = axis_variance? * if fused_axis { 0.1 } else { 1.0 };
        let var = centroid_var + lever * lever * axis_var;
        (var.is_finite() && var > 0.0).then(|| var.sqrt())
    }

    /// Widens each stereo candidate's covariance by the error of moving its other-camera blob
    /// to the pair's time at constant velocity ([`align::extrapolation_error`]): under a fast
    /// turn of the pen, a pair whose other camera was exposed most of a frame earlier is worth
    /// less than one completed just after it, and its tip's uncertainty says so.
    fn widen_for_extrapolation(&mut self) {
        let sigma = self.config.correspondence.pixel_sigma;
        if sigma <= 0.0 {
            return;
        }
        let focal = [self.rig.left.focal_px(), self.rig.right.focal_px()];
        let (left, right) = (&self.points.left_norm, &self.points.right_norm);
        for cand in &mut self.correspondences.candidates {
            let error = [
                self.points.move_error_px(CameraId::Left, cand.left),
                self.points.move_error_px(CameraId::Right, cand.right),
            ];
            if error == [0.0; 2] {
                continue;
            }
            let px = [sigma.hypot(error[0]), sigma.hypot(error[1])];
            let (Some(&ml), Some(&mr)) = (left.get(cand.left), right.get(cand.right)) else {
                continue;
            };
            cand.covariance = crate::stereo::correspond::covariance(
                &self.triangulator,
                ml,
                mr,
                &cand.point,
                [px[0] / focal[0], px[1] / focal[1]],
            );
        }
    }

    /// Specific force at the tip in the pen frame: the accelerometer's plus the lever-arm terms
    /// `α × r + ω × (ω × r)` for the IMU-to-tip offset `r` (α from consecutive gyro samples).
    fn tip_specific_force(&self, sample: &ImuSample) -> Vector3<f64> {
        let f = Vector3::from(sample.accel);
        let r = Vector3::from(self.config.imu_to_tip);
        if r == Vector3::zeros() {
            return f;
        }
        let w = Vector3::from(sample.gyro);
        let alpha = match self.last_gyro {
            Some((t0, w0)) if sample.t_ns > t0 && sample.t_ns - t0 < 50_000_000 => {
                (w - w0) / ((sample.t_ns - t0) as f64 * 1e-9)
            }
            _ => Vector3::zeros(),
        };
        f + alpha.cross(&r) + w.cross(&w.cross(&r))
    }

    /// The tip predicted at `t_ns` (e.g. an IMU timestamp between frames) from the tip filter and
    /// the IMU acceleration; None while occluded or when the last vision tip is too old.
    pub fn predict_tip(&self, t_ns: u64) -> Option<[f64; 3]> {
        if self.occluded {
            return None;
        }
        self.tip_filter.predict(t_ns).map(Into::into)
    }

    /// Search window for the blob detector of `camera` at `t_ns`: the whole pen (all four LEDs
    /// of the last pose, moved to `t_ns`, and the last identified LEDs) projected into that
    /// camera, grown by `margin_px`; None when there is no recent track. The unlabelled LEDs
    /// must be inside it too: a window around the two labelled LEDs of a two-LED frame would
    /// hide the others from every later frame, which then could label only those two.
    pub fn predicted_window(&self, camera: CameraId, t_ns: u64, margin_px: f64) -> Option<Rect> {
        let leds = self.labels.recent_leds(t_ns)?;
        let pen = self.align.predicted_leds(t_ns);
        let pts: Vec<[f64; 2]> = leds
            .iter()
            .flatten()
            .chain(pen.iter().flatten())
            .filter_map(|p| self.rig.project(camera, p).ok())
            .collect();
        let cam = self.rig.camera(camera);
        Rect::around(&pts, margin_px, cam.width as usize, cam.height as usize)
    }
}
