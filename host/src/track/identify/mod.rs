//! LED identification and interference rejection in 3D (FIRES thesis, §4.1.2 and Fig. 4.4: the
//! LEDs are told apart by comparing the triangulated points' pairwise distances with the pen's six
//! physical distances, and points that match none are interference).
//!
//! The thesis's distance test, made robust: the candidates are the triangulated, ray-gap-gated
//! left/right pairs ([`crate::stereo::correspond`]). Every candidate pair whose distance matches
//! one of the six physical distances `|l_a - l_b|` (within `tolerance` < 5 mm for the 70/40/50
//! pen) seeds two oriented hypotheses (a at one end, b at the other); each hypothesis is extended
//! by looking for the remaining LEDs at their predicted positions along the line, using only
//! candidates with distinct left and right blobs, and is kept only if *all* its pairwise distances
//! match. Hypotheses with three or more LEDs must be collinear (max distance to the least-squares
//! line) and with four LEDs must reproduce the pen's cross-ratio.
//!
//! The largest hypothesis wins. When several different labellings of that size survive (always
//! the case with two LEDs: the mirrored labelling has the same distance), the prior pen direction
//! (from fusion) and temporal continuity (previous LED positions) must leave exactly one otherwise the frame is refused with [`IdentifyError::Ambiguous`]: no tip
//! rather than a wrong one. With the images, the labelled pen must also explain the blobs near its
//! predicted image. Candidates that share no blob with the chosen LEDs are
//! reported as interference.

mod config;
mod disambiguate;
mod hypotheses;
mod image_checks;
#[cfg(test)]
mod tests;

pub use config::{IdentifyConfig, IdentifyPrior, RangeNoise};

use super::line_fit::labelled_direction;
use super::pen::{PenGeometry, LED_COUNT};
use crate::stereo::Candidate;
use image_checks::ImageGeometry;
use nalgebra::Vector3;
use thiserror::Error;

/// What decided between competing labellings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Resolution {
    /// Only one labelling is geometrically consistent.
    Geometry,
    /// The prior direction (or continuity) eliminated the alternatives.
    Prior,
}

/// A labelled frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Identification {
    /// Candidate index assigned to each LED (index 0 = LED 1).
    pub assignment: [Option<usize>; LED_COUNT],
    /// The labelled 3D points.
    pub points: [Option<Vector3<f64>>; LED_COUNT],
    /// RMS mismatch between measured and physical distances, metres.
    pub distance_rms: f64,
    /// Confidence in (0, 1]: grows with the LED count, falls with the distance mismatch.
    pub confidence: f64,
    /// How the labelling was decided.
    pub resolution: Resolution,
    /// Number of candidates sharing no blob with the labelled LEDs (interference points).
    pub interference: usize,
}

impl Identification {
    /// Number of identified LEDs.
    pub fn count(&self) -> usize {
        self.assignment.iter().flatten().count()
    }

    /// Bit mask of identified LEDs (bit i = LED i+1).
    pub fn mask(&self) -> u8 {
        self.assignment
            .iter()
            .enumerate()
            .fold(0, |m, (i, a)| if a.is_some() { m | (1 << i) } else { m })
    }
}

/// Why a frame could not be labelled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum IdentifyError {
    /// Fewer than two candidates.
    #[error("fewer than two 3D candidates")]
    TooFewCandidates,
    /// No candidate pair matches a physical LED distance.
    #[error("no pair of points matches a physical LED distance")]
    NoConsistentSet,
    /// Several labellings fit and the priors cannot decide between them.
    #[error("ambiguous labelling")]
    Ambiguous,
    /// An unexplained blob lies on the labelled pen's image line away from every predicted LED.
    #[error("labelling contradicted by an image blob")]
    ContradictedByImage,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Hypothesis {
    assignment: [Option<usize>; LED_COUNT],
    size: usize,
    distance_rms: f64,
    /// The mirrored labelling of the same points is also consistent within the noise.
    needs_prior: bool,
    /// Three LEDs whose spacing ratio is also that of another LED triple ("twin"): only the
    /// absolute scale separates them, and timing/motion errors of unsynchronised cameras can
    /// stretch it, so the labelling is accepted only when continuity confirms it.
    needs_continuity: bool,
    /// Consistent within the wide (ambiguity) band but either not within the acceptance band or
    /// another same-direction labelling of its points fits as well: never accepted, yet it still
    /// counts as a rival of conflicting labellings.
    refused: bool,
}

/// LED identifier with its precomputed pen distances (reusable, no per-frame allocation after warm-up).
#[derive(Debug, Clone)]
pub struct Identifier {
    pen: PenGeometry,
    config: IdentifyConfig,
    cross_ratio: f64,
    noise: Option<RangeNoise>,
    geometry: Option<ImageGeometry>,
    hypotheses: Vec<Hypothesis>,
    /// The twin scale bound of the frame being identified.
    twin_scale: f64,
}

