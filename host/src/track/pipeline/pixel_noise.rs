//! The blob-centroid noise of the rig, measured online from the epipolar residuals of labelled
//! LEDs, so the tip's expected noise follows the cameras at hand rather than one configured
//! figure.
//!
//! The tip's noise (`Tracker::tip_sigma`) is propagated from the candidates' covariances, which
//! assume [`crate::stereo::CorrespondenceConfig::pixel_sigma`] of isotropic noise per blob
//! centre. That figure suits the 1024×768 blob cameras (0.5 px); a 640×480 webcam's centroids
//! over a dozen pixels of a sharp spot are ten times steadier, and a tip filter told 0.5 px then
//! trusts its motion model over the measurements and trails the pen by millimetres wherever it
//! accelerates (webcam seed 4, stroke 3: 1.1 mm RMS, 2.4 mm at the turns). A correctly labelled
//! LED's blobs lie on each other's epipolar lines up to the two centres' noise, so the residual
//! (right image pixels) has standard deviation `√2 σ`; the median of its magnitude over the last
//! [`WINDOW`] labelled LEDs, divided by `0.6745 √2`, estimates `σ` robustly (a labelling's
//! outliers do not move a median).

use std::collections::VecDeque;

/// Residuals kept, the most recent labelled LEDs'.
const WINDOW: usize = 512;
/// Residuals needed before the estimate replaces the configured figure.
const MIN_RESIDUALS: usize = 64;
/// The estimate is refreshed after this many new residuals.
const REFRESH: usize = 32;
/// The estimated noise is kept within these multiples of the configured one.
const SCALE_RANGE: (f64, f64) = (0.05, 4.0);

/// Online estimate of the blob-centroid noise, pixels.
#[derive(Debug, Clone)]
pub(super) struct PixelNoise {
    configured_px: f64,
    residuals: VecDeque<f64>,
    since_refresh: usize,
    /// The estimate at the last refresh.
    sigma_px: Option<f64>,
    scale: f64,
    /// Reused for the median.
    scratch: Vec<f64>,
}

impl PixelNoise {
    /// An estimator for a rig configured with `configured_px` of centroid noise.
    pub(super) fn new(configured_px: f64) -> Self {
        Self {
            configured_px,
            residuals: VecDeque::with_capacity(WINDOW),
            since_refresh: 0,
            sigma_px: None,
            scale: 1.0,
            scratch: Vec::with_capacity(WINDOW),
        }
    }

    /// Adds the epipolar residuals (pixels) of a labelled pair's LEDs.
    pub(super) fn observe(&mut self, epipolar_px: impl IntoIterator<Item = f64>) {
        for e in epipolar_px.into_iter().filter(|e| e.is_finite()) {
            if self.residuals.len() == WINDOW {
                self.residuals.pop_front();
            }
            self.residuals.push_back(e.abs());
            self.since_refresh += 1;
        }
        let due = self.since_refresh >= REFRESH || self.sigma_px.is_none();
        if due && self.residuals.len() >= MIN_RESIDUALS && self.configured_px > 0.0 {
            self.since_refresh = 0;
            self.scratch.clear();
            self.scratch.extend(self.residuals.iter().copied());
            let mid = self.scratch.len() / 2;
            let (_, median, _) = self.scratch.select_nth_unstable_by(mid, f64::total_cmp);
            let sigma = *median / (0.6745 * std::f64::consts::SQRT_2);
            self.sigma_px = Some(sigma);
            self.scale = (sigma / self.configured_px).clamp(SCALE_RANGE.0, SCALE_RANGE.1);
        }
    }

    /// The estimated centroid noise at the last refresh, pixels; None before [`MIN_RESIDUALS`]
    /// residuals.
    #[cfg(test)]
    pub(super) fn sigma_px(&self) -> Option<f64> {
        self.sigma_px
    }

    /// The factor from the configured noise to the measured one (1 until it is measured),
    /// within [`SCALE_RANGE`].
    pub(super) fn scale(&self) -> f64 {
        self.scale
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::synth::SplitMix64;

    /// Residuals of two centres with σ = 0.05 px each: the estimate finds σ within 10 % and the
    /// scale from a configured 0.5 px is 0.1; a few gross outliers (wrong pairs) do not move it.
    #[test]
    fn the_noise_is_measured_from_epipolar_residuals() {
        let mut rng = SplitMix64::new(7);
        let mut noise = PixelNoise::new(0.5);
        assert_eq!(noise.scale(), 1.0);
        let sigma = 0.05;
        for k in 0..2000 {
            let e = if k % 50 == 0 {
                30.0
            } else {
                sigma * std::f64::consts::SQRT_2 * rng.gaussian()
            };
            noise.observe([e]);
        }
        let est = noise.sigma_px().unwrap();
        assert!((est / sigma - 1.0).abs() < 0.1, "estimated {est} px");
        assert!(
            (noise.scale() - 0.1).abs() < 0.01,
            "scale {}",
            noise.scale()
        );
    }

    /// Too few residuals leave the configured figure; the scale stays within its range.
    #[test]
    fn the_scale_is_bounded_and_waits_for_residuals() {
        let mut noise = PixelNoise::new(0.5);
        noise.observe([0.0; MIN_RESIDUALS - 1]);
        assert_eq!(noise.sigma_px(), None);
        assert_eq!(noise.scale(), 1.0);
        noise.observe([0.0; REFRESH]);
        assert_eq!(noise.scale(), SCALE_RANGE.0);
        noise.observe([1e3; WINDOW]);
        assert_eq!(noise.scale(), SCALE_RANGE.1);
    }
}
