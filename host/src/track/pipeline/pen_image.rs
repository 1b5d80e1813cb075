//! The image checks of pen-line stereo (`pipeline/pen_line.rs`): whether a candidate pen explains
//! both cameras' blobs, the clear camera's as separate spots at the pen's spacing and the crowded
//! camera's as its own or merged spots along the pen's image, with the LEDs it misses a run at
//! one end of the pen; and which labelled LEDs have an image of their own to check.

use super::align::KeptFrame;
use super::merged::segment_distance;
use super::pen_line::{other, LineLed, LineOptions};
use super::safety::{PairView, MERGE_MARGIN};
use crate::stereo::{CameraId, Candidate};
use crate::track::identify::Identification;
use crate::track::pen::LED_COUNT;
use nalgebra::Vector3;

/// The labelled LEDs of the pen `model` whose clear-camera blobs are `clear_blob`, at `points`,
/// when both images are explained by it (`clear_image_explained`, `crowded_image_explained`):
/// at least three LEDs with a blob in each camera, or as many LEDs with a spot of their own there
/// as [`LineOptions::own_spots`] asks (two, or one end LED; fewer than the three that point
/// stereo needs; the clear camera's spots fix which LEDs they are). An LED hidden in the crowded
/// camera keeps its clear spot, for the fit, and has no stereo pair.
pub(super) fn explained_leds(
    pair: &PairView<'_>,
    options: &LineOptions,
    crowded: CameraId,
    model: &[Vector3<f64>; LED_COUNT],
    clear_blob: &[Option<usize>; LED_COUNT],
    points: &[Vector3<f64>; LED_COUNT],
) -> Option<[Option<LineLed>; LED_COUNT]> {
    if !clear_image_explained(pair, options, other(crowded), model, clear_blob) {
        return None;
    }
    let crowded_blob = crowded_image_explained(pair, options, crowded, model, clear_blob)?;
    let leds: [Option<LineLed>; LED_COUNT] = std::array::from_fn(|k| {
        clear_blob[k].map(|c| LineLed {
            clear_blob: c,
            crowded_blob: crowded_blob[k],
            point: points[k],
            covariance: None,
        })
    });
    // With `own_spots` the crowded camera's LEDs have spots of their own (no merge), and all of
    // them must be stereo LEDs.
    let stereo = leds
        .iter()
        .flatten()
        .filter(|l| l.crowded_blob.is_some())
        .count();
    (stereo >= 3 || options.own_spots == Some(stereo)).then_some(leds)
}

/// The pen's images (distorted pixels) of `camera` and the blobs' radii there.
fn images<'a>(
    pair: &PairView<'a>,
    camera: CameraId,
    model: &[Vector3<f64>; LED_COUNT],
) -> Option<([[f64; 2]; LED_COUNT], &'a [f64])> {
    let mut px = [[0.0; 2]; LED_COUNT];
    for (k, p) in model.iter().enumerate() {
        px[k] = pair.rig.project(camera, p).ok()?;
    }
    let radii = frame(pair, camera).map_or(&[][..], |f| &f.radii[..]);
    Some((px, radii))
}

/// The newest frame of `camera` (its blobs' radii and second moments).
pub(super) fn frame<'a>(pair: &PairView<'a>, camera: CameraId) -> Option<&'a KeptFrame> {
    pair.align.current(usize::from(camera == CameraId::Right))
}

/// The clear camera: at least three LEDs with separate spots (`blob`), each apart from every
/// other LED's image, and no other blob on the pen's image.
fn clear_image_explained(
    pair: &PairView<'_>,
    options: &LineOptions,
    camera: CameraId,
    model: &[Vector3<f64>; LED_COUNT],
    blob: &[Option<usize>; LED_COUNT],
) -> bool {
    let Some((px, radii)) = images(pair, camera, model) else {
        return false;
    };
    let blobs = pair.points.pixels(camera);
    let radius = |k: usize| blob[k].and_then(|n| radii.get(n).copied());
    let largest = (0..LED_COUNT).filter_map(radius).fold(0.0, f64::max);
    for k in (0..LED_COUNT).filter(|&k| blob[k].is_some()) {
        let Some(&b) = blob[k].and_then(|n| blobs.get(n)) else {
            return false;
        };
        if dist(b, px[k]) > options.gate_px {
            return false;
        }
        let r_k = radius(k).unwrap_or(largest);
        let apart = (0..LED_COUNT).filter(|&j| j != k).all(|j| {
            let min = options
                .gate_px
                .max(MERGE_MARGIN * (r_k + radius(j).unwrap_or(largest)));
            dist(px[j], px[k]) >= min
        });
        if !apart {
            return false;
        }
    }
    let used = |n: usize| blob.contains(&Some(n));
    let on_pen = |q: [f64; 2]| segment_distance(q, px[0], px[LED_COUNT - 1]) <= options.gate_px;
    blob.iter().flatten().count() >= 3 && (0..blobs.len()).all(|n| used(n) || !on_pen(blobs[n]))
}

