//! Pen-tip pivot calibration: the user holds the tip still on a point and rotates the pen; the
//! tip offset and the pivot point are fitted by linear least squares, and the residual is reported
//! in millimetres (the standard pivot calibration of tracked tools, with a coverage check).
//!
//! - [`pivot_axis`]: the optical case. Collinear LEDs give a reference point `p_i` (e.g. LED 1)
//!   and the unit axis `v_i` (towards the tip) per frame; the tip lies on the axis, so
//!   `p_i + T v_i = c` with unknown scalar offset `T` and pivot `c` (4 unknowns).
//! - [`pivot_full`]: with a full orientation `R_i` (e.g. fused IMU + vision), the tip in the pen
//!   frame `x` satisfies `R_i x + p_i = c` (6 unknowns, the classic pivot calibration).
//!
//! Both solve `[M_i, -I] [x; c] = -p_i` stacked over all poses by SVD, and refuse with
//! [`PivotError::InsufficientRotation`] when the poses span too small a cone of directions.

use nalgebra::{DMatrix, DVector, UnitQuaternion, Vector3};
use thiserror::Error;

/// Why a pivot fit failed.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum PivotError {
    /// Too few poses for the unknowns.
    #[error("need at least {0} poses")]
    TooFewPoses(usize),
    /// The pen was not rotated enough (largest angle between axes, radians).
    #[error("pen rotated over only {0:.3} rad; rotate it more")]
    InsufficientRotation(f64),
    /// NaN/inf input or a failed solve.
    #[error("invalid input or singular system")]
    Invalid,
}

/// Result of the axis-only fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PivotAxisFit {
    /// Tip offset from the reference point along the axis, metres (`T` when the reference is LED 1).
    pub tip_offset: f64,
    /// Pivot point, world frame.
    pub pivot: Vector3<f64>,
    /// RMS distance of the per-pose tip from the pivot, millimetres.
    pub rms_mm: f64,
    /// Largest per-pose distance, millimetres.
    pub max_mm: f64,
    /// Largest angle between two pose axes, radians (coverage).
    pub spread_rad: f64,
}

/// Result of the full-orientation fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PivotFullFit {
    /// Tip position in the pen frame, metres.
    pub tip_in_pen: Vector3<f64>,
    /// Pivot point, world frame.
    pub pivot: Vector3<f64>,
    /// RMS residual, millimetres.
    pub rms_mm: f64,
    /// Largest residual, millimetres.
    pub max_mm: f64,
    /// Largest angle between two pose x-axes, radians (coverage).
    pub spread_rad: f64,
}

/// Minimum angular spread of the poses accepted by the fits (radians, about 11 degrees).
pub const MIN_SPREAD_RAD: f64 = 0.2;

/// Fits the tip offset along the axis and the pivot from `(reference point, unit axis)` pairs.
pub fn pivot_axis(poses: &[(Vector3<f64>, Vector3<f64>)]) -> Result<PivotAxisFit, PivotError> {
    if poses.len() < 3 {
        return Err(PivotError::TooFewPoses(3));
    }
    let axes: Vec<Vector3<f64>> = poses
        .iter()
        .map(|(_, v)| v.try_normalize(1e-12))
        .collect::<Option<_>>()
        .ok_or(PivotError::Invalid)?;
    let spread = spread(&axes);
    if spread < MIN_SPREAD_RAD {
        return Err(PivotError::InsufficientRotation(spread));
    }
    let mut a = DMatrix::zeros(3 * poses.len(), 4);
    let mut b = DVector::zeros(3 * poses.len());
    for (i, ((p, _), v)) in poses.iter().zip(&axes).enumerate() {
        for r in 0..3 {
            a[(3 * i + r, 0)] = v[r];
            a[(3 * i + r, 1 + r)] = -1.0;
            b[3 * i + r] = -p[r];
        }
    }
    let x = solve(a, b)?;
    let (t, c) = (x[0], Vector3::new(x[1], x[2], x[3]));
    let res: Vec<f64> = poses
        .iter()
        .zip(&axes)
        .map(|((p, _), v)| (p + v * t - c).norm())
        .collect();
    let (rms_mm, max_mm) = stats_mm(&res);
    Ok(PivotAxisFit {
        tip_offset: t,
        pivot: c,
        rms_mm,
        max_mm,
        spread_rad: spread,
    })
}

