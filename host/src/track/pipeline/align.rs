//! Time alignment of the two cameras. They are not synchronised ("pairs of image points on the two
//! cameras are never captured in the same time instant", FIRES thesis, §4.1.3), so before a pair
//! is triangulated the other camera's blobs are moved to this frame's time with their image
//! velocity. [`TimeAlignment`] keeps each camera's last two frames (with the blob index of every
//! LED once a vision sample labelled them) and the last two vision poses of the pen, which predict
//! where the LEDs image in frames no vision sample labelled. Times are on the left camera's clock
//! (docs/architecture.md §3).
//!
//! With a rolling shutter each row is exposed at its own time (`TrackerConfig::row_time_ns`), so a
//! frame's blobs are not simultaneous: a kept frame's time is that of its blobs' median row, each
//! blob keeps its own delay from it, and every blob of both cameras is moved to the pair's time
//! with its image velocity (Ait-Aider et al., "Simultaneous object pose and velocity computation
//! using a single view from a rolling shutter camera", ECCV 2006, model the same per-row times).

use self::motion::{rigid_translation, MeasuredTranslation};
use super::line_order::{match_along_line, LineOrderOptions};
use super::pattern::{PatternOptions, PenGuess};
use super::pen_motion::{AccelHistory, GyroHistory};
use super::TrackerConfig;
use crate::stereo::{CameraId, CameraModel, StereoRig};
use crate::track::pen::LED_COUNT;
use nalgebra::Vector3;

/// One camera frame kept for time alignment: time, blob centres and, once a vision sample labelled
/// it, the blob index of every LED.
#[derive(Debug, Clone, Default)]
pub(super) struct KeptFrame {
    /// Exposure time on the left camera's clock, nanoseconds.
    pub(super) t_ns: u64,
    /// Blob centres, distorted pixels.
    pub(super) blobs: Vec<[f64; 2]>,
    /// Blob index of each LED (index 0 = LED 1), once labelled.
    pub(super) labels: [Option<usize>; LED_COUNT],
    /// Per blob, the radius of its thresholded area, pixels (empty when unknown).
    pub(super) radii: Vec<f64>,
    /// Per blob, the central second moments `[cxx, cxy, cyy]` of its thresholded area, pixels²
    /// (empty when unknown).
    pub(super) shapes: Vec<[f64; 3]>,
    /// Per blob, when it was exposed after `t_ns` (its row's rolling-shutter delay), nanoseconds;
    /// empty for a global shutter (every blob at `t_ns`).
    pub(super) blob_delay_ns: Vec<f64>,
    /// Where the pen was believed to be at `t_ns` (the last vision tip and the inertial
    /// direction), for labelling the frame by its pattern when no recent vision pose predicts it.
    pub(super) guess: Option<PenGuess>,
}

impl KeptFrame {
    /// Delay of blob `i`'s exposure after the frame time, nanoseconds.
    pub(super) fn delay(&self, i: usize) -> f64 {
        self.blob_delay_ns.get(i).copied().unwrap_or(0.0)
    }

    /// Exposure time of blob `i`, nanoseconds (left clock).
    fn blob_time(&self, i: usize) -> f64 {
        self.t_ns as f64 + self.delay(i)
    }
}

/// The current and the two previous frames of one camera.
#[derive(Debug, Clone, Default)]
pub(super) struct CameraHistory {
    /// The newest frame.
    pub(super) current: Option<KeptFrame>,
    /// The frame before it.
    pub(super) previous: Option<KeptFrame>,
    /// The frame before that: with the other two it measures a blob's image acceleration, which
    /// bounds the error of moving it at constant velocity.
    pub(super) older: Option<KeptFrame>,
}

