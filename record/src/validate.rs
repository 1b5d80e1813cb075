//! Checks of `meta.json` beyond its syntax: calibrations that describe cameras, a rig whose cameras stand
//! apart, a pen whose LEDs are in order (`docs/recording.md`, section "Validation").
//!
//! Whether the LED distances can be told apart depends on the tracker's matching tolerance; the host checks
//! that itself.

use crate::meta::{CalibratedCamera, Meta};

/// Smallest accepted distance between two camera centres, metres: below it stereo depth is meaningless
/// (at 1 m a 600 px focal length and a 1 cm baseline give 6 px of disparity, so one pixel of error is
/// already 17 % of the depth).
pub const MIN_BASELINE_M: f64 = 0.01;

/// Largest accepted deviation of `R Rᵀ` from the identity and of `det R` from +1 (per entry).
pub const ROTATION_TOLERANCE: f64 = 1e-6;

/// One field of `meta.json` that fails a check.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{field} = {value}: {reason}")]
pub struct MetaProblem {
    /// JSON path of the field, e.g. `rig.cameras[1].intrinsics.fx`.
    pub field: String,
    /// The value found, as text.
    pub value: String,
    /// What is wrong.
    pub reason: String,
}

fn problem(field: String, value: impl std::fmt::Debug, reason: impl Into<String>) -> MetaProblem {
    MetaProblem {
        field,
        value: format!("{value:?}"),
        reason: reason.into(),
    }
}

fn finite(field: String, v: f64) -> Result<(), MetaProblem> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(problem(field, v, "must be a finite number"))
    }
}

fn positive(field: String, v: f64, what: &str) -> Result<(), MetaProblem> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(problem(field, v, format!("{what} must be positive")))
    }
}

/// Checks one calibrated camera (`at` is its JSON path, e.g. `rig.cameras[1]`).
pub fn validate_camera(cam: &CalibratedCamera, at: &str) -> Result<(), MetaProblem> {
    let m = &cam.intrinsics;
    let f = |name: &str| format!("{at}.intrinsics.{name}");
    for (name, v) in [("width", m.width), ("height", m.height)] {
        if v == 0 {
            return Err(problem(f(name), v, "image size must be positive"));
        }
    }
    positive(f("fx"), m.fx, "focal length")?;
    positive(f("fy"), m.fy, "focal length")?;
    for (name, v) in [("cx", m.cx), ("cy", m.cy)] {
        finite(f(name), v)?;
    }
    for (name, v) in [
        ("k1", m.k1),
        ("k2", m.k2),
        ("p1", m.p1),
        ("p2", m.p2),
        ("k3", m.k3),
    ] {
        if !v.is_finite() {
            return Err(problem(f(name), v, "distortion coefficient must be finite"));
        }
    }
    let r = &cam.extrinsics.rotation;
    let rot = format!("{at}.extrinsics.rotation");
    if r.iter().flatten().any(|v| !v.is_finite()) {
        return Err(problem(rot, r, "rotation entries must be finite"));
    }
    let mut worst = 0.0f64;
    for i in 0..3 {
        for j in 0..3 {
            let dot: f64 = (0..3).map(|k| r[i][k] * r[j][k]).sum();
            worst = worst.max((dot - f64::from(u8::from(i == j))).abs());
        }
    }
    if worst > ROTATION_TOLERANCE {
        return Err(problem(
            rot,
            r,
            format!("not a rotation: R Rᵀ differs from the identity by {worst:.3e} (tolerance {ROTATION_TOLERANCE:e})"),
        ));
    }
    let det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
        - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
        + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
    if (det - 1.0).abs() > ROTATION_TOLERANCE {
        return Err(problem(
            rot,
            r,
            format!("not a rotation: determinant {det:.6} (a reflection when -1), must be +1"),
        ));
    }
    let t = &cam.extrinsics.translation_m;
    if t.iter().any(|v| !v.is_finite()) {
        return Err(problem(
            format!("{at}.extrinsics.translation_m"),
            t,
            "translation must be finite",
        ));
    }
    Ok(())
}

