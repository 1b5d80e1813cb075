//! Accuracy and health of a replay, measured against the recording's ground truth when it has one.
//!
//! Tip errors compare each tracked tip with the true tip interpolated at the sample's time (exposure truth of
//! the left camera, the frame the tracker's samples are timed by). A *mislabel* is an accepted LED label whose left or right
//! image blob is not the image of that LED in that frame (see [`label_errors`]): the wrong-identity error the
//! thesis's distance test exists to prevent, checked in the images so that a depth error is not mistaken
//! for one.

use std::collections::HashMap;

pub use fires_record::report::{Accuracy, WorldReport};
use fires_record::ExposureTruth;

use super::display::{display_report, DisplayOptions, TipTruth};
use super::run::ReplayOutput;
use super::strokes_vs_truth::{strokes_summary, strokes_vs_truth, StrokeCompareOptions};
use crate::track::fusion::WorldReference;
use crate::track::pipeline::TrackQuality;

/// A labelled blob farther than this from the true image of its LED is not that LED's image, pixels.
pub const MISLABEL_PX: f64 = 3.0;

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
        frac_within_2mm: (n > 0).then(|| within as f64 / n as f64),
        frac_within_2mm_le_1m: (near.0 > 0).then(|| near.1 as f64 / near.0 as f64),
        frames_le_1m: near.0,
        mislabels,
        labels_checked: checked,
    }
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

/// The whole report of a replayed pen session (`report.json`, `kind: "replay"`); `fusion` names the
/// direction filter used. The tip-error plot is added by whoever draws it.
pub fn replay_report(
    reader: &fires_record::RecordingReader,
    out: &ReplayOutput,
    fusion: &str,
) -> Result<fires_record::ReplayReport, fires_record::RecordError> {
    use fires_record::report::{Latency, LinkSummary, StageMs};
    let count = |f: &dyn Fn(&crate::track::pipeline::TrackSample) -> bool| {
        out.samples.iter().filter(|s| f(s)).count()
    };
    let frames = out.samples.len().max(1) as f64;
    let world_truth = reader.world_truth()?;
    let exposure_truth = reader.exposure_truth()?;
    let t = &out.times;
    let mut report = fires_record::ReplayReport {
        format: fires_record::REPORT_FORMAT.into(),
        version: fires_record::REPORT_VERSION.into(),
        recording: Some(reader.dir().to_path_buf()),
        fusion: fusion.into(),
        frames: out.samples.len(),
        frames_tracked: count(&|s| s.tip.is_some()),
        frames_vision: count(&|s| matches!(s.quality, TrackQuality::Vision { .. })),
        camera_frames: out.frames,
        strokes: out.strokes.len(),
        world_reference: out.world_reference.into(),
        world: world_report(
            out,
            world_truth
                .as_ref()
                .map(super::run::world_reference)
                .as_ref(),
        ),
        magnetometer: mag_report(out.mag_offset.as_ref(), world_truth.as_ref()),
        link: LinkSummary {
            bytes: out.imu.bytes,
            stats: out.imu.stats,
        },
        latency_us_per_frame: Latency {
            blobs: t.blobs_ns as f64 / 1e3 / frames,
            track: t.track_ns as f64 / 1e3 / frames,
        },
        stage_ms: StageMs {
            link: t.link_ns as f64 / 1e6,
            blobs: t.blobs_ns as f64 / 1e6,
            track: t.track_ns as f64 / 1e6,
            strokes: t.strokes_ns as f64 / 1e6,
        },
        wall_ms: out.wall_ns as f64 / 1e6,
        damaged: out.damage.clone(),
        accuracy: None,
        realtime_factor: None,
        tip_error_plot: None,
        display: None,
        strokes_vs_truth: None,
        strokes_summary: None,
        strokes_floor: None,
        strokes_floor_summary: None,
        vision_refusals: None,
        surface: None,
        surface_from_truth: None,
        network: None,
    };
    let stroke_times: Option<Vec<(u64, u64)>> = reader
        .strokes()?
        .map(|s| s.iter().map(|s| (s.start_time_ns, s.end_time_ns)).collect());
    report.vision_refusals = Some(super::refusals::vision_refusals(
        out,
        exposure_truth.as_deref(),
        stroke_times.as_deref(),
    ));
    let tip_truth = tip_truth(reader)?;
    let display: Vec<(u64, [f64; 3])> = out
        .samples
        .iter()
        .zip(&out.display_tips)
        .filter_map(|(s, d)| Some((s.t_ns, (*d)?)))
        .collect();
    let raw: Vec<(u64, [f64; 3])> = out
        .samples
        .iter()
        .filter_map(|s| Some((s.t_ns, s.tip?)))
        .collect();
    report.display = Some(display_report(
        out.display_filter,
        &display,
        &raw,
        tip_truth.as_ref(),
        &DisplayOptions::default(),
    ));
    if let Some(truth_strokes) = reader.strokes()? {
        let opt = StrokeCompareOptions::default();
        let vs = strokes_vs_truth(&out.strokes, &truth_strokes, &opt);
        report.strokes_summary = Some(strokes_summary(&vs));
        report.strokes_vs_truth = Some(vs);
    }
    if let Some(truth) = exposure_truth {
        report.accuracy = Some(accuracy(out, &truth));
        let t0 = truth.iter().map(|e| e.exposure_time_ns).min().unwrap_or(0);
        let t1 = truth.iter().map(|e| e.exposure_time_ns).max().unwrap_or(0);
        let duration_s = (t1 - t0) as f64 / 1e9;
        report.realtime_factor = Some(duration_s / (out.wall_ns as f64 / 1e9));
    }
    Ok(report)
}

/// The true tip over time: the IMU truth (one pose per IMU sample), else the left camera's exposure truth.
pub fn tip_truth(
    reader: &fires_record::RecordingReader,
) -> Result<Option<TipTruth>, fires_record::RecordError> {
    if let Some(imu) = reader.imu_truth()? {
        if !imu.is_empty() {
            return Ok(Some(TipTruth::new(
                imu.iter().map(|s| (s.time_ns, s.pose.tip_m)).collect(),
            )));
        }
    }
    Ok(reader.exposure_truth()?.map(|e| {
        TipTruth::new(
            e.iter()
                .filter(|e| e.camera == 0)
                .map(|e| (e.exposure_time_ns, e.pose.tip_m))
                .collect(),
        )
    }))
}

/// The hard-iron offset found in the session and, with ground truth, its error (microtesla).
pub fn mag_report(
    offset: Option<&crate::track::fusion::MagOffset>,
    truth: Option<&fires_record::WorldTruth>,
) -> fires_record::report::MagReport {
    let Some(o) = offset else {
        return fires_record::report::MagReport::default();
    };
    // Readings are in microtesla (the recording's scale factors), the truth in tesla.
    let hard_iron_error = truth.map(|t| {
        (0..3)
            .map(|k| (o.hard_iron[k] - t.hard_iron_t[k] * 1e6).powi(2))
            .sum::<f64>()
            .sqrt()
    });
    fires_record::report::MagReport {
        calibrated: true,
        hard_iron: Some(o.hard_iron),
        field: Some(o.field),
        sigma_of_field: Some(o.sigma),
        samples: Some(o.samples),
        hard_iron_error,
    }
}