impl CameraHistory {
    /// Makes a new frame the current one.
    pub(super) fn push(
        &mut self,
        t_ns: u64,
        blobs: Vec<[f64; 2]>,
        radii: Vec<f64>,
        blob_delay_ns: Vec<f64>,
    ) {
        self.older = self.previous.take();
        self.previous = self.current.take();
        self.current = Some(KeptFrame {
            t_ns,
            blobs,
            labels: [None; LED_COUNT],
            radii,
            shapes: Vec::new(),
            blob_delay_ns,
            guess: None,
        });
    }

    /// Records which blob of the current frame is which LED.
    pub(super) fn label_current(&mut self, labels: [Option<usize>; LED_COUNT]) {
        if let Some(f) = &mut self.current {
            f.labels = labels;
        }
    }
}

/// What the alignment needs from the configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct AlignOptions {
    /// Move the other camera's blobs to the frame time ([`TrackerConfig::time_align`]).
    pub(super) time_align: bool,
    /// A vision pose predicts the LEDs for this long, nanoseconds.
    pub(super) continuity_ns: u64,
    /// Largest image motion between consecutive frames used for velocity, pixels.
    pub(super) max_blob_motion_px: f64,
    /// Rolling-shutter delay of one row, per camera, nanoseconds ([`TrackerConfig::row_time_ns`]).
    pub(super) row_time_ns: [f64; 2],
    /// A blob centre's noise, pixels: the floor under which a measured image acceleration is
    /// noise, not motion.
    pub(super) pixel_sigma: f64,
    /// The pen's axial LED offsets and tip offset, for the LED images of a [`PenGuess`].
    pub(super) pen: crate::track::pen::PenGeometry,
    /// How a frame is labelled by its pattern ([`label_by_pattern`]).
    pub(super) pattern: PatternOptions,
}

impl AlignOptions {
    /// The options of a tracker configuration.
    pub(super) fn from_config(config: &TrackerConfig) -> Self {
        Self {
            time_align: config.time_align,
            continuity_ns: config.continuity_ns,
            max_blob_motion_px: config.max_blob_motion_px,
            row_time_ns: config.row_time_ns,
            pixel_sigma: config.correspondence.pixel_sigma,
            pen: config.pen,
            pattern: PatternOptions::default(),
        }
    }
}

/// The points of one stereo pair, reused from frame to frame: the other camera's blobs moved to
/// the pair's time and both cameras' blobs undistorted (normalised coordinates, indexed as the
/// frames' blobs).
#[derive(Debug, Clone, Default)]
pub(super) struct PairPoints {
    /// Camera of the frame that completed the pair (0 left, 1 right).
    pub(super) this: usize,
    /// The other camera's current blobs moved to the pair's time, pixels.
    pub(super) aligned: Vec<[f64; 2]>,
    /// This camera's blobs at the pair's time, pixels: the frame's own blobs, moved from their rows'
    /// times with a rolling shutter.
    pub(super) own: Vec<[f64; 2]>,
    /// Image velocity of each of those blobs, pixels per nanosecond (None: not moved).
    pub(super) aligned_velocity: Vec<Option<[f64; 2]>>,
    /// Per blob of the other camera, the error of moving it at constant velocity that its image
    /// acceleration predicts, pixels (0: not moved, or no acceleration measured).
    pub(super) aligned_error_px: Vec<f64>,
    /// Undistorted left points.
    pub(super) left_norm: Vec<[f64; 2]>,
    /// Undistorted right points.
    pub(super) right_norm: Vec<[f64; 2]>,
}

impl PairPoints {
    /// The predicted error of moving blob `blob` of `camera` to the pair's time, pixels: 0 for
    /// the camera that completed the pair (its blobs move by rows' delays only) and for blobs
    /// not moved.
    pub(super) fn move_error_px(&self, camera: CameraId, blob: usize) -> f64 {
        let cam = usize::from(camera == CameraId::Right);
        if cam == self.this {
            0.0
        } else {
            self.aligned_error_px.get(blob).copied().unwrap_or(0.0)
        }
    }

