//! Pen-ray planes: the crowded camera's pen plane when the pen points almost straight at that
//! camera, so that the LED spots it shows merge into one compact blob with no usable axis.
//!
//! [`super::pen_line`] needs the pen's image line in the crowded camera: through two or more
//! blobs, or along one streak's principal axis. When the pen points within a few degrees of the
//! camera, its four spots lie 2–5 px apart and merge into one round blob (elongation under 2;
//! webcam seed 3, the last stroke: 0.1 s of pairs with one blob in the left camera and LEDs 2–4
//! plain in the right), and the axis of such a blob is set by the exposure's smear as much as by
//! the pen. What the blob still gives is its centroid: the intensity-weighted mean of collinear
//! spots lies on the pen's image line, so the blob's viewing ray meets the pen, and every plane
//! through that ray and the pen holds it. Such planes form a one-parameter family (the angle
//! about the ray). Each plane meets the clear camera's LED rays at points along the pen; the
//! plane that puts them at the pen's LED spacing (FIRES thesis, §4.1.2) is the pen's plane.
//! A lone streak whose axis plane labels nothing is scanned the same way: when the pen swings
//! through the camera's view during the exposure, the streak's axis is the smear's, while its
//! centroid still lies on the pen's image line (webcam seed 3's boundary stroke: a 200.7 ms gap
//! of such pairs, past what the IMU bridges, closed).
//!
//! The family is scanned in [`SCAN_STEPS`] steps over half a turn, each plane labelled by
//! [`super::pen_line`]'s own checks (spacing within tolerance, both images explained, the fused
//! direction), and each labelling's best plane is refined by a golden-section search on its
//! spacing mismatch. When the pen points straight at the camera, the clear rays meet the blob's
//! ray where the LEDs are, for every plane of the family: the mismatch is flat and the points do
//! not depend on the angle. The pen's position is then as well determined as the pen's line.
//! A labelling accepted on two separate arcs of the family whose points differ by more than the
//! tolerance is two pens: the pair is refused. The best plane only starts the pen's line: the
//! points are then fitted to every spot and to the blob's centroid (`pipeline/pen_fit.rs`), whose
//! covariance says how well this geometry fixes them (webcam seed 3, the last stroke: the plane
//! alone left the tip 1-8 mm off where the fit leaves it 0.3-1.8 mm, and says so).

use super::pen_line::{labellings, normals, ray, same_labels, LineLabelling, LineOptions};
use super::safety::PairView;
use crate::stereo::CameraId;
use nalgebra::Vector3;

/// Planes tried about the blob's ray, over half a turn (2° apart).
const SCAN_STEPS: usize = 90;

/// Golden-section iterations refining one labelling's plane (the bracket shrinks to 0.6^k).
const REFINE_STEPS: usize = 24;

/// Two pens explain the images equally: the pair must be refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Ambiguous;

/// The labellings of the clear camera's collinear blobs `set_k` along planes through the
/// crowded camera's ray of blob `blob`, each at its best plane (see the module doc).
pub(super) fn ray_labellings(
    pair: &PairView<'_>,
    options: &LineOptions,
    crowded: CameraId,
    blob: usize,
    set_k: u32,
    direction: Option<&Vector3<f64>>,
) -> Result<Vec<LineLabelling>, Ambiguous> {
    let Some(&m) = normals(pair, crowded).get(blob) else {
        return Ok(Vec::new());
    };
    let (origin, axis) = ray(pair.rig, crowded, m);
    // Two unit vectors across the ray: plane normals are their combinations.
    let (a, b) = across(&axis);
    let step = std::f64::consts::PI / SCAN_STEPS as f64;
    // The free plane may shift the LEDs by one along the crowded image and still cover them
    // with blobs a few pixels apart (fires-v1 seed 3): the labelling marks itself so, and its
    // LEDs' images are not taken for labels.
    let at = |theta: f64| -> Vec<LineLabelling> {
        let normal = a * theta.cos() + b * theta.sin();
        let mut ls = labellings(pair, options, crowded, &(normal, origin), &set_k, direction);
        for l in &mut ls {
            l.from_ray = true;
        }
        ls
    };
    // Per distinct labelling: the scan steps that accept it.
    let mut found: Vec<(LineLabelling, Vec<usize>)> = Vec::new();
    for i in 0..SCAN_STEPS {
        for l in at(i as f64 * step) {
            match found.iter_mut().find(|(f, _)| same_labels(f, &l)) {
                Some((_, steps)) => steps.push(i),
                None => found.push((l, vec![i])),
            }
        }
    }
    let mut out = Vec::new();
    for (first, steps) in found {
        let mut best: Option<LineLabelling> = None;
        for arc in arcs(&steps) {
            let Some(l) = refine(&at, &first, arc, step) else {
                continue;
            };
            match &best {
                Some(b) if !same_points(b, &l, options.tolerance) => return Err(Ambiguous),
                Some(b) if b.mismatch <= l.mismatch => {}
                _ => best = Some(l),
            }
        }
        out.extend(best);
    }
    Ok(out)
}

