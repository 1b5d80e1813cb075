//! The live loop without hardware: a simulated recording's images as the two cameras, its link bytes sent
//! through a pseudo-terminal as the pen, stopped through the same flag Ctrl-C sets; the recording it writes
//! must open and replay.
#![cfg(unix)]

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::Command as Process;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use fires_host::capture::{FrameSource, RecordedFrames, SourceOpener};
use fires_host::clock::HostClock;
use fires_host::link::SerialConfig;
use fires_host::live::{run_live, LiveConfig, LiveError};
use fires_host::replay::{replay, ReplayConfig};
use fires_protocol::Command;
use fires_record::RecordingReader;
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

fn config(reader: &RecordingReader, serial: &Path, record: Option<PathBuf>) -> LiveConfig {
    let replay = ReplayConfig::default();
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
    }
}

#[test]
fn a_live_session_over_a_pty_records_a_replayable_recording() {
    let sim = temp("sim");
    run_scenario("fires-v2", 11, 3.0, &sim, SimOptions::default()).expect("simulate");
    let reader = RecordingReader::open(&sim).expect("open");
    let link_bytes: Vec<u8> = reader
        .link_chunks()
        .expect("link")
        .into_iter()
        .flat_map(|c| c.bytes)
        .collect();

    let (mut master, slave) = TTYPort::pair().expect("pty pair");
    let port = slave.name().expect("slave path");
    let link = temp("tty");
    std::os::unix::fs::symlink(&port, &link).expect("symlink");
    master
        .set_timeout(Duration::from_millis(50))
        .expect("timeout");
    let stop = Arc::new(AtomicBool::new(false));
    // The pen: waits for Start, streams its bytes in 1 KiB pieces, then collects what the host sent until Stop.
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
            for piece in link_bytes.chunks(1024) {
                master.write_all(piece).expect("pen write");
                std::thread::sleep(Duration::from_millis(10));
            }
            // The host stops after 2.5 s, as Ctrl-C would.
            std::thread::sleep(Duration::from_millis(1500));
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
    let summary = run_live(
        [recorded(&sim, 0), recorded(&sim, 1)],
        &cfg,
        HostClock::new(),
        stop.clone(),
    )
    .expect("live run");
    let (got_start, got_stop) = pen.join().expect("pen thread");
    assert!(got_start, "the host sent Start");
    assert!(got_stop, "the host sent Stop");
    assert!(
        summary.frames[0] > 5 && summary.frames[1] > 5,
        "{summary:?}"
    );
    assert!(summary.link.sensor_frames > 100, "{summary:?}");
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
        summary.link_bytes
    );
    let out = replay(&written, &ReplayConfig::default()).expect("the recording replays");
    assert_eq!(out.frames[0] as u64, summary.frames[0]);
    assert!(out.imu.samples.len() > 100);

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
