//! Live tracking (`fires track`): two frame sources and the pen's serial link, run until a stop flag is set.
//!
//! One thread per camera captures frames (host time taken at capture) and one thread reads the serial link
//! (sending [`Command::Start`] on connect and on every reconnect, [`Command::Stop`] at the end); the calling
//! thread takes everything in arrival order, times the link's packets with [`LiveImuTimer`], detects blobs,
//! and writes a recording as it goes. IMU samples, button changes and frames then pass through a short
//! reorder buffer ([`LiveConfig::reorder_ns`]: the radio and the cameras deliver with different latencies)
//! into the same [`Session`] that replay uses: tracker with IMU fusion, strokes, display smoothing. The
//! recording is written crash-safe ([`fires_record::WriterOptions::default`]: every record flushed as it is
//! appended, data synced to disk about every second, also while the session is quiet), so a killed process
//! leaves a recording that replays up to its last record and a power cut loses about a second; it is finished
//! (every file synced) whenever the loop ends.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::Arc;
use std::time::{Duration, Instant};

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use fires_protocol::Command;
use fires_record::{
    CameraFrame as RecordedFrame, CameraStream, FrameContent, LinkChunk, Meta, PenGeometry,
    RecordingWriter, RigCalibration, Source,
};

use crate::capture::{CaptureError, CapturedFrame, SourceOpener};
use crate::clock::HostClock;
use crate::link::{
    ButtonChange, LinkError, LinkEvent, LiveImuTimer, SerialConfig, SerialLink, TimedLinkEvent,
};
use crate::meta::{checked_pen_geometry, imu_scale, imu_to_tip, stereo_rig};
use crate::session::{Session, SessionSample, StrokeConfig};
use crate::stereo::CameraId;
use crate::track::fusion::ImuSample;
use crate::track::pipeline::{CameraFrame, TrackQuality, Tracker, TrackerConfig};
use crate::vision::{BlobConfig, BlobDetector, GrayImage};
use start::StartBuffer;

mod start;

/// What the live loop needs besides its sources.
#[derive(Clone, Debug)]
pub struct LiveConfig {
    /// The stereo rig (camera 0 = left).
    pub rig: RigCalibration,
    /// The pen's serial port.
    pub serial: SerialConfig,
    /// Write a recording here as the session goes.
    pub record: Option<PathBuf>,
    /// Nominal camera frame rate written to the recording's metadata, hertz.
    pub nominal_rate_hz: f64,
    /// Blob detector settings.
    pub blobs: BlobConfig,
    /// Tracker settings.
    pub tracker: TrackerConfig,
    /// End by itself after this long (None: only the stop flag ends it).
    pub max_duration: Option<Duration>,
    /// Strokes: draw button, display smoothing, post-processing.
    pub strokes: StrokeConfig,
    /// Events are held until they are this much older than the newest event, then tracked in time
    /// order, nanoseconds (longer than the radio's and the cameras' latency difference).
    pub reorder_ns: u64,
}

/// Default [`LiveConfig::reorder_ns`]: Bluetooth SPP delivers sensor packets 10-60 ms late, webcams
/// their frames 30-80 ms late; events are tracked once both streams have passed them.
pub const DEFAULT_REORDER_NS: u64 = 100_000_000;

/// Everything a live session produced.
#[derive(Clone, Debug, Default)]
pub struct LiveOutput {
    /// Totals.
    pub summary: LiveSummary,
    /// Tracker samples in time order (stereo frames, and IMU samples while dead-reckoning).
    pub samples: Vec<SessionSample>,
    /// Finished strokes.
    pub strokes: Vec<fires_record::Stroke>,
}

/// Totals of a live session.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct LiveSummary {
    /// Frames captured per camera.
    pub frames: [u64; 2],
    /// Link bytes read and the decoder's totals.
    pub link: fires_record::report::LinkSummary,
    /// Serial disconnects seen.
    pub disconnects: u64,
    /// Tracker samples from stereo frames.
    pub samples: u64,
    /// Samples with a vision fix of the tip.
    pub samples_vision: u64,
    /// IMU samples fused.
    pub imu_samples: u64,
    /// Strokes finished.
    pub strokes: u64,
    /// The last tracked tip, metres (left camera frame).
    pub last_tip_m: Option<[f64; 3]>,
    /// The world reference in use at the end (configured, or estimated during the session);
    /// `fires track --world` takes it back to skip the estimate next time.
    pub world: Option<crate::track::fusion::WorldReference>,
    /// The online estimate behind `world`, when it was estimated.
    pub world_fit: Option<crate::track::fusion::WorldFit>,
    /// The magnetometer's hard-iron offset, when the session calibrated it.
    pub mag_offset: Option<crate::track::fusion::MagOffset>,
    /// The recording written, if any.
    pub recording: Option<PathBuf>,
    /// Wall time, seconds.
    pub seconds: f64,
}

