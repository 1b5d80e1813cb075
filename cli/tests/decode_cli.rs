//! `fires decode` on the committed sample stream (samples/make_pen_stream.py says which faults it holds).

use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Stdio};

fn sample() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../samples/pen-stream.bin")
}

fn lines(stdout: &[u8]) -> Vec<serde_json::Value> {
    String::from_utf8_lossy(stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("every line is JSON"))
        .collect()
}

fn check_sample_output(values: &[serde_json::Value]) {
    let summary = values.last().expect("a summary line");
    assert_eq!(summary["kind"], "summary");
    assert_eq!(summary["sensor_frames"], 494);
    assert_eq!(summary["status_frames"], 5);
    assert_eq!(summary["lost"], 6);
    assert_eq!(summary["duplicates"], 1);
    // 40 bytes of banner, two corrupted packets, one packet short of a byte.
    assert_eq!(summary["bytes_skipped"], 40 + 2 * 22 + 21);
    let counters: Vec<u64> = values
        .iter()
        .filter(|v| v["kind"] == "sensor")
        .map(|v| v["counter"].as_u64().expect("counter"))
        .collect();
    let expected: Vec<u64> = (0..500u64)
        .filter(|i| ![100, 101, 200, 300, 350, 420].contains(i))
        .map(|i| i % 256)
        .collect();
    assert_eq!(counters, expected);
    let resting = &values[0];
    assert_eq!(resting["accel"], serde_json::json!([0, 0, 1024]));
}

#[test]
fn decodes_exactly_the_intact_packets_of_the_sample() {
    let out = Command::new(env!("CARGO_BIN_EXE_fires"))
        .arg("decode")
        .arg(sample())
        .output()
        .expect("run fires");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    check_sample_output(&lines(&out.stdout));
}

#[test]
fn reads_standard_input() {
    let bytes = std::fs::read(sample()).expect("sample is committed");
    let mut child = Command::new(env!("CARGO_BIN_EXE_fires"))
        .args(["decode", "-"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .expect("run fires");
    child
        .stdin
        .take()
        .expect("stdin")
        .write_all(&bytes)
        .expect("write");
    let out = child.wait_with_output().expect("wait");
    assert!(out.status.success());
    check_sample_output(&lines(&out.stdout));
}

#[test]
fn a_missing_file_is_one_clear_line_and_exit_code_2() {
    let out = Command::new(env!("CARGO_BIN_EXE_fires"))
        .args(["decode", "/nonexistent/pen.bin"])
        .output()
        .expect("run fires");
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("/nonexistent/pen.bin") && err.contains("No such file"),
        "{err}"
    );
    assert!(out.stdout.is_empty());
}

#[test]
fn a_directory_is_an_error_not_a_panic() {
    let out = Command::new(env!("CARGO_BIN_EXE_fires"))
        .args(["decode", env!("CARGO_MANIFEST_DIR")])
        .output()
        .expect("run fires");
    assert_eq!(out.status.code(), Some(2));
    assert!(!String::from_utf8_lossy(&out.stderr).contains("panicked"));
}
