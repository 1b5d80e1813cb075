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
}

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
