//! The live loop without hardware: a simulated recording's images as the two cameras, its link bytes sent
//! through a pseudo-terminal as the pen, stopped through the same flag Ctrl-C sets; the recording it writes
//! must open and replay.
#![cfg(unix)]

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::Command as Process;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use fires_host::capture::{FrameSource, RecordedFrames, SourceOpener};
use fires_host::clock::HostClock;
use fires_host::link::SerialConfig;
use fires_host::live::{run_live, LiveConfig, LiveError, DEFAULT_REORDER_NS};
use fires_host::replay::run::{tip_axis_for, world_reference};
use fires_host::replay::{replay, ReplayConfig};
use fires_host::track::pipeline::TrackQuality;
use fires_protocol::Command;
use fires_record::{FrameContent, RecordingReader};
use fires_sim::{run_scenario, SimOptions};
use serialport::{SerialPort, TTYPort};

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fires-live-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_file(&dir);
    dir
}

fn recorded(dir: &Path, cam: u8) -> SourceOpener {
    let dir = dir.to_path_buf();
    Box::new(move || {
        let reader = RecordingReader::open(&dir).expect("open simulated recording");
        RecordedFrames::from_recording(&reader, cam).map(|s| Box::new(s) as Box<dyn FrameSource>)
    })
}

/// A camera replaying its recorded exposure schedule from `start` (both cameras keep their offset).
fn scheduled(dir: &Path, cam: u8, start: Instant, epoch_ns: u64) -> SourceOpener {
    let dir = dir.to_path_buf();
    Box::new(move || {
        let reader = RecordingReader::open(&dir).expect("open simulated recording");
        RecordedFrames::from_recording(&reader, cam)
            .map(|s| Box::new(s.on_schedule(start, epoch_ns)) as Box<dyn FrameSource>)
    })
}

/// The live configuration. The tracker takes the simulated world reference, as the replay it is
/// compared with does: the online estimate is accepted at a time that depends on the IMU time
/// anchor, which live tracking refines as packets arrive, so it would not compare frame by frame.
fn config(reader: &RecordingReader, serial: &Path, record: Option<PathBuf>) -> LiveConfig {
    let mut replay = ReplayConfig::default();
    // As `fires track` does: live cameras are webcams, and the replay of the written recording (image
    // frames) places the tip along the same axis.
    replay.tracker.direction_source = tip_axis_for(FrameContent::Images);
    replay.tracker.world = reader
        .world_truth()
        .expect("world truth")
        .map(|w| world_reference(&w));
    let mut serial = SerialConfig::pen(serial);
    serial.read_timeout = Duration::from_millis(20);
    LiveConfig {
        rig: reader.meta().rig.clone(),
        serial,
        record,
        nominal_rate_hz: 15.0,
        blobs: replay.blobs,
        tracker: replay.tracker,
        max_duration: Some(Duration::from_secs(20)),
        strokes: replay.strokes,
        reorder_ns: DEFAULT_REORDER_NS,
    }
}

