//! Accuracy and health of a replay, measured against the recording's ground truth when it has one.
//!
//! Tip errors compare each tracked tip with the true tip interpolated at the sample's time (exposure truth of
//! the left camera, the frame the tracker's samples are timed by). A *mislabel* is an accepted LED label whose left or right
//! image blob is not the image of that LED in that frame (see [`label_errors`]): the wrong-identity error the
//! thesis's distance test exists to prevent, checked in the images so that a depth error is not mistaken
//! for one.

use std::collections::HashMap;

use fires_record::ExposureTruth;
use serde::Serialize;

use super::run::ReplayOutput;
use crate::track::fusion::WorldReference;
use crate::track::pipeline::TrackQuality;

/// A labelled blob farther than this from the true image of its LED is not that LED's image, pixels.
pub const MISLABEL_PX: f64 = 3.0;

/// Tip accuracy figures (present when the recording has ground truth).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Accuracy {
    /// Root mean square tip error, millimetres.
    pub tip_rmse_mm: f64,
    /// 95th percentile tip error, millimetres.
    pub tip_p95_mm: f64,
    /// Fraction of tracked frames with the tip within 2 mm.
    pub frac_within_2mm: f64,
    /// The same over frames whose tip is at most 1 m from the left camera.
    pub frac_within_2mm_le_1m: f64,
    /// Frames (tracked, with truth) at most 1 m from the left camera.
    pub frames_le_1m: usize,
    /// Accepted LED labels that name the wrong LED.
    pub mislabels: usize,
    /// Accepted LED labels checked.
    pub labels_checked: usize,
}