    /// The pixel blobs of `camera` as the pair uses them: the newest frame's own blobs (moved from
    /// their rows' times with a rolling shutter) for the camera that completed the pair, the
    /// aligned blobs for the other one.
    pub(super) fn pixels(&self, camera: CameraId) -> &[[f64; 2]] {
        let cam = usize::from(camera == CameraId::Right);
        if cam == self.this {
            &self.own
        } else {
            &self.aligned
        }
    }
}

/// Camera histories and recent pen poses: pairs frames across cameras and moves blobs in time.
#[derive(Debug, Clone)]
pub(super) struct TimeAlignment {
    options: AlignOptions,
    cameras: [CameraHistory; 2],
    /// All four LED positions of the newest and the one older vision pose, for predicting where
    /// the LEDs appear in a frame that no vision sample labelled.
    pen_history: [Option<(u64, [Vector3<f64>; LED_COUNT])>; 2],
    /// The measured blob-centre noise over the configured one ([`AlignOptions::pixel_sigma`]).
    noise_scale: f64,
    /// The gyro's last samples: how the pen turned between a blob's frames and the pair.
    gyro: GyroHistory,
    /// The tip's last world accelerations: how its velocity changed since the frame before.
    accel: AccelHistory,
}

impl TimeAlignment {
    /// Empty histories.
    pub(super) fn new(options: AlignOptions) -> Self {
        Self {
            options,
            cameras: Default::default(),
            pen_history: [None; 2],
            noise_scale: 1.0,
            gyro: GyroHistory::default(),
            accel: AccelHistory::default(),
        }
    }

    /// Keeps the tip's world acceleration (m/s², gravity removed) for the blobs' motion.
    pub(super) fn push_accel(&mut self, t_ns: u64, accel: Vector3<f64>) {
        self.accel.push(t_ns, accel);
    }

    /// Keeps a gyro sample (pen frame, rad/s) for the turn part of the blobs' motion.
    pub(super) fn push_gyro(&mut self, t_ns: u64, rate: Vector3<f64>) {
        self.gyro.push(t_ns, rate);
    }

    /// Sets the measured blob-centre noise as a factor of the configured one.
    pub(super) fn set_noise_scale(&mut self, scale: f64) {
        self.noise_scale = scale;
    }

    /// Keeps a new frame of camera `cam` (0 left, 1 right) exposed at `t_ns` (left clock, its first
    /// row), with its blobs' radii (empty when unknown), and returns the frame's time: `t_ns` for a
    /// global shutter, else the time of its blobs' median row, from which each blob keeps its own
    /// row's delay.
    pub(super) fn push(
        &mut self,
        cam: usize,
        t_ns: u64,
        blobs: Vec<[f64; 2]>,
        radii: Vec<f64>,
    ) -> u64 {
        let row = self.options.row_time_ns[cam];
        if row <= 0.0 || blobs.is_empty() {
            self.cameras[cam].push(t_ns, blobs, radii, Vec::new());
            return t_ns;
        }
        let mut rows: Vec<f64> = blobs.iter().map(|b| b[1]).collect();
        rows.sort_by(f64::total_cmp);
        let median = rows[rows.len() / 2].max(0.0);
        let t = t_ns.saturating_add((row * median).round() as u64);
        let delays = blobs.iter().map(|b| row * (b[1] - median)).collect();
        self.cameras[cam].push(t, blobs, radii, delays);
        t
    }

    /// Keeps the blobs' second moments with the newest frame of camera `cam` (see
    /// [`KeptFrame::shapes`]).
    pub(super) fn set_shapes(&mut self, cam: usize, shapes: Vec<[f64; 3]>) {
        if let Some(f) = self.cameras[cam].current.as_mut() {
            f.shapes = shapes;
        }
    }

