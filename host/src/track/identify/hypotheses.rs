//! The hypothesis search: every candidate pair at a physical LED distance seeds two oriented
//! labellings, each extended with the LEDs found at their predicted places along the line and
//! kept only when all its distances fit the noise band, its points are collinear and four LEDs
//! reproduce the pen's cross-ratio.

use super::{finite, labelled_points, shares_blob, Hypothesis, Identifier};
use crate::stereo::Candidate;
use crate::track::line_fit::principal_axis;
use crate::track::pen::{cross_ratio_1d, PenGeometry, LED_COUNT};
use nalgebra::Vector3;

impl Identifier {
    pub(super) fn collect_hypotheses(&mut self, cands: &[Candidate]) {
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
    pub(super) fn extend(
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

    pub(super) fn distances_match(
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

    pub(super) fn check(
        &self,
        cands: &[Candidate],
        assignment: [Option<usize>; LED_COUNT],
    ) -> Option<Hypothesis> {
        let pts = labelled_points(cands, &assignment);
        let size = pts.iter().flatten().count();
        let (mut sum, mut n) = (0.0, 0usize);
        for (a, b) in PenGeometry::pairs() {
            if let (Some(ka), Some(kb)) = (assignment[a], assignment[b]) {
                let e = (cands[ka].point - cands[kb].point).norm() - self.pen.distance(a, b);
                if e.abs() > self.band(&cands[ka], &cands[kb]) {
                    return None;
                }
                sum += e * e;
                n += 1;
            }
        }
        let tight = self.tight(cands, &assignment, size);
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

    /// True when every labelled distance is within the acceptance band (`accept_sigmas`) of the
    /// pen's, after removing a common scale error that the time between the pair's two exposures
    /// allows (the twin test's bound, `1 + v Δt / baseline`, see [`Self::has_scaled_twin`]). A pen
    /// that moves between the two unsynchronised exposures is triangulated slightly too long or
    /// too short, so on `fires-v1` the right four-LED labelling missed the band by 2-4.5 mm on
    /// 160 mm and only its mirrored two-LED parts were left, for the direction prior to refuse.
    /// The test asks whether some scale within that bound puts every distance in its band (each
    /// pair allows an interval of scales; they must meet), not whether the least-squares scale
    /// does: one LED's own error of 2 mm along the pen pulls the fitted scale and can push a short
    /// pair out of a band that the unscaled distances meet (`fires-v1` seed 1: in 76 of the 86
    /// stroke pairs refused for the direction prior, the right four-LED labelling had failed
    /// only here; vision in strokes 0.941 -> 0.956). Three or more LEDs show a common factor; two
    /// cannot tell it from a distance error, so pairs get none.
    fn tight(
        &self,
        cands: &[Candidate],
        assignment: &[Option<usize>; LED_COUNT],
        size: usize,
    ) -> bool {
        let max = if size >= 3 {
            self.twin_scale.max(1.0)
        } else {
            1.0
        };
        let (mut lo, mut hi) = (1.0 / max, max);
        for (a, b) in PenGeometry::pairs() {
            let (Some(ka), Some(kb)) = (assignment[a], assignment[b]) else {
                continue;
            };
            let (p, q) = (&cands[ka], &cands[kb]);
            let (d, l) = ((p.point - q.point).norm(), self.pen.distance(a, b));
            let band = self.band_at(p, q, self.config.accept_sigmas);
            if !(d.is_finite() && l > 0.0) {
                return false;
            }
            lo = lo.max((d - band) / l);
            hi = hi.min((d + band) / l);
        }
        lo <= hi
    }

    /// Collinearity: every labelled point within `max(max_line_residual_floor, ambiguity_sigmas σ⊥)`
    /// of the least-squares line, σ⊥ from the candidate's covariance perpendicular to the line
    /// (`max_line_residual` when no covariance is known).
    pub(super) fn collinear(
        &self,
        cands: &[Candidate],
        assignment: &[Option<usize>; LED_COUNT],
    ) -> bool {
        let pts = labelled_points(cands, assignment);
        let n = pts.iter().flatten().count() as f64;
        let centroid = pts.iter().flatten().sum::<Vector3<f64>>() / n;
        let Some(axis) = principal_axis(&pts, &centroid) else {
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

    pub(super) fn cross_ratio_ok(&self, pts: &[Option<Vector3<f64>>; LED_COUNT]) -> bool {
        let (Some(p0), Some(p3)) = (pts[0], pts[3]) else {
            return false;
        };
        let axis = p3 - p0;
        let n2 = axis.norm_squared();
        if n2.is_nan() || n2 <= 0.0 {
            return false;
        }
        let s = pts.map(|p| p.map_or(0.0, |p| (p - p0).dot(&axis) / n2.sqrt()));
        self.cross_ratio_fits(s, self.config.cross_ratio_tolerance)
    }

    /// True when four positions along one line (LEDs 1-4, any origin and scale) have the pen's
    /// cross-ratio within the relative `tolerance`. The cross-ratio of four collinear points is
    /// invariant under perspective projection, so the same test serves the triangulated LEDs
    /// and their images.
    pub(super) fn cross_ratio_fits(&self, s: [f64; LED_COUNT], tolerance: f64) -> bool {
        let cr = cross_ratio_1d(s);
        cr.is_finite() && ((cr - self.cross_ratio) / self.cross_ratio).abs() <= tolerance
    }

    /// Distance-matching band for two points: `max(tolerance, ambiguity_sigmas * σ_d)`; it grows
    /// with range when the rig noise is known, so that far-range labellings that are only
    /// consistent "by luck" meet their rivals and are refused rather than accepted wrongly.
    pub(super) fn band(&self, a: &Candidate, b: &Candidate) -> f64 {
        self.band_at(a, b, self.config.ambiguity_sigmas)
    }

    /// `max(floor, sigmas * σ_d)`; the floor is `tolerance` without any noise information and
    /// `tolerance_floor` with it.
    pub(super) fn band_at(&self, a: &Candidate, b: &Candidate, sigmas: f64) -> f64 {
        let sigma = self.distance_sigma(a, b);
        if sigma > 0.0 {
            (sigmas * sigma).max(self.config.tolerance_floor)
        } else {
            self.config.tolerance
        }
    }

    /// Standard deviation of the distance between two candidates: from their propagated
    /// covariances when available, else from the rig's [`RangeNoise`] model (0 without either).
    pub(super) fn distance_sigma(&self, a: &Candidate, b: &Candidate) -> f64 {
        let cov = a.covariance + b.covariance;
        match ((b.point - a.point).try_normalize(1e-12), cov.trace() > 0.0) {
            (Some(u), true) => (u.dot(&(cov * u))).max(0.0).sqrt(),
            _ => self
                .noise
                .map_or(0.0, |n| n.distance_sigma(&a.point, &b.point)),
        }
    }

    /// Standard deviation (radians) of the direction between two candidates.
    pub(super) fn direction_sigma(&self, a: &Candidate, b: &Candidate) -> Option<f64> {
        let cov = a.covariance + b.covariance;
        let d = b.point - a.point;
        let u = d.try_normalize(1e-12)?;
        if cov.trace() > 0.0 {
            let perp = cov.trace() - u.dot(&(cov * u));
            return Some((0.5 * perp.max(0.0)).sqrt() / d.norm());
        }
        self.noise.map(|n| n.direction_sigma(&a.point, &b.point))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::identify::IdentifyConfig;

    fn identifier() -> Identifier {
        Identifier::new(PenGeometry::thesis(), IdentifyConfig::default()).unwrap()
    }

    /// The pen's LED positions through a 1D projective map `x -> (a x + b) / (c x + d)` (what a
    /// camera does to points of one line) keep their cross-ratio; a reordering does not.
    #[test]
    fn the_cross_ratio_survives_projection_and_exposes_reordering() {
        let id = identifier();
        let l = PenGeometry::thesis().led_offsets;
        for (a, b, c, d) in [
            (1.0, 0.0, 0.0, 1.0),
            (700.0, 3.0, 2.5, 0.9),
            (-40.0, 12.0, -1.3, 1.0),
        ] {
            let s = l.map(|x| (a * x + b) / (c * x + d));
            assert!(id.cross_ratio_fits(s, 1e-9), "{s:?}");
        }
        assert!(!id.cross_ratio_fits([l[1], l[0], l[2], l[3]], 0.05));
        assert!(!id.cross_ratio_fits([0.0; LED_COUNT], 0.05));
    }

    /// Four LEDs, exact: accepted; one LED moved 8 mm along the axis: the distances no longer fit.
    #[test]
    fn a_hypothesis_needs_every_distance_and_the_line() {
        let id = identifier();
        let u = Vector3::new(0.6, 0.0, -0.8);
        let o = Vector3::new(0.05, -0.02, 0.7);
        let pts = PenGeometry::thesis().led_offsets.map(|s| o - u * s);
        let cands: Vec<Candidate> = pts
            .iter()
            .enumerate()
            .map(|(i, p)| Candidate::at(i, i, *p))
            .collect();
        let all = [Some(0), Some(1), Some(2), Some(3)];
        assert!(id.cross_ratio_ok(&labelled_points(&cands, &all)));
        assert!(id.collinear(&cands, &all));
        let h = id.check(&cands, all).expect("the exact pen fits");
        assert_eq!(h.size, 4);
        assert!(h.distance_rms < 1e-12);
        let mut moved = cands.clone();
        moved[2].point -= u * 0.008;
        assert!(id.check(&moved, all).is_none());
        let mut bent = cands;
        bent[1].point += Vector3::new(0.0, 0.01, 0.0);
        assert!(!id.collinear(&bent, &all));
    }

    /// A pen triangulated 1.5% too long (2.4 mm on LEDs 1-4, beyond the 3σ acceptance band of
    /// 2.1 mm, within the 4σ rival band) is accepted when the pair's time offset allows that
    /// scale, and refused when it allows none (synchronised exposures).
    #[test]
    fn a_common_scale_error_is_accepted_only_within_the_time_offset_bound() {
        let mut id = identifier();
        let u = Vector3::new(0.6, 0.0, -0.8);
        let o = Vector3::new(0.05, -0.02, 0.7);
        let cands: Vec<Candidate> = PenGeometry::thesis()
            .led_offsets
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let mut c = Candidate::at(i, i, o - u * (1.015 * s));
                c.covariance = nalgebra::Matrix3::identity() * 0.0005f64.powi(2);
                c
            })
            .collect();
        let all = [Some(0), Some(1), Some(2), Some(3)];
        id.twin_scale = 1.05;
        let h = id.check(&cands, all).expect("within the rival band");
        assert!(!h.refused, "a common 1.5% scale is allowed by a 5% bound");
        id.twin_scale = 1.0;
        let h = id.check(&cands, all).expect("within the rival band");
        assert!(
            h.refused,
            "no scale allowed: 2.4 mm is outside the acceptance band"
        );
    }

    /// LED 3 triangulated 2 mm towards LED 4 (distances 1-3 and 2-3 2 mm long, 3-4 2 mm short,
    /// inside the 2.1 mm band) is accepted, although the least-squares scale (1.0036) would push
    /// 3-4 to 2.2 mm; 3 mm is refused, since no one scale meets both 2-3 and 3-4.
    #[test]
    fn one_led_off_along_the_pen_is_judged_at_the_best_allowed_scale() {
        let mut id = identifier();
        id.twin_scale = 1.05;
        let u = Vector3::new(0.6, 0.0, -0.8);
        let o = Vector3::new(0.05, -0.02, 0.7);
        let with_led3_off = |shift: f64| -> Vec<Candidate> {
            let mut offsets = PenGeometry::thesis().led_offsets;
            offsets[2] += shift;
            offsets
                .iter()
                .enumerate()
                .map(|(i, s)| {
                    let mut c = Candidate::at(i, i, o - u * *s);
                    c.covariance = nalgebra::Matrix3::identity() * 0.0005f64.powi(2);
                    c
                })
                .collect()
        };
        let all = [Some(0), Some(1), Some(2), Some(3)];
        let h = id
            .check(&with_led3_off(0.002), all)
            .expect("within the rival band");
        assert!(!h.refused, "every distance is within its band at scale 1");
        let h = id.check(&with_led3_off(0.003), all);
        assert!(
            h.is_none_or(|h| h.refused),
            "2-3 needs a scale over 1.02, 3-4 under 0.99"
        );
    }
}
