//! The replay loop: every IMU sample and camera frame of a recording, in time order, through the tracker.

use std::time::Instant;

use fires_record::{Damage, FrameContent, FrameImage, RecordError, RecordingReader};

use super::imu_stream::{imu_stream, ImuStream};
use crate::meta::{
    checked_pen_geometry, frame_timings, imu_scale, imu_to_tip, row_times_ns, stereo_rig, MetaError,
};

use super::retrack;
use crate::session::{Session, StrokeConfig};
use crate::stereo::CameraId;
use crate::track::fusion::{MagOffset, WorldFit, WorldReference};
use crate::track::pipeline::{
    area_radius, CameraFrame, DirectionSource, Refusal, TrackSample, Tracker, TrackerConfig,
};
use crate::vision::{BlobConfig, BlobDetector, GrayImage};

/// What to run.
#[derive(Debug, Clone)]
pub struct ReplayConfig {
    /// Tracker settings (the pen geometry is taken from the recording).
    pub tracker: TrackerConfig,
    /// Blob detector settings for image cameras.
    pub blobs: BlobConfig,
    /// Strokes: draw button, display smoothing, post-processing.
    pub strokes: StrokeConfig,
    /// Search margin around the predicted LED positions, pixels.
    pub window_margin_px: f64,
    /// Where the world reference (gravity and magnetic field in the camera frame) comes from.
    pub world: WorldSource,
    /// The axis the tip is placed along; None: by the cameras, [`tip_axis_for`].
    pub tip_axis: Option<DirectionSource>,
    /// Re-track the strokes begun before the online world estimate was accepted, once it is
    /// (`replay/retrack.rs`).
    pub retrack_startup: bool,
}

/// The live tip's axis for cameras delivering `content` (strokes are drawn along the vision axis
/// on every rig, [`TrackerConfig::stroke_direction_source`]). Measured on 60 s sessions (the
/// closing note of the webcam-physics change): on image cameras the least-squares axis of the
/// labelled LEDs gives strokes about half as far from the pen's path as the fused axis (`webcam`
/// seeds 1, 3, 4: median stroke RMS 0.37 / 0.28 / 0.59 mm against 0.69 / 0.63 / 1.09;
/// `fires-v2` seed 1: 2.59 against 2.86 mm), whose error is correlated over a stroke where the
/// vision axis's noise is smoothed away; on the Wii-like blob cameras the fused axis keeps the
/// display steadier (`fires-v1` seeds 1-8: jitter at rest 0.17-0.34 mm against 0.22-0.63 mm on
/// the vision axis).
pub fn tip_axis_for(content: FrameContent) -> DirectionSource {
    match content {
        FrameContent::Images => DirectionSource::Vision,
        FrameContent::Blobs => DirectionSource::Fused,
    }
}

/// Source of the world reference in a replay.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum WorldSource {
    /// Estimated during the replay, as a live session must (the default).
    #[default]
    Estimate,
    /// The recording's ground truth when it has one (a perfectly calibrated rig), else estimated.
    Truth,
}

impl Default for ReplayConfig {
    fn default() -> Self {
        ReplayConfig {
            tracker: TrackerConfig::default(),
            blobs: BlobConfig::default(),
            strokes: StrokeConfig::default(),
            window_margin_px: 24.0,
            world: WorldSource::default(),
            tip_axis: None,
            retrack_startup: true,
        }
    }
}

/// Errors of a replay.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// The recording could not be read.
    #[error(transparent)]
    Record(#[from] RecordError),
    /// The recording's metadata does not fit the tracker.
    #[error(transparent)]
    Meta(#[from] MetaError),
    /// The tracker rejected its configuration.
    #[error("tracker: {0}")]
    Tracker(String),
}

/// Time spent per stage, nanoseconds in total.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct StageTimes {
    /// Link decode and IMU timing.
    pub link_ns: u64,
    /// Blob detection on images.
    pub blobs_ns: u64,
    /// Stereo, identification, tip and fusion.
    pub track_ns: u64,
    /// Stroke post-processing.
    pub strokes_ns: u64,
}

/// Which image blobs a sample's labels name, for checking identities against ground truth.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelPixels {
    /// Index of the left frame the labels refer to.
    pub left_frame: u64,
    /// Index of the right frame the labels refer to.
    pub right_frame: u64,
    /// Per LED: the labelled left and right blob positions, pixels.
    pub px: [Option<([f64; 2], [f64; 2])>; 4],
}

