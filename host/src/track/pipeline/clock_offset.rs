//! Online estimate of the residual right-camera clock offset. With the time-aligned blobs, a
//! residual offset `δ` leaves an epipolar residual `e ≈ e0 + g δ` on every moving LED, where `g`
//! is the rate of change of the epipolar distance along the aligned blob's image velocity;
//! over a window of labelled frames `δ = -Σ e0 g / Σ g²` (least squares), applied when its
//! standard deviation is below the configured precision. Clocks and offsets:
//! docs/architecture.md §3.

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

/// The estimated residual offset and the sums of the current window.
#[derive(Debug, Clone)]
pub(super) struct ClockOffsetEstimator {
    options: ClockOptions,
    offset_ns: i64,
    sum_eg: f64,
    sum_gg: f64,
    frames: usize,
}

impl ClockOffsetEstimator {
    /// No offset estimated yet.
    pub(super) fn new(options: ClockOptions) -> Self {
        Self {
            options,
            offset_ns: 0,
            sum_eg: 0.0,
            sum_gg: 0.0,
            frames: 0,
        }
    }

    /// The estimated residual offset, nanoseconds (added to the configured one).
    pub(super) fn offset_ns(&self) -> i64 {
        self.offset_ns
    }

    /// Adds the labelled LEDs' epipolar residuals of one labelled pair to the estimate.
    pub(super) fn observe(
        &mut self,
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
        self.end_frame(sigma_e);
    }

    /// Adds one residual `e` with its sensitivity `g` to the offset (non-finite ones are skipped).
    fn add(&mut self, e: f64, g: f64) {
        if e.is_finite() && g.is_finite() {
            self.sum_eg += e * g;
            self.sum_gg += g * g;
        }
    }

    /// Ends a frame; every `window` frames applies the update if precise enough (`sigma_e`: noise
    /// of one residual).
    fn end_frame(&mut self, sigma_e: f64) {
        self.frames += 1;
        if self.frames < self.options.window {
            return;
        }
        if self.sum_gg > 0.0 && sigma_e / self.sum_gg.sqrt() <= self.options.precision_ns {
            // Half steps: the estimate converges geometrically and its noise is halved.
            let delta = (-0.5 * self.sum_eg / self.sum_gg).clamp(-5e6, 5e6);
            self.offset_ns = self.offset_ns.saturating_add(delta.round() as i64);
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

    /// Residuals `e = -g δ` of a true offset `δ` over one window: the update is half of `δ`
    /// (half steps), applied only once the window is full, and the window then starts afresh.
    #[test]
    fn a_full_window_applies_half_the_least_squares_offset() {
        let mut c = ClockOffsetEstimator::new(OPTIONS);
        let delta = 2_000_000.0;
        for (frame, gs) in [[1e-9, -2e-9], [3e-9, 0.5e-9], [-1e-9, 1.5e-9]]
            .iter()
            .enumerate()
        {
            for g in gs {
                c.add(-g * delta, *g);
            }
            c.add(f64::NAN, 1e-9);
            c.end_frame(1e-6);
            if frame < 2 {
                assert_eq!(c.offset_ns(), 0);
            }
        }
        assert_eq!(c.offset_ns(), 1_000_000);
        assert_eq!((c.sum_eg, c.sum_gg, c.frames), (0.0, 0.0, 0));
    }

    /// An imprecise window (residual noise large against the sensitivity) changes nothing; a
    /// huge offset is applied in steps of at most 5 ms.
    #[test]
    fn imprecise_windows_are_discarded_and_steps_are_bounded() {
        let mut c = ClockOffsetEstimator::new(ClockOptions {
            window: 1,
            ..OPTIONS
        });
        c.add(-1e-9 * 1e6, 1e-9);
        // sigma_e / |g| = 2e6 ns > 1e6 ns precision.
        c.end_frame(2e-3);
        assert_eq!(c.offset_ns(), 0);
        c.add(-1e-9 * 1e9, 1e-9);
        c.end_frame(1e-6);
        assert_eq!(c.offset_ns(), 5_000_000);
        c.end_frame(1e-6);
        assert_eq!(c.offset_ns(), 5_000_000, "an empty window changes nothing");
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
            &rig,
            &PairPoints::default(),
            &[Candidate::at(0, 0, Vector3::z())],
            &id,
        );
        assert_eq!(c.frames, 0);
    }
}
