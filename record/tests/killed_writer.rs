//! A writer killed (SIGKILL) at random moments leaves a recording that reads, with no error, up to its last
//! whole record, and that holds every record whose append had returned before the kill.
//!
//! The writer is this test binary itself, re-run with `FIRES_KILLED_WRITER_DIR` set: it then runs the
//! ignored test `child_writes_records_forever`, which appends records until it is killed and prints
//! `wrote N` after the append of link record `N` returns.

#![cfg(unix)]

mod common;
use common::test_meta;
use fires_record::*;
use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const ENV: &str = "FIRES_KILLED_WRITER_DIR";

fn meta() -> Meta {
    test_meta((16, 12), 0.06, &[FrameContent::Images], None, true)
}

/// Link record `i`: time `10 i` ns, `i % 97 + 1` bytes derived from `i`.
fn chunk(i: u64) -> LinkChunk {
    LinkChunk {
        host_time_ns: 10 * i,
        bytes: (0..i % 97 + 1).map(|k| (i * 31 + k) as u8).collect(),
    }
}

fn image(i: u64) -> GrayImage {
    let mut img = GrayImage::new(16, 12);
    for (k, p) in img.data.iter_mut().enumerate() {
        *p = (i as usize + k) as u8;
    }
    img
}

fn imu(i: u64) -> ImuTruth {
    ImuTruth {
        sample_index: i,
        counter: i as u8,
        device_time_us: i,
        time_ns: 10 * i,
        pose: PoseTruth {
            tip_m: [i as f64; 3],
            orientation_xyzw: [0.0, 0.0, 0.0, 1.0],
            leds_m: vec![],
        },
        specific_force_mps2: [0.0; 3],
        angular_velocity_radps: [0.0; 3],
        earth_field_t: [0.0; 3],
        gyro_bias_radps: [0.0; 3],
        buttons: 0,
    }
}

/// The child: appends link records, an IMU truth line per record and an image frame every 4th record, until
/// killed. (Ignored: it never ends; the parent test runs it in a child process.)
#[test]
#[ignore = "runs forever; started by killed_writer_leaves_a_readable_recording"]
fn child_writes_records_forever() {
    let Some(dir) = std::env::var_os(ENV) else {
        return;
    };
    let mut w = RecordingWriter::create(Path::new(&dir), &meta()).expect("create");
    let mut out = std::io::stdout().lock();
    for i in 0.. {
        w.write_link_chunk(&chunk(i)).expect("link");
        w.write_imu_truth(&imu(i)).expect("imu");
        if i % 4 == 0 {
            let f = CameraFrame {
                camera: 0,
                index: i / 4,
                exposure_time_ns: 10 * i,
                blobs: None,
                image: None,
            };
            w.write_frame(&f, Some(&image(i / 4))).expect("frame");
        }
        writeln!(out, "wrote {i}").expect("stdout");
        out.flush().expect("stdout");
    }
}

/// SplitMix64: a seeded, dependency-free source of kill times.
fn splitmix(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[test]
fn killed_writer_leaves_a_readable_recording() {
    let exe = std::env::current_exe().expect("test binary");
    let mut seed = 12;
    for iteration in 0..8 {
        let dir = tempfile::tempdir().expect("tempdir");
        let mut child = Command::new(&exe)
            .args([
                "child_writes_records_forever",
                "--exact",
                "--ignored",
                "--nocapture",
                "--test-threads=1",
            ])
            .env(ENV, dir.path())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("spawn the writer");
        let stdout = child.stdout.take().expect("piped");
        let (tx, rx) = std::sync::mpsc::channel();
        let reader = std::thread::spawn(move || {
            let mut last = None;
            for line in BufReader::new(stdout).lines() {
                let Ok(line) = line else { break };
                if let Some(n) = line.strip_prefix("wrote ") {
                    if last.is_none() {
                        let _ = tx.send(());
                    }
                    last = n.parse::<u64>().ok();
                }
            }
            last
        });
        // Kill 0-300 ms after the first record returned.
        rx.recv_timeout(Duration::from_secs(60))
            .expect("the writer starts writing");
        let delay = Duration::from_micros(splitmix(&mut seed) % 300_000);
        let t = Instant::now();
        while t.elapsed() < delay {
            std::thread::sleep(Duration::from_millis(1));
        }
        child.kill().expect("SIGKILL");
        let status = child.wait().expect("wait");
        assert!(!status.success(), "killed");
        let acknowledged = reader
            .join()
            .expect("reader thread")
            .expect("at least one record");

        let r = RecordingReader::open_salvaging(dir.path()).expect("meta.json survives");
        let chunks = r.link_chunks().expect("no error");
        let imu_lines = r.imu_truth().expect("no error").expect("truth");
        let frames = r.frames(0).expect("no error");
        // Every record in the file is whole and in order; every acknowledged record is there.
        assert!(
            chunks.len() as u64 > acknowledged,
            "iteration {iteration}: {} records, {acknowledged} acknowledged",
            chunks.len()
        );
        for (i, c) in chunks.iter().enumerate() {
            assert_eq!(c, &chunk(i as u64), "iteration {iteration}, record {i}");
        }
        for (i, t) in imu_lines.iter().enumerate() {
            assert_eq!(t, &imu(i as u64));
        }
        assert!(imu_lines.len() as u64 > acknowledged);
        assert!(frames.len() as u64 > acknowledged / 4);
        for (k, f) in frames.iter().enumerate() {
            assert_eq!(f.index, k as u64);
            // The image is written whole before its line: never lost.
            assert_eq!(
                r.frame_image(f).expect("no error"),
                FrameImage::Image(image(k as u64)),
                "iteration {iteration}, frame {k}"
            );
        }
        // At most the record being written when the kill came is torn; nothing is skipped or lost.
        let dmg = r.damage();
        assert!(
            dmg.skipped_records.is_empty() && dmg.unread_bytes.is_empty(),
            "{dmg:?}"
        );
        assert_eq!(
            (dmg.frames_missing, dmg.frames_unreadable),
            (0, 0),
            "{dmg:?}"
        );
        assert!(dmg.lost_files.is_empty(), "{dmg:?}");
    }
}
