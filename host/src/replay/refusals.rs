//! The `vision_refusals` block of the report: per refusal reason, how many stereo pairs it cost, over
//! all pairs and over the pairs in which both cameras truly see at least three LEDs (docs/report.md,
//! "Vision refusals").

use std::collections::HashMap;

use fires_record::report::{PairRefusals, RefusalCounts, VisionRefusals};
use fires_record::truth::Visibility;
use fires_record::ExposureTruth;

use super::run::{PairOutcome, ReplayOutput};
use crate::track::identify::RefusedBy;
use crate::track::pipeline::{Refusal, Unsafe};

/// Adds one refusal to its counter.
pub fn count(counts: &mut RefusalCounts, refusal: Refusal) {
    let c = match refusal {
        Refusal::Blobs => &mut counts.blobs,
        Refusal::Correspondence => &mut counts.correspondence,
        Refusal::Identify(by) => match by {
            RefusedBy::TooFewCandidates => &mut counts.too_few_candidates,
            RefusedBy::Distances => &mut counts.distances,
            RefusedBy::DirectionPrior => &mut counts.direction_prior,
            RefusedBy::Mirror => &mut counts.mirror,
            RefusedBy::NoPrior => &mut counts.no_prior,
            RefusedBy::SeveralAgree => &mut counts.several_agree,
            RefusedBy::NoneAgrees => &mut counts.none_agrees,
            RefusedBy::Twin => &mut counts.twin,
            RefusedBy::Rival => &mut counts.rival,
            RefusedBy::TradingPlaces => &mut counts.trading_places,
            RefusedBy::ImageEvidence => &mut counts.image_evidence,
        },
        Refusal::Tip => &mut counts.tip,
        Refusal::Safety(Unsafe::TwoLedsUnconfirmed) => &mut counts.safety_two_leds,
        Refusal::Safety(Unsafe::PenImagesOverlap) => &mut counts.safety_pen_images,
        Refusal::Safety(Unsafe::BlobNotIsolated) => &mut counts.safety_crowded,
        Refusal::NoWorld => &mut counts.world_not_accepted,
        Refusal::Unaligned => &mut counts.unaligned,
    };
    *c += 1;
}

/// The figures of a set of pairs.
pub fn pair_refusals<'a>(pairs: impl IntoIterator<Item = &'a PairOutcome>) -> PairRefusals {
    let mut r = PairRefusals::default();
    for p in pairs {
        r.pairs += 1;
        match p.refusal {
            None => r.vision += 1,
            Some(why) => count(&mut r.refused, why),
        }
    }
    r.vision_fraction = (r.pairs > 0).then(|| r.vision as f64 / r.pairs as f64);
    r
}

/// The `vision_refusals` block; with exposure truth also over the truly visible pairs (both frames
/// with at least three LEDs `visible`), and with the true strokes' `[start, end]` times (ns) over
/// the truly visible pairs whose left exposure lies in a stroke.
pub fn vision_refusals(
    out: &ReplayOutput,
    truth: Option<&[ExposureTruth]>,
    strokes: Option<&[(u64, u64)]>,
) -> VisionRefusals {
    let Some(truth) = truth else {
        return VisionRefusals {
            unpaired_frames: out.unpaired_frames,
            all: pair_refusals(&out.pairs),
            truly_visible: None,
            truly_visible_in_strokes: None,
        };
    };
    // (visible LEDs, exposure time) per (camera, frame index).
    let frames: HashMap<(u8, u64), (usize, u64)> = truth
        .iter()
        .map(|e| {
            let n = e
                .leds
                .iter()
                .filter(|l| l.visibility == Visibility::Visible && l.pixel.is_some())
                .count();
            ((e.camera, e.index), (n, e.exposure_time_ns))
        })
        .collect();
    let seen = |cam: u8, i: u64| frames.get(&(cam, i)).is_some_and(|&(n, _)| n >= 3);
    let visible: Vec<&PairOutcome> = out
        .pairs
        .iter()
        .filter(|p| seen(0, p.left_frame) && seen(1, p.right_frame))
        .collect();
    let in_strokes = strokes.map(|strokes| {
        pair_refusals(visible.iter().copied().filter(|p| {
            frames
                .get(&(0, p.left_frame))
                .is_some_and(|&(_, t)| strokes.iter().any(|&(a, b)| a <= t && t <= b))
        }))
    });
    VisionRefusals {
        unpaired_frames: out.unpaired_frames,
        all: pair_refusals(&out.pairs),
        truly_visible: Some(pair_refusals(visible.iter().copied())),
        truly_visible_in_strokes: in_strokes,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_reason_has_its_counter_and_fractions_over_nothing_are_null() {
        let pair = |refusal| PairOutcome {
            t_ns: 0,
            left_frame: 0,
            right_frame: 0,
            refusal,
        };
        let pairs = [
            pair(None),
            pair(Some(Refusal::Identify(RefusedBy::Twin))),
            pair(Some(Refusal::Identify(RefusedBy::Twin))),
            pair(Some(Refusal::Blobs)),
            pair(Some(Refusal::Safety(Unsafe::BlobNotIsolated))),
        ];
        let r = pair_refusals(&pairs);
        assert_eq!((r.pairs, r.vision), (5, 1));
        assert_eq!(r.vision_fraction, Some(0.2));
        assert_eq!(r.refused.twin, 2);
        assert_eq!(r.refused.blobs, 1);
        assert_eq!(r.refused.safety_crowded, 1);
        assert_eq!(r.refused.distances, 0);
        assert_eq!(pair_refusals(&[]).vision_fraction, None);
    }
}
