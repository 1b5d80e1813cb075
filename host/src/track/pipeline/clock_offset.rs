//! Online estimate of the residual right-camera clock offset. With the time-aligned blobs, a
//! residual offset `δ` leaves an epipolar residual `e ≈ e0 + g δ` on every moving LED, where `g`
//! is the rate of change of the epipolar distance along the aligned blob's image velocity;
//! a window of labelled frames measures `δ = -Σ e0 g / Σ g²` (least squares) with variance
//! `k σₑ² / Σ g²`. The offset is a constant latency difference between the two cameras' stamps
//! (each camera's own rate is fitted by its frame clock), so the windows are fused by a scalar
//! Kalman filter with a slow random walk: every window counts by its precision, and the estimate
//! settles instead of following each window's noise. Clocks and offsets: docs/architecture.md §3.

use super::align::PairPoints;
use super::TrackerConfig;
use crate::stereo::{Candidate, StereoRig};
use crate::track::identify::Identification;
use nalgebra::Vector3;

/// What the estimator needs from the configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct ClockOptions {
    /// Estimate at all (needs time alignment, whose image velocities give `g`).
    pub(super) enabled: bool,
    /// Labelled frames per update.
    pub(super) window: usize,
    /// Required precision of one update, nanoseconds (else the window is discarded).
    pub(super) precision_ns: f64,
    /// Blob centroid noise, pixels (gives the residuals' noise).
    pub(super) pixel_sigma: f64,
}

impl ClockOptions {
    /// The options of a tracker configuration.
    pub(super) fn from_config(config: &TrackerConfig) -> Self {
        Self {
            enabled: config.estimate_clock_offset && config.time_align,
            window: config.clock_window,
            precision_ns: config.clock_precision_ns,
            pixel_sigma: config.correspondence.pixel_sigma,
        }
    }
}

/// Variance of the offset before the first window, ns²: (5 ms)², a latency difference of a
/// few milliseconds between two USB cameras' stamps.
const PRIOR_VARIANCE_NS2: f64 = 25e12;

/// Random walk of the offset, ns² per second: (0.1 ms)² per second, far above a stamp
/// latency's slow change and far below a window's noise, so the estimate averages over tens
/// of seconds and still follows a latency that changes.
const WALK_NS2_PER_S: f64 = 1e10;

/// A window's true error against the pixel-noise variance it is given: its residuals also
/// hold the blob moves' and the calibration's errors. Measured over the simulated rigs: the
/// windows' squared errors are about 4 times their pixel-noise variance (fires-v1).
const WINDOW_NOISE_FACTOR: f64 = 4.0;

/// A window whose measured offset lies this many standard deviations from the estimate is
/// an outlier (a mislabelled or badly moved frame in it) and is dropped.
const OUTLIER_SIGMAS: f64 = 4.0;

/// The estimated residual offset, its variance, and the sums of the current window.
#[derive(Debug, Clone)]
pub(super) struct ClockOffsetEstimator {
    options: ClockOptions,
    offset_ns: f64,
    variance_ns2: f64,
    last_update_ns: Option<u64>,
    sum_eg: f64,
    sum_gg: f64,
    frames: usize,
}

impl ClockOffsetEstimator {
    /// No offset estimated yet.
    pub(super) fn new(options: ClockOptions) -> Self {
        Self {
            options,
            offset_ns: 0.0,
            variance_ns2: PRIOR_VARIANCE_NS2,
            last_update_ns: None,
            sum_eg: 0.0,
            sum_gg: 0.0,
            frames: 0,
        }
    }

    /// The estimated residual offset, nanoseconds (added to the configured one).
    pub(super) fn offset_ns(&self) -> i64 {
        self.offset_ns.round() as i64
    }

    /// Adds the labelled LEDs' epipolar residuals of one labelled pair at time `t_ns` to the
    /// estimate.
    pub(super) fn observe(
        &mut self,
        t_ns: u64,
        rig: &StereoRig,
        points: &PairPoints,
        candidates: &[Candidate],
        id: &Identification,
    ) {
        if !self.options.enabled {
            return;
        }
        let this = points.this;
        let e_mat = *rig.essential();
        for k in id.assignment.iter().flatten() {
            let c = &candidates[*k];
            let (Some(ml), Some(mr)) =
                (points.left_norm.get(c.left), points.right_norm.get(c.right))
            else {
                continue;
            };
            let other_idx = if this == 0 { c.right } else { c.left };
            let Some(Some(v)) = points.aligned_velocity.get(other_idx) else {
                continue;
            };
            let (l3, r3) = (
                Vector3::new(ml[0], ml[1], 1.0),
                Vector3::new(mr[0], mr[1], 1.0),
            );
            let line = e_mat * l3;
            let n = line.x.hypot(line.y);
            if n <= 0.0 {
                continue;
            }
            let e = r3.dot(&line) / n;
            let g = if this == 0 {
                let f = rig.right.focal_px();
                -(line.x * v[0] + line.y * v[1]) / (n * f)
            } else {
                let f = rig.left.focal_px();
                let grad = e_mat.transpose() * r3;
                (grad.x * v[0] + grad.y * v[1]) / (n * f)
            };
            self.add(e, g);
        }
        let sigma_e = std::f64::consts::SQRT_2 * self.options.pixel_sigma / rig.right.focal_px();
        self.end_frame(t_ns, sigma_e);
    }

    /// Adds one residual `e` with its sensitivity `g` to the offset (non-finite ones are skipped).
    fn add(&mut self, e: f64, g: f64) {
        if e.is_finite() && g.is_finite() {
            self.sum_eg += e * g;
            self.sum_gg += g * g;
        }
    }