#[test]
fn a_live_session_over_a_pty_records_a_replayable_recording() {
    let sim = temp("sim");
    run_scenario("fires-v2", 11, 3.0, &sim, SimOptions::default()).expect("simulate");
    let reader = RecordingReader::open(&sim).expect("open");
    let link_chunks = reader.link_chunks().expect("link");
    // Cameras and pen replay the simulated session on its own schedule from one start instant.
    let epoch_ns = (0..2)
        .filter_map(|c| Some(reader.frames(c).ok()?.first()?.exposure_time_ns))
        .chain(link_chunks.first().map(|c| c.host_time_ns))
        .min()
        .expect("a session");
    let t_start = Instant::now() + Duration::from_millis(500);

    let (mut master, slave) = TTYPort::pair().expect("pty pair");
    let port = slave.name().expect("slave path");
    let link = temp("tty");
    std::os::unix::fs::symlink(&port, &link).expect("symlink");
    master
        .set_timeout(Duration::from_millis(50))
        .expect("timeout");
    let stop = Arc::new(AtomicBool::new(false));
    // The pen: waits for Start, streams its bytes at the pace the simulator timed them, then collects what the
    // host sent until Stop.
    let pen = {
        let stop = stop.clone();
        std::thread::spawn(move || {
            let mut from_host = Vec::new();
            let mut buf = [0u8; 256];
            let start = Command::Start.encode();
            let stop_cmd = Command::Stop.encode();
            let contains = |h: &[u8], n: &[u8]| h.windows(n.len()).any(|w| w == n);
            for _ in 0..200 {
                if let Ok(n) = master.read(&mut buf) {
                    from_host.extend_from_slice(&buf[..n]);
                }
                if contains(&from_host, start.as_bytes()) {
                    break;
                }
            }
            for c in &link_chunks {
                let at = t_start + Duration::from_nanos(c.host_time_ns.saturating_sub(epoch_ns));
                if let Some(wait) = at.checked_duration_since(Instant::now()) {
                    std::thread::sleep(wait);
                }
                master.write_all(&c.bytes).expect("pen write");
            }
            // The host stops after the session, as Ctrl-C would.
            std::thread::sleep(Duration::from_millis(300));
            stop.store(true, Ordering::Relaxed);
            for _ in 0..100 {
                if let Ok(n) = master.read(&mut buf) {
                    from_host.extend_from_slice(&buf[..n]);
                }
                if contains(&from_host, stop_cmd.as_bytes()) {
                    break;
                }
            }
            (
                contains(&from_host, start.as_bytes()),
                contains(&from_host, stop_cmd.as_bytes()),
            )
        })
    };

    let rec = temp("rec");
    let cfg = config(&reader, &link, Some(rec.clone()));
    let live = run_live(
        [
            scheduled(&sim, 0, t_start, epoch_ns),
            scheduled(&sim, 1, t_start, epoch_ns),
        ],
        &cfg,
        HostClock::new(),
        stop.clone(),
    )
    .expect("live run");
    let summary = &live.summary;
    let (got_start, got_stop) = pen.join().expect("pen thread");
    assert!(got_start, "the host sent Start");
    assert!(got_stop, "the host sent Stop");
    assert!(
        summary.frames[0] > 5 && summary.frames[1] > 5,
        "{summary:?}"
    );
    assert!(summary.link.stats.sensor_frames > 100, "{summary:?}");
    assert!(summary.seconds < 15.0, "stopped by the flag: {summary:?}");

    let written = RecordingReader::open(&rec).expect("the recording opens");
    assert_eq!(
        written.frames(0).expect("frames").len() as u64,
        summary.frames[0]
    );
    assert_eq!(
        written
            .link_chunks()
            .expect("link")
            .iter()
            .map(|c| c.bytes.len() as u64)
            .sum::<u64>(),
        summary.link.bytes
    );
    // The written recording has no ground truth: the replay gets the live run's world reference.
    let truth_world = ReplayConfig {
        tracker: cfg.tracker.clone(),
        ..ReplayConfig::default()
    };
    let out = replay(&written, &truth_world).expect("the recording replays");
    assert_eq!(out.frames[0] as u64, summary.frames[0]);
    assert!(out.imu.samples.len() > 100);

    // Live tracking is the replay pipeline: every decoded sensor packet was fused, and the live track
    // matches the replay of what it recorded. The only difference is the IMU time anchor, which live
    // tracking refines as packets arrive: the vision tip (along the LEDs' own axis) must agree to 1 mm,
    // the filtered tip, whose acceleration input follows the anchor, to 2 mm.
    assert_eq!(
        summary.imu_samples, summary.link.stats.sensor_frames,
        "{summary:?}"
    );
    assert!(summary.samples_vision >= 5, "{summary:?}");
    let vision = |s: &fires_host::track::pipeline::TrackSample| {
        matches!(s.quality, TrackQuality::Vision { .. }).then_some((s.t_ns, s.raw_tip?))
    };
    let filtered = |s: &fires_host::track::pipeline::TrackSample| {
        matches!(s.quality, TrackQuality::Vision { .. }).then_some((s.t_ns, s.tip?))
    };
    let replayed_filtered: std::collections::HashMap<u64, [f64; 3]> =
        out.samples.iter().filter_map(filtered).collect();
    for (t, p) in live.samples.iter().filter_map(|s| filtered(&s.track)) {
        if let Some(q) = replayed_filtered.get(&t) {
            let d = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
            assert!(d < 2e-3, "filtered tips {d} m apart at {t}");
        }
    }
    let replayed: std::collections::HashMap<u64, [f64; 3]> =
        out.samples.iter().filter_map(vision).collect();
    let live_tips: Vec<(u64, [f64; 3])> = live
        .samples
        .iter()
        .filter_map(|s| vision(&s.track))
        .collect();
    let matched: Vec<f64> = live_tips
        .iter()
        .filter_map(|(t, p)| {
            let q = replayed.get(t)?;
            Some(((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt())
        })
        .collect();
    assert!(
        matched.len() * 10 >= live_tips.len() * 9,
        "{} of {} live vision samples at replayed times",
        matched.len(),
        live_tips.len()
    );
    let close = matched.iter().filter(|d| **d < 1e-3).count();
    assert!(
        close * 10 >= matched.len() * 9,
        "{close} of {} within 1 mm: {matched:?}",
        matched.len()
    );
    eprintln!(
        "live: {} vision samples, {} at replayed times, {close} within 1 mm, {} strokes",
        live_tips.len(),
        matched.len(),
        live.strokes.len()
    );
    assert_eq!(live.strokes.len(), out.strokes.len());

    // `fires replay` on it, as a user would.
    let replay_out = temp("replay");
    let status = Process::new(env!("CARGO_BIN_EXE_fires"))
        .arg("replay")
        .arg(&rec)
        .arg("--out")
        .arg(&replay_out)
        .output()
        .expect("run fires");
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    for d in [&sim, &rec, &replay_out] {
        let _ = std::fs::remove_dir_all(d);
    }
    let _ = std::fs::remove_file(&link);
}

#[test]
fn a_missing_serial_port_is_an_error_not_a_panic() {
    let sim = temp("sim-noport");
    run_scenario("fires-v2", 2, 0.5, &sim, SimOptions::default()).expect("simulate");
    let reader = RecordingReader::open(&sim).expect("open");
    let cfg = config(&reader, Path::new("/nonexistent/fires-pen"), None);
    let err = run_live(
        [recorded(&sim, 0), recorded(&sim, 1)],
        &cfg,
        HostClock::new(),
        Arc::new(AtomicBool::new(false)),
    )
    .expect_err("no port");
    assert!(matches!(err, LiveError::Link(_)), "{err}");
    assert!(err.to_string().contains("/nonexistent/fires-pen"), "{err}");
    let _ = std::fs::remove_dir_all(&sim);
}

#[test]
fn fires_track_with_a_missing_camera_fails_with_one_line() {
    let out = Process::new(env!("CARGO_BIN_EXE_fires"))
        .args([
            "track",
            "--left",
            "/dev/video-fires-missing",
            "--right",
            "/dev/video-fires-missing",
            "--serial",
            "/nonexistent/fires-pen",
        ])
        .output()
        .expect("run fires");
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.is_empty()).collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(lines[0].starts_with("fires: error:"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    if cfg!(feature = "camera") {
        assert!(lines[0].contains("video-fires-missing"), "{stderr}");
    } else {
        assert!(lines[0].contains("camera` feature"), "{stderr}");
    }
}
