//! Identification tolerances ([`IdentifyConfig`]), the rig's triangulation noise model
//! ([`RangeNoise`]) and the knowledge carried from earlier frames ([`IdentifyPrior`]).

use crate::track::pen::LED_COUNT;
use nalgebra::Vector3;

/// Identification tolerances.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct IdentifyConfig {
    /// Maximum mismatch between a measured and a physical distance when no noise information is
    /// available, metres (< half the smallest gap between two physical distances); with candidate
    /// covariances or a rig noise model the band is `max(tolerance_floor, k σ_d)` instead.
    pub tolerance: f64,
    /// Maximum distance of an LED from the least-squares axis without noise information, metres.
    pub max_line_residual: f64,
    /// Smallest collinearity limit when covariances are known, metres.
    pub max_line_residual_floor: f64,
    /// Maximum relative deviation of the 4-LED cross-ratio from the pen's.
    pub cross_ratio_tolerance: f64,
    /// A labelling agrees with the prior direction when the cosine of the angle exceeds this.
    pub prior_min_cos: f64,
    /// Expected error of the direction prior (fused direction), radians.
    pub prior_sigma: f64,
    /// A labelling agrees with the previous frame when every LED moved less than this, metres.
    pub continuity_max_jump: f64,
    /// Candidates beyond this count are ignored (bounds the search).
    pub max_candidates: usize,
    /// A labelling is refused (or needs the direction prior, if only its mirror image fits) when
    /// another labelling of the same points fits within this many standard deviations of the
    /// rig's [`RangeNoise`].
    pub ambiguity_sigmas: f64,
    /// A labelling is accepted only if every distance is within this many standard deviations,
    /// three or more LEDs after a common scale within the pair's time-offset bound
    /// ([`IdentifyPrior::scale_error_max`]) (rivals are searched with the wider `ambiguity_sigmas`).
    pub accept_sigmas: f64,
    /// Smallest distance band when the noise is known, metres (model and calibration errors).
    pub tolerance_floor: f64,
    /// Maximum relative deviation of the 4-LED image cross-ratio from the pen's.
    pub image_cross_ratio_tolerance: f64,
    /// Image-evidence check: an unused blob within this distance of the predicted pen line
    /// (pixels) must be near a predicted LED.
    pub image_line_px: f64,
    /// Image-evidence check: radius around a predicted LED at the labelled LEDs (pixels); it grows
    /// with the extrapolation distance.
    pub image_match_px: f64,
    /// Largest common scale error (either way) under which a three-LED labelling's "twin" triple
    /// is still considered a rival; such labellings need continuity.
    pub twin_scale_max: f64,
    /// Two-LED labellings are refused when a labelled blob pairs with another blob with an
    /// epipolar distance smaller by more than this, pixels.
    pub competitor_margin_px: f64,
}

impl Default for IdentifyConfig {
    fn default() -> Self {
        Self {
            tolerance: 0.0045,
            max_line_residual: 0.004,
            max_line_residual_floor: 0.0015,
            cross_ratio_tolerance: 0.05,
            prior_min_cos: 0.9,
            prior_sigma: 0.035,
            continuity_max_jump: 0.03,
            max_candidates: 24,
            ambiguity_sigmas: 4.0,
            competitor_margin_px: 1.0,
            twin_scale_max: 2.0,
            image_line_px: 2.5,
            image_cross_ratio_tolerance: 0.1,
            accept_sigmas: 3.0,
            tolerance_floor: 0.0015,
            image_match_px: 3.0,
        }
    }
}

/// Expected triangulation noise of the rig, used to judge whether a measured distance is
/// unambiguous: depth noise `σ_z = k_depth Z^2` (from disparity, `k_depth = √2 σ_px / (f B)`) and
/// lateral noise `σ_xy = k_lateral Z` (`k_lateral = σ_px / f`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RangeNoise {
    /// Depth noise per square metre of depth.
    pub k_depth: f64,
    /// Lateral noise per metre of depth.
    pub k_lateral: f64,
}