/// One stereo pair's frames and why it gave no vision tip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairOutcome {
    /// Time of the pair's sample, nanoseconds (left clock).
    pub t_ns: u64,
    /// Index of the left frame.
    pub left_frame: u64,
    /// Index of the right frame.
    pub right_frame: u64,
    /// Why the pair gave no vision tip (None when it gave one).
    pub refusal: Option<Refusal>,
}

/// Everything a replay produced.
#[derive(Debug, Clone)]
pub struct ReplayOutput {
    /// One tracker sample per stereo frame pair (and per IMU sample while dead-reckoning).
    pub samples: Vec<TrackSample>,
    /// For each sample, the tip after the real-time display filter.
    pub display_tips: Vec<Option<[f64; 3]>>,
    /// For each sample, the image blobs its labels name (None for IMU-driven samples).
    pub label_pixels: Vec<Option<LabelPixels>>,
    /// Every stereo pair (one per frame sample), in order.
    pub pairs: Vec<PairOutcome>,
    /// Camera frames the tracker could not pair with the other camera's.
    pub unpaired_frames: usize,
    /// Finished strokes.
    pub strokes: Vec<fires_record::Stroke>,
    /// Name of the display filter behind `display_tips` ("one-euro" or "thesis").
    pub display_filter: &'static str,
    /// The link as decoded.
    pub imu: ImuStream,
    /// Camera frames read, per camera.
    pub frames: [usize; 2],
    /// Time per stage.
    pub times: StageTimes,
    /// Wall time of the whole replay, nanoseconds.
    pub wall_ns: u64,
    /// Where the gravity/magnetic world reference came from ("truth", "configured" or "estimated").
    pub world_reference: &'static str,
    /// The online world estimate (time accepted, fit) when it was estimated.
    pub world_fit: Option<(u64, WorldFit)>,
    /// The magnetometer's hard-iron offset, when the session calibrated it.
    pub mag_offset: Option<MagOffset>,
    /// What the reads of the replay skipped (a salvaging reader's log; clean for a strict reader).
    pub damage: Damage,
}

/// The latest frame of a camera: its index and blob positions.
type LastFrame = Option<(u64, Vec<[f64; 2]>)>;

enum Event {
    Imu(usize),
    Frame(CameraId, fires_record::CameraFrame),
}

impl Event {
    fn time(&self, imu: &ImuStream) -> u64 {
        match self {
            Event::Imu(i) => imu.samples[*i].t_ns,
            Event::Frame(_, f) => f.exposure_time_ns,
        }
    }
}