    /// Keeps where the pen was believed to be with the newest frame of camera `cam` (see
    /// [`KeptFrame::guess`]).
    pub(super) fn set_guess(&mut self, cam: usize, guess: Option<PenGuess>) {
        if let Some(f) = self.cameras[cam].current.as_mut() {
            f.guess = guess;
        }
    }

    /// The newest frame of camera `cam`.
    pub(super) fn current(&self, cam: usize) -> Option<&KeptFrame> {
        self.cameras[cam].current.as_ref()
    }

    /// Records which blob of each camera's current frame is which LED (`this` is the camera that
    /// completed the pair).
    pub(super) fn label(
        &mut self,
        this: usize,
        own: [Option<usize>; LED_COUNT],
        other: [Option<usize>; LED_COUNT],
    ) {
        self.cameras[this].label_current(own);
        self.cameras[1 - this].label_current(other);
    }

    /// Keeps a vision pose (all four LED positions at `t_ns`) for predicting the LED images. The
    /// older pose, which with the newest gives the velocity, is kept at least
    /// [`MIN_VELOCITY_BASELINE_NS`] older: two free-running cameras drift into phase, and two
    /// poses from nearly simultaneous frames would divide their noise by microseconds.
    pub(super) fn remember_pose(&mut self, t_ns: u64, leds: [Vector3<f64>; LED_COUNT]) {
        let older = match self.pen_history[0] {
            Some((t0, _)) if t_ns.saturating_sub(t0) >= MIN_VELOCITY_BASELINE_NS => {
                self.pen_history[0]
            }
            _ => self.pen_history[1],
        };
        self.pen_history = [Some((t_ns, leds)), older];
    }

    /// Fills `points` for the newest frame of `this` at `t`: the other camera's latest frame
    /// moved to `t` (when time alignment is on), then both undistorted.
    pub(super) fn prepare(&self, rig: &StereoRig, this: usize, t: u64, points: &mut PairPoints) {
        let other = 1 - this;
        points.this = this;
        points.aligned.clear();
        points.aligned_velocity.clear();
        points.aligned_error_px.clear();
        if let Some(cur) = &self.cameras[other].current {
            points.aligned.extend_from_slice(&cur.blobs);
            points.aligned_velocity.resize(cur.blobs.len(), None);
            points.aligned_error_px.resize(cur.blobs.len(), 0.0);
        }
        if self.options.time_align {
            for m in self.alignment(rig, other, t) {
                points.aligned[m.blob] = m.moved;
                points.aligned_velocity[m.blob] = Some(m.velocity);
                points.aligned_error_px[m.blob] = m.error_px;
            }
        }
        points.own.clear();
        if let Some(cur) = &self.cameras[this].current {
            points.own.extend_from_slice(&cur.blobs);
        }
        if self.options.time_align && self.options.row_time_ns[this] > 0.0 {
            for m in self.alignment(rig, this, t) {
                points.own[m.blob] = m.moved;
            }
        }
        let (l_px, r_px): (&[[f64; 2]], &[[f64; 2]]) = if this == 0 {
            (&points.own, &points.aligned)
        } else {
            (&points.aligned, &points.own)
        };
        undistort_all(&rig.left, l_px, &mut points.left_norm);
        undistort_all(&rig.right, r_px, &mut points.right_norm);
    }

