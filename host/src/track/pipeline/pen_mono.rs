//! One-camera pen line: the pen's pose from the clear camera's collinear spots alone, at the
//! pen's known LED spacing, for the pairs whose crowded camera gives no well-conditioned plane.
//!
//! [`super::pen_line`] meets the clear camera's LED rays with a pen plane of the crowded camera
//! (through its blobs, along a streak's axis, or about a compact blob's ray). When the pen lies
//! nearly in an epipolar plane, every such plane holds the clear rays nearly too: they meet it at
//! a grazing angle and the LEDs' positions along the pen are not fixed (webcam seed 3, the
//! boundary stroke: the pen about 8 degrees off one camera's ray, its spots one streak there,
//! whose plane meets the other camera's rays at sines of 0.10-0.15; the best plane about the
//! streak's ray put the LEDs at 0.58-0.85 of the pen's spacing). Yet the clear camera alone fixes
//! the pen then. Its LED rays lie in one plane through its centre, which holds the pen; in that
//! plane, with unit vectors `b1`, `b2` spanning it, the pen is the line `o + s e` and LED `k`
//! (offset `s_k`) lies on its spot's ray `u`:
//!
//! ```text
//! u.x (o.y + s_k e.y) - u.y (o.x + s_k e.x) = 0,
//! ```
//!
//! one homogeneous linear equation in `(o.x, o.y, e.x, e.y)` per spot: the pen's line in the
//! plane is the null vector of three or four such rows, scaled to `|e| = 1` (the 1-D projective
//! map of the pen onto its image line, FIRES thesis §4.1.2: collinear LEDs at known offsets).
//! Three spots fix it exactly; a fourth checks it (the cross-ratio). It is best conditioned
//! where the plane's labelling is worst: a pen pointing at the other camera is seen
//! foreshortened here, its far LEDs markedly closer together than its near ones. The pose only
//! starts the pen's line: every labelling it gives passes [`super::pen_line`]'s checks on both
//! images (the crowded camera's blobs must cover the LEDs where this pose puts them) and the
//! prior, only the unique one is kept, and its points are fitted to every spot of both images
//! (`pipeline/pen_fit.rs`), where the crowded camera's blob, seen across the baseline, pins the
//! depth the clear camera measures least well.
//!
//! **Not yet on in the tracker** ([`LineOptions::mono_start`]). Measured on `webcam` seeds 1-7
//! (60 s) against the tracker without it: no wrong label; seed 3's boundary stroke is no longer
//! split (coverage 0.862 -> 0.984, length 0.849 -> 1.017) and seed 1's worst coverage 0.981 ->
//! 1.000, but seed 3's worst RMS rises 0.68 -> 1.04 mm and seed 4's 0.91 -> 1.11 mm; seeds 2, 5,
//! 6, 7, `fires-v1` seed 1 and `stress` 13-15 are unchanged. In seed 3's gap the pose from three
//! spots alone is 0.3-0.9 mm from the truth, while the fit with the crowded camera's merged blob
//! (moved 2.7 px in time, its centroid 0.65 px off the pen's true image line) moves it 3-5 mm:
//! with three spots the clear camera fixes the depth weakly, so a small error of the merged blob's
//! time alignment becomes millimetres. What is left: the merged blob's motion between frames (or a
//! fit whose covariance says how little it knows), and the stroke's use of that covariance.

use super::pen_image::explained_leds;
use super::pen_line::{normals, other, pen_plane, ray, LineLabelling, LineOptions};
use super::safety::PairView;
use crate::stereo::CameraId;
use crate::track::pen::LED_COUNT;
use nalgebra::{Matrix4, SymmetricEigen, Vector3, Vector4};

/// A clear-camera ray in its pen plane: its angle across the image line, its blob, its direction
/// in the plane's basis, and its world origin and unit direction.
type InPlane = (f64, usize, [f64; 2], Vector3<f64>, Vector3<f64>);