/// Replays a recording through the tracker. With a reader from [`RecordingReader::open_salvaging`] a damaged
/// recording replays as far as it is whole: a frame whose image is lost is skipped (the tracker sees a gap,
/// not an empty frame) and [`ReplayOutput::damage`] says what was skipped.
pub fn replay(
    reader: &RecordingReader,
    config: &ReplayConfig,
) -> Result<ReplayOutput, ReplayError> {
    let wall = Instant::now();
    let meta = reader.meta();
    let mut times = StageTimes::default();
    let t = Instant::now();
    let imu = imu_stream(
        &reader.link_chunks()?,
        meta.link.baud,
        meta.link.sample_rate_hz,
        &imu_scale(meta),
    );
    times.link_ns = t.elapsed().as_nanos() as u64;

    let mut tracker_cfg = config.tracker.clone();
    tracker_cfg.pen = checked_pen_geometry(meta, tracker_cfg.identify.tolerance)?;
    tracker_cfg.row_time_ns = row_times_ns(meta);
    tracker_cfg.imu_to_tip = imu_to_tip(meta).unwrap_or(tracker_cfg.imu_to_tip);
    tracker_cfg.frame_timing = frame_timings(meta);
    let content = if meta
        .cameras
        .iter()
        .any(|c| c.provides == FrameContent::Images)
    {
        FrameContent::Images
    } else {
        FrameContent::Blobs
    };
    tracker_cfg.direction_source = config.tip_axis.unwrap_or(tip_axis_for(content));
    let truth = match config.world {
        WorldSource::Truth => reader.world_truth()?,
        WorldSource::Estimate => None,
    };
    let world_reference = match (truth, tracker_cfg.world) {
        (Some(w), _) => {
            tracker_cfg.world = Some(world_reference(&w));
            "truth"
        }
        (None, Some(_)) => "configured",
        (None, None) => "estimated",
    };
    let rig = stereo_rig(meta)?;

    let mut events: Vec<Event> = (0..imu.samples.len()).map(Event::Imu).collect();
    let mut frames = [0usize; 2];
    let mut images = [false; 2];
    for (cam, id) in [(0u8, CameraId::Left), (1u8, CameraId::Right)] {
        let list = reader.frames(cam)?;
        frames[usize::from(cam)] = list.len();
        images[usize::from(cam)] = meta
            .cameras
            .iter()
            .any(|c| c.id == cam && c.provides == FrameContent::Images);
        events.extend(list.into_iter().map(|f| Event::Frame(id, f)));
    }
    events.sort_by_key(|e| e.time(&imu));

    let input = PassInput {
        reader,
        config,
        imu: &imu,
        events: &events,
        images,
    };
    let mut pass = track_pass(&input, &rig, tracker_cfg.clone(), None, &mut times)?;
    // The start before the world estimate was accepted, strokes begun there included: once more
    // with that world.
    if let (true, "estimated", Some((accepted_ns, fit))) =
        (config.retrack_startup, world_reference, pass.world_fit)
    {
        let until = retrack::replay_retrack_until(
            &imu.buttons,
            config.strokes.draw_button_mask,
            accepted_ns,
        );
        let cfg = TrackerConfig {
            world: Some(fit.reference),
            ..tracker_cfg
        };
        let second = track_pass(&input, &rig, cfg, Some(until), &mut times)?;
        pass = retrack::splice(pass, second, accepted_ns);
    }
    Ok(ReplayOutput {
        samples: pass.samples,
        display_tips: pass.display_tips,
        label_pixels: pass.label_pixels,
        pairs: pass.pairs,
        unpaired_frames: pass.unpaired_frames,
        strokes: pass.strokes,
        display_filter: config.strokes.display.name(),
        imu,
        frames,
        times,
        wall_ns: wall.elapsed().as_nanos() as u64,
        world_reference,
        world_fit: pass.world_fit,
        mag_offset: pass.mag_offset,
        damage: reader.damage(),
    })
}

/// What every tracking pass of one replay reads.
struct PassInput<'a> {
    reader: &'a RecordingReader,
    config: &'a ReplayConfig,
    imu: &'a ImuStream,
    /// IMU samples and camera frames in time order.
    events: &'a [Event],
    /// Per camera, whether it delivers images (else blob lists).
    images: [bool; 2],
}

/// What one pass of the tracker over the events produced.
pub(super) struct Pass {
    pub(super) samples: Vec<TrackSample>,
    pub(super) display_tips: Vec<Option<[f64; 3]>>,
    pub(super) label_pixels: Vec<Option<LabelPixels>>,
    pub(super) pairs: Vec<PairOutcome>,
    pub(super) unpaired_frames: usize,
    pub(super) strokes: Vec<fires_record::Stroke>,
    pub(super) world_fit: Option<(u64, WorldFit)>,
    pub(super) mag_offset: Option<MagOffset>,
}