/// Errors of the live loop.
#[derive(Debug, thiserror::Error)]
pub enum LiveError {
    /// A camera could not be opened or failed.
    #[error(transparent)]
    Capture(#[from] CaptureError),
    /// The serial port could not be opened or written.
    #[error(transparent)]
    Link(#[from] LinkError),
    /// The recording could not be written.
    #[error("recording: {0}")]
    Record(#[from] fires_record::RecordError),
    /// The rig or tracker settings were rejected.
    #[error("tracker: {0}")]
    Tracker(String),
    /// The rig calibration or pen geometry is impossible (a field and what is wrong with it).
    #[error("calibration: {0}")]
    Calibration(#[from] fires_record::MetaProblem),
}

enum Msg {
    Frame(u8, CapturedFrame),
    Link(LinkChunk),
    Disconnected,
    SourceEnded,
    Failed(LiveError),
}

/// The recording metadata of a live session.
pub fn live_meta(rig: RigCalibration, nominal_rate_hz: f64) -> Meta {
    let cameras = (0..2u8)
        .map(|id| CameraStream::global(id, FrameContent::Images, nominal_rate_hz))
        .collect();
    Meta::new(
        Source {
            kind: "hardware".into(),
            scenario: None,
            seed: None,
            generator: Some(format!("fires track {}", env!("CARGO_PKG_VERSION"))),
        },
        rig,
        PenGeometry::fires_default(),
        cameras,
        false,
    )
}

/// Runs until `stop` is set (Ctrl-C), `max_duration` passes or a frame source ends. Cameras and the serial
/// port are opened first: a missing device is an error before anything runs.
pub fn run_live(
    sources: [SourceOpener; 2],
    cfg: &LiveConfig,
    clock: HostClock,
    stop: Arc<AtomicBool>,
) -> Result<LiveOutput, LiveError> {
    let start = Instant::now();
    let meta = live_meta(cfg.rig.clone(), cfg.nominal_rate_hz);
    meta.validate()?;
    let rig = stereo_rig(&meta).map_err(|e| LiveError::Tracker(e.to_string()))?;
    let mut tracker_cfg = cfg.tracker.clone();
    tracker_cfg.pen = checked_pen_geometry(&meta, tracker_cfg.identify.tolerance)
        .map_err(|e| LiveError::Tracker(e.to_string()))?;
    tracker_cfg.imu_to_tip = imu_to_tip(&meta).unwrap_or(tracker_cfg.imu_to_tip);
    let tracker = Tracker::new(rig.clone(), tracker_cfg.clone())
        .map_err(|e| LiveError::Tracker(e.to_string()))?;
    let mut session = Session::new(tracker, cfg.strokes);
    let mut start_buffer = StartBuffer::new(rig, tracker_cfg, cfg.strokes);
    let mut timer = LiveImuTimer::new(meta.link.baud, meta.link.sample_rate_hz, imu_scale(&meta));
    let mut link = SerialLink::open(cfg.serial.clone(), clock)?;
    let (tx, rx) = mpsc::channel::<Msg>();

    // Cameras: each opened on its own thread; the open result comes back before streaming starts.
    let mut threads = Vec::new();
    for (cam, open) in (0u8..).zip(sources) {
        let (ready_tx, ready_rx) = mpsc::channel::<Result<(), CaptureError>>();
        let tx = tx.clone();
        let stop_capture = stop.clone();
        threads.push(std::thread::spawn(move || {
            let stop = stop_capture;
            let mut source = match open() {
                Ok(s) => {
                    let _ = ready_tx.send(Ok(()));
                    s
                }
                Err(e) => {
                    let _ = ready_tx.send(Err(e));
                    return;
                }
            };
            while !stop.load(Ordering::Relaxed) {
                match source.next_frame(&clock) {
                    Ok(Some(f)) => {
                        if tx.send(Msg::Frame(cam, f)).is_err() {
                            return;
                        }
                    }
                    Ok(None) => {
                        let _ = tx.send(Msg::SourceEnded);
                        return;
                    }
                    Err(e) => {
                        let _ = tx.send(Msg::Failed(e.into()));
                        return;
                    }
                }
            }
        }));
        match ready_rx.recv() {
            Ok(Ok(())) => {}
            Ok(Err(e)) => {
                stop.store(true, Ordering::Relaxed);
                join_all(threads);
                return Err(e.into());
            }
            Err(_) => {
                stop.store(true, Ordering::Relaxed);
                join_all(threads);
                return Err(LiveError::Capture(CaptureError {
                    device: format!("camera {cam}"),
                    message: "capture thread ended while opening".into(),
                }));
            }
        }
    }

    let started = (|| -> Result<Option<RecordingWriter>, LiveError> {
        link.send(Command::Start)?;
        Ok(match &cfg.record {
            Some(dir) => Some(RecordingWriter::create(dir, &meta)?),
            None => None,
        })
    })();
    let mut writer = match started {
        Ok(w) => w,
        Err(e) => {
            stop.store(true, Ordering::Relaxed);
            drop(rx);
            join_all(threads);
            return Err(e);
        }
    };

    // The pen link.
    {
        let tx = tx.clone();
        let stop = stop.clone();
        threads.push(std::thread::spawn(move || {
            let mut buf = vec![0u8; 4096];
            while !stop.load(Ordering::Relaxed) {
                let msg = match link.poll(&mut buf) {
                    LinkEvent::Bytes { host_time_ns, len } => Msg::Link(LinkChunk {
                        host_time_ns,
                        bytes: buf[..len].to_vec(),
                    }),
                    LinkEvent::Idle => continue,
                    LinkEvent::Disconnected { .. } => Msg::Disconnected,
                    LinkEvent::Reconnected { .. } => {
                        let _ = link.send(Command::Start);
                        continue;
                    }
                };
                if tx.send(msg).is_err() {
                    break;
                }
            }
            let _ = link.send(Command::Stop);
        }));
    }
    drop(tx);

    let mut summary = LiveSummary {
        recording: cfg.record.clone(),
        ..Default::default()
    };
    let mut out = LiveOutput::default();
    let mut reorder = Reorder::new(cfg.reorder_ns);
    let mut link_events = Vec::new();
    let mut detectors = [BlobDetector::new(cfg.blobs), BlobDetector::new(cfg.blobs)];
    let mut failure = None;
    loop {
        if stop.load(Ordering::Relaxed) || cfg.max_duration.is_some_and(|d| start.elapsed() >= d) {
            stop.store(true, Ordering::Relaxed);
        }
        let msg = match rx.recv_timeout(Duration::from_millis(20)) {
            Ok(m) => m,
            Err(mpsc::RecvTimeoutError::Timeout) => {
                // Nothing arrives: the last records still reach the disk within the sync interval.
                if let Some(Err(e)) = writer.as_mut().map(RecordingWriter::sync_if_due) {
                    stop.store(true, Ordering::Relaxed);
                    failure.get_or_insert(e.into());
                }
                continue;
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => break,
        };
        let step = (|| -> Result<(), LiveError> {
            match msg {
                Msg::Frame(cam, f) => {
                    let index = summary.frames[usize::from(cam)];
                    summary.frames[usize::from(cam)] += 1;
                    if let Some(w) = writer.as_mut() {
                        let rec = RecordedFrame {
                            camera: cam,
                            index,
                            exposure_time_ns: f.t_ns,
                            blobs: None,
                            image: None,
                        };
                        w.write_frame(&rec, Some(&f.image))?;
                    }
                    let id = if cam == 0 {
                        CameraId::Left
                    } else {
                        CameraId::Right
                    };
                    let blobs = match GrayImage::new(
                        f.image.width as usize,
                        f.image.height as usize,
                        &f.image.data,
                    ) {
                        Ok(view) => {
                            let window = session.tracker().predicted_window(id, f.t_ns, 24.0);
                            detectors[usize::from(cam)].detect(&view, window)
                        }
                        Err(_) => Vec::new(),
                    };
                    reorder.push(Event::Frame(CameraFrame::from_blobs(id, f.t_ns, &blobs)));
                }
                Msg::Link(chunk) => {
                    summary.link.bytes += chunk.bytes.len() as u64;
                    timer.feed(&chunk, &mut link_events);
                    for e in link_events.drain(..) {
                        reorder.push(e.into());
                    }
                    if let Some(w) = writer.as_mut() {
                        w.write_link_chunk(&chunk)?;
                    }
                }
                Msg::Disconnected => summary.disconnects += 1,
                Msg::SourceEnded => stop.store(true, Ordering::Relaxed),
                Msg::Failed(e) => return Err(e),
            }
            Ok(())
        })();
        if let Err(e) = step {
            stop.store(true, Ordering::Relaxed);
            failure.get_or_insert(e);
        }
        while let Some(e) = reorder.pop_ready() {
            let t = e.t_ns();
            start_buffer.keep(&e);
            track_event(&mut session, e, &mut summary, &mut out.samples);
            start_buffer.update(session.tracker(), t);
        }
    }
    join_all(threads);
    let end_ns = clock.now_ns();
    timer.finish(end_ns, &mut link_events);
    for e in link_events.drain(..) {
        reorder.push(e.into());
    }
    while let Some(e) = reorder.pop() {
        let t = e.t_ns();
        start_buffer.keep(&e);
        track_event(&mut session, e, &mut summary, &mut out.samples);
        start_buffer.update(session.tracker(), t);
    }
    summary.world = session.tracker().world().copied();
    summary.world_fit = session.tracker().world_fit().map(|(_, f)| *f);
    summary.mag_offset = session.tracker().mag_offset().copied();
    session.finish(out.samples.last().map_or(0, |s| s.track.t_ns));
    // The strokes begun before the world estimate was accepted, re-tracked with it.
    out.strokes = start_buffer.finish(session.into_strokes());
    summary.strokes = out.strokes.len() as u64;
    summary.link.stats = timer.stats();
    summary.seconds = start.elapsed().as_secs_f64();
    if let Some(w) = writer {
        w.finish()?;
    }
    out.summary = summary;
    match failure {
        Some(e) => Err(e),
        None => Ok(out),
    }
}

/// One live event for the session.
#[derive(Debug, Clone)]
enum Event {
    Imu(ImuSample),
    Button(ButtonChange),
    Frame(CameraFrame),
}

impl From<TimedLinkEvent> for Event {
    fn from(e: TimedLinkEvent) -> Self {
        match e {
            TimedLinkEvent::Imu(s) => Event::Imu(s),
            TimedLinkEvent::Button(b) => Event::Button(b),
        }
    }
}

impl Event {
    /// Feeds the event to `session`; returns the sample it produced, if any.
    fn feed(self, session: &mut Session) -> Option<SessionSample> {
        match self {
            Event::Button(b) => {
                session.button(b);
                None
            }
            Event::Imu(i) => session.imu(&i),
            Event::Frame(f) => session.frame(f),
        }
    }

    fn t_ns(&self) -> u64 {
        match self {
            Event::Imu(s) => s.t_ns,
            Event::Button(b) => b.t_ns,
            Event::Frame(f) => f.t_ns,
        }
    }
}

/// A heap entry ordered by (time, arrival number) only.
#[derive(Debug)]
struct Queued(u64, u64, Event);

impl PartialEq for Queued {
    fn eq(&self, other: &Self) -> bool {
        (self.0, self.1) == (other.0, other.1)
    }
}
impl Eq for Queued {}
impl PartialOrd for Queued {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Queued {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        (self.0, self.1).cmp(&(other.0, other.1))
    }
}

/// Holds events until they are `delay_ns` older than the newest one, then releases them in time order
/// (ties in arrival order).
struct Reorder {
    heap: BinaryHeap<Reverse<Queued>>,
    delay_ns: u64,
    newest_ns: u64,
    arrivals: u64,
}

impl Reorder {
    fn new(delay_ns: u64) -> Self {
        Reorder {
            heap: BinaryHeap::new(),
            delay_ns,
            newest_ns: 0,
            arrivals: 0,
        }
    }

    fn push(&mut self, e: Event) {
        let t = e.t_ns();
        self.newest_ns = self.newest_ns.max(t);
        self.arrivals += 1;
        self.heap.push(Reverse(Queued(t, self.arrivals, e)));
    }

    /// The oldest event, if it has waited long enough.
    fn pop_ready(&mut self) -> Option<Event> {
        let Reverse(Queued(t, _, _)) = self.heap.peek()?;
        if t.saturating_add(self.delay_ns) > self.newest_ns {
            return None;
        }
        self.pop()
    }

    /// The oldest event.
    fn pop(&mut self) -> Option<Event> {
        self.heap.pop().map(|Reverse(Queued(_, _, e))| e)
    }
}

/// Tracks one event and counts what came out.
fn track_event(
    session: &mut Session,
    e: Event,
    summary: &mut LiveSummary,
    samples: &mut Vec<SessionSample>,
) {
    let (imu, frame) = (matches!(e, Event::Imu(_)), matches!(e, Event::Frame(_)));
    let s = e.feed(session);
    summary.imu_samples += u64::from(imu);
    if let (true, Some(s)) = (frame, &s) {
        summary.samples += 1;
        if matches!(s.track.quality, TrackQuality::Vision { .. }) {
            summary.samples_vision += 1;
            summary.last_tip_m = s.track.tip;
        }
    }
    samples.extend(s);
}

fn join_all(threads: Vec<std::thread::JoinHandle<()>>) {
    for t in threads {
        let _ = t.join();
    }
}
