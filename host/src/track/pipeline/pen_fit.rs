//! The pen's line fitted to every image of a pen-line labelling ([`super::pen_line`]).
//!
//! A pen-line labelling locates the LEDs seen apart in the clear camera where their rays meet
//! one pen plane of the crowded camera. That plane comes from blob centres or a merged blob's
//! ray, and says nothing of how well it is known: treated as a stereo pair, its points got the
//! covariance of two measured spots (tens of micrometres at the tip) where the pen was off by
//! millimetres (webcam seed 3, the boundary stroke's turn). This fit uses what the images
//! measure, each with its own uncertainty, in one least-squares pose of the rigid pen (FIRES
//! thesis, §4.1.2: the LEDs lie on one line at known offsets):
//!
//! * each LED seen apart in the clear camera projects onto its spot;
//! * each LED with a spot of its own in the crowded camera projects onto it;
//! * each merged blob of the crowded camera is the intensity-weighted centroid of the LEDs it
//!   covers, which lies on the pen between them: it is the projection of the pen's point at an
//!   offset that is a parameter, bounded by the covered LEDs' offsets (their brightnesses are
//!   unknown), and its centroid is given half a spot's weight.
//!
//! A labelling found about a compact blob's ray (`pipeline/pen_ray.rs`) does not know which LED
//! each crowded blob images: every crowded blob is then a point of the pen at a free offset
//! between its end LEDs'.
//!
//! Each spot's standard deviation is the tracker's pixel noise, widened for a blob moved to the
//! pair's time by the error its image acceleration predicts ([`super::align::extrapolation_error`]).
//! The unknowns are the pen's point at offset zero, its direction (two angles) and the merged
//! blobs' offsets, solved by Levenberg-Marquardt from the labelling's points. Each LED's
//! covariance is the fit's, carried through `p = o + s e` and multiplied by the number of LEDs:
//! they share the fit's errors, and the tip, which treats them as independent, would otherwise
//! take their count's worth of precision.

use super::pen_line::{normals, other, LineLabelling, LineOptions};
use super::pen_ray::across;
use super::safety::PairView;
use crate::stereo::CameraId;
use crate::track::pen::LED_COUNT;
use nalgebra::{DMatrix, DVector, Matrix3, SMatrix, Vector3};

/// Levenberg-Marquardt iterations; the fit starts within millimetres of its solution.
const FIT_STEPS: usize = 12;

/// A merged blob's centroid weighs half a spot of its own: the merged spots' brightnesses
/// differ (which its offset absorbs) and its outline is wider.
const MERGED_WEIGHT: f64 = 0.5;

/// Largest RMS residual of a fit, in standard deviations: every spot must be where the pen puts
/// it.
const FIT_MAX_RMS_SIGMA: f64 = 3.0;

/// One image measurement of the fit.
#[derive(Debug, Clone, Copy)]
struct Spot {
    camera: CameraId,
    /// Its normalised image point.
    target: [f64; 2],
    /// Pixels per normalised unit over the spot's standard deviation (and weight).
    scale: f64,
    /// The LED's offset, or the merged blob's offset parameter (index into the extra ones).
    at: Offset,
}

#[derive(Debug, Clone, Copy)]
enum Offset {
    Led(f64),
    Merged(usize),
}