/// One pass of a fresh tracker with `tracker_cfg` over the events up to `until_ns` (all of them
/// when None), adding its stage times to `times`.
fn track_pass(
    input: &PassInput<'_>,
    rig: &crate::stereo::StereoRig,
    tracker_cfg: TrackerConfig,
    until_ns: Option<u64>,
    times: &mut StageTimes,
) -> Result<Pass, ReplayError> {
    let PassInput {
        reader,
        config,
        imu,
        events,
        images,
    } = *input;
    let tracker =
        Tracker::new(rig.clone(), tracker_cfg).map_err(|e| ReplayError::Tracker(e.to_string()))?;
    let mut session = Session::new(tracker, config.strokes);
    let mut detectors = [
        BlobDetector::new(config.blobs),
        BlobDetector::new(config.blobs),
    ];
    let mut samples = Vec::new();
    let mut display_tips = Vec::new();
    let mut label_pixels = Vec::new();
    let mut pairs = Vec::new();
    let mut unpaired_frames = 0;
    let mut last: [LastFrame; 2] = [None, None];
    let mut buttons = imu.buttons.iter().peekable();
    for event in events {
        let now = event.time(imu);
        if until_ns.is_some_and(|u| now > u) {
            break;
        }
        while let Some(b) = buttons.next_if(|b| b.t_ns <= now) {
            session.button(*b);
        }
        match event {
            Event::Imu(i) => {
                let t = Instant::now();
                if let Some(s) = session.imu(&imu.samples[*i]) {
                    samples.push(s.track);
                    display_tips.push(s.display_tip);
                    label_pixels.push(None);
                }
                times.track_ns += t.elapsed().as_nanos() as u64;
            }
            Event::Frame(id, f) => {
                let id = *id;
                let t = Instant::now();
                let frame = camera_frame(
                    reader,
                    f,
                    id,
                    images[id as usize],
                    &mut detectors,
                    session.tracker(),
                    config,
                )?;
                times.blobs_ns += t.elapsed().as_nanos() as u64;
                let Some(frame) = frame else {
                    continue;
                };
                last[id as usize] = Some((f.index, frame.blobs.clone()));
                let t = Instant::now();
                if let Some(s) = session.frame(frame) {
                    label_pixels.push(labelled_pixels(&s.track, &last));
                    if let (Some((l, _)), Some((r, _))) = (&last[0], &last[1]) {
                        pairs.push(PairOutcome {
                            t_ns: s.track.t_ns,
                            left_frame: *l,
                            right_frame: *r,
                            refusal: session.tracker().last_refusal(),
                        });
                    }
                    samples.push(s.track);
                    display_tips.push(s.display_tip);
                } else {
                    unpaired_frames += 1;
                }
                times.track_ns += t.elapsed().as_nanos() as u64;
            }
        }
    }
    session.finish(samples.last().map_or(0, |s: &TrackSample| s.t_ns));
    let world_fit = session.tracker().world_fit().copied();
    let mag_offset = session.tracker().mag_offset().copied();
    times.strokes_ns += session.strokes_ns();
    Ok(Pass {
        samples,
        display_tips,
        label_pixels,
        pairs,
        unpaired_frames,
        strokes: session.into_strokes(),
        world_fit,
        mag_offset,
    })
}

/// The blob positions a sample's labels point at in the current left and right frames.
fn labelled_pixels(s: &TrackSample, last: &[LastFrame; 2]) -> Option<LabelPixels> {
    let (Some((li, lb)), Some((ri, rb))) = (&last[0], &last[1]) else {
        return None;
    };
    let px = s
        .labels
        .map(|l| l.and_then(|(a, b)| Some((*lb.get(a)?, *rb.get(b)?))));
    Some(LabelPixels {
        left_frame: *li,
        right_frame: *ri,
        px,
    })
}

/// The world reference of a recording's ground truth.
pub fn world_reference(w: &fires_record::WorldTruth) -> WorldReference {
    let g = w.gravity_world_mps2;
    let norm = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
    let up = if norm > 0.0 {
        [-g[0] / norm, -g[1] / norm, -g[2] / norm]
    } else {
        WorldReference::default().up
    };
    WorldReference {
        up,
        magnetic: w.earth_field_world_t,
        gravity: if norm > 0.0 {
            norm
        } else {
            WorldReference::default().gravity
        },
    }
}

/// The blobs of one recorded frame: the device's list, or detection on the image around the predicted LEDs;
/// `None` when its image is lost (salvaging reader).
fn camera_frame(
    reader: &RecordingReader,
    f: &fires_record::CameraFrame,
    id: CameraId,
    is_image: bool,
    detectors: &mut [BlobDetector; 2],
    tracker: &Tracker,
    config: &ReplayConfig,
) -> Result<Option<CameraFrame>, ReplayError> {
    if !is_image {
        let blobs = f.blobs.as_deref().unwrap_or_default();
        return Ok(Some(CameraFrame {
            camera: id,
            t_ns: f.exposure_time_ns,
            blobs: blobs.iter().map(|b| [b.x, b.y]).collect(),
            radii: blobs.iter().map(|b| area_radius(b.area)).collect(),
            shapes: Vec::new(),
        }));
    }
    let img = match reader.frame_image(f)? {
        FrameImage::Image(img) => img,
        FrameImage::NoImage => {
            return Ok(Some(CameraFrame::new(id, f.exposure_time_ns, Vec::new())))
        }
        FrameImage::Lost => return Ok(None),
    };
    let blobs = match GrayImage::new(img.width as usize, img.height as usize, &img.data) {
        Ok(view) => {
            let window = tracker.predicted_window(id, f.exposure_time_ns, config.window_margin_px);
            detectors[id as usize].detect(&view, window)
        }
        Err(_) => Vec::new(),
    };
    Ok(Some(CameraFrame::from_blobs(
        id,
        f.exposure_time_ns,
        &blobs,
    )))
}
