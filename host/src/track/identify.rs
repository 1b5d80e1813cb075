//! LED identification and interference rejection in 3D (thesis §4.1.2, digest §2.2).
//!
//! Implements the digest's "recommended robust algorithm": the candidates are the triangulated,
//! ray-gap-gated left/right pairs ([`crate::stereo::correspond`]). Every candidate pair whose
//! distance matches one of the six physical distances `|l_a - l_b|` (within `tolerance` < 5 mm for
//! the 70/40/50 pen) seeds two oriented hypotheses (a at one end, b at the other); each hypothesis
//! is extended by looking for the remaining LEDs at their predicted positions along the line, using
//! only candidates with distinct left and right blobs, and is kept only if *all* its pairwise
//! distances match. Hypotheses with three or more LEDs must be collinear (max distance to the
//! least-squares line) and with four LEDs must reproduce the pen's cross-ratio.
//!
//! The largest hypothesis wins. When several different labellings of that size survive (always
//! the case with two LEDs: the mirrored labelling has the same distance), the prior pen direction
//! (from fusion) and temporal continuity (previous LED positions) must leave exactly one; otherwise
//! the frame is refused with [`IdentifyError::Ambiguous`]: no tip rather than a wrong one.
//! Candidates that share no blob with the chosen LEDs are reported as interference.

use super::pen::{cross_ratio_1d, PenGeometry, LED_COUNT};
use crate::stereo::Candidate;
use nalgebra::Vector3;
use thiserror::Error;

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
    /// A labelling is accepted only if every distance is within this many standard deviations
    /// (rivals are searched with the wider `ambiguity_sigmas`).
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

/// Rig terms for projecting predicted LEDs into normalised image coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
struct ImageGeometry {
    r: nalgebra::Matrix3<f64>,
    t: Vector3<f64>,
    focal: [f64; 2],
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

    /// As [`Self::identify`], then checks the labelling against all blobs of both images
    /// (undistorted normalised coordinates, indexed as in the candidates): the labelled pen predicts
    /// where all four LEDs project; an unused blob lying on the predicted pen segment but away from
    /// every predicted LED contradicts the labelling. This exposes "ghost pens" made of wrong
    /// left/right pairings of collinear LEDs (which share epipolar lines when the pen is parallel
    /// to the baseline).
    pub fn identify_with_images(
        &mut self,
        candidates: &[Candidate],
        prior: &IdentifyPrior,
        left: &[[f64; 2]],
        right: &[[f64; 2]],
    ) -> Result<Identification, IdentifyError> {
        let id = self.identify(candidates, prior)?;
        if self.image_consistent(candidates, &id, [left, right]) {
            Ok(id)
        } else {
            Err(IdentifyError::ContradictedByImage)
        }
    }

    /// With four labelled LEDs, the cross-ratio of their blobs along the image line must match
    /// the pen's (a projective invariant, anchors-tracking.md §8.3); checked when the pen spans at
    /// least 40 px in that image.
    #[allow(clippy::too_many_arguments)]
    fn image_cross_ratio_ok(
        &self,
        cands: &[Candidate],
        id: &Identification,
        cam: usize,
        blobs: &[[f64; 2]],
        origin: &[f64; 2],
        d: &[f64; 2],
        span_px: f64,
    ) -> bool {
        if id.count() < LED_COUNT || span_px < 40.0 {
            return true;
        }
        let mut s = [0.0; LED_COUNT];
        for (i, k) in id.assignment.iter().enumerate() {
            let Some(k) = k else { return true };
            let idx = if cam == 0 {
                cands[*k].left
            } else {
                cands[*k].right
            };
            let Some(b) = blobs.get(idx) else { return true };
            s[i] = (b[0] - origin[0]) * d[0] + (b[1] - origin[1]) * d[1];
        }
        let cr = cross_ratio_1d(s);
        cr.is_finite()
            && ((cr - self.cross_ratio) / self.cross_ratio).abs()
                <= self.config.image_cross_ratio_tolerance
    }