/// Interpolates the true tip and LEDs at `t_ns` from time-sorted exposure truth of one camera.
pub fn truth_at(truth: &[&ExposureTruth], t_ns: u64) -> Option<([f64; 3], Vec<[f64; 3]>)> {
    let i = truth.partition_point(|e| e.exposure_time_ns <= t_ns);
    let (a, b) = (
        truth.get(i.checked_sub(1)?)?,
        truth.get(i).unwrap_or(truth.get(i - 1)?),
    );
    let span = b.exposure_time_ns.saturating_sub(a.exposure_time_ns);
    // Frames are matched on exposure times: refuse to extrapolate beyond one frame gap.
    if t_ns.saturating_sub(a.exposure_time_ns) > span.max(1) * 2 {
        return None;
    }
    let w = if span == 0 {
        0.0
    } else {
        (t_ns - a.exposure_time_ns) as f64 / span as f64
    };
    let lerp = |p: &[f64; 3], q: &[f64; 3]| [0, 1, 2].map(|k| p[k] + w * (q[k] - p[k]));
    let tip = lerp(&a.pose.tip_m, &b.pose.tip_m);
    let leds = a
        .pose
        .leds_m
        .iter()
        .zip(&b.pose.leds_m)
        .map(|(p, q)| lerp(p, q))
        .collect();
    Some((tip, leds))
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Percentile (0..=1) of a sorted slice.
fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let i = ((sorted.len() - 1) as f64 * q).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

/// Counts accepted LED labels whose left or right blob is not the image of that LED: farther than
/// [`MISLABEL_PX`] from where the truth says the LED appeared in that frame, or the LED was not visible at all.
/// Returns (mislabels, labels checked).
pub fn label_errors(out: &ReplayOutput, truth: &[ExposureTruth]) -> (usize, usize) {
    let by_frame: HashMap<(u8, u64), &ExposureTruth> =
        truth.iter().map(|e| ((e.camera, e.index), e)).collect();
    let is_image_of = |cam: u8, frame: u64, led: usize, px: [f64; 2]| -> Option<bool> {
        let t = by_frame.get(&(cam, frame))?;
        Some(
            t.leds
                .get(led)?
                .pixel
                .is_some_and(|p| (p[0] - px[0]).hypot(p[1] - px[1]) <= MISLABEL_PX),
        )
    };
    let (mut wrong, mut checked) = (0, 0);
    for lp in out.label_pixels.iter().flatten() {
        for (led, pair) in lp.px.iter().enumerate() {
            let Some((l, r)) = pair else { continue };
            let (Some(ok_l), Some(ok_r)) = (
                is_image_of(0, lp.left_frame, led, *l),
                is_image_of(1, lp.right_frame, led, *r),
            ) else {
                continue;
            };
            checked += 1;
            if !(ok_l && ok_r) {
                wrong += 1;
            }
        }
    }
    (wrong, checked)
}

/// Tip error of every vision-tracked sample that has truth: (sample time ns, error metres), in sample order.
pub fn tip_errors(out: &ReplayOutput, truth: &[ExposureTruth]) -> Vec<(u64, f64)> {
    let mut left_truth: Vec<&ExposureTruth> = truth.iter().filter(|e| e.camera == 0).collect();
    left_truth.sort_by_key(|e| e.exposure_time_ns);
    out.samples
        .iter()
        .filter_map(|s| match (s.tip, s.quality) {
            (Some(tip), TrackQuality::Vision { .. }) => {
                let (tip_true, _) = truth_at(&left_truth, s.t_ns)?;
                Some((s.t_ns, dist(&tip, &tip_true)))
            }
            _ => None,
        })
        .collect()
}

/// Tip accuracy and label correctness of the replay against exposure truth (world = left camera frame).
pub fn accuracy(out: &ReplayOutput, truth: &[ExposureTruth]) -> Accuracy {
    let mut left_truth: Vec<&ExposureTruth> = truth.iter().filter(|e| e.camera == 0).collect();
    left_truth.sort_by_key(|e| e.exposure_time_ns);
    let mut errors = Vec::new();
    let mut near = (0usize, 0usize);
    for s in &out.samples {
        let Some((tip_true, _)) = truth_at(&left_truth, s.t_ns) else {
            continue;
        };
        if let (Some(tip), TrackQuality::Vision { .. }) = (s.tip, s.quality) {
            let e = dist(&tip, &tip_true);
            errors.push(e);
            if dist(&tip_true, &[0.0; 3]) <= 1.0 {
                near.0 += 1;
                near.1 += usize::from(e <= 0.002);
            }
        }
    }
    let (mislabels, checked) = label_errors(out, truth);
    let n = errors.len();
    let rmse = if n == 0 {
        0.0
    } else {
        (errors.iter().map(|e| e * e).sum::<f64>() / n as f64).sqrt()
    };
    errors.sort_by(f64::total_cmp);
    let within = errors.iter().filter(|e| **e <= 0.002).count();
    Accuracy {
        tip_rmse_mm: rmse * 1e3,
        tip_p95_mm: percentile(&errors, 0.95) * 1e3,
        frac_within_2mm: if n == 0 {
            0.0
        } else {
            within as f64 / n as f64
        },
        frac_within_2mm_le_1m: if near.0 == 0 {
            0.0
        } else {
            near.1 as f64 / near.0 as f64
        },
        frames_le_1m: near.0,
        mislabels,
        labels_checked: checked,
    }
}

/// Where the world reference came from and, when it was estimated and the recording has ground
/// truth, how far the estimate is from the truth.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct WorldReport {
    /// "truth", "configured" or "estimated".
    pub source: String,
    /// Seconds from the first IMU sample to the first accepted estimate.
    pub accepted_after_s: Option<f64>,
    /// Axis pairs behind the final estimate (inliers / all).
    pub pairs: Option<[usize; 2]>,
    /// RMS residual of the final fit, degrees.
    pub residual_rms_deg: Option<f64>,
    /// Standard deviation of the worst-determined axis of the final fit, degrees.
    pub worst_axis_sigma_deg: Option<f64>,
    /// Angle between the estimated and the true "up", degrees.
    pub up_error_deg: Option<f64>,
    /// Angle between the estimated and the true magnetic north (horizontal), degrees.
    pub heading_error_deg: Option<f64>,
}

/// The world-reference part of the report.
pub fn world_report(out: &ReplayOutput, truth: Option<&WorldReference>) -> WorldReport {
    let mut r = WorldReport {
        source: out.world_reference.to_string(),
        ..WorldReport::default()
    };
    let Some((t_accept, fit)) = &out.world_fit else {
        return r;
    };
    let t0 = out.imu.samples.first().map_or(*t_accept, |s| s.t_ns);
    r.accepted_after_s = Some(t_accept.saturating_sub(t0) as f64 / 1e9);
    r.pairs = Some([fit.pairs, fit.candidates]);
    r.residual_rms_deg = Some(fit.residual_rms.to_degrees());
    r.worst_axis_sigma_deg = Some(fit.worst_axis_sigma.to_degrees());
    if let Some(t) = truth {
        let up = t.up();
        r.up_error_deg = Some(fit.reference.up().angle(&up).to_degrees());
        let north = |m: nalgebra::Vector3<f64>| m - up * m.dot(&up);
        r.heading_error_deg = Some(
            north(fit.reference.magnetic())
                .angle(&north(t.magnetic()))
                .to_degrees(),
        );
    }
    r
}