impl Meta {
    /// Checks every calibration (positive finite focal lengths, finite principal point and distortion, a
    /// proper rotation within [`ROTATION_TOLERANCE`], finite translation), the baseline between every two
    /// cameras (at least [`MIN_BASELINE_M`]), the camera streams (a calibration per stream, distinct ids,
    /// positive rate), the pen (LED positions finite, `0` first and strictly increasing; tip offset finite
    /// and not negative), the scale factors (finite) and the link (positive baud and sample rate).
    pub fn validate(&self) -> Result<(), MetaProblem> {
        let cams = &self.rig.cameras;
        for (i, cam) in cams.iter().enumerate() {
            validate_camera(cam, &format!("rig.cameras[{i}]"))?;
        }
        for (j, b) in cams.iter().enumerate() {
            for (i, a) in cams.iter().enumerate().take(j) {
                let (ca, cb) = (a.extrinsics.centre_world(), b.extrinsics.centre_world());
                let d = (0..3).map(|k| (ca[k] - cb[k]).powi(2)).sum::<f64>().sqrt();
                if d < MIN_BASELINE_M {
                    return Err(problem(
                        format!("rig.cameras[{j}].extrinsics.translation_m"),
                        b.extrinsics.translation_m,
                        format!(
                            "camera {j} stands {d:.4} m from camera {i}; the baseline must be at least {MIN_BASELINE_M} m"
                        ),
                    ));
                }
            }
        }
        for (k, s) in self.cameras.iter().enumerate() {
            if usize::from(s.id) >= cams.len() {
                return Err(problem(
                    format!("cameras[{k}].id"),
                    s.id,
                    format!(
                        "no calibration for this camera (rig.cameras has {})",
                        cams.len()
                    ),
                ));
            }
            if self.cameras[..k].iter().any(|o| o.id == s.id) {
                return Err(problem(format!("cameras[{k}].id"), s.id, "listed twice"));
            }
            positive(
                format!("cameras[{k}].nominal_rate_hz"),
                s.nominal_rate_hz,
                "frame rate",
            )?;
            let period = 1.0 / s.nominal_rate_hz;
            for (field, v) in [("exposure_s", s.exposure_s), ("readout_s", s.readout_s)] {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(problem(
                        format!("cameras[{k}].{field}"),
                        v,
                        "must be a finite time of at least 0 s",
                    ));
                }
                if v > period {
                    return Err(problem(
                        format!("cameras[{k}].{field}"),
                        v,
                        format!("must fit in one frame period ({period:.4} s)"),
                    ));
                }
            }
            for (field, v) in [
                ("exposure_jitter_s", s.exposure_jitter_s),
                ("timestamp_noise_s", s.timestamp_noise_s),
            ] {
                // Beyond a quarter period the frames' order and count are no longer readable from their times.
                if !(v.is_finite() && v >= 0.0 && v < 0.25 * period) {
                    return Err(problem(
                        format!("cameras[{k}].{field}"),
                        v,
                        format!("must be a standard deviation from 0 s to a quarter frame period ({:.4} s)", 0.25 * period),
                    ));
                }
            }
        }
        let l = &self.pen.led_positions_m;
        for (i, &v) in l.iter().enumerate() {
            finite(format!("pen.led_positions_m[{i}]"), v)?;
        }
        if l.first().is_some_and(|&v| v != 0.0) {
            return Err(problem(
                "pen.led_positions_m[0]".into(),
                l[0],
                "LED 1's position must be 0 (positions are measured from LED 1)",
            ));
        }
        if let Some(i) = (1..l.len()).find(|&i| l[i] <= l[i - 1]) {
            return Err(problem(
                format!("pen.led_positions_m[{i}]"),
                l[i],
                format!(
                    "LED positions must increase strictly (previous {})",
                    l[i - 1]
                ),
            ));
        }
        let tip = self.pen.tip_offset_m;
        if !(tip.is_finite() && tip >= 0.0) {
            return Err(problem(
                "pen.tip_offset_m".into(),
                tip,
                "must be finite and not negative (the tip lies ahead of LED 1)",
            ));
        }
        for (k, &v) in self.pen.imu_position_m.iter().flatten().enumerate() {
            finite(format!("pen.imu_position_m[{k}]"), v)?;
        }
        let s = &self.scale_factors;
        for (name, v) in [
            ("accel_mps2_per_count", s.accel_mps2_per_count),
            ("gyro_radps_per_count", s.gyro_radps_per_count),
            ("mag_tesla_per_count", s.mag_tesla_per_count),
        ] {
            finite(format!("scale_factors.{name}"), v)?;
        }
        for (name, v) in [
            ("baud", self.link.baud),
            ("sample_rate_hz", self.link.sample_rate_hz),
        ] {
            if v == 0 {
                return Err(problem(format!("link.{name}"), v, "must be positive"));
            }
        }
        Ok(())
    }
}