/// Fits the tip in the pen frame and the pivot from `(world-from-pen rotation, reference point)`.
pub fn pivot_full(
    poses: &[(UnitQuaternion<f64>, Vector3<f64>)],
) -> Result<PivotFullFit, PivotError> {
    if poses.len() < 3 {
        return Err(PivotError::TooFewPoses(3));
    }
    let axes: Vec<Vector3<f64>> = poses.iter().map(|(q, _)| q * Vector3::x()).collect();
    let spread = spread(&axes);
    if spread < MIN_SPREAD_RAD {
        return Err(PivotError::InsufficientRotation(spread));
    }
    let mut a = DMatrix::zeros(3 * poses.len(), 6);
    let mut b = DVector::zeros(3 * poses.len());
    for (i, (q, p)) in poses.iter().enumerate() {
        let r = q.to_rotation_matrix();
        for row in 0..3 {
            for col in 0..3 {
                a[(3 * i + row, col)] = r[(row, col)];
            }
            a[(3 * i + row, 3 + row)] = -1.0;
            b[3 * i + row] = -p[row];
        }
    }
    let x = solve(a, b)?;
    let (tip, c) = (
        Vector3::new(x[0], x[1], x[2]),
        Vector3::new(x[3], x[4], x[5]),
    );
    let res: Vec<f64> = poses
        .iter()
        .map(|(q, p)| (q * tip + p - c).norm())
        .collect();
    let (rms_mm, max_mm) = stats_mm(&res);
    Ok(PivotFullFit {
        tip_in_pen: tip,
        pivot: c,
        rms_mm,
        max_mm,
        spread_rad: spread,
    })
}

fn solve(a: DMatrix<f64>, b: DVector<f64>) -> Result<DVector<f64>, PivotError> {
    if !(a.iter().all(|v| v.is_finite()) && b.iter().all(|v| v.is_finite())) {
        return Err(PivotError::Invalid);
    }
    let svd = a.svd(true, true);
    let max_s = svd.singular_values.max();
    let x = svd
        .solve(&b, max_s * 1e-9)
        .map_err(|_| PivotError::Invalid)?;
    if x.iter().all(|v| v.is_finite()) {
        Ok(x)
    } else {
        Err(PivotError::Invalid)
    }
}

fn spread(axes: &[Vector3<f64>]) -> f64 {
    let mut best: f64 = 0.0;
    for (i, a) in axes.iter().enumerate() {
        for b in &axes[i + 1..] {
            best = best.max(a.angle(b));
        }
    }
    best
}

fn stats_mm(res: &[f64]) -> (f64, f64) {
    let rms = (res.iter().map(|r| r * r).sum::<f64>() / res.len() as f64).sqrt();
    (rms * 1e3, res.iter().fold(0.0f64, |m, r| m.max(*r)) * 1e3)
}