    /// Where the other camera's current blobs would be at `t` ([`MovedBlob`]) for every blob
    /// whose LED is known. The velocity is measured between the same LED's blobs in the previous
    /// and current frame of that camera; without a previous blob it is the predicted pen motion
    /// projected into the image. With the same LED's blob in the frame before, the image
    /// acceleration (above the centres' noise) moves it too, and gives the move's error (see
    /// [`extrapolation_error`]): at 15 frames/s a stroke's curve accelerates a blob by thousands
    /// of px/s², and moving it a third of a frame at the velocity of the frame before missed the
    /// other camera's epipolar gate by several pixels (fires-v2).
    ///
    /// Blobs are matched by LED identity (labels of earlier vision samples, or the predicted LED
    /// images), never by nearest neighbour: at 15-30 frames/s a fast pen moves about one LED
    /// spacing per frame, a nearest-neighbour velocity then aliases to the neighbouring LED, and
    /// the whole pen shifts by one LED into a consistent but wrongly labelled configuration.
    pub(super) fn alignment(&self, rig: &StereoRig, other: usize, t: u64) -> Vec<MovedBlob> {
        let history = &self.cameras[other];
        let Some(cur) = &history.current else {
            return Vec::new();
        };
        let camera = if other == 0 {
            CameraId::Left
        } else {
            CameraId::Right
        };
        let cur_ids = self.frame_identities(rig, camera, cur);
        let prev = history
            .previous
            .as_ref()
            .filter(|p| p.t_ns < cur.t_ns && cur.t_ns - p.t_ns <= 100_000_000);
        let prev_ids = prev.map(|p| self.frame_identities(rig, camera, p));
        let older = prev.and_then(|p| {
            history
                .older
                .as_ref()
                .filter(|o| o.t_ns < p.t_ns && p.t_ns - o.t_ns <= 100_000_000)
        });
        let older_ids = older.map(|o| self.frame_identities(rig, camera, o));
        let shift = t as f64 - cur.t_ns as f64;
        // Predicted LEDs at the frame's time and at this one (or, when they coincide, one prediction
        // step later: a rolling shutter still moves the blobs), computed once per frame.
        let step = if shift != 0.0 {
            shift
        } else {
            PREDICTION_STEP_NS
        };
        let (at_frame, at_target) = (
            self.predicted_leds(cur.t_ns),
            self.predicted_leds(cur.t_ns.saturating_add_signed(step as i64)),
        );
        let project =
            |leds: Option<[Vector3<f64>; LED_COUNT]>, k: usize| rig.project(camera, &leds?[k]).ok();
        // The image motion of LED k between two times that the pen's turn alone causes, zero
        // without a guess or gyro samples ([`Self::turn_px`]).
        let turn = |k: usize, t0: f64, t1: f64| -> [f64; 2] {
            self.turn_px(rig, camera, cur, k, t0, t1)
                .unwrap_or([0.0; 2])
        };
        let mut out = Vec::new();
        // The LEDs whose blobs measured the motion the turn does not explain (LED, that image
        // velocity, the move's error), and the LEDs nothing measured (LED, blob, shift).
        let (mut translations, mut unmeasured) = (Vec::new(), Vec::new());
        for (k, id) in cur_ids.iter().enumerate() {
            let Some(i) = *id else { continue };
            let b = cur.blobs[i];
            let own_shift = shift - cur.delay(i);
            let mut error_px = 0.0;
            let mut correction = [0.0; 2];
            let measured = prev.zip(prev_ids).and_then(|(p, ids)| {
                let j = ids[k]?;
                let q = p.blobs[j];
                let dt = cur.blob_time(i) - p.blob_time(j);
                let near = (b[0] - q[0]).hypot(b[1] - q[1]) <= self.motion_limit_px(dt);
                // The velocity of the motion the turn does not explain.
                let r = turn(k, p.blob_time(j), cur.blob_time(i));
                let v = (near && dt > 0.0)
                    .then(|| [(b[0] - q[0] - r[0]) / dt, (b[1] - q[1] - r[1]) / dt])?;
                // The same LED one frame earlier: the acceleration between the two velocities.
                let before = older.zip(older_ids).and_then(|(o, ids)| {
                    let n = ids[k]?;
                    let r = o.blobs[n];
                    let dt0 = p.blob_time(j) - o.blob_time(n);
                    let near = (q[0] - r[0]).hypot(q[1] - r[1]) <= self.motion_limit_px(dt0);
                    let w = turn(k, o.blob_time(n), p.blob_time(j));
                    (near && dt0 > 0.0).then(|| {
                        (
                            [(q[0] - r[0] - w[0]) / dt0, (q[1] - r[1] - w[1]) / dt0],
                            dt0,
                        )
                    })
                });
                if let Some((v0, dt0)) = before {
                    let a = [
                        (v[0] - v0[0]) / (0.5 * (dt + dt0)),
                        (v[1] - v0[1]) / (0.5 * (dt + dt0)),
                    ];
                    // Three noisy centres give an acceleration of standard deviation about
                    // √6 σ / (dt dt0) per axis even at rest: only what exceeds twice that is
                    // motion. σ is the rig's measured centre noise (a webcam's is a tenth of the
                    // configured 0.5 px; with that the floor hid the flicks of webcam seed 4).
                    let sigma = self.options.pixel_sigma * self.noise_scale;
                    let floor = 2.0 * 6f64.sqrt() * sigma / (dt * dt0);
                    let accel = (a[0].hypot(a[1]) - floor).max(0.0);
                    error_px = extrapolation_error(accel, dt, own_shift);
                    // The move follows the acceleration above that floor (constant acceleration
                    // over the three frames, so the velocity's lag over dt / 2 and the
                    // acceleration over the move are both taken up); the error keeps the size of
                    // the constant-velocity move's, since a flick's acceleration itself changes
                    // within three frames.
                    let norm = a[0].hypot(a[1]);
                    let keep = if norm > 0.0 { accel / norm } else { 0.0 };
                    let c = 0.5 * own_shift * (dt + own_shift) * keep;
                    correction = [a[0] * c, a[1] * c];
                    // What the IMU measured beyond what the three frames show (a pen setting off
                    // from rest, which they do not show yet) moves the blob too: its move less the
                    // image acceleration the same samples would have given. Only that change is
                    // taken from the IMU: its own slowly varying error (gravity left by a degree
                    // of orientation error, 0.17 m/s^2) cancels, where it would otherwise move a
                    // resting pen's blobs a few tenths of a pixel, millimetres of depth on the
                    // 6 cm baseline.
                    let frames = (p.blob_time(j) - dt0, p.blob_time(j), cur.blob_time(i));
                    let mv = (p.blob_time(j), cur.blob_time(i), own_shift);
                    if let Some(px) = self.imu_move_px(rig, camera, cur, k, mv, frames) {
                        correction = [correction[0] + px[0], correction[1] + px[1]];
                    }
                }
                let m = turn(k, cur.blob_time(i), cur.blob_time(i) + own_shift);
                correction = [correction[0] + m[0], correction[1] + m[1]];
                Some(v)
            });
            let was_measured = measured.is_some();
            let v = measured.or_else(|| {
                // One pose predicts no motion: the blob is not moved, and says so (None).
                if !self.pen_velocity_known() {
                    return None;
                }
                let (a, c) = (project(at_frame, k)?, project(at_target, k)?);
                let v = [(c[0] - a[0]) / step, (c[1] - a[1]) / step];
                error_px = unmeasured_move_error(v, own_shift);
                Some(v)
            });
            let Some(v) = v else {
                unmeasured.push((k, i, own_shift));
                continue;
            };
            if was_measured {
                translations.push(MeasuredTranslation {
                    led: k,
                    velocity: v,
                    error_px,
                });
            }
            out.push(MovedBlob::new(i, b, v, own_shift, correction, error_px));
        }
        if out.is_empty() {
            if let Some(p) = prev {
                // No LED identities: match the two frames' blobs by their order along the pen line.
                let o = LineOrderOptions {
                    max_motion_px: self.options.max_blob_motion_px,
                    ..LineOrderOptions::default()
                };
                for (q, i) in match_along_line(&p.blobs, &cur.blobs, &o).unwrap_or_default() {
                    let (a, b) = (p.blobs[q], cur.blobs[i]);
                    let dt = cur.blob_time(i) - p.blob_time(q);
                    let own_shift = shift - cur.delay(i);
                    if dt <= 0.0 {
                        continue;
                    }
                    let v = [(b[0] - a[0]) / dt, (b[1] - a[1]) / dt];
                    let error_px = unmeasured_move_error(v, own_shift);
                    out.push(MovedBlob::new(i, b, v, own_shift, [0.0; 2], error_px));
                }
            }
        }
        // The pen is rigid: a blob that nothing measured (the frame before showed a reflection
        // beside it) moves with the translation its LEDs' neighbours measured plus its own turn.
        let error_px = translations.iter().map(|x| x.error_px).fold(0.0, f64::max);
        for (k, i, own_shift) in unmeasured {
            let t0 = cur.blob_time(i);
            let (Some(tv), Some(m)) = (
                rigid_translation(&translations, &self.options.pen.led_offsets, k),
                self.turn_px(rig, camera, cur, k, t0, t0 + own_shift),
            ) else {
                continue;
            };
            out.push(MovedBlob::new(i, cur.blobs[i], tv, own_shift, m, error_px));
        }
        out
    }

