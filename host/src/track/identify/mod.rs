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
    /// LEDs without a stereo candidate that were still found where the labelled pen puts them:
    /// a blob of their own in one camera, and in the other inside one blob with a neighbour's
    /// spot (the tracker's merged-spot completion) or, for a pen-line labelling, no blob at all
    /// (hidden by the hand or too dim there; its spot was fitted) (bit i = LED i+1).
    pub completed: u8,
    /// The LEDs were located along the pen's image line of a camera in which their spots merged
    /// (the tracker's pen-line stereo): that camera's blob of an LED may be a merge covering it, so
    /// the checks that read an LED's own image there (merges, clock offset) leave it out.
    pub from_pen_line: bool,
    /// The camera about one of whose compact blobs' rays the pen-line labelling was found (the
    /// pen pointing at it): the spots there lie pixels apart, so no LED's image in it is vouched
    /// for, neither in the output's labels nor in those that give the next frames' velocities.
    pub from_pen_ray: Option<crate::stereo::CameraId>,
}

impl Identification {
    /// Number of identified LEDs.
    pub fn count(&self) -> usize {
        self.assignment.iter().flatten().count()
    }

    /// Number of LEDs the labelling located: identified plus completed.
    pub fn located(&self) -> usize {
        self.count() + self.completed.count_ones() as usize
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

/// Which identification test refused the last frame (finer than [`IdentifyError`]; what
/// `report.json` → `vision_refusals` counts, docs/report.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum RefusedBy {
    /// Fewer than two candidates.
    TooFewCandidates,
    /// No labelling fits the physical distances (and the line, the cross ratio) within the bands.
    Distances,
    /// Labellings fit the distances but all disagree with the fused direction.
    DirectionPrior,
    /// The only labelling is also consistent mirrored and no prior resolves it.
    Mirror,
    /// Several labellings fit and there is no prior at all.
    NoPrior,
    /// Several labellings fit and more than one agrees with the priors.
    SeveralAgree,
    /// Several labellings fit and none agrees with the priors.
    NoneAgrees,
    /// A three-LED labelling with a scaled twin that continuity does not confirm.
    Twin,
    /// A conflicting rival labelling agrees with the priors as well.
    Rival,
    /// A labelled LED sits where another LED was in the previous frame (trading places).
    TradingPlaces,
    /// The labelled pen does not explain the image blobs (image line, cross ratio in the image).
    ImageEvidence,
}

impl RefusedBy {
    /// The coarse error of this refusal.
    pub fn error(self) -> IdentifyError {
        match self {
            RefusedBy::TooFewCandidates => IdentifyError::TooFewCandidates,
            RefusedBy::Distances | RefusedBy::DirectionPrior => IdentifyError::NoConsistentSet,
            RefusedBy::ImageEvidence => IdentifyError::ContradictedByImage,
            _ => IdentifyError::Ambiguous,
        }
    }
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
    /// The test that refused the last frame (None when it was labelled).
    refused_by: Option<RefusedBy>,
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
            refused_by: None,
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

    /// The test that refused the last frame given to [`Self::identify`] or
    /// [`Self::identify_with_images`] (None when it was labelled).
    pub fn refused_by(&self) -> Option<RefusedBy> {
        self.refused_by
    }

    /// Labels the candidates, or refuses.
    pub fn identify(
        &mut self,
        candidates: &[Candidate],
        prior: &IdentifyPrior,
    ) -> Result<Identification, IdentifyError> {
        let result = self.identify_inner(candidates, prior);
        self.refused_by = result.as_ref().err().copied();
        result.map_err(RefusedBy::error)
    }

    fn identify_inner(
        &mut self,
        candidates: &[Candidate],
        prior: &IdentifyPrior,
    ) -> Result<Identification, RefusedBy> {
        let cands = &candidates[..candidates.len().min(self.config.max_candidates)];
        if cands.len() < 2 {
            return Err(RefusedBy::TooFewCandidates);
        }
        self.twin_scale = prior
            .scale_error_max
            .filter(|s| s.is_finite() && *s >= 1.0)
            .map_or(self.config.twin_scale_max, |s| {
                s.min(self.config.twin_scale_max)
            });
        self.collect_hypotheses(cands);
        let fitting = self.hypotheses.iter().any(|h| !h.refused);
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
            .ok_or(if fitting {
                RefusedBy::DirectionPrior
            } else {
                RefusedBy::Distances
            })?;
        let (chosen, resolution) = self.choose(cands, best_size, prior)?;
        if chosen.needs_continuity && !self.continuity_confirms(cands, &chosen, prior) {
            return Err(RefusedBy::Twin);
        }
        if self.has_conflicting_rival(cands, &chosen, prior) {
            return Err(RefusedBy::Rival);
        }
        if self.switches_identity(cands, &chosen, prior) {
            return Err(RefusedBy::TradingPlaces);
        }
        Ok(self.finish(cands, chosen, resolution))
    }

    fn finish(&self, cands: &[Candidate], h: Hypothesis, resolution: Resolution) -> Identification {
        Identification::graded(
            cands,
            h.assignment,
            h.distance_rms,
            resolution,
            self.config.tolerance,
        )
    }
}

impl Identification {
    /// The labelling `assignment` of `cands`, decided by `resolution`, graded as the identifier
    /// grades its own: the candidates sharing no blob with it are interference, and the
    /// confidence falls with the distance mismatch over the identification `tolerance` (metres),
    /// grows with the LED count, and is discounted for a prior's decision.
    pub(crate) fn graded(
        cands: &[Candidate],
        assignment: [Option<usize>; LED_COUNT],
        distance_rms: f64,
        resolution: Resolution,
        tolerance: f64,
    ) -> Self {
        let used: Vec<&Candidate> = assignment.iter().flatten().map(|&k| &cands[k]).collect();
        let interference = cands
            .iter()
            .filter(|c| !used.iter().any(|u| shares_blob(u, c)))
            .count();
        let fit = (-(distance_rms / tolerance).powi(2)).exp();
        let coverage = (used.len() as f64 / LED_COUNT as f64).sqrt();
        let penalty = if resolution == Resolution::Prior {
            0.8
        } else {
            1.0
        };
        Identification {
            assignment,
            points: labelled_points(cands, &assignment),
            distance_rms,
            confidence: fit * coverage * penalty,
            resolution,
            interference,
            completed: 0,
            from_pen_line: false,
            from_pen_ray: None,
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
