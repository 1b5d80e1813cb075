//! Why a stereo pair gave no vision tip: one reason per refused pair, what `report.json` →
//! `vision_refusals` counts (docs/report.md).

use super::safety::Unsafe;
use crate::track::identify::RefusedBy;

/// The reason a stereo pair gave no vision tip, attributed in pipeline order: a camera with
/// fewer than three blobs first, then fewer than three stereo candidates, then the stage that
/// refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum Refusal {
    /// Blob detection: a camera has fewer than three blobs.
    Blobs,
    /// Correspondence: fewer than three stereo candidates from at least three blobs per camera.
    Correspondence,
    /// Identification refused, by this test.
    Identify(RefusedBy),
    /// The eq. 4.13 tip could not be computed from the labelled LEDs.
    Tip,
    /// The tracker's labelling safety refused, by this check.
    Safety(Unsafe),
    /// A labelling with fewer than four LEDs before the world reference is accepted.
    NoWorld,
    /// A labelling whose other-camera blobs could not be moved to the pair's time (no image
    /// velocity yet, the first pair after a loss) from a frame exposed more than
    /// [`UNALIGNED_MAX_DT_NS`] before or after: kept for continuity, but its stereo is stale.
    Unaligned,
}

/// The longest time between a pair's two exposures over which blobs that could not be moved
/// are still triangulated together, nanoseconds. Free-running 60 Hz and 30 Hz webcams pair frames
/// up to 17 and 33 ms apart, over which a quickly drawn pen moves 5-10 mm: such a pair waits for
/// image velocities (webcam seed 3: a 13-18 mm excursion in the boundary stroke; stress seed 3:
/// two wrong labels). Pairs of the 100 Hz blob cameras lie within about half their period and
/// are not delayed.
pub const UNALIGNED_MAX_DT_NS: u64 = 6_000_000;

/// The reason for a pair with `blobs` per camera and `candidates` stereo candidates refused at
/// `stage`.
pub(super) fn attribute(blobs: [usize; 2], candidates: usize, stage: Refusal) -> Refusal {
    if blobs.iter().any(|&n| n < 3) {
        Refusal::Blobs
    } else if candidates < 3 {
        Refusal::Correspondence
    } else {
        stage
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blobs_come_before_correspondence_before_the_stage() {
        let stage = Refusal::Identify(RefusedBy::Twin);
        assert_eq!(attribute([2, 4], 1, stage), Refusal::Blobs);
        assert_eq!(attribute([4, 3], 2, stage), Refusal::Correspondence);
        assert_eq!(attribute([3, 3], 3, stage), stage);
    }
}