    /// True when the pair's other camera (of `this`) was exposed within `max_dt_ns` of `t`, or
    /// every one of its `blobs` was moved to `t` with an image velocity.
    pub(super) fn other_moved(
        &self,
        points: &PairPoints,
        this: usize,
        t: u64,
        max_dt_ns: u64,
        mut blobs: impl Iterator<Item = usize>,
    ) -> bool {
        let near = self
            .current(1 - this)
            .is_none_or(|f| f.t_ns.abs_diff(t) <= max_dt_ns);
        near || blobs.all(|b| points.aligned_velocity.get(b).is_some_and(Option::is_some))
    }

    /// The largest motion of one LED's blob over `dt` ns between two frames of a camera that
    /// gives a velocity: [`AlignOptions::max_blob_motion_px`] per frame of a 60 Hz camera, for
    /// frames further apart at that speed.
    fn motion_limit_px(&self, dt: f64) -> f64 {
        let per_60hz_frame = self.options.max_blob_motion_px;
        per_60hz_frame.max(per_60hz_frame * dt / FRAME_60HZ_NS)
    }

    /// True when the last two vision poses give the pen's velocity (not one pose alone).
    fn pen_velocity_known(&self) -> bool {
        matches!(
            (self.pen_history[0], self.pen_history[1]),
            (Some((t1, _)), Some((t0, _))) if t1 > t0 && t1 - t0 <= 100_000_000
        )
    }