    fn image_consistent(
        &self,
        cands: &[Candidate],
        id: &Identification,
        blobs: [&[[f64; 2]]; 2],
    ) -> bool {
        let Some(g) = &self.geometry else { return true };
        let l = &self.pen.led_offsets;
        let n = id.count() as f64;
        let Some(centroid) = id
            .points
            .iter()
            .flatten()
            .copied()
            .reduce(|a, b| a + b)
            .map(|s| s / n)
        else {
            return true;
        };
        let Some(v) = super::tip::principal_axis(&id.points, &centroid) else {
            return true;
        };
        let v = if labelled_direction(&id.points).is_some_and(|d| d.dot(&v) < 0.0) {
            -v
        } else {
            v
        };
        let labels = || (0..LED_COUNT).filter(|&i| id.assignment[i].is_some());
        let c_h = labels().map(|i| l[i]).sum::<f64>() / n;
        let spread = labels().map(|i| l[i]).fold(f64::NEG_INFINITY, f64::max)
            - labels().map(|i| l[i]).fold(f64::INFINITY, f64::min);
        let predicted: [Vector3<f64>; LED_COUNT] =
            std::array::from_fn(|i| centroid + v * (c_h - l[i]));
        for (cam, blob_list) in blobs.iter().enumerate() {
            let used = |b: usize| {
                id.assignment.iter().flatten().any(|&k| {
                    if cam == 0 {
                        cands[k].left == b
                    } else {
                        cands[k].right == b
                    }
                })
            };
            let proj: Option<Vec<[f64; 2]>> = predicted
                .iter()
                .map(|p| {
                    let q = if cam == 0 { *p } else { g.r * p + g.t };
                    (q.z > 1e-6).then(|| [q.x / q.z, q.y / q.z])
                })
                .collect();
            let Some(m) = proj else { continue };
            let f = g.focal[cam];
            let d = [m[3][0] - m[0][0], m[3][1] - m[0][1]];
            let len = d[0].hypot(d[1]);
            if len * f < 3.0 {
                continue;
            }
            if !self.image_cross_ratio_ok(cands, id, cam, blob_list, &m[0], &d, len * f) {
                return false;
            }
            for (b, blob) in blob_list.iter().enumerate() {
                if used(b) || !blob.iter().all(|v| v.is_finite()) {
                    continue;
                }
                let rel = [blob[0] - m[0][0], blob[1] - m[0][1]];
                let along = (rel[0] * d[0] + rel[1] * d[1]) / (len * len);
                let perp_px = (rel[0] * d[1] - rel[1] * d[0]).abs() / len * f;
                if perp_px > self.config.image_line_px || !(-0.6..=1.6).contains(&along) {
                    continue;
                }
                let near_led = (0..LED_COUNT).any(|i| {
                    let radius =
                        self.config.image_match_px * (1.0 + (l[i] - c_h).abs() / spread.max(1e-6));
                    (blob[0] - m[i][0]).hypot(blob[1] - m[i][1]) * f <= radius
                });
                if !near_led {
                    return false;
                }
            }
        }
        true
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

    fn collect_hypotheses(&mut self, cands: &[Candidate]) {
        self.hypotheses.clear();
        for i in 0..cands.len() {
            for j in i + 1..cands.len() {
                if shares_blob(&cands[i], &cands[j]) || !finite(&cands[i]) || !finite(&cands[j]) {
                    continue;
                }
                let d = (cands[i].point - cands[j].point).norm();
                for (a, b) in PenGeometry::pairs() {
                    if (d - self.pen.distance(a, b)).abs() > self.band(&cands[i], &cands[j]) {
                        continue;
                    }
                    for (x, y) in [(i, j), (j, i)] {
                        if let Some(h) = self.extend(cands, a, x, b, y) {
                            if !self.hypotheses.iter().any(|o| o.assignment == h.assignment) {
                                self.hypotheses.push(h);
                            }
                        }
                    }
                }
            }
        }
    }

    /// Seeds LED `a` at candidate `ia`, LED `b` at `ib`, then adds the other LEDs near their
    /// predicted positions; returns the hypothesis if all checks pass.
    fn extend(
        &self,
        cands: &[Candidate],
        a: usize,
        ia: usize,
        b: usize,
        ib: usize,
    ) -> Option<Hypothesis> {
        let l = &self.pen.led_offsets;
        let (pa, pb) = (cands[ia].point, cands[ib].point);
        let per_metre = (pb - pa) / (l[b] - l[a]);
        let mut assignment = [None; LED_COUNT];
        assignment[a] = Some(ia);
        assignment[b] = Some(ib);
        for c in (0..LED_COUNT).filter(|&c| c != a && c != b) {
            let predicted = pa + per_metre * (l[c] - l[a]);
            let gate = self.band(&cands[ia], &cands[ib])
                * (1.0 + 2.0 * ((l[c] - l[a]) / (l[b] - l[a])).abs());
            let mut best: Option<(usize, f64)> = None;
            for (k, cand) in cands.iter().enumerate() {
                if !finite(cand)
                    || assignment
                        .iter()
                        .flatten()
                        .any(|&u| u == k || shares_blob(&cands[u], cand))
                {
                    continue;
                }
                let e = (cand.point - predicted).norm();
                if e <= gate && best.is_none_or(|(_, be)| e < be) {
                    best = Some((k, e));
                }
            }
            if let Some((k, _)) = best {
                if self.distances_match(cands, &assignment, c, k) {
                    // Keep the extension only if the larger set still passes every check, so a
                    // near-miss point cannot destroy a valid smaller labelling.
                    let mut extended = assignment;
                    extended[c] = Some(k);
                    if self.check(cands, extended).is_some() {
                        assignment = extended;
                    }
                }
            }
        }
        self.check(cands, assignment)
    }

    fn distances_match(
        &self,
        cands: &[Candidate],
        assignment: &[Option<usize>; LED_COUNT],
        c: usize,
        k: usize,
    ) -> bool {
        assignment.iter().enumerate().all(|(o, idx)| match idx {
            Some(u) => {
                let (p, q) = (&cands[*u], &cands[k]);
                ((p.point - q.point).norm() - self.pen.distance(o, c)).abs() <= self.band(p, q)
            }
            None => true,
        })
    }

    fn check(
        &self,
        cands: &[Candidate],
        assignment: [Option<usize>; LED_COUNT],
    ) -> Option<Hypothesis> {
        let pts = labelled_points(cands, &assignment);
        let size = pts.iter().flatten().count();
        let (mut sum, mut n, mut tight) = (0.0, 0usize, true);
        for (a, b) in PenGeometry::pairs() {
            if let (Some(ka), Some(kb)) = (assignment[a], assignment[b]) {
                let e = (cands[ka].point - cands[kb].point).norm() - self.pen.distance(a, b);
                if e.abs() > self.band(&cands[ka], &cands[kb]) {
                    return None;
                }
                tight &= e.abs() <= self.band_at(&cands[ka], &cands[kb], self.config.accept_sigmas);
                sum += e * e;
                n += 1;
            }
        }
        if size == 2 && self.has_better_pairing(cands, &assignment) {
            return None;
        }
        let (shifted, mirrored) = self.plausible_alternatives(cands, &assignment);
        if size >= 3 && !self.collinear(cands, &assignment) {
            return None;
        }
        if size == 4 && !self.cross_ratio_ok(&pts) {
            return None;
        }
        let twin = size == 3 && self.has_scaled_twin(cands, &assignment);
        Some(Hypothesis {
            needs_prior: mirrored,
            needs_continuity: twin,
            refused: shifted || !tight,
            assignment,
            size,
            distance_rms: (sum / n.max(1) as f64).sqrt(),
        })
    }

    /// Ghost-pairing check for two-LED labellings: true when a blob of a labelled candidate pairs
    /// with another blob noticeably better (epipolar distance smaller by `competitor_margin_px`).
    /// With collinear LEDs, wrong left/right pairings form a shifted "ghost pen" whose distances
    /// can match by chance; a better alternative pairing of the same blob exposes it.
    fn has_better_pairing(
        &self,
        cands: &[Candidate],
        assignment: &[Option<usize>; LED_COUNT],
    ) -> bool {
        assignment.iter().flatten().any(|&k| {
            let member = &cands[k];
            cands.iter().enumerate().any(|(j, alt)| {
                j != k
                    && shares_blob(member, alt)
                    && alt.epipolar_px + self.config.competitor_margin_px < member.epipolar_px
            })
        })
    }

    /// Other labellings of the same ordered points that fit the physical distances within the
    /// noise band (`max(tolerance, ambiguity_sigmas * σ_d)` per pair, σ_d from [`RangeNoise`]):
    /// returns (a same-direction alternative exists, a mirrored alternative exists). A
    /// same-direction alternative (e.g. LEDs {1,2} vs {2,3} read off one noisy pair, or {1,2,3}
    /// vs {2,3,4}) cannot be told apart by any prior, so such labellings are refused.
    fn plausible_alternatives(
        &self,
        cands: &[Candidate],
        assignment: &[Option<usize>; LED_COUNT],
    ) -> (bool, bool) {
        let labelled: Vec<(usize, &Candidate)> = assignment
            .iter()
            .enumerate()
            .filter_map(|(i, k)| k.map(|k| (i, &cands[k])))
            .collect();
        let k = labelled.len();
        let l = &self.pen.led_offsets;
        let (mut shifted, mut mirrored) = (false, false);
        for subset in 0u8..16 {
            if subset.count_ones() as usize != k {
                continue;
            }
            let labels: Vec<usize> = (0..LED_COUNT).filter(|i| subset & (1 << i) != 0).collect();
            for reversed in [false, true] {
                let alt = |j: usize| {
                    if reversed {
                        labels[k - 1 - j]
                    } else {
                        labels[j]
                    }
                };
                if !reversed && (0..k).all(|j| alt(j) == labelled[j].0) {
                    continue;
                }
                let fits = (0..k).all(|a| {
                    (a + 1..k).all(|b| {
                        let (p, q) = (labelled[a].1, labelled[b].1);
                        ((p.point - q.point).norm() - (l[alt(a)] - l[alt(b)]).abs()).abs()
                            <= self.band(p, q)
                    })
                });
                if fits {
                    if reversed {
                        mirrored = true;
                    } else {
                        shifted = true;
                    }
                }
            }
        }
        (shifted, mirrored)
    }

    /// True when another three-LED labelling of the same ordered points (same direction) fits the
    /// measured distances up to a common scale factor within `[1 / twin_scale_max,
    /// twin_scale_max]`, each distance within the acceptance band (`accept_sigmas`). The pen's triples come in
    /// near-twins ({1,2,4} vs {2,3,4}: 70:90 vs 40:50; {1,2,3} vs {1,3,4}: 70:40 vs 110:50), so a
    /// scale error (depth error from motion between unsynchronised exposures) turns one into the
    /// other while every ratio still fits.
    fn has_scaled_twin(
        &self,
        cands: &[Candidate],
        assignment: &[Option<usize>; LED_COUNT],
    ) -> bool {
        let labelled: Vec<(usize, &Candidate)> = assignment
            .iter()
            .enumerate()
            .filter_map(|(i, k)| k.map(|k| (i, &cands[k])))
            .collect();
        if labelled.len() != 3 {
            return false;
        }
        let l = &self.pen.led_offsets;
        let pairs = [(0, 1), (1, 2), (0, 2)];
        let measured = pairs.map(|(a, b)| (labelled[a].1.point - labelled[b].1.point).norm());
        let bands = pairs
            .map(|(a, b)| self.band_at(labelled[a].1, labelled[b].1, self.config.accept_sigmas));
        let max_scale = self.twin_scale;
        (0u8..16)
            .filter(|s| s.count_ones() == 3)
            .map(|s| {
                (0..LED_COUNT)
                    .filter(|i| s & (1 << i) != 0)
                    .collect::<Vec<_>>()
            })
            .filter(|labels| (0..3).any(|j| labels[j] != labelled[j].0))
            .any(|labels| {
                let alt = pairs.map(|(a, b)| (l[labels[a]] - l[labels[b]]).abs());
                let aa: f64 = alt.iter().map(|a| a * a).sum();
                let da: f64 = alt.iter().zip(&measured).map(|(a, d)| a * d).sum();
                let scale = da / aa.max(1e-12);
                scale.is_finite()
                    && scale * max_scale >= 1.0
                    && scale <= max_scale
                    && (0..3).all(|k| (measured[k] - scale * alt[k]).abs() <= bands[k])
            })
    }

    /// True when the previous frame's LED positions confirm the labelling: at least one labelled
    /// LED was seen recently and none moved more than `continuity_max_jump`.
    fn continuity_confirms(
        &self,
        cands: &[Candidate],
        h: &Hypothesis,
        prior: &IdentifyPrior,
    ) -> bool {
        let pts = labelled_points(cands, &h.assignment);
        let mut compared = false;
        for (p, q) in pts.iter().zip(prior.previous.iter()) {
            if let (Some(p), Some(q)) = (p, q) {
                if (p - q).norm() > self.config.continuity_max_jump {
                    return false;
                }
                compared = true;
            }
        }
        compared
    }

    /// True when a labelled point lies within `continuity_max_jump` of where a *different* LED
    /// was in the previous frame (and nearer it than any other): LEDs do not trade places between
    /// frames, so the labelling contradicts continuity however well its distances fit (a depth
    /// outlier can make LEDs 2-4 fit 1-3).
    fn switches_identity(
        &self,
        cands: &[Candidate],
        h: &Hypothesis,
        prior: &IdentifyPrior,
    ) -> bool {
        let pts = labelled_points(cands, &h.assignment);
        pts.iter().enumerate().any(|(label, p)| {
            let Some(p) = p else { return false };
            let nearest = prior
                .previous
                .iter()
                .enumerate()
                .filter_map(|(k, q)| q.map(|q| (k, (p - q).norm())))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            nearest.is_some_and(|(k, d)| k != label && d < self.config.continuity_max_jump)
        })
    }

    fn cross_ratio_ok(&self, pts: &[Option<Vector3<f64>>; LED_COUNT]) -> bool {
        let (Some(p0), Some(p3)) = (pts[0], pts[3]) else {
            return false;
        };
        let axis = p3 - p0;
        let n2 = axis.norm_squared();
        if n2.is_nan() || n2 <= 0.0 {
            return false;
        }
        let s = pts.map(|p| p.map_or(0.0, |p| (p - p0).dot(&axis) / n2.sqrt()));
        let cr = cross_ratio_1d(s);
        cr.is_finite()
            && ((cr - self.cross_ratio) / self.cross_ratio).abs()
                <= self.config.cross_ratio_tolerance
    }

    /// Picks the unique hypothesis of the largest size, using the priors to break ties.
    fn choose(
        &self,
        cands: &[Candidate],
        size: usize,
        prior: &IdentifyPrior,
    ) -> Result<(Hypothesis, Resolution), IdentifyError> {
        let mut top = self
            .hypotheses
            .iter()
            .filter(|h| h.size == size && !h.refused);
        let first = *top.next().ok_or(IdentifyError::NoConsistentSet)?;
        if top.next().is_none() {
            if !first.needs_prior {
                return Ok((first, Resolution::Geometry));
            }
            let resolved =
                prior.direction.is_some() && self.agrees_with_prior(cands, &first, prior);
            return if resolved {
                Ok((first, Resolution::Prior))
            } else {
                Err(IdentifyError::Ambiguous)
            };
        }
        if prior.direction.is_none() && prior.previous.iter().all(Option::is_none) {
            return Err(IdentifyError::Ambiguous);
        }
        let mut survivor = None;
        for h in self
            .hypotheses
            .iter()
            .filter(|h| h.size == size && !h.refused)
        {
            if self.agrees_with_prior(cands, h, prior) {
                if survivor.is_some() {
                    return Err(IdentifyError::Ambiguous);
                }
                survivor = Some(*h);
            }
        }
        survivor
            .map(|h| (h, Resolution::Prior))
            .ok_or(IdentifyError::Ambiguous)
    }

    /// Collinearity: every labelled point within `max(max_line_residual_floor, ambiguity_sigmas σ⊥)`
    /// of the least-squares line, σ⊥ from the candidate's covariance perpendicular to the line
    /// (`max_line_residual` when no covariance is known).
    fn collinear(&self, cands: &[Candidate], assignment: &[Option<usize>; LED_COUNT]) -> bool {
        let pts = labelled_points(cands, assignment);
        let n = pts.iter().flatten().count() as f64;
        let centroid = pts.iter().flatten().sum::<Vector3<f64>>() / n;
        let Some(axis) = super::tip::principal_axis(&pts, &centroid) else {
            return false;
        };
        assignment.iter().flatten().all(|&k| {
            let c = &cands[k];
            let d = c.point - centroid;
            let residual = (d - axis * d.dot(&axis)).norm();
            let perp_var = c.covariance.trace() - axis.dot(&(c.covariance * axis));
            let limit = if c.covariance.trace() > 0.0 {
                (self.config.ambiguity_sigmas * perp_var.max(0.0).sqrt())
                    .max(self.config.max_line_residual_floor)
            } else {
                self.config.max_line_residual
            };
            residual <= limit
        })
    }

    /// Distance-matching band for two points: `max(tolerance, ambiguity_sigmas * σ_d)`; it grows
    /// with range when the rig noise is known, so that far-range labellings that are only
    /// consistent "by luck" meet their rivals and are refused rather than accepted wrongly.
    fn band(&self, a: &Candidate, b: &Candidate) -> f64 {
        self.band_at(a, b, self.config.ambiguity_sigmas)
    }

    /// `max(floor, sigmas * σ_d)`; the floor is `tolerance` without any noise information and
    /// `tolerance_floor` with it.
    fn band_at(&self, a: &Candidate, b: &Candidate, sigmas: f64) -> f64 {
        let sigma = self.distance_sigma(a, b);
        if sigma > 0.0 {
            (sigmas * sigma).max(self.config.tolerance_floor)
        } else {
            self.config.tolerance
        }
    }

    /// Standard deviation of the distance between two candidates: from their propagated
    /// covariances when available, else from the rig's [`RangeNoise`] model (0 without either).
    fn distance_sigma(&self, a: &Candidate, b: &Candidate) -> f64 {
        let cov = a.covariance + b.covariance;
        match ((b.point - a.point).try_normalize(1e-12), cov.trace() > 0.0) {
            (Some(u), true) => (u.dot(&(cov * u))).max(0.0).sqrt(),
            _ => self
                .noise
                .map_or(0.0, |n| n.distance_sigma(&a.point, &b.point)),
        }
    }

    /// Standard deviation (radians) of the direction between two candidates.
    fn direction_sigma(&self, a: &Candidate, b: &Candidate) -> Option<f64> {
        let cov = a.covariance + b.covariance;
        let d = b.point - a.point;
        let u = d.try_normalize(1e-12)?;
        if cov.trace() > 0.0 {
            let perp = cov.trace() - u.dot(&(cov * u));
            return Some((0.5 * perp.max(0.0)).sqrt() / d.norm());
        }
        self.noise.map(|n| n.direction_sigma(&a.point, &b.point))
    }

    /// Cosine threshold for agreeing with the direction prior: `prior_min_cos`, tightened with the
    /// rig noise to `3 σ_angle + prior_sigma` of the labelled end points (at least 3 degrees).
    fn prior_cos(
        &self,
        cands: &[Candidate],
        assignment: &[Option<usize>; LED_COUNT],
        prior: &IdentifyPrior,
    ) -> f64 {
        let (Some(p), Some(q)) = (
            assignment.iter().flatten().next(),
            assignment.iter().rev().flatten().next(),
        ) else {
            return self.config.prior_min_cos;
        };
        let Some(sigma) = self.direction_sigma(&cands[*p], &cands[*q]) else {
            return self.config.prior_min_cos;
        };
        let prior_sigma = prior
            .direction_sigma
            .filter(|s| s.is_finite() && *s >= 0.0)
            .unwrap_or(self.config.prior_sigma);
        let limit = (3.0 * sigma + prior_sigma).max(3f64.to_radians());
        limit.cos().max(self.config.prior_min_cos)
    }

    /// True when another labelling at least as large, not excluded by the priors, uses one of the
    /// chosen blobs in a different pairing or gives a chosen candidate a different label
    /// (including labellings refused as ambiguous): the frame is then not labelled with confidence.
    fn has_conflicting_rival(
        &self,
        cands: &[Candidate],
        chosen: &Hypothesis,
        prior: &IdentifyPrior,
    ) -> bool {
        let has_prior = prior.direction.is_some() || prior.previous.iter().any(Option::is_some);
        self.hypotheses.iter().any(|h| {
            h.assignment != chosen.assignment
                && h.size >= chosen.size
                && conflicts(cands, chosen, h)
                && (!has_prior || self.agrees_with_prior(cands, h, prior))
        })
    }

    fn agrees_with_prior(
        &self,
        cands: &[Candidate],
        h: &Hypothesis,
        prior: &IdentifyPrior,
    ) -> bool {
        let pts = labelled_points(cands, &h.assignment);
        if let Some(dir) = prior.direction {
            let Some(v) = labelled_direction(&pts) else {
                return false;
            };
            if v.dot(&dir) < self.prior_cos(cands, &h.assignment, prior) * dir.norm() {
                return false;
            }
        }
        let mut compared = false;
        for (p, q) in pts.iter().zip(prior.previous.iter()) {
            if let (Some(p), Some(q)) = (p, q) {
                compared = true;
                if (p - q).norm() > self.config.continuity_max_jump {
                    return false;
                }
            }
        }
        compared || prior.direction.is_some()
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

/// Two labellings conflict when they give a candidate different labels or pair a blob differently.
fn conflicts(cands: &[Candidate], a: &Hypothesis, b: &Hypothesis) -> bool {
    a.assignment.iter().enumerate().any(|(la, ka)| {
        let Some(ka) = ka else { return false };
        b.assignment.iter().enumerate().any(|(lb, kb)| match kb {
            Some(kb) if kb == ka => la != lb,
            Some(kb) => shares_blob(&cands[*ka], &cands[*kb]),
            None => false,
        })
    })
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

/// Unit direction from the highest-numbered labelled LED to the lowest (towards the tip).
pub fn labelled_direction(pts: &[Option<Vector3<f64>>; LED_COUNT]) -> Option<Vector3<f64>> {
    let front = pts.iter().flatten().next()?;
    let back = pts.iter().rev().flatten().next()?;
    (front - back).try_normalize(1e-12)
}

/// Maximum distance of the labelled points from their least-squares line (0 for two points).
pub fn line_residual(pts: &[Option<Vector3<f64>>; LED_COUNT]) -> f64 {
    let n = pts.iter().flatten().count();
    if n < 3 {
        return 0.0;
    }
    let centroid = pts.iter().flatten().sum::<Vector3<f64>>() / n as f64;
    let Some(axis) = super::tip::principal_axis(pts, &centroid) else {
        return f64::INFINITY;
    };
    pts.iter()
        .flatten()
        .map(|p| {
            let d = p - centroid;
            (d - axis * d.dot(&axis)).norm()
        })
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::synth::{PenPose, SplitMix64};

    fn candidates(points: &[Vector3<f64>]) -> Vec<Candidate> {
        points
            .iter()
            .enumerate()
            .map(|(i, p)| Candidate::at(i, i, *p))
            .collect()
    }

    /// Scene: visible LEDs (by mask) + spurious points, with per-point 3D noise; returns the
    /// candidates and, for each candidate, its true LED (or None for interference).
    fn scene(
        rng: &mut SplitMix64,
        mask: u8,
        spurious: usize,
        noise: f64,
    ) -> (Vec<Candidate>, Vec<Option<usize>>, PenPose) {
        let pen = PenGeometry::thesis();
        let pose = PenPose::random(rng, 0.4, 1.2, 1.2);
        let leds = pen.led_positions(&pose.led1, &pose.rotation);
        let mut pts = Vec::new();
        let mut truth = Vec::new();
        for (i, p) in leds.iter().enumerate() {
            if mask & (1 << i) != 0 {
                // Gaussian noise, clipped to the +-2 mm per point of digest §7 criterion 5.
                let n = Vector3::new(rng.gaussian(), rng.gaussian(), rng.gaussian()) * noise;
                pts.push(p + n.cap_magnitude(0.002));
                truth.push(Some(i));
            }
        }
        while truth.len() < mask.count_ones() as usize + spurious {
            let s = pose.led1
                + Vector3::new(
                    rng.uniform(-0.2, 0.2),
                    rng.uniform(-0.2, 0.2),
                    rng.uniform(-0.2, 0.2),
                );
            // A point within ~2 cm of where an LED should be (distance tolerance plus line residual)
            // is geometrically indistinguishable from that LED: it is not "interference".
            if leds.iter().any(|l| (l - s).norm() < 0.02) {
                continue;
            }
            pts.push(s);
            truth.push(None);
        }
        // Shuffle so the order carries no information.
        for k in (1..pts.len()).rev() {
            let j = (rng.next_u64() % (k as u64 + 1)) as usize;
            pts.swap(k, j);
            truth.swap(k, j);
        }
        (candidates(&pts), truth, pose)
    }

    fn wrong_labels(id: &Identification, truth: &[Option<usize>]) -> usize {
        id.assignment
            .iter()
            .enumerate()
            .filter(|(led, a)| a.is_some_and(|k| truth[k] != Some(*led)))
            .count()
    }

    #[test]
    fn every_subset_is_labelled_with_a_direction_prior() {
        let mut rng = SplitMix64::new(7);
        let mut id = Identifier::new(PenGeometry::thesis(), IdentifyConfig::default()).unwrap();
        for mask in 1u8..16 {
            if mask.count_ones() < 2 {
                continue;
            }
            for _ in 0..200 {
                let (c, truth, pose) = scene(&mut rng, mask, 0, 0.0007);
                let prior = IdentifyPrior {
                    direction: Some(pose.direction()),
                    previous: continuity_for_triples(mask, &pose),
                    ..Default::default()
                };
                let r = id.identify(&c, &prior).unwrap();
                assert_eq!(r.mask(), mask);
                assert_eq!(wrong_labels(&r, &truth), 0);
            }
        }
    }

    /// Previous LED positions (continuity) for three-LED masks, whose twin triples need them.
    fn continuity_for_triples(mask: u8, pose: &PenPose) -> [Option<Vector3<f64>>; LED_COUNT] {
        if mask.count_ones() == 3 {
            PenGeometry::thesis()
                .led_positions(&pose.led1, &pose.rotation)
                .map(Some)
        } else {
            [None; LED_COUNT]
        }
    }

    /// LEDs 1-3 seen where LEDs 2-4 were a frame ago: the distances fit 1-3 exactly, but the
    /// labels would trade places between frames, so the frame is refused; with the previous
    /// frame agreeing, it is labelled.
    #[test]
    fn labels_that_trade_places_between_frames_are_refused() {
        let mut rng = SplitMix64::new(8);
        let pen = PenGeometry::thesis();
        let mut id = Identifier::new(pen, IdentifyConfig::default()).unwrap();
        let pose = PenPose::random(&mut rng, 0.5, 0.7, 0.3);
        let leds = pen.led_positions(&pose.led1, &pose.rotation);
        let c = candidates(&leds[..3]);
        let agreeing = IdentifyPrior {
            previous: [Some(leds[0]), Some(leds[1]), Some(leds[2]), None],
            ..Default::default()
        };
        let r = id.identify(&c, &agreeing).expect("labelled");
        assert_eq!(r.assignment, [Some(0), Some(1), Some(2), None]);
        let shifted = IdentifyPrior {
            previous: [None, Some(leds[0]), Some(leds[1]), Some(leds[2])],
            ..Default::default()
        };
        assert_eq!(id.identify(&c, &shifted), Err(IdentifyError::Ambiguous));
    }

    #[test]
    fn two_leds_without_prior_are_refused_and_three_need_continuity() {
        let mut rng = SplitMix64::new(3);
        let mut id = Identifier::new(PenGeometry::thesis(), IdentifyConfig::default()).unwrap();
        let (c, _, _) = scene(&mut rng, 0b0101, 0, 0.0);
        assert_eq!(
            id.identify(&c, &IdentifyPrior::default()),
            Err(IdentifyError::Ambiguous)
        );
        // {1,2,4} (70:90) and {2,3,4} (40:50) are twins up to scale: without continuity a scale
        // error could swap them, so the frame is refused, even with the direction prior (twins
        // point the same way). ({1,2,3} vs {1,3,4} differ by more than the band here.)
        for mask in [0b1011u8, 0b1110] {
            let (c, truth, pose) = scene(&mut rng, mask, 0, 0.0);
            let direction = IdentifyPrior {
                direction: Some(pose.direction()),
                ..Default::default()
            };
            assert_eq!(id.identify(&c, &direction), Err(IdentifyError::Ambiguous));
            let continuity = IdentifyPrior {
                direction: None,
                previous: continuity_for_triples(mask, &pose),
                ..Default::default()
            };
            let r = id.identify(&c, &continuity).unwrap();
            assert_eq!((r.count(), wrong_labels(&r, &truth)), (3, 0));
        }
        // Continuity alone also resolves the two-LED case.
        let (c, truth, pose) = scene(&mut rng, 0b0011, 0, 0.0);
        let leds = PenGeometry::thesis().led_positions(&pose.led1, &pose.rotation);
        let prior = IdentifyPrior {
            direction: None,
            previous: leds.map(Some),
            ..Default::default()
        };
        let r = id.identify(&c, &prior).unwrap();
        assert_eq!(wrong_labels(&r, &truth), 0);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(200))]
        /// Random pens, visibility patterns and spurious points: never a wrong label.
        #[test]
        fn random_pens_and_spurious_points_never_get_wrong_labels(seed in 0u64..u64::MAX, mask in 3u8..16, spurious in 0usize..4) {
            proptest::prop_assume!(mask.count_ones() >= 2);
            let mut rng = SplitMix64::new(seed);
            let mut id = Identifier::new(PenGeometry::thesis(), IdentifyConfig::default()).unwrap();
            let (c, truth, pose) = scene(&mut rng, mask, spurious, 0.0007);
            let prior = IdentifyPrior { direction: Some(pose.direction()), ..Default::default() };
            if let Ok(r) = id.identify(&c, &prior) {
                proptest::prop_assert_eq!(wrong_labels(&r, &truth), 0);
            }
        }
    }

    #[test]
    fn interference_never_yields_a_wrong_label() {
        let mut rng = SplitMix64::new(11);
        let mut id = Identifier::new(PenGeometry::thesis(), IdentifyConfig::default()).unwrap();
        let (mut wrong, mut labelled, mut frames) = (0, 0, 0);
        for mask in [
            0b1111u8, 0b1110, 0b0111, 0b1011, 0b1101, 0b0011, 0b1100, 0b0110, 0b1001,
        ] {
            for spurious in 1..=3 {
                for _ in 0..400 {
                    let (c, truth, pose) = scene(&mut rng, mask, spurious, 0.0007);
                    let prior = IdentifyPrior {
                        direction: Some(pose.direction()),
                        previous: continuity_for_triples(mask, &pose),
                        ..Default::default()
                    };
                    frames += 1;
                    if let Ok(r) = id.identify(&c, &prior) {
                        labelled += 1;
                        wrong += wrong_labels(&r, &truth);
                    }
                }
            }
        }
        assert_eq!(wrong, 0);
        assert!(labelled as f64 > 0.9 * frames as f64, "{labelled}/{frames}");
    }
}