/// The `(LED 1 on the axis, unit axis)` pose of every vision sample of a tracked pivot gesture:
/// each labelled LED `k` gives LED 1 at `p_k + l_k v` (LED `k` sits `l_k` behind LED 1 along the
/// axis `v`, which points towards the tip), averaged over the labelled LEDs.
pub fn axis_poses(
    samples: &[crate::track::TrackSample],
    pen: &crate::track::PenGeometry,
) -> Vec<(Vector3<f64>, Vector3<f64>)> {
    samples
        .iter()
        .filter(|s| matches!(s.quality, crate::track::TrackQuality::Vision { .. }))
        .filter_map(|s| {
            let v = Vector3::from(s.direction?).try_normalize(1e-12)?;
            let led1: Vec<Vector3<f64>> = s
                .leds
                .iter()
                .zip(&pen.led_offsets)
                .filter_map(|(p, l)| p.map(|p| Vector3::from(p) + v * *l))
                .collect();
            (led1.len() >= 2).then(|| {
                let mean = led1.iter().sum::<Vector3<f64>>() / led1.len() as f64;
                (mean, v)
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    #[test]
    fn axis_poses_put_led_1_on_the_axis_from_any_labelled_leds() {
        use crate::track::{PenGeometry, TrackQuality, TrackSample};
        let pen = PenGeometry::thesis();
        let v = Vector3::new(0.2, -0.3, 0.9).normalize();
        let led1 = Vector3::new(0.1, 0.05, 0.7);
        let at = |k: usize| Some((led1 - v * pen.led_offsets[k]).into());
        let sample = |leds: [Option<[f64; 3]>; 4], quality| TrackSample {
            t_ns: 0,
            tip: None,
            raw_tip: None,
            direction: Some(v.into()),
            leds,
            labels: [None; 4],
            quality,
            confidence: 1.0,
            interference: 0,
            tip_sigma_m: None,
            stroke_tip: None,
            stroke_tip_sigma_m: None,
        };
        let samples = [
            sample([None, at(1), None, at(3)], TrackQuality::Vision { leds: 2 }),
            sample(
                [at(0), at(1), at(2), at(3)],
                TrackQuality::Vision { leds: 4 },
            ),
            sample([None, None, at(2), None], TrackQuality::Vision { leds: 1 }),
            sample([at(0), at(1), None, None], TrackQuality::DeadReckoned),
        ];
        let p = axis_poses(&samples, &pen);
        assert_eq!(p.len(), 2, "one-LED and non-vision samples are skipped");
        for (q, axis) in p {
            assert!((q - led1).norm() < 1e-12 && (axis - v).norm() < 1e-12);
        }
    }

    fn poses(
        rng: &mut SplitMix64,
        tip_in_pen: Vector3<f64>,
        pivot: Vector3<f64>,
        cone: f64,
        noise_m: f64,
        noise_rad: f64,
    ) -> Vec<(UnitQuaternion<f64>, Vector3<f64>)> {
        let base =
            UnitQuaternion::rotation_between(&Vector3::x(), &Vector3::new(0.2, 1.0, 0.3)).unwrap();
        (0..60)
            .map(|_| {
                let tilt = UnitQuaternion::from_euler_angles(
                    rng.uniform(-3.0, 3.0),
                    rng.uniform(-cone, cone),
                    rng.uniform(-cone, cone),
                );
                let q = base * tilt;
                let p = pivot - q * tip_in_pen;
                let qn = q * UnitQuaternion::from_scaled_axis(
                    Vector3::new(rng.gaussian(), rng.gaussian(), rng.gaussian()) * noise_rad,
                );
                let pn = p + Vector3::new(rng.gaussian(), rng.gaussian(), rng.gaussian()) * noise_m;
                (qn, pn)
            })
            .collect()
    }

    #[test]
    fn axis_fit_recovers_the_tip_offset() {
        let mut rng = SplitMix64::new(1);
        let pivot = Vector3::new(0.05, 0.1, 0.7);
        let ps = poses(
            &mut rng,
            Vector3::new(0.021, 0.0, 0.0),
            pivot,
            0.5,
            0.0003,
            0.002,
        );
        let axis: Vec<_> = ps.iter().map(|(q, p)| (*p, q * Vector3::x())).collect();
        let fit = pivot_axis(&axis).unwrap();
        assert!((fit.tip_offset - 0.021).abs() < 0.001, "{}", fit.tip_offset);
        assert!((fit.pivot - pivot).norm() < 0.001);
        assert!(fit.rms_mm < 1.0 && fit.rms_mm > 0.1, "{}", fit.rms_mm);
    }

    #[test]
    fn full_fit_recovers_an_off_axis_tip() {
        let mut rng = SplitMix64::new(2);
        let pivot = Vector3::new(-0.1, 0.0, 0.9);
        let tip = Vector3::new(0.03, 0.004, -0.002);
        let fit = pivot_full(&poses(&mut rng, tip, pivot, 0.5, 0.0002, 0.001)).unwrap();
        assert!((fit.tip_in_pen - tip).norm() < 0.001, "{}", fit.tip_in_pen);
        assert!(fit.rms_mm < 0.6);
        let exact = pivot_full(&poses(&mut rng, tip, pivot, 0.5, 0.0, 0.0)).unwrap();
        assert!((exact.tip_in_pen - tip).norm() < 1e-9 && exact.rms_mm < 1e-6);
    }

    #[test]
    fn too_little_rotation_is_refused() {
        let mut rng = SplitMix64::new(3);
        let ps = poses(
            &mut rng,
            Vector3::new(0.02, 0.0, 0.0),
            Vector3::zeros(),
            0.02,
            0.0,
            0.0,
        );
        let axis: Vec<_> = ps.iter().map(|(q, p)| (*p, q * Vector3::x())).collect();
        assert!(matches!(
            pivot_axis(&axis),
            Err(PivotError::InsufficientRotation(_))
        ));
        assert_eq!(pivot_axis(&axis[..2]), Err(PivotError::TooFewPoses(3)));
    }
}