impl RangeNoise {
    /// The noise model of a rig with centroid noise `pixel_sigma` (pixels).
    pub fn from_rig(rig: &crate::stereo::StereoRig, pixel_sigma: f64) -> Self {
        let f = 0.5 * (rig.left.focal_px() + rig.right.focal_px());
        // Disparity noise is the difference of two centroid errors: sqrt(2) σ_px.
        let k_depth = std::f64::consts::SQRT_2 * pixel_sigma / (f * rig.baseline().max(1e-6));
        Self {
            k_depth,
            k_lateral: pixel_sigma / f,
        }
    }

    /// Standard deviation (radians) of the direction from `p` to `q`.
    pub fn direction_sigma(&self, p: &Vector3<f64>, q: &Vector3<f64>) -> f64 {
        let d = (q - p).norm();
        let Some(u) = (q - p).try_normalize(1e-12) else {
            return std::f64::consts::PI;
        };
        let var = |x: &Vector3<f64>| {
            let z = x.norm();
            let c = x.try_normalize(1e-12).map_or(0.0, |r| u.dot(&r).powi(2));
            (self.k_depth * z * z).powi(2) * (1.0 - c) + (self.k_lateral * z).powi(2) * (1.0 + c)
        };
        (var(p) + var(q)).sqrt() / d
    }

    /// Standard deviation of the distance between two triangulated points (left camera at origin).
    pub fn distance_sigma(&self, p: &Vector3<f64>, q: &Vector3<f64>) -> f64 {
        let Some(u) = (q - p).try_normalize(1e-12) else {
            return 0.0;
        };
        let var = |x: &Vector3<f64>| {
            let z = x.norm();
            let c = x.try_normalize(1e-12).map_or(1.0, |r| u.dot(&r).powi(2));
            (self.k_depth * z * z).powi(2) * c + (self.k_lateral * z).powi(2) * (1.0 - c)
        };
        (var(p) + var(q)).sqrt()
    }
}

/// Knowledge carried from earlier frames to break ties.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct IdentifyPrior {
    /// Expected unit pen direction (towards the tip), e.g. the fused orientation.
    pub direction: Option<Vector3<f64>>,
    /// LED positions labelled in the previous frame (if recent).
    pub previous: [Option<Vector3<f64>>; LED_COUNT],
    /// Expected error of `direction`, radians (`None`: [`IdentifyConfig::prior_sigma`]); an
    /// orientation filter without recent vision is less certain than one corrected a frame ago.
    pub direction_sigma: Option<f64>,
    /// Largest common scale error this frame's triangulation can have (from the exposure time
    /// difference of its two images), at most [`IdentifyConfig::twin_scale_max`] (`None`: that).
    pub scale_error_max: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stereo::StereoRig;

    /// On the optical axis at depth z the distance along the axis has the depth noise
    /// `k_depth z^2` per point and across it the lateral noise `k_lateral z`.
    #[test]
    fn range_noise_follows_the_disparity_model() {
        let rig = StereoRig::parallel(1024, 768, 45f64.to_radians(), 0.25);
        let n = RangeNoise::from_rig(&rig, 0.5);
        let f = rig.left.focal_px();
        assert!((n.k_lateral - 0.5 / f).abs() < 1e-15);
        assert!((n.k_depth - std::f64::consts::SQRT_2 * 0.5 / (f * 0.25)).abs() < 1e-15);
        let z = 0.8;
        let (p, q) = (Vector3::new(0.0, 0.0, z), Vector3::new(0.0, 0.0, z + 1e-3));
        let along = n.distance_sigma(&p, &q);
        let expected =
            ((n.k_depth * z * z).powi(2) + (n.k_depth * (z + 1e-3).powi(2)).powi(2)).sqrt();
        assert!((along - expected).abs() < 1e-12 * expected);
        let across = n.distance_sigma(&p, &Vector3::new(0.07, 0.0, z));
        assert!(across < along && across > 0.0);
        assert_eq!(n.distance_sigma(&p, &p), 0.0);
        assert_eq!(n.direction_sigma(&p, &p), std::f64::consts::PI);
    }

    #[test]
    fn defaults_separate_the_thesis_pen() {
        let c = IdentifyConfig::default();
        crate::track::pen::PenGeometry::thesis()
            .validate(c.tolerance)
            .expect("the default tolerance identifies the thesis pen");
        assert!(c.accept_sigmas <= c.ambiguity_sigmas);
    }
}