    /// All four LED positions at `t` from the last two vision poses (constant velocity), or None
    /// without a recent pose.
    pub(super) fn predicted_leds(&self, t: u64) -> Option<[Vector3<f64>; LED_COUNT]> {
        let (t1, p1) = self.pen_history[0]?;
        if t.abs_diff(t1) > self.options.continuity_ns {
            return None;
        }
        let dt = (t as f64 - t1 as f64) * 1e-9;
        let velocity = |k: usize| match self.pen_history[1] {
            Some((t0, p0)) if self.pen_velocity_known() => {
                (p1[k] - p0[k]) / ((t1 - t0) as f64 * 1e-9)
            }
            _ => Vector3::zeros(),
        };
        Some(std::array::from_fn(|k| p1[k] + velocity(k) * dt))
    }
}

/// One blob moved to a pair's time ([`TimeAlignment::alignment`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct MovedBlob {
    /// The blob's index in its frame.
    pub(super) blob: usize,
    /// Its position at the pair's time, distorted pixels.
    pub(super) moved: [f64; 2],
    /// The image velocity it was moved with, pixels per nanosecond.
    pub(super) velocity: [f64; 2],
    /// The move's error that the blob's image acceleration predicts, pixels (0 when unmeasured).
    pub(super) error_px: f64,
}

