//! Merged-spot completion: a labelling for the pairs in which two neighbouring LED spots merged
//! into one blob in one camera.
//!
//! When the pen points nearly at one camera its LED images crowd together there, and two spots
//! whose thresholded discs touch are detected as one blob between them. That blob lies on
//! neither LED's epipolar line, so the pair has only the stereo candidates of the other LEDs
//! (typically the two ends, LEDs 1 and 4), too few for the identifier's three-LED tests, while
//! the other camera sees all four LEDs plainly. The pen is rigid and straight, so two
//! triangulated LEDs at one of the pen's six distances fix where the other two must be
//! (FIRES thesis, §4.1.2: the LEDs are told apart by their distances along the pen). The
//! completion accepts such a labelling only when the rest of the pen explains both images:
//!
//! * each missing LED has a blob of its own in one camera within the epipolar gate of its
//!   predicted image, and in the other camera either such a blob or a blob that covers its
//!   predicted image (within the blob's radius);
//! * a covering blob covers at least two LEDs (it is a merge), none of them triangulated, and
//!   its centre lies on the segment between their images (the centroid of merged spots);
//! * every blob on the pen's image in either camera is one of its LEDs' (own or covering);
//! * no other labelling (the mirrored pen, another pair of LEDs at the same distance, other
//!   candidates) explains the images as well.
//!
//! Only the triangulated LEDs enter the labelling's points (the tip's line runs through them);
//! the completed ones are counted in [`Identification::completed`], which is what lets the
//! tracker report the labelling as a located four-LED pattern.

use super::safety::{PairView, MERGE_MARGIN};
use super::Tracker;
use crate::stereo::{CameraId, Candidate};
use crate::track::identify::{Identification, RefusedBy, Resolution};
use crate::track::pen::LED_COUNT;
use nalgebra::Vector3;

/// What the completion needs from the configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct MergedOptions {
    /// The pen's LED offsets along its axis, metres.
    pub(super) led_offsets: [f64; LED_COUNT],
    /// Largest mismatch between the two triangulated LEDs' distance and the pen's, metres.
    pub(super) tolerance: f64,
    /// Largest distance of an LED's own blob from its predicted image, pixels.
    pub(super) gate_px: f64,
}

impl Tracker {
    /// The labelling of a pair whose identification was refused for want of LEDs or for a blob
    /// its pen did not explain (not for a conflict: a rival, a twin, an identity swap or the
    /// fused direction), when two triangulated LEDs and the images of the other two, merged
    /// with a neighbour's spot in one camera, explain the pen uniquely (`pipeline/merged.rs`).
    pub(super) fn complete_merged_pair(
        &self,
        t: u64,
        refused_by: RefusedBy,
    ) -> Option<Identification> {
        if is_conflict(refused_by) || self.correspondences.candidates.len() < 2 {
            return None;
        }
        let pair = self.pair_view(t);
        let options = MergedOptions {
            led_offsets: self.config.pen.led_offsets,
            tolerance: self.config.identify.tolerance,
            gate_px: self.config.correspondence.max_epipolar_px,
        };
        complete_merged(&pair, &options)
    }
}

/// True when identification refused for a conflict (a rival, a twin, an identity swap or the
/// fused direction), which no completion may override.
pub(super) fn is_conflict(refused_by: RefusedBy) -> bool {
    matches!(
        refused_by,
        RefusedBy::Twin | RefusedBy::Rival | RefusedBy::TradingPlaces | RefusedBy::DirectionPrior
    )
}

/// One pen pose that explains both images: per LED, the candidate (triangulated LEDs) and the
/// blob of each camera (left, right) that images it.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Completion {
    stereo: [Option<usize>; LED_COUNT],
    blobs: [[Option<usize>; 2]; LED_COUNT],
    mismatch: f64,
}

/// The unique labelling that two triangulated LEDs and the images of the other two give, or None
/// (no such labelling, or several).
pub(super) fn complete_merged(
    pair: &PairView<'_>,
    options: &MergedOptions,
) -> Option<Identification> {
    let cands = pair.candidates;
    let mut found: Option<Completion> = None;
    for (i, ci) in cands.iter().enumerate() {
        for (j, cj) in cands.iter().enumerate().skip(i + 1) {
            if ci.left == cj.left || ci.right == cj.right {
                continue;
            }
            let d = (cj.point - ci.point).norm();
            for a in 0..LED_COUNT {
                for b in 0..LED_COUNT {
                    let span = options.led_offsets[b] - options.led_offsets[a];
                    if a == b || (d - span.abs()).abs() > options.tolerance {
                        continue;
                    }
                    let Some(c) = explain(pair, options, [(a, i), (b, j)]) else {
                        continue;
                    };
                    match &found {
                        None => found = Some(c),
                        Some(f) if f.blobs == c.blobs => {}
                        Some(_) => return None,
                    }
                }
            }
        }
    }
    let c = found?;
    let assignment = c.stereo;
    let used: Vec<&Candidate> = assignment.iter().flatten().map(|&k| &cands[k]).collect();
    let interference = cands
        .iter()
        .filter(|c| !used.iter().any(|u| u.left == c.left || u.right == c.right))
        .count();
    let completed = (0..LED_COUNT)
        .filter(|&k| assignment[k].is_none())
        .fold(0u8, |m, k| m | (1 << k));
    let fit = (-(c.mismatch / options.tolerance).powi(2)).exp();
    Some(Identification {
        assignment,
        points: assignment.map(|a| a.map(|k| cands[k].point)),
        distance_rms: c.mismatch,
        confidence: fit * (2.0 / LED_COUNT as f64).sqrt(),
        resolution: Resolution::Geometry,
        interference,
        completed,
        from_pen_line: false,
        from_pen_ray: None,
    })
}

