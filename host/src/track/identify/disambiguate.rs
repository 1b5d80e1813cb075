//! Choosing between labellings that all fit the distances: mirrored, shifted and scaled
//! alternatives of the same points, the direction prior and temporal continuity (previous LED
//! positions), and rivals that conflict with the chosen labelling; when they cannot leave exactly
//! one labelling the frame is refused.

use super::{
    labelled_points, shares_blob, Hypothesis, Identifier, IdentifyPrior, RefusedBy, Resolution,
};
use crate::stereo::Candidate;
use crate::track::line_fit::labelled_direction;
use crate::track::pen::LED_COUNT;

impl Identifier {
    /// Picks the unique hypothesis of the largest size, using the priors to break ties.
    pub(super) fn choose(
        &self,
        cands: &[Candidate],
        size: usize,
        prior: &IdentifyPrior,
    ) -> Result<(Hypothesis, Resolution), RefusedBy> {
        let mut top = self
            .hypotheses
            .iter()
            .filter(|h| h.size == size && !h.refused);
        let first = *top.next().ok_or(RefusedBy::Distances)?;
        if top.next().is_none() {
            if !first.needs_prior {
                return Ok((first, Resolution::Geometry));
            }
            let resolved =
                prior.direction.is_some() && self.agrees_with_prior(cands, &first, prior);
            return if resolved {
                Ok((first, Resolution::Prior))
            } else {
                Err(RefusedBy::Mirror)
            };
        }
        if prior.direction.is_none() && prior.previous.iter().all(Option::is_none) {
            return Err(RefusedBy::NoPrior);
        }
        let mut survivor = None;
        for h in self
            .hypotheses
            .iter()
            .filter(|h| h.size == size && !h.refused)
        {
            if self.agrees_with_prior(cands, h, prior) {
                if survivor.is_some() {
                    return Err(RefusedBy::SeveralAgree);
                }
                survivor = Some(*h);
            }
        }
        survivor
            .map(|h| (h, Resolution::Prior))
            .ok_or(RefusedBy::NoneAgrees)
    }

    pub(super) fn agrees_with_prior(
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

    /// Cosine threshold for agreeing with the direction prior: `prior_min_cos`, tightened with the
    /// rig noise to `3 σ_angle + prior_sigma` of the labelled end points (at least 3 degrees).
    pub(super) fn prior_cos(
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

    /// True when the previous frame's LED positions confirm the labelling: at least one labelled
    /// LED was seen recently and none moved more than `continuity_max_jump`.
    pub(super) fn continuity_confirms(
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
    pub(super) fn switches_identity(
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

    /// True when another labelling at least as large, not excluded by the priors, uses one of the
    /// chosen blobs in a different pairing or gives a chosen candidate a different label
    /// (including labellings refused as ambiguous): the frame is then not labelled with confidence.
    pub(super) fn has_conflicting_rival(
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

    /// Ghost-pairing check for two-LED labellings: true when a blob of a labelled candidate pairs
    /// with another blob noticeably better (epipolar distance smaller by `competitor_margin_px`).
    /// With collinear LEDs, wrong left/right pairings form a shifted "ghost pen" whose distances
    /// can match by chance; a better alternative pairing of the same blob exposes it.
    pub(super) fn has_better_pairing(
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
    pub(super) fn plausible_alternatives(
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
    pub(super) fn has_scaled_twin(
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