/// `l` with its points on the pen's line fitted to every image it has and their covariances (see
/// the module doc). None when the fit does not explain the images.
pub(super) fn fit_pen_line(
    pair: &PairView<'_>,
    options: &LineOptions,
    mut l: LineLabelling,
) -> Option<LineLabelling> {
    let (crowded, clear) = (l.crowded, other(l.crowded));
    let offsets = &options.led_offsets;
    let seen: Vec<(usize, Vector3<f64>)> = (0..LED_COUNT)
        .filter_map(|k| l.leds[k].map(|led| (k, led.point)))
        .collect();
    let (first, last) = (seen.first()?, seen.last()?);
    if seen.len() < 2 {
        return None;
    }
    let mut e = ((last.1 - first.1) / (offsets[last.0] - offsets[first.0])).try_normalize(1e-12)?;
    let mut origin = seen
        .iter()
        .map(|&(k, p)| p - e * offsets[k])
        .sum::<Vector3<f64>>()
        / seen.len() as f64;
    let sigma = |camera: CameraId, blob: usize| -> f64 {
        options
            .pixel_sigma
            .max(1e-3)
            .hypot(pair.points.move_error_px(camera, blob))
    };
    let focal = |camera: CameraId| pair.rig.camera(camera).focal_px();
    let mut spots = Vec::new();
    // Merged blobs' offset bounds: (lowest, highest).
    let mut merged: Vec<(f64, f64)> = Vec::new();
    for &(k, _) in &seen {
        let led = l.leds[k]?;
        spots.push(Spot {
            camera: clear,
            target: *normals(pair, clear).get(led.clear_blob)?,
            scale: focal(clear) / sigma(clear, led.clear_blob),
            at: Offset::Led(offsets[k]),
        });
        // An LED hidden in the crowded camera has its clear spot only.
        let Some(blob) = led.crowded_blob else {
            continue;
        };
        let covering: Vec<usize> = seen
            .iter()
            .filter(|&&(j, _)| l.leds[j].is_some_and(|o| o.crowded_blob == Some(blob)))
            .map(|&(j, _)| j)
            .collect();
        let target = *normals(pair, crowded).get(blob)?;
        let scale = focal(crowded) / sigma(crowded, blob);
        if covering[0] != k {
            continue;
        }
        if covering.len() == 1 && !l.from_ray {
            spots.push(Spot {
                camera: crowded,
                target,
                scale,
                at: Offset::Led(offsets[k]),
            });
            continue;
        }
        // The LEDs the blob may image, by index: about a ray, which LED a crowded blob images is
        // not known (they lie pixels apart), so any of them; otherwise those it covers and the
        // neighbours beyond them that the clear camera does not see.
        let (mut first, mut last) = (covering[0], covering[covering.len() - 1]);
        if l.from_ray {
            (first, last) = (0, LED_COUNT - 1);
        }
        while first > 0 && l.leds[first - 1].is_none() {
            first -= 1;
        }
        while last + 1 < LED_COUNT && l.leds[last + 1].is_none() {
            last += 1;
        }
        spots.push(Spot {
            camera: crowded,
            target,
            scale: scale * MERGED_WEIGHT,
            at: Offset::Merged(merged.len()),
        });
        merged.push((
            offsets[first].min(offsets[last]),
            offsets[first].max(offsets[last]),
        ));
    }
    let mut extra: Vec<f64> = merged.iter().map(|m| 0.5 * (m.0 + m.1)).collect();
    let n_params = 5 + extra.len();
    let rows = 2 * spots.len();
    if rows <= n_params {
        return None;
    }
    let view = |camera: CameraId, p: &Vector3<f64>| -> Option<[f64; 2]> {
        let q = match camera {
            CameraId::Left => *p,
            CameraId::Right => pair.rig.to_right(p),
        };
        (q.z > 0.0).then(|| [q.x / q.z, q.y / q.z])
    };
    let residuals = |origin: &Vector3<f64>, e: &Vector3<f64>, extra: &[f64]| {
        let mut r = DVector::zeros(rows);
        for (i, s) in spots.iter().enumerate() {
            let at = match s.at {
                Offset::Led(o) => o,
                Offset::Merged(m) => extra[m],
            };
            let m = view(s.camera, &(origin + e * at))?;
            r[2 * i] = s.scale * (m[0] - s.target[0]);
            r[2 * i + 1] = s.scale * (m[1] - s.target[1]);
        }
        Some(r)
    };
    // A step of the parameters: the origin's shift, the direction's turn about two axes across
    // it, the merged blobs' offsets (kept between their LEDs').
    let apply = |origin: &Vector3<f64>, e: &Vector3<f64>, extra: &[f64], d: &[f64]| {
        let (b1, b2) = across(e);
        let o = origin + Vector3::new(d[0], d[1], d[2]);
        let dir = (e + b1 * d[3] + b2 * d[4]).normalize();
        let x: Vec<f64> = extra
            .iter()
            .zip(&merged)
            .enumerate()
            .map(|(m, (v, &(lo, hi)))| (v + d[5 + m]).clamp(lo, hi))
            .collect();
        (o, dir, x)
    };
    let jacobian = |origin: &Vector3<f64>, e: &Vector3<f64>, extra: &[f64], r: &DVector<f64>| {
        let h = 1e-7;
        let mut jac = DMatrix::zeros(rows, n_params);
        for c in 0..n_params {
            let mut d = vec![0.0; n_params];
            // Offsets at their bound are perturbed inwards.
            d[c] = if c >= 5 && extra[c - 5] + h > merged[c - 5].1 {
                -h
            } else {
                h
            };
            let (o, dir, x) = apply(origin, e, extra, &d);
            let rp = residuals(&o, &dir, &x)?;
            jac.set_column(c, &((rp - r) / d[c]));
        }
        Some(jac)
    };
    let mut r = residuals(&origin, &e, &extra)?;
    let mut lambda = 1e-3;
    for _ in 0..FIT_STEPS {
        let jac = jacobian(&origin, &e, &extra, &r)?;
        let jtj = jac.transpose() * &jac;
        let jtr = jac.transpose() * &r;
        let mut improved = false;
        for _ in 0..8 {
            let mut a = jtj.clone();
            for c in 0..n_params {
                a[(c, c)] += lambda * jtj[(c, c)].max(1e-12);
            }
            let Some(step) = a.cholesky().map(|ch| ch.solve(&(-&jtr))) else {
                lambda *= 10.0;
                continue;
            };
            let (o, dir, x) = apply(&origin, &e, &extra, step.as_slice());
            if let Some(rn) = residuals(&o, &dir, &x) {
                if rn.norm_squared() < r.norm_squared() {
                    (origin, e, extra, r) = (o, dir, x, rn);
                    lambda = (lambda * 0.1).max(1e-9);
                    improved = true;
                    break;
                }
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    if (r.norm_squared() / rows as f64).sqrt() > FIT_MAX_RMS_SIGMA {
        return None;
    }
    let jac = jacobian(&origin, &e, &extra, &r)?;
    let params = (jac.transpose() * &jac).try_inverse()?;
    let p5 = SMatrix::<f64, 5, 5>::from_fn(|i, j| params[(i, j)]);
    let (b1, b2) = across(&e);
    let shared = seen.len() as f64;
    for (k, led) in l.leds.iter_mut().enumerate() {
        if let Some(led) = led {
            led.point = origin + e * offsets[k];
            let mut g = SMatrix::<f64, 3, 5>::zeros();
            g.fixed_view_mut::<3, 3>(0, 0)
                .copy_from(&Matrix3::identity());
            g.set_column(3, &(b1 * offsets[k]));
            g.set_column(4, &(b2 * offsets[k]));
            led.covariance = Some(g * p5 * g.transpose() * shared);
        }
    }
    Some(l)
}