impl MovedBlob {
    /// Blob `blob` at `at` (pixels) moved by `shift` (ns) at `velocity` (px/ns), plus
    /// `correction` (pixels: the parts of the move no constant velocity explains).
    fn new(
        blob: usize,
        at: [f64; 2],
        velocity: [f64; 2],
        shift: f64,
        correction: [f64; 2],
        error_px: f64,
    ) -> Self {
        MovedBlob {
            blob,
            moved: [
                at[0] + velocity[0] * shift + correction[0],
                at[1] + velocity[1] * shift + correction[1],
            ],
            velocity,
            error_px,
        }
    }
}

/// The error of moving a blob by `shift` (ns) with the velocity measured over the `dt` (ns)
/// before it, when its image accelerates at `accel` (px/ns²), pixels. That velocity is the one
/// at the middle of `dt`, so the true position differs by `a s (dt + s) / 2`: the velocity's
/// lag over `dt / 2` and the acceleration over the move itself. It is what a chord's flick
/// costs a pair whose other camera was exposed most of a frame earlier (webcam seed 4: up to
/// 1.5 px, 5 mm of depth, where the pair completed by that camera's next frame moves it by a
/// few milliseconds and stays within 0.2 px).
pub(super) fn extrapolation_error(accel: f64, dt: f64, shift: f64) -> f64 {
    (0.5 * accel * shift * (dt + shift)).abs()
}

/// The error of moving a blob by `shift` (ns) at velocity `v` (px/ns) that no LED's own blobs
/// measured, pixels: a velocity predicted from the pen's last poses, or that of blobs matched
/// by their order along the pen (a merged blob, whose centroid moves as its spots merge and
/// part), can be wrong by as much as the motion itself under a turn; half the move is the
/// middle of that range.
fn unmeasured_move_error(v: [f64; 2], shift: f64) -> f64 {
    0.5 * v[0].hypot(v[1]) * shift.abs()
}

/// The shortest time between the two vision poses whose difference predicts the pen's motion,
/// nanoseconds: a quarter of a 60 Hz frame, so that a millimetre of triangulation noise makes at
/// most 0.25 m/s of velocity error.
const MIN_VELOCITY_BASELINE_NS: u64 = 4_000_000;

/// The time step over which a predicted pen motion gives an image velocity when the blobs' frame
/// is the pair's own (a rolling shutter's rows still need moving), nanoseconds.
const PREDICTION_STEP_NS: f64 = 10_000_000.0;

/// The shortest interval between a camera's frames over which the tip's measured acceleration
/// joins the move, nanoseconds (two 60 Hz periods). Faster cameras' three frames follow a drawn
/// curve within 0.2 px, and there the IMU's tip acceleration, whose lever term differentiates
/// the gyro, adds more error in a flick than it removes (webcam seed 10: the boundary stroke's
/// pen-line tips 4-8 mm off with it, within 0.3 mm without).
const IMU_MOVE_MIN_INTERVAL_NS: f64 = 2.0 * FRAME_60HZ_NS;

/// A 60 Hz camera's frame period, nanoseconds: the period over which
/// [`AlignOptions::max_blob_motion_px`] is the largest motion of an LED's blob.
const FRAME_60HZ_NS: f64 = 1e9 / 60.0;

/// Undistorts every blob into `out`, index for index.
fn undistort_all(cam: &CameraModel, px: &[[f64; 2]], out: &mut Vec<[f64; 2]>) {
    out.clear();
    // A blob that cannot be undistorted is replaced by a NaN point, which the triangulation
    // rejects, so blob indices stay aligned with the frame.
    out.extend(
        px.iter()
            .map(|p| cam.undistort(*p).unwrap_or([f64::NAN, f64::NAN])),
    );
}

#[path = "align_identities.rs"]
mod identities;
#[path = "align_motion.rs"]
mod motion;
#[cfg(test)]
#[path = "align_tests.rs"]
pub(super) mod tests;