/// The pen with LED `a` at candidate `i` and LED `b` at candidate `j` (`seeds`), if every other
/// LED is explained by the images.
fn explain(
    pair: &PairView<'_>,
    options: &MergedOptions,
    seeds: [(usize, usize); 2],
) -> Option<Completion> {
    let cands = pair.candidates;
    let [(a, i), (b, j)] = seeds;
    let (pa, pb) = (cands[i].point, cands[j].point);
    let l = &options.led_offsets;
    let led = |k: usize| pa + (pb - pa) * ((l[k] - l[a]) / (l[b] - l[a]));
    let mut c = Completion {
        stereo: [None; LED_COUNT],
        blobs: [[None; 2]; LED_COUNT],
        mismatch: ((pb - pa).norm() - (l[b] - l[a]).abs()).abs(),
    };
    c.stereo[a] = Some(i);
    c.stereo[b] = Some(j);
    c.blobs[a] = [Some(cands[i].left), Some(cands[i].right)];
    c.blobs[b] = [Some(cands[j].left), Some(cands[j].right)];
    let leds: [Vector3<f64>; LED_COUNT] = std::array::from_fn(led);
    for camera in [CameraId::Left, CameraId::Right] {
        let cam = usize::from(camera == CameraId::Right);
        let blobs = pair.points.pixels(camera);
        let radii = pair.align.current(cam).map_or(&[][..], |f| &f.radii[..]);
        let taken = [c.blobs[a][cam], c.blobs[b][cam]];
        let px: Vec<[f64; 2]> = leds
            .iter()
            .map(|p| pair.rig.project(camera, p).ok())
            .collect::<Option<_>>()?;
        // Per missing LED: its own blob, or the blob covering it (a merge).
        let mut covering: [Option<usize>; LED_COUNT] = [None; LED_COUNT];

        for k in (0..LED_COUNT).filter(|&k| k != a && k != b) {
            let (n, dist) = nearest(blobs, px[k])?;
            if taken.contains(&Some(n)) {
                return None;
            }
            if dist <= options.gate_px {
                c.blobs[k][cam] = Some(n);
            } else if radii.get(n).is_some_and(|&r| dist <= r) {
                covering[k] = Some(n);
            } else {
                return None;
            }
        }
        // A blob used as an LED's own must not be another LED's too.
        for k in 0..LED_COUNT {
            for m in (k + 1)..LED_COUNT {
                if c.blobs[k][cam].is_some() && c.blobs[k][cam] == c.blobs[m][cam] {
                    return None;
                }
            }
        }
        if !merges_explained(blobs, &px, &covering, options.gate_px) {
            return None;
        }
        // Every blob on the pen's image is one of its LEDs' (an unexplained one there means
        // the labelling is shifted along the pen).
        let explained =
            |n: usize| (0..LED_COUNT).any(|k| c.blobs[k][cam] == Some(n) || covering[k] == Some(n));
        let on_pen = |q: [f64; 2]| segment_distance(q, px[0], px[LED_COUNT - 1]) <= options.gate_px;
        if (0..blobs.len()).any(|n| on_pen(blobs[n]) && !explained(n)) {
            return None;
        }
        // The triangulated LEDs' own spots are apart from every other LED's image: each blob is
        // one spot, not a merge, and no neighbour's spot pulls its centre.
        for (k, n) in [(a, taken[0]), (b, taken[1])] {
            let r = n.and_then(|n| radii.get(n)).copied().unwrap_or(0.0);
            let min = options.gate_px.max(MERGE_MARGIN * 2.0 * r);
            let apart = (0..LED_COUNT)
                .filter(|&j| j != k)
                .all(|j| (px[j][0] - px[k][0]).hypot(px[j][1] - px[k][1]) >= min);
            if !apart {
                return None;
            }
        }
    }
    // Every missing LED needs a blob of its own in at least one camera.
    (0..LED_COUNT)
        .all(|k| c.blobs[k].iter().any(Option::is_some))
        .then_some(c)
}

/// True when every covering blob covers at least two LEDs and lies within `gate_px` of the
/// segment between the outermost of their images.
fn merges_explained(
    blobs: &[[f64; 2]],
    px: &[[f64; 2]],
    covering: &[Option<usize>; LED_COUNT],
    gate_px: f64,
) -> bool {
    covering.iter().flatten().all(|&n| {
        let members: Vec<usize> = (0..LED_COUNT).filter(|&k| covering[k] == Some(n)).collect();
        let (Some(&first), Some(&last)) = (members.first(), members.last()) else {
            return false;
        };
        members.len() >= 2 && segment_distance(blobs[n], px[first], px[last]) <= gate_px
    })
}

/// The blob nearest to `p` and its distance, pixels.
fn nearest(blobs: &[[f64; 2]], p: [f64; 2]) -> Option<(usize, f64)> {
    blobs
        .iter()
        .map(|q| (q[0] - p[0]).hypot(q[1] - p[1]))
        .enumerate()
        .min_by(|x, y| x.1.total_cmp(&y.1))
}

/// Distance from `p` to the segment `a`–`b`.
pub(super) fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let s = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - s * dx).hypot(p[1] - a[1] - s * dy)
}
