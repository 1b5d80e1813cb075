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
    /// Maximum mismatch between a measured and a physical distance, metres (< half the smallest
    /// gap between two physical distances).
    pub tolerance: f64,
    /// Maximum distance of an LED from the least-squares axis, metres (3 or more LEDs).
    pub max_line_residual: f64,
    /// Maximum relative deviation of the 4-LED cross-ratio from the pen's.
    pub cross_ratio_tolerance: f64,
    /// A labelling agrees with the prior direction when the cosine of the angle exceeds this.
    pub prior_min_cos: f64,
    /// A labelling agrees with the previous frame when every LED moved less than this, metres.
    pub continuity_max_jump: f64,
    /// Candidates beyond this count are ignored (bounds the search).
    pub max_candidates: usize,
}

impl Default for IdentifyConfig {
    fn default() -> Self {
        Self {
            tolerance: 0.0045,
            max_line_residual: 0.004,
            cross_ratio_tolerance: 0.05,
            prior_min_cos: 0.9,
            continuity_max_jump: 0.03,
            max_candidates: 24,
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
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Hypothesis {
    assignment: [Option<usize>; LED_COUNT],
    size: usize,
    distance_rms: f64,
}

/// LED identifier with its precomputed pen distances (reusable, no per-frame allocation after warm-up).
#[derive(Debug, Clone)]
pub struct Identifier {
    pen: PenGeometry,
    config: IdentifyConfig,
    cross_ratio: f64,
    hypotheses: Vec<Hypothesis>,
}

impl Identifier {
    /// Builds an identifier; fails if the pen's distances are not separable at this tolerance.
    pub fn new(pen: PenGeometry, config: IdentifyConfig) -> Result<Self, super::pen::PenError> {
        pen.validate(config.tolerance)?;
        Ok(Self {
            pen,
            config,
            cross_ratio: pen.cross_ratio(),
            hypotheses: Vec::with_capacity(64),
        })
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
        self.collect_hypotheses(cands);
        let best_size = self
            .hypotheses
            .iter()
            .map(|h| h.size)
            .max()
            .ok_or(IdentifyError::NoConsistentSet)?;
        let (chosen, resolution) = self.choose(cands, best_size, prior)?;
        Ok(self.finish(cands, chosen, resolution))
    }

    fn collect_hypotheses(&mut self, cands: &[Candidate]) {
        self.hypotheses.clear();
        for i in 0..cands.len() {
            for j in i + 1..cands.len() {
                if shares_blob(&cands[i], &cands[j]) {
                    continue;
                }
                let d = (cands[i].point - cands[j].point).norm();
                for (a, b) in PenGeometry::pairs() {
                    if (d - self.pen.distance(a, b)).abs() > self.config.tolerance {
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
            let gate = self.config.tolerance * (1.0 + 2.0 * ((l[c] - l[a]) / (l[b] - l[a])).abs());
            let mut best: Option<(usize, f64)> = None;
            for (k, cand) in cands.iter().enumerate() {
                if assignment
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
                ((cands[*u].point - cands[k].point).norm() - self.pen.distance(o, c)).abs()
                    <= self.config.tolerance
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
        let (mut sum, mut n) = (0.0, 0usize);
        for (a, b) in PenGeometry::pairs() {
            if let (Some(p), Some(q)) = (pts[a], pts[b]) {
                let e = (p - q).norm() - self.pen.distance(a, b);
                if e.abs() > self.config.tolerance {
                    return None;
                }
                sum += e * e;
                n += 1;
            }
        }
        if size >= 3 && line_residual(&pts) > self.config.max_line_residual {
            return None;
        }
        if size == 4 && !self.cross_ratio_ok(&pts) {
            return None;
        }
        Some(Hypothesis {
            assignment,
            size,
            distance_rms: (sum / n.max(1) as f64).sqrt(),
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
        let mut top = self.hypotheses.iter().filter(|h| h.size == size);
        let first = *top.next().ok_or(IdentifyError::NoConsistentSet)?;
        if top.next().is_none() {
            return Ok((first, Resolution::Geometry));
        }
        if prior.direction.is_none() && prior.previous.iter().all(Option::is_none) {
            return Err(IdentifyError::Ambiguous);
        }
        let mut survivor = None;
        for h in self.hypotheses.iter().filter(|h| h.size == size) {
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
            if v.dot(&dir) < self.config.prior_min_cos * dir.norm() {
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
            .map(|(i, p)| Candidate {
                left: i,
                right: i,
                point: *p,
                ray_gap: 0.0,
                epipolar_px: 0.0,
            })
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
                    ..Default::default()
                };
                let r = id.identify(&c, &prior).unwrap();
                assert_eq!(r.mask(), mask);
                assert_eq!(wrong_labels(&r, &truth), 0);
            }
        }
    }

    #[test]
    fn two_leds_without_prior_are_refused_and_three_are_not() {
        let mut rng = SplitMix64::new(3);
        let mut id = Identifier::new(PenGeometry::thesis(), IdentifyConfig::default()).unwrap();
        let (c, _, _) = scene(&mut rng, 0b0101, 0, 0.0);
        assert_eq!(
            id.identify(&c, &IdentifyPrior::default()),
            Err(IdentifyError::Ambiguous)
        );
        let (c, truth, _) = scene(&mut rng, 0b1101, 0, 0.0);
        let r = id.identify(&c, &IdentifyPrior::default()).unwrap();
        assert_eq!(
            (r.count(), wrong_labels(&r, &truth), r.resolution),
            (3, 0, Resolution::Geometry)
        );
        // Continuity alone also resolves the two-LED case.
        let (c, truth, pose) = scene(&mut rng, 0b0011, 0, 0.0);
        let leds = PenGeometry::thesis().led_positions(&pose.led1, &pose.rotation);
        let prior = IdentifyPrior {
            direction: None,
            previous: leds.map(Some),
        };
        let r = id.identify(&c, &prior).unwrap();
        assert_eq!(wrong_labels(&r, &truth), 0);
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