/// Every labelling of the clear camera's collinear blobs `set_k` by the pen's pose fitted to
/// them alone (see the module doc) that passes the pen-line checks.
pub(super) fn mono_labellings(
    pair: &PairView<'_>,
    options: &LineOptions,
    crowded: CameraId,
    set_k: u32,
    direction: Option<&Vector3<f64>>,
) -> Vec<LineLabelling> {
    let clear = other(crowded);
    let norm_k = normals(pair, clear);
    let Some((n, _)) = pen_plane(pair.rig, clear, norm_k, set_k) else {
        return Vec::new();
    };
    let rays: Vec<(usize, Vector3<f64>, Vector3<f64>)> = (0..norm_k.len())
        .filter(|&m| set_k & (1 << m) != 0)
        .map(|m| {
            let (origin, d) = ray(pair.rig, clear, norm_k[m]);
            (m, origin, d)
        })
        .collect();
    let count = rays.len();
    if !(3..=LED_COUNT).contains(&count) {
        return Vec::new();
    }
    let centre = rays[0].1;
    // The plane's basis: the rays' mean direction and the direction across it in the plane.
    let Some(b1) = rays
        .iter()
        .map(|r| r.2)
        .sum::<Vector3<f64>>()
        .try_normalize(1e-12)
    else {
        return Vec::new();
    };
    let Some(b2) = n.cross(&b1).try_normalize(1e-12) else {
        return Vec::new();
    };
    // Each ray in the plane (angle across the image line, blob, direction in the plane, world
    // ray), ordered across the image line.
    let mut in_plane: Vec<InPlane> = rays
        .iter()
        .map(|&(m, origin, d)| {
            let u = [d.dot(&b1), d.dot(&b2)];
            (u[1].atan2(u[0]), m, u, origin, d)
        })
        .collect();
    in_plane.sort_by(|a, b| a.0.total_cmp(&b.0));
    let focal = pair.rig.camera(clear).focal_px();
    let offsets = &options.led_offsets;
    let mut out = Vec::new();
    for reverse in [false, true] {
        for subset in 0u32..(1 << LED_COUNT) {
            if subset.count_ones() as usize != count {
                continue;
            }
            let mut order: Vec<usize> =
                (0..LED_COUNT).filter(|&k| subset & (1 << k) != 0).collect();
            if reverse {
                order.reverse();
            }
            let spots: Vec<([f64; 2], f64)> = in_plane
                .iter()
                .zip(&order)
                .map(|(r, &k)| (r.2, offsets[k]))
                .collect();
            let Some((o, e)) = line_in_plane(&spots) else {
                continue;
            };
            let to_world = |q: [f64; 2]| centre + b1 * q[0] + b2 * q[1];
            let model: [Vector3<f64>; LED_COUNT] = std::array::from_fn(|k| {
                to_world([o[0] + offsets[k] * e[0], o[1] + offsets[k] * e[1]])
            });
            // Every LED in front of both cameras, and each spot's ray through its LED.
            let in_front = model
                .iter()
                .all(|p| (p - centre).dot(&b1) > 0.0 && p.z > 0.0 && pair.rig.to_right(p).z > 0.0);
            if !in_front {
                continue;
            }
            let mut clear_blob = [None; LED_COUNT];
            let mut square = 0.0;
            let mut fits = true;
            for (&(_, m, _, origin, d), &k) in in_plane.iter().zip(&order) {
                let v = model[k] - origin;
                let off = v - d * v.dot(&d);
                square += off.norm_squared();
                fits &= focal * off.norm() / v.norm() <= options.gate_px;
                clear_blob[k] = Some(m);
            }
            if !fits {
                continue;
            }
            // The pen points from its LEDs towards the tip, against increasing offsets.
            let towards_tip = model[0] - model[LED_COUNT - 1];
            if direction.is_some_and(|d| {
                d.dot(&towards_tip) < options.prior_min_cos * d.norm() * towards_tip.norm()
            }) {
                continue;
            }
            let Some(leds) = explained_leds(pair, options, crowded, &model, &clear_blob, &model)
            else {
                continue;
            };
            out.push(LineLabelling {
                crowded,
                leds,
                mismatch: (square / count as f64).sqrt(),
                // The crowded camera's blobs image LEDs this pose placed, not measured ones.
                from_ray: true,
            });
        }
    }
    out
}

/// The line `o + s e` (`|e| = 1`, in front of the centre) through the plane's rays `u` at
/// offsets `s`: the null vector of the rows `[-u.y, u.x, -u.y s, u.x s]` (least squares over four
/// rays). None when the rays do not fix one line, or put a spot behind the camera.
fn line_in_plane(spots: &[([f64; 2], f64)]) -> Option<([f64; 2], [f64; 2])> {
    let mut normal = Matrix4::<f64>::zeros();
    for &(u, s) in spots {
        let row = Vector4::new(-u[1], u[0], -u[1] * s, u[0] * s);
        normal += row * row.transpose();
    }
    let eigen = SymmetricEigen::new(normal);
    let mut by_value: Vec<usize> = (0..4).collect();
    by_value.sort_by(|&a, &b| eigen.eigenvalues[a].total_cmp(&eigen.eigenvalues[b]));
    // A second null direction: the rays fix no single line (fewer than three distinct rays).
    if eigen.eigenvalues[by_value[1]] <= 1e-9 * eigen.eigenvalues[by_value[3]].max(1e-300) {
        return None;
    }
    let x = eigen.eigenvectors.column(by_value[0]);
    let scale = x[2].hypot(x[3]);
    if scale.is_nan() || scale <= 1e-12 {
        return None;
    }
    let (mut o, mut e) = ([x[0] / scale, x[1] / scale], [x[2] / scale, x[3] / scale]);
    // The sign that puts the spots in front of the camera (positive depth along each ray).
    let depth = |o: &[f64; 2], e: &[f64; 2], (u, s): ([f64; 2], f64)| {
        (o[0] + s * e[0]) * u[0] + (o[1] + s * e[1]) * u[1]
    };
    if depth(&o, &e, spots[0]) < 0.0 {
        o = [-o[0], -o[1]];
        e = [-e[0], -e[1]];
    }
    spots
        .iter()
        .all(|&spot| depth(&o, &e, spot) > 0.0)
        .then_some((o, e))
}
