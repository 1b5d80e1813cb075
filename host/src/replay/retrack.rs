//! Start-up re-tracking: strokes drawn before the online world estimate was accepted are tracked
//! once more with it.
//!
//! Until the world reference (gravity and the magnetic field in the camera frame) is known the
//! tracker has no direction prior: it reports only the labellings the geometry alone decides and
//! refuses the others (`world_not_accepted` in `report.json`), so the first strokes of a session,
//! the boundary above all, come out with gaps. Once the estimate is accepted the replay runs a
//! fresh tracker configured with it over the start of the recording, up to the end of the last
//! stroke begun before the acceptance, and the strokes of that second pass replace the first
//! versions (stroke ids count pen-downs, so a re-tracked stroke keeps its id; docs/strokes.md).
//! The per-sample output (track, refusals, display) is spliced at the same time, so the report
//! describes the strokes it lists. The second pass runs in every session whose world was accepted
//! late, at least up to the acceptance: without strokes there (the thesis's tip experiment) the
//! samples before it are re-tracked too. Without a world the tip's axis is vision's alone, and
//! the tips before `tip` seed 2's acceptance at 7.8 s were 70% within 2 mm, against 98% after it.

use super::run::Pass;
use crate::link::ButtonChange;

/// Time after the last re-tracked stroke's pen-up up to which the second pass runs, so that
/// its pen-up is processed, nanoseconds.
const MARGIN_NS: u64 = 200_000_000;

/// The end of the re-tracked start: `MARGIN_NS` after the pen-up of the last stroke pressed
/// (`draw_mask`) before `accepted_ns`, or the end of time when that stroke is never released;
/// None when no stroke began before `accepted_ns`.
pub(crate) fn retrack_until(
    buttons: &[ButtonChange],
    draw_mask: u8,
    accepted_ns: u64,
) -> Option<u64> {
    let mut drawing = false;
    let mut until = None;
    for b in buttons {
        let pressed = b.buttons & draw_mask != 0;
        if pressed == drawing {
            continue;
        }
        drawing = pressed;
        if pressed && b.t_ns < accepted_ns {
            until = Some(u64::MAX);
        } else if !pressed && until == Some(u64::MAX) {
            until = Some(b.t_ns.saturating_add(MARGIN_NS));
        }
    }
    until
}

/// The end of the re-tracked start of a replay: the end of [`retrack_until`] or `MARGIN_NS` after
/// the acceptance, whichever is later.
pub(crate) fn replay_retrack_until(
    buttons: &[ButtonChange],
    draw_mask: u8,
    accepted_ns: u64,
) -> u64 {
    let start = accepted_ns.saturating_add(MARGIN_NS);
    retrack_until(buttons, draw_mask, accepted_ns).map_or(start, |u| u.max(start))
}

/// True when the second pass is to replace the first's start: by [`second_is_better`] when
/// either pass has a stroke begun before `accepted_ns`; always otherwise. The samples after the
/// acceptance are tracked with the same world, and with it the tip's axis is fused with the IMU's
/// (without, `tip` seed 2's start gave 628 tips within 1 m, 70% within 2 mm; with it 491, 90%: as
/// many good tips, and 185 fewer poor ones).
fn second_pass_wins(first: &Pass, second: &Pass, accepted_ns: u64) -> bool {
    let early_stroke = |p: &Pass| p.strokes.iter().any(|s| s.t_start_ns < accepted_ns);
    !(early_stroke(first) || early_stroke(second))
        || second_is_better(&first.strokes, &second.strokes, accepted_ns)
}

/// True when the second pass tracked at least as many points of the strokes begun before
/// `accepted_ns` as the first (a direction prior from a world estimate still off by degrees can
/// refuse frames the geometry alone labelled).
pub(crate) fn second_is_better(
    first: &[fires_record::Stroke],
    second: &[fires_record::Stroke],
    accepted_ns: u64,
) -> bool {
    let tracked = |strokes: &[fires_record::Stroke]| -> usize {
        strokes
            .iter()
            .filter(|s| s.t_start_ns < accepted_ns)
            .map(|s| s.raw_points)
            .sum()
    };
    tracked(second) >= tracked(first)
}

/// The strokes with the second pass's begun before `accepted_ns` in place of the first pass's of
/// the same id (a stroke the second pass lost keeps its first version), in id order.
pub(crate) fn replace_strokes(
    first: Vec<fires_record::Stroke>,
    second: Vec<fires_record::Stroke>,
    accepted_ns: u64,
) -> Vec<fires_record::Stroke> {
    let retracked: Vec<fires_record::Stroke> = second
        .into_iter()
        .filter(|s| s.t_start_ns < accepted_ns)
        .collect();
    let ids: Vec<u32> = retracked.iter().map(|s| s.id).collect();
    let mut strokes: Vec<fires_record::Stroke> = first
        .into_iter()
        .filter(|s| !ids.contains(&s.id))
        .chain(retracked)
        .collect();
    strokes.sort_by_key(|s| s.id);
    strokes
}

/// The first pass with the start re-tracked, when [`second_pass_wins`]: the strokes as
/// [`replace_strokes`], and the per-sample output before the second pass's end the second
/// pass's. Otherwise the first pass unchanged.
pub(super) fn splice(first: Pass, second: Pass, accepted_ns: u64) -> Pass {
    if !second_pass_wins(&first, &second, accepted_ns) {
        return first;
    }
    let cut = second
        .samples
        .last()
        .map_or(0, |s| s.t_ns.saturating_add(1));
    let strokes = replace_strokes(first.strokes, second.strokes, accepted_ns);
    let keep = |t: u64| t >= cut;
    let mut samples = second.samples;
    let mut display_tips = second.display_tips;
    let mut label_pixels = second.label_pixels;
    for ((s, d), l) in first
        .samples
        .into_iter()
        .zip(first.display_tips)
        .zip(first.label_pixels)
    {
        if keep(s.t_ns) {
            samples.push(s);
            display_tips.push(d);
            label_pixels.push(l);
        }
    }
    let mut pairs = second.pairs;
    pairs.extend(first.pairs.into_iter().filter(|p| keep(p.t_ns)));
    Pass {
        samples,
        display_tips,
        label_pixels,
        pairs,
        unpaired_frames: first.unpaired_frames,
        strokes,
        world_fit: first.world_fit,
        mag_offset: first.mag_offset,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn change(t_ns: u64, buttons: u8) -> ButtonChange {
        ButtonChange { t_ns, buttons }
    }

    #[test]
    fn the_start_ends_after_the_last_stroke_begun_before_acceptance() {
        let buttons = [
            change(10, 1),
            change(20, 0),
            change(30, 1),
            change(40, 3),
            change(50, 0),
            change(60, 1),
            change(70, 0),
        ];
        // Button 2 alone does not draw; the press at 40 is still the stroke begun at 30.
        assert_eq!(retrack_until(&buttons, 1, 35), Some(50 + MARGIN_NS));
        assert_eq!(retrack_until(&buttons, 1, 15), Some(20 + MARGIN_NS));
        assert_eq!(retrack_until(&buttons, 1, 5), None);
        assert_eq!(retrack_until(&buttons, 2, 45), Some(50 + MARGIN_NS));
        // Still drawing when the recording ends: the whole recording.
        assert_eq!(retrack_until(&buttons[..4], 1, 35), Some(u64::MAX));
    }
}