/// Two unit vectors across unit `e`, orthogonal to each other.
pub(super) fn across(e: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let a = if e.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let a = (a - e * e.dot(&a)).normalize();
    (a, e.cross(&a))
}

/// The circularly contiguous runs of `steps` (sorted scan indices): (first, length).
fn arcs(steps: &[usize]) -> Vec<(usize, usize)> {
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for &i in steps {
        match runs.last_mut() {
            Some((start, len)) if *start + *len == i => *len += 1,
            _ => runs.push((i, 1)),
        }
    }
    // The scan wraps at half a turn (the plane at π is the plane at 0).
    if runs.len() > 1 {
        let (first_start, first_len) = runs[0];
        let (last_start, last_len) = runs[runs.len() - 1];
        if first_start == 0 && last_start + last_len == SCAN_STEPS {
            runs[0] = (last_start, last_len + first_len);
            runs.pop();
        }
    }
    runs
}

/// The labelling like `like` at the plane of least mismatch on the arc (first step, length),
/// widened by a step on each side: a golden-section search.
fn refine(
    at: &impl Fn(f64) -> Vec<LineLabelling>,
    like: &LineLabelling,
    (first, len): (usize, usize),
    step: f64,
) -> Option<LineLabelling> {
    let eval = |theta: f64| at(theta).into_iter().find(|l| same_labels(l, like));
    let cost = |l: &Option<LineLabelling>| l.as_ref().map_or(f64::INFINITY, |l| l.mismatch);
    let (mut lo, mut hi) = ((first as f64 - 1.0) * step, (first + len) as f64 * step);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let mut x1 = hi - g * (hi - lo);
    let mut x2 = lo + g * (hi - lo);
    let (mut l1, mut l2) = (eval(x1), eval(x2));
    for _ in 0..REFINE_STEPS {
        if cost(&l1) <= cost(&l2) {
            hi = x2;
            (x2, l2) = (x1, l1);
            x1 = hi - g * (hi - lo);
            l1 = eval(x1);
        } else {
            lo = x1;
            (x1, l1) = (x2, l2);
            x2 = lo + g * (hi - lo);
            l2 = eval(x2);
        }
    }
    let best = if cost(&l1) <= cost(&l2) { l1 } else { l2 };
    // An arc's own scan steps accepted the labelling; its refinement keeps the best seen.
    best.or_else(|| {
        (first..first + len)
            .filter_map(|i| eval((i % SCAN_STEPS) as f64 * step))
            .min_by(|x, y| x.mismatch.total_cmp(&y.mismatch))
    })
}

/// Every LED located by both labellings lies within `tolerance` of itself.
fn same_points(a: &LineLabelling, b: &LineLabelling, tolerance: f64) -> bool {
    a.leds.iter().zip(&b.leds).all(|(x, y)| match (x, y) {
        (Some(x), Some(y)) => (x.point - y.point).norm() <= tolerance,
        _ => true,
    })
}