    /// Ends a frame at `t_ns`; every `window` frames fuses the window's offset into the
    /// estimate if it is precise enough (`sigma_e`: pixel noise of one residual) and no outlier.
    fn end_frame(&mut self, t_ns: u64, sigma_e: f64) {
        self.frames += 1;
        if self.frames < self.options.window {
            return;
        }
        let precision = sigma_e / self.sum_gg.sqrt();
        if self.sum_gg > 0.0 && precision <= self.options.precision_ns {
            let measured = self.offset_ns - self.sum_eg / self.sum_gg;
            let noise = WINDOW_NOISE_FACTOR * precision * precision;
            let elapsed = self
                .last_update_ns
                .map_or(0.0, |t0| t_ns.saturating_sub(t0) as f64 * 1e-9);
            let predicted = self.variance_ns2 + WALK_NS2_PER_S * elapsed;
            let innovation = measured - self.offset_ns;
            if measured.is_finite()
                && innovation * innovation <= OUTLIER_SIGMAS.powi(2) * (predicted + noise)
            {
                let gain = predicted / (predicted + noise);
                self.offset_ns += gain * innovation;
                self.variance_ns2 = (1.0 - gain) * predicted;
                self.last_update_ns = Some(t_ns);
            }
        }
        self.sum_eg = 0.0;
        self.sum_gg = 0.0;
        self.frames = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const OPTIONS: ClockOptions = ClockOptions {
        enabled: true,
        window: 3,
        precision_ns: 1_000_000.0,
        pixel_sigma: 0.5,
    };

    /// Feeds one window of residuals `e = -g (δ - offset)` of a true offset `δ` (ns) with an
    /// error `noise_ns` on the measured offset, ending at `t_ns`; the window's pixel noise
    /// gives it a precision of 0.5 ms (so 1 ms with the noise factor).
    fn window(c: &mut ClockOffsetEstimator, t_ns: u64, delta: f64, noise_ns: f64) {
        for frame in 0..c.options.window {
            let g = 1e-9 * (1.0 + frame as f64);
            if frame == 0 {
                let offset = c.offset_ns + noise_ns;
                c.add(-g * (delta - offset), g);
            }
            c.add(f64::NAN, g);
            c.end_frame(t_ns, 0.5e-3);
        }
    }

    /// A noise-free window of a 2 ms offset: the first update takes it almost whole (the prior
    /// is 5 ms wide, the window far narrower); nothing changes before the window is full, and
    /// the window then starts afresh.
    #[test]
    fn a_full_window_measures_the_least_squares_offset() {
        let mut c = ClockOffsetEstimator::new(OPTIONS);
        let g = 1e-9;
        c.add(-g * 2e6, g);
        c.end_frame(0, 1e-12);
        c.end_frame(0, 1e-12);
        assert_eq!(c.offset_ns(), 0);
        c.end_frame(0, 1e-12);
        assert!((c.offset_ns() - 2_000_000).abs() <= 1, "{}", c.offset_ns());
        assert_eq!((c.sum_eg, c.sum_gg, c.frames), (0.0, 0.0, 0));
    }

    /// Windows with alternating ±1 ms errors around a 0.5 ms offset: the estimate settles on
    /// it (the errors average out) instead of jumping with each window, as a fixed-gain step
    /// would.
    #[test]
    fn noisy_windows_average_out() {
        let mut c = ClockOffsetEstimator::new(OPTIONS);
        let mut worst_late = 0.0f64;
        for k in 0..400u64 {
            let noise = if k % 2 == 0 { 1e6 } else { -1e6 };
            window(&mut c, k * 300_000_000, 0.5e6, noise);
            if k >= 100 {
                worst_late = worst_late.max((c.offset_ns - 0.5e6).abs());
            }
        }
        assert!(worst_late < 0.15e6, "{worst_late}");
    }

    /// An imprecise window (residual noise large against the sensitivity) changes nothing; a
    /// window far outside the estimate's and its own uncertainty is dropped as an outlier.
    #[test]
    fn imprecise_and_outlying_windows_are_discarded() {
        let mut c = ClockOffsetEstimator::new(ClockOptions {
            window: 1,
            ..OPTIONS
        });
        c.add(-1e-9 * 1e6, 1e-9);
        // sigma_e / |g| = 2e6 ns > 1e6 ns precision.
        c.end_frame(0, 2e-3);
        assert_eq!(c.offset_ns(), 0);
        for k in 0..20 {
            c.add(-1e-9 * (1e6 - c.offset_ns), 1e-9);
            c.end_frame(k, 1e-4);
        }
        assert!(
            (c.offset_ns() - 1_000_000).abs() < 1_000,
            "{}",
            c.offset_ns()
        );
        c.add(-1e-9 * 50e6, 1e-9);
        c.end_frame(21, 1e-4);
        assert!(
            (c.offset_ns() - 1_000_000).abs() < 1_000,
            "an outlier moved it"
        );
        c.end_frame(22, 1e-4);
        assert!(
            (c.offset_ns() - 1_000_000).abs() < 1_000,
            "an empty window changes nothing"
        );
    }

    #[test]
    fn disabled_estimation_observes_nothing() {
        let rig = StereoRig::parallel(640, 480, 1.0, 0.2);
        let mut c = ClockOffsetEstimator::new(ClockOptions {
            enabled: false,
            ..OPTIONS
        });
        let id = Identification {
            assignment: [Some(0), None, None, None],
            points: [None; 4],
            distance_rms: 0.0,
            confidence: 1.0,
            resolution: crate::track::identify::Resolution::Geometry,
            interference: 0,
            completed: 0,
            from_pen_line: false,
            from_pen_ray: None,
        };
        c.observe(
            0,
            &rig,
            &PairPoints::default(),
            &[Candidate::at(0, 0, Vector3::z())],
            &id,
        );
        assert_eq!(c.frames, 0);
    }
}