impl Identifier {
    /// Builds an identifier; fails if the pen's distances are not separable at this tolerance.
    pub fn new(pen: PenGeometry, config: IdentifyConfig) -> Result<Self, super::pen::PenError> {
        pen.validate(config.tolerance)?;
        Ok(Self {
            pen,
            config,
            cross_ratio: pen.cross_ratio(),
            noise: None,
            geometry: None,
            hypotheses: Vec::with_capacity(64),
            twin_scale: config.twin_scale_max,
        })
    }

    /// Enables the range-dependent ambiguity check for two-LED labellings.
    pub fn with_noise(mut self, noise: RangeNoise) -> Self {
        self.noise = Some(noise);
        self
    }

    /// Enables the range-dependent checks and the image-evidence check of
    /// [`Self::identify_with_images`] for this rig with centroid noise `pixel_sigma` (pixels).
    pub fn with_rig(mut self, rig: &crate::stereo::StereoRig, pixel_sigma: f64) -> Self {
        self.noise = Some(RangeNoise::from_rig(rig, pixel_sigma));
        self.geometry = Some(ImageGeometry {
            r: rig.r_right_from_left,
            t: rig.t_right_from_left,
            focal: [rig.left.focal_px(), rig.right.focal_px()],
        });
        self
    }

    /// The configuration in use.
    pub fn config(&self) -> &IdentifyConfig {
        &self.config
    }

    /// Labels the candidates, or refuses.
    pub fn identify(
        &mut self,
        candidates: &[Candidate],
        prior: &IdentifyPrior,
    ) -> Result<Identification, IdentifyError> {
        let cands = &candidates[..candidates.len().min(self.config.max_candidates)];
        if cands.len() < 2 {
            return Err(IdentifyError::TooFewCandidates);
        }
        self.twin_scale = prior
            .scale_error_max
            .filter(|s| s.is_finite() && *s >= 1.0)
            .map_or(self.config.twin_scale_max, |s| {
                s.min(self.config.twin_scale_max)
            });
        self.collect_hypotheses(cands);
        if let Some(dir) = prior.direction {
            // Labellings that disagree with the fused direction (beyond its noise and theirs)
            // are never accepted: this removes mirrored labellings and most ghost pens.
            let keep: Vec<bool> = self
                .hypotheses
                .iter()
                .map(|h| {
                    let v = labelled_direction(&labelled_points(cands, &h.assignment));
                    v.is_some_and(|v| {
                        v.dot(&dir) >= self.prior_cos(cands, &h.assignment, prior) * dir.norm()
                    })
                })
                .collect();
            let mut it = keep.iter();
            self.hypotheses
                .retain(|_| it.next().copied().unwrap_or(false));
        }
        let best_size = self
            .hypotheses
            .iter()
            .filter(|h| !h.refused)
            .map(|h| h.size)
            .max()
            .ok_or(IdentifyError::NoConsistentSet)?;
        let (chosen, resolution) = self.choose(cands, best_size, prior)?;
        if chosen.needs_continuity && !self.continuity_confirms(cands, &chosen, prior) {
            return Err(IdentifyError::Ambiguous);
        }
        if self.has_conflicting_rival(cands, &chosen, prior) {
            return Err(IdentifyError::Ambiguous);
        }
        if self.switches_identity(cands, &chosen, prior) {
            return Err(IdentifyError::Ambiguous);
        }
        Ok(self.finish(cands, chosen, resolution))
    }

    fn finish(&self, cands: &[Candidate], h: Hypothesis, resolution: Resolution) -> Identification {
        let used: Vec<&Candidate> = h.assignment.iter().flatten().map(|&k| &cands[k]).collect();
        let interference = cands
            .iter()
            .filter(|c| !used.iter().any(|u| shares_blob(u, c)))
            .count();
        let fit = (-(h.distance_rms / self.config.tolerance).powi(2)).exp();
        let coverage = (h.size as f64 / LED_COUNT as f64).sqrt();
        let penalty = if resolution == Resolution::Prior {
            0.8
        } else {
            1.0
        };
        Identification {
            assignment: h.assignment,
            points: labelled_points(cands, &h.assignment),
            distance_rms: h.distance_rms,
            confidence: fit * coverage * penalty,
            resolution,
            interference,
        }
    }
}

fn finite(c: &Candidate) -> bool {
    c.point
        .iter()
        .chain(c.covariance.iter())
        .all(|v| v.is_finite())
}

fn shares_blob(a: &Candidate, b: &Candidate) -> bool {
    a.left == b.left || a.right == b.right
}

fn labelled_points(
    cands: &[Candidate],
    assignment: &[Option<usize>; LED_COUNT],
) -> [Option<Vector3<f64>>; LED_COUNT] {
    assignment.map(|a| a.map(|k| cands[k].point))
}
