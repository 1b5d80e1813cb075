//! The floor of the stroke figures: strokes built from the truth-labelled blob centroids of every frame.
//!
//! Every frame's blobs (the device's list, or detection on the whole image) are labelled with the truth
//! (`truth/exposures.jsonl`): the blob nearest to an LED's true pixel, within [`super::report::MISLABEL_PX`], is
//! that LED. Each left frame is paired with the right camera at the same true exposure time (each LED's right
//! centroid linearly interpolated between the two right frames around it), triangulated with the tracker's own
//! triangulation, and the tip follows from eq. 4.13 (FIRES thesis §4.1.2) with the least-squares pen axis. The
//! tips go through the same button segmentation and end-of-stroke post-processing as the tracker's, so the
//! difference between `strokes_vs_truth` and `strokes_floor` is what identification, time alignment and
//! fusion lose. Rolling-shutter row times are not modelled here, and the floor's tips are not moved onto
//! the IMU-smoothed path (`crate::stroke::imu_smooth`: the floor has no tracker, so no tip acceleration),
//! so the tracked strokes, which are, can lie below it.

use std::collections::HashMap;

use fires_record::{ExposureTruth, FrameContent, FrameImage, RecordingReader, Visibility};
use nalgebra::Vector3;

use super::report::MISLABEL_PX;
use super::run::{ReplayConfig, ReplayError};
use crate::link::ButtonChange;
use crate::meta::{checked_pen_geometry, stereo_rig};
use crate::stereo::{CameraId, Triangulator};
use crate::stroke::{stroke_record, StrokeEvent, StrokeSegmenter};
use crate::track::pen::LED_COUNT;
use crate::track::tip::TipEstimator;
use crate::vision::{BlobDetector, GrayImage};

/// One frame's truth-labelled centroids: (true exposure time, recorded time, pixel per LED).
type Labelled = (u64, u64, [Option<[f64; 2]>; LED_COUNT]);

/// Per LED, the blob nearest to its true pixel (when it is visible and a blob lies within `MISLABEL_PX`).
fn label_blobs(blobs: &[[f64; 2]], truth: &ExposureTruth) -> [Option<[f64; 2]>; LED_COUNT] {
    std::array::from_fn(|i| {
        let led = truth.leds.get(i)?;
        if led.visibility != Visibility::Visible {
            return None;
        }
        let px = led.pixel?;
        blobs
            .iter()
            .map(|b| (b, (b[0] - px[0]).hypot(b[1] - px[1])))
            .filter(|(_, d)| *d <= MISLABEL_PX)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(b, _)| *b)
    })
}

/// The labelled frames of one camera, sorted by true exposure time.
fn labelled_frames(
    reader: &RecordingReader,
    cam: u8,
    truth: &HashMap<(u8, u64), &ExposureTruth>,
    config: &ReplayConfig,
) -> Result<Vec<Labelled>, ReplayError> {
    let images = reader
        .meta()
        .cameras
        .iter()
        .any(|c| c.id == cam && c.provides == FrameContent::Images);
    let mut detector = BlobDetector::new(config.blobs);
    let mut out = Vec::new();
    for f in reader.frames(cam)? {
        let Some(t) = truth.get(&(cam, f.index)) else {
            continue;
        };
        let blobs: Vec<[f64; 2]> = if images {
            match reader.frame_image(&f)? {
                FrameImage::Image(img) => {
                    match GrayImage::new(img.width as usize, img.height as usize, &img.data) {
                        Ok(view) => detector
                            .detect(&view, None)
                            .iter()
                            .map(|b| [b.x, b.y])
                            .collect(),
                        Err(_) => Vec::new(),
                    }
                }
                _ => Vec::new(),
            }
        } else {
            f.blobs
                .as_deref()
                .unwrap_or_default()
                .iter()
                .map(|b| [b.x, b.y])
                .collect()
        };
        out.push((
            t.exposure_time_ns,
            f.exposure_time_ns,
            label_blobs(&blobs, t),
        ));
    }
    out.sort_by_key(|l| l.0);
    Ok(out)
}

