//! The pair as the labelling checks read it, and from a labelling to a checked vision tip: the tip of the labelled LEDs, merged LEDs dropped,
//! the labelling safety (`LabelGuard::check`), and the pen-line retry for crowded images.

use super::refusal::Refusal;
use super::safety::{PairView, Unsafe};
use super::Tracker;
use crate::track::identify::Identification;
use crate::track::pen::LED_COUNT;
use crate::track::tip::TipEstimate;

impl Tracker {
    /// The current pair at time `t` as the labelling checks and completions read it.
    pub(super) fn pair_view(&self, t: u64) -> PairView<'_> {
        PairView {
            rig: &self.rig,
            align: &self.align,
            points: &self.points,
            candidates: &self.correspondences.candidates,
            tip: &self.tip,
            t,
        }
    }

    /// [`Self::checked`], and where it refuses fewer than three LEDs for crowded images (merge
    /// reach, or two LEDs the prediction does not confirm) the pen-line labelling, checked in
    /// turn: the pen's image lines may still locate three or more (`pipeline/pen_line.rs`).
    pub(super) fn checked_or_pen_line(
        &mut self,
        t: u64,
        id: Identification,
        stale: bool,
    ) -> Result<(Identification, TipEstimate), Refusal> {
        match self.checked(t, id, stale) {
            Err(r @ Refusal::Safety(Unsafe::PenImagesOverlap | Unsafe::TwoLedsUnconfirmed))
                if id.count() < 3 =>
            {
                match self
                    .complete_pen_line(t)
                    .map(|id| self.checked(t, id, stale))
                {
                    Some(Ok(checked)) => Ok(checked),
                    _ => Err(r),
                }
            }
            result => result,
        }
    }

    /// The vision tip of labelling `id` (its axis also feeds the safety checks and the fusion)
    /// and the labelling safety: merged LEDs dropped from a labelling of three or more, then
    /// `LabelGuard::check`; the stage that refused otherwise.
    pub(super) fn checked(
        &self,
        t: u64,
        mut id: Identification,
        stale: bool,
    ) -> Result<(Identification, TipEstimate), Refusal> {
        let Ok(mut vision) = self.tip.estimate(&id.points) else {
            return Err(Refusal::Tip);
        };
        // Safety.
        let pair = self.pair_view(t);
        // An LED whose image touches another's was seen as a merged blob, half-way between the
        // two: a labelling of at least three LEDs keeps the others (at least two) and drops it.
        let merges_checked = id.completed != 0 || id.from_pen_line;
        if let Some(merged) = (!merges_checked)
            .then(|| self.labels.merged_leds(&pair, &vision, &id))
            .flatten()
        {
            let kept = (0..LED_COUNT)
                .filter(|&k| id.assignment[k].is_some() && !merged[k])
                .count();
            if merged.iter().any(|&m| m) && id.count() >= 3 && kept >= 2 {
                for k in (0..LED_COUNT).filter(|&k| merged[k]) {
                    id.assignment[k] = None;
                    id.points[k] = None;
                }
                match self.tip.estimate(&id.points) {
                    Ok(v) => vision = v,
                    Err(_) => return Err(Refusal::Tip),
                }
            }
        }
        match self.labels.check(&pair, &id, &vision, stale) {
            Some(why) => Err(Refusal::Safety(why)),
            None => Ok((id, vision)),
        }
    }
}
