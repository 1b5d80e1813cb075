//! Live tracking (`fires track`): two frame sources and the pen's serial link, run until a stop flag is set.
//!
//! One thread per camera captures frames (host time taken at capture) and one thread reads the serial link
//! (sending [`Command::Start`] on connect and on every reconnect, [`Command::Stop`] at the end); the calling
//! thread takes everything in arrival order, decodes the link with [`StreamDecoder`], detects blobs and feeds
//! the stereo frames to the [`Tracker`] as they come, and writes a recording as it goes. The recording is
//! finished (every file flushed) whenever the loop ends, so `fires replay` can track it afterwards with the
//! IMU fusion and strokes.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::Arc;
use std::time::{Duration, Instant};

use fires_protocol::{Command, DecoderStats, StreamDecoder};
use fires_record::{
    CameraFrame as RecordedFrame, CameraStream, FrameContent, LinkChunk, Meta, PenGeometry,
    RecordingWriter, RigCalibration, Source,
};

use crate::capture::{CaptureError, CapturedFrame, SourceOpener};
use crate::clock::HostClock;
use crate::link::{LinkError, LinkEvent, SerialConfig, SerialLink};
use crate::replay::rig::{pen_geometry, stereo_rig};
use crate::stereo::CameraId;
use crate::track::pipeline::{CameraFrame, TrackQuality, Tracker, TrackerConfig};
use crate::vision::{BlobConfig, BlobDetector, GrayImage};

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
}

/// Totals of a live session.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct LiveSummary {
    /// Frames captured per camera.
    pub frames: [u64; 2],
    /// Link bytes read.
    pub link_bytes: u64,
    /// The link decoder's totals.
    pub link: LinkTotals,
    /// Serial disconnects seen.
    pub disconnects: u64,
    /// Tracker samples from stereo frames.
    pub samples: u64,
    /// Samples with a vision fix of the tip.
    pub samples_vision: u64,
    /// The last tracked tip, metres (left camera frame).
    pub last_tip_m: Option<[f64; 3]>,
    /// The recording written, if any.
    pub recording: Option<PathBuf>,
    /// Wall time, seconds.
    pub seconds: f64,
}

/// [`DecoderStats`] in a serialisable form.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct LinkTotals {
    /// Sensor frames decoded.
    pub sensor_frames: u64,
    /// Status frames decoded.
    pub status_frames: u64,
    /// Checksum failures.
    pub checksum_errors: u64,
    /// Bytes skipped.
    pub bytes_skipped: u64,
    /// Packets lost (counter gaps).
    pub lost: u64,
}

impl From<DecoderStats> for LinkTotals {
    fn from(s: DecoderStats) -> Self {
        LinkTotals {
            sensor_frames: s.sensor_frames,
            status_frames: s.status_frames,
            checksum_errors: s.checksum_errors,
            bytes_skipped: s.bytes_skipped,
            lost: s.lost,
        }
    }
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
        .map(|id| CameraStream {
            id,
            provides: FrameContent::Images,
            nominal_rate_hz,
        })
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
) -> Result<LiveSummary, LiveError> {
    let start = Instant::now();
    let meta = live_meta(cfg.rig.clone(), cfg.nominal_rate_hz);
    let rig = stereo_rig(&meta).map_err(|e| LiveError::Tracker(e.to_string()))?;
    let mut tracker_cfg = cfg.tracker.clone();
    tracker_cfg.pen = pen_geometry(&meta).map_err(|e| LiveError::Tracker(e.to_string()))?;
    let mut tracker =
        Tracker::new(rig, tracker_cfg).map_err(|e| LiveError::Tracker(e.to_string()))?;
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
    let mut decoder = StreamDecoder::default();
    let mut detectors = [BlobDetector::new(cfg.blobs), BlobDetector::new(cfg.blobs)];
    let mut failure = None;
    loop {
        if stop.load(Ordering::Relaxed) || cfg.max_duration.is_some_and(|d| start.elapsed() >= d) {
            stop.store(true, Ordering::Relaxed);
        }
        let msg = match rx.recv_timeout(Duration::from_millis(20)) {
            Ok(m) => m,
            Err(mpsc::RecvTimeoutError::Timeout) => continue,
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
                            let window = tracker.predicted_window(id, f.t_ns, 24.0);
                            detectors[usize::from(cam)].detect(&view, window)
                        }
                        Err(_) => Vec::new(),
                    };
                    if let Some(s) = tracker.push_frame(CameraFrame::from_blobs(id, f.t_ns, &blobs))
                    {
                        summary.samples += 1;
                        if matches!(s.quality, TrackQuality::Vision { .. }) {
                            summary.samples_vision += 1;
                            summary.last_tip_m = s.tip;
                        }
                    }
                }
                Msg::Link(chunk) => {
                    summary.link_bytes += chunk.bytes.len() as u64;
                    decoder.feed(&chunk.bytes, |_| {});
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
    }
    join_all(threads);
    summary.link = decoder.stats().into();
    summary.seconds = start.elapsed().as_secs_f64();
    if let Some(w) = writer {
        w.finish()?;
    }
    match failure {
        Some(e) => Err(e),
        None => Ok(summary),
    }
}

fn join_all(threads: Vec<std::thread::JoinHandle<()>>) {
    for t in threads {
        let _ = t.join();
    }
}