/// LED `led`'s centroid in `frames` at true time `t`, interpolated between the frames around it.
fn centroid_at(frames: &[Labelled], led: usize, t: u64) -> Option<[f64; 2]> {
    let i = frames.partition_point(|f| f.0 <= t);
    let a = &frames[i.checked_sub(1)?];
    if a.0 == t {
        return a.2[led];
    }
    let b = frames.get(i)?;
    let (pa, pb) = (a.2[led]?, b.2[led]?);
    let w = (t - a.0) as f64 / (b.0 - a.0) as f64;
    Some([pa[0] + w * (pb[0] - pa[0]), pa[1] + w * (pb[1] - pa[1])])
}

/// The floor strokes of a recording with exposure truth (`None` without it), segmented by `buttons`.
pub fn floor_strokes(
    reader: &RecordingReader,
    config: &ReplayConfig,
    buttons: &[ButtonChange],
) -> Result<Option<Vec<fires_record::Stroke>>, ReplayError> {
    let Some(truth) = reader.exposure_truth()? else {
        return Ok(None);
    };
    let by_frame: HashMap<(u8, u64), &ExposureTruth> =
        truth.iter().map(|e| ((e.camera, e.index), e)).collect();
    let meta = reader.meta();
    let rig = stereo_rig(meta)?;
    let pen = checked_pen_geometry(meta, config.tracker.identify.tolerance)?;
    let tip = TipEstimator::new(&pen);
    let tri = Triangulator::new(&rig, config.tracker.method);
    let left = labelled_frames(reader, 0, &by_frame, config)?;
    let right = labelled_frames(reader, 1, &by_frame, config)?;
    let mut tips: Vec<(u64, [f64; 3])> = Vec::new();
    for (t_true, t_rec, px) in &left {
        let pts: [Option<Vector3<f64>>; LED_COUNT] = std::array::from_fn(|i| {
            let l = rig.camera(CameraId::Left).undistort(px[i]?).ok()?;
            let r = centroid_at(&right, i, *t_true)?;
            let r = rig.camera(CameraId::Right).undistort(r).ok()?;
            Some(tri.triangulate(l, r).ok()?.point)
        });
        if let Ok(e) = tip.estimate(&pts) {
            tips.push((*t_rec, [e.tip.x, e.tip.y, e.tip.z]));
        }
    }
    tips.sort_by_key(|t| t.0);
    // The session's segmentation: ids count pen-downs, kept or not.
    let mut segmenter = StrokeSegmenter::default();
    let (mut drawing, mut held, mut pen_downs) = (false, 0u8, 0u32);
    let mut strokes = Vec::new();
    let mut finish = |event: Option<StrokeEvent>, held: u8, pen_downs: &mut u32| {
        let stroke = match event {
            Some(StrokeEvent::Ended(s)) => Some(s),
            Some(StrokeEvent::Discarded { .. }) => None,
            _ => return,
        };
        let id = *pen_downs;
        *pen_downs += 1;
        if let Some(s) = stroke {
            strokes.push(stroke_record(id, held, &s, &config.strokes.record));
        }
    };
    let mut b = buttons.iter().peekable();
    let end = tips.last().map_or(0, |t| t.0);
    for (t, p) in tips.iter().map(|&(t, p)| (t, Some(p))).chain([(end, None)]) {
        while let Some(c) = b.next_if(|c| c.t_ns <= t || p.is_none()) {
            let pressed = c.buttons & config.strokes.draw_button_mask != 0;
            if pressed != drawing {
                drawing = pressed;
                if pressed {
                    held = c.buttons;
                }
                let event = segmenter.button(c.t_ns, pressed);
                finish(event, held, &mut pen_downs);
            }
        }
        segmenter.tip(t, p);
    }
    if drawing {
        finish(segmenter.button(end, false), held, &mut pen_downs);
    }
    Ok(Some(strokes))
}

/// `strokes_floor` and its summary for a recording with truth strokes and exposure truth.
pub fn floor_figures(
    reader: &RecordingReader,
    config: &ReplayConfig,
    buttons: &[ButtonChange],
) -> Result<
    Option<(
        Vec<fires_record::report::StrokeVsTruth>,
        fires_record::report::StrokesSummary,
    )>,
    ReplayError,
> {
    let Some(truth) = reader.strokes()? else {
        return Ok(None);
    };
    let Some(floor) = floor_strokes(reader, config, buttons)? else {
        return Ok(None);
    };
    let vs = super::strokes_vs_truth::strokes_vs_truth(&floor, &truth, &Default::default());
    let summary = super::strokes_vs_truth::strokes_summary(&vs);
    Ok(Some((vs, summary)))
}
