//! A labelling from the two frames' own LED identities, for pairs the identifier found ambiguous
//! or at odds with a fused direction that has strayed.
//!
//! The identifier labels a pair from its stereo points alone, with the fused direction and the
//! last labels as priors. After a loss longer than a second it has neither: the direction prior
//! has timed out and the last labels are stale, and three LEDs with the first hidden by the hand
//! are refused as the scaled twin of another triple (LEDs 2-4 at 40:50 mm look like LEDs 1, 2 and
//! 4 at 70:90 scaled by 1.78), or as a labelling that holds mirrored too (fires-v2 seed 4: a
//! whole stroke of well aligned pairs refused as twins after a 1.2 s loss in the pen-up move).
//! And on the 6 cm Minoru baseline the vision axes that correct the orientation filter are a few
//! degrees off themselves, so the filter can stray by more than the prior's 2 degrees: fires-v2
//! seed 5 drew the last 0.45 s of a stroke with all four LEDs plain in both cameras, every pair
//! refused for disagreeing with a fused direction 7 degrees off the pen.
//!
//! Each camera's frames may still know their LEDs: from the prediction of a recent vision pose,
//! or from the pen's pattern placed along the inertial direction where vision last saw it, up to
//! a small turn and a scale of 0.8-1.25 (`pipeline/pattern.rs`). That scale bound is what settles
//! the twin, and the direction's sign the mirror. When both frames name the blobs of at least
//! three LEDs, every such LED has a stereo candidate made of exactly its two blobs, and those
//! points lie at the pen's distances within the identification tolerance, this is the pair's
//! labelling. It then goes through the same labelling safety as every other.

use super::Tracker;
use crate::stereo::{CameraId, Candidate};
use crate::track::identify::{Identification, RefusedBy, Resolution};
use crate::track::pen::LED_COUNT;

impl Tracker {
    /// The labelling both frames' LED identities give a pair the identifier refused as
    /// ambiguous or for the fused direction (see the module doc), or None.
    pub(super) fn complete_from_frame_labels(
        &self,
        refused_by: RefusedBy,
    ) -> Option<Identification> {
        if !matches!(
            refused_by,
            RefusedBy::Twin
                | RefusedBy::DirectionPrior
                | RefusedBy::Mirror
                | RefusedBy::NoPrior
                | RefusedBy::SeveralAgree
                | RefusedBy::NoneAgrees
        ) {
            return None;
        }
        let ids = [(0, CameraId::Left), (1, CameraId::Right)].map(|(c, camera)| {
            self.align
                .current(c)
                .map(|f| self.align.frame_identities(&self.rig, camera, f))
        });
        let [Some(left), Some(right)] = ids else {
            return None;
        };
        labelling_from_identities(
            &self.correspondences.candidates,
            &left,
            &right,
            &self.config.pen.led_offsets,
            self.config.identify.tolerance,
        )
    }
}

/// The labelling whose LED `k` is the candidate of blobs `left[k]` and `right[k]`, when at least
/// three LEDs have one and every two of them lie at the pen's distance within `tolerance`
/// (metres); None otherwise.
pub(super) fn labelling_from_identities(
    cands: &[Candidate],
    left: &[Option<usize>; LED_COUNT],
    right: &[Option<usize>; LED_COUNT],
    led_offsets: &[f64; LED_COUNT],
    tolerance: f64,
) -> Option<Identification> {
    let assignment: [Option<usize>; LED_COUNT] = std::array::from_fn(|k| {
        let (i, j) = (left[k]?, right[k]?);
        cands.iter().position(|c| c.left == i && c.right == j)
    });
    let labelled: Vec<usize> = (0..LED_COUNT)
        .filter(|&k| assignment[k].is_some())
        .collect();
    if labelled.len() < 3 {
        return None;
    }
    let point = |k: usize| assignment[k].map(|c| cands[c].point);
    let (mut sum, mut n) = (0.0, 0);
    for (x, &a) in labelled.iter().enumerate() {
        for &b in &labelled[x + 1..] {
            let d = (point(b)? - point(a)?).norm();
            let miss = d - (led_offsets[b] - led_offsets[a]).abs();
            if miss.abs() > tolerance {
                return None;
            }
            sum += miss * miss;
            n += 1;
        }
    }
    let distance_rms = (sum / n as f64).sqrt();
    // Decided by the frames' identities: a prior.
    Some(Identification::graded(
        cands,
        assignment,
        distance_rms,
        Resolution::Prior,
        tolerance,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    const OFFSETS: [f64; LED_COUNT] = [0.0, 0.070, 0.110, 0.160];

    /// Candidates of LEDs 2-4 (left blobs 0-2, right blobs 2, 0, 1) and a reflection.
    fn candidates() -> Vec<Candidate> {
        let dir = Vector3::new(0.6, 0.0, 0.8);
        let led = |k: usize| Vector3::new(0.0, 0.0, 0.6) - dir * OFFSETS[k];
        vec![
            Candidate::at(0, 2, led(1)),
            Candidate::at(1, 0, led(2)),
            Candidate::at(2, 1, led(3)),
            Candidate::at(3, 3, Vector3::new(0.2, 0.1, 0.7)),
        ]
    }

    #[test]
    fn both_frames_identities_label_the_pair() {
        let cands = candidates();
        let left = [None, Some(0), Some(1), Some(2)];
        let right = [None, Some(2), Some(0), Some(1)];
        let id = labelling_from_identities(&cands, &left, &right, &OFFSETS, 0.004).unwrap();
        assert_eq!(id.assignment, [None, Some(0), Some(1), Some(2)]);
        assert!(id.distance_rms < 1e-12);
        assert_eq!(id.interference, 1);
        assert_eq!(id.resolution, Resolution::Prior);
    }

    #[test]
    fn too_few_leds_or_wrong_distances_give_nothing() {
        let cands = candidates();
        // The right frame names only two of the three LEDs.
        let left = [None, Some(0), Some(1), Some(2)];
        let right = [None, Some(2), Some(0), None];
        assert!(labelling_from_identities(&cands, &left, &right, &OFFSETS, 0.004).is_none());
        // Identities that call LEDs 2-4 LEDs 1, 2 and 4 (the twin): the distances refuse them.
        let left = [Some(0), Some(1), None, Some(2)];
        let right = [Some(2), Some(0), None, Some(1)];
        assert!(labelling_from_identities(&cands, &left, &right, &OFFSETS, 0.004).is_none());
        // Blobs whose pairing is no stereo candidate.
        let left = [None, Some(0), Some(1), Some(2)];
        let right = [None, Some(0), Some(2), Some(1)];
        assert!(labelling_from_identities(&cands, &left, &right, &OFFSETS, 0.004).is_none());
    }
}