/// The crowded camera: the blob that images each LED (its own spot, or a blob covering it and at
/// least one neighbour, centred on their segment), with no other blob on the pen's image, and at
/// least one such merge or else exactly two LEDs imaged (point stereo's three candidates are
/// missing either way). The LEDs it does not image form a run at one end of the pen: the hand
/// holding the pen covers its tip end, and the LEDs' emission cones fade towards the back end
/// first (webcam seeds 6, 8 and 9 at a stroke's start: one camera sees LEDs 1-3, the other
/// LEDs 1-2, the rest too dim). With own spots, no LED it does not image may lie within merging
/// distance of an imaged one ([`MERGE_MARGIN`]): that spot could be both. None when the image is
/// not explained so.
fn crowded_image_explained(
    pair: &PairView<'_>,
    options: &LineOptions,
    camera: CameraId,
    model: &[Vector3<f64>; LED_COUNT],
    clear_blob: &[Option<usize>; LED_COUNT],
) -> Option<[Option<usize>; LED_COUNT]> {
    let (px, radii) = images(pair, camera, model)?;
    let blobs = pair.points.pixels(camera);
    let shapes = frame(pair, camera).map_or(&[][..], |f| &f.shapes[..]);
    // Each LED's blob: the nearest of those whose extent covers it (a small spot next to a long
    // merge may be nearer by centroid while the merge covers the LED).
    let covers = |n: usize, p: [f64; 2]| match shapes.get(n) {
        Some(shape) => within_extent(shape, blobs[n], p, options.gate_px),
        None => dist(blobs[n], p) <= options.gate_px.max(radii.get(n).copied().unwrap_or(0.0)),
    };
    let mut blob = [None; LED_COUNT];
    for k in 0..LED_COUNT {
        blob[k] = (0..blobs.len())
            .filter(|&n| covers(n, px[k]))
            .min_by(|&x, &y| dist(blobs[x], px[k]).total_cmp(&dist(blobs[y], px[k])));
    }
    let hidden = (0..LED_COUNT).filter(|&k| blob[k].is_none()).count();
    let front_run = (0..hidden).all(|k| blob[k].is_none());
    let back_run = (LED_COUNT - hidden..LED_COUNT).all(|k| blob[k].is_none());
    let allowed = if let Some(n) = options.own_spots {
        (front_run || back_run) && hidden + n == LED_COUNT
    } else {
        // One end LED, which the clear camera sees (the hand's).
        hidden == 0
            || (hidden == 1 && (front_run || back_run) && {
                let k = if front_run { 0 } else { LED_COUNT - 1 };
                clear_blob[k].is_some()
            })
    };
    if !allowed {
        return None;
    }
    // A hidden LED whose image would touch an own spot's LED image is as likely merged into that
    // spot as hidden: the spot is then no LED's own (webcam seed 17: LEDs 2 and 3 merged 9 px
    // apart on the left, taken for LED 2's own spot with LEDs 3 and 4 hidden; LED 2 labelled
    // 5.4 px off its image).
    if options.own_spots.is_some() {
        let touches = |k: usize, j: usize| {
            let r = blob[j].and_then(|n| radii.get(n).copied()).unwrap_or(0.0);
            dist(px[k], px[j]) < MERGE_MARGIN * 2.0 * r
        };
        let ambiguous = (0..LED_COUNT)
            .filter(|&k| blob[k].is_none())
            .any(|k| (0..LED_COUNT).any(|j| blob[j].is_some() && touches(k, j)));
        if ambiguous {
            return None;
        }
    }
    let mut merges = 0;
    for k in (0..LED_COUNT).filter(|&k| blob[k].is_some()) {
        let members: Vec<usize> = (0..LED_COUNT).filter(|&j| blob[j] == blob[k]).collect();
        let (first, last) = (members[0], members[members.len() - 1]);
        if first != k {
            continue;
        }
        let centre = blobs[blob[k]?];
        if members.len() == 1 {
            if dist(centre, px[k]) > options.gate_px {
                return None;
            }
        } else {
            // A merge covers neighbours only, and its centroid lies between them.
            if last - first + 1 != members.len()
                || segment_distance(centre, px[first], px[last]) > options.gate_px
            {
                return None;
            }
            merges += 1;
        }
    }
    let on_pen = |q: [f64; 2]| segment_distance(q, px[0], px[LED_COUNT - 1]) <= options.gate_px;
    let explained = (0..blobs.len()).all(|n| blob.contains(&Some(n)) || !on_pen(blobs[n]));
    let found = if options.own_spots.is_some() {
        merges == 0
    } else {
        merges > 0
    };
    (found && explained).then_some(blob)
}

/// True when `p` lies within the extent of a blob centred at `centre` with second moments
/// `shape`, widened by `gate_px`: `d^T (4 C + g^2 I)^-1 d <= 1` (a uniform disc of radius r has
/// `C = r^2 / 4`, so its extent is the disc grown by the gate).
fn within_extent(shape: &[f64; 3], centre: [f64; 2], p: [f64; 2], gate_px: f64) -> bool {
    let g2 = gate_px * gate_px;
    let (a, b, c) = (4.0 * shape[0] + g2, 4.0 * shape[1], 4.0 * shape[2] + g2);
    let det = a * c - b * b;
    let (dx, dy) = (p[0] - centre[0], p[1] - centre[1]);
    det > 0.0 && (c * dx * dx - 2.0 * b * dx * dy + a * dy * dy) / det <= 1.0
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Each labelled LED's own blob in the left and right image: an LED that a pen-line labelling
/// located inside a blob it shares with a neighbour (a merge) has no image of its own there.
pub(super) fn own_images(
    id: &Identification,
    cands: &[Candidate],
) -> [Option<(usize, usize)>; LED_COUNT] {
    let pairs = id
        .assignment
        .map(|a| a.map(|k| (cands[k].left, cands[k].right)));
    let shared = |k: usize, side: fn(&(usize, usize)) -> usize| {
        pairs[k].is_some_and(|p| {
            (0..LED_COUNT).any(|j| j != k && pairs[j].is_some_and(|q| side(&q) == side(&p)))
        })
    };
    std::array::from_fn(|k| {
        let merged = id.from_pen_line && (shared(k, |p| p.0) || shared(k, |p| p.1));
        pairs[k].filter(|_| !merged && id.from_pen_ray.is_none())
    })
}
