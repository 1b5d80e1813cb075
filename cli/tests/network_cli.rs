//! `fires network` as a user runs it: strokes in (a simulated session's true strokes), `network.json`, a
//! picture and one summary line out; the journal it writes replays to the same network; a broken input is one
//! error line with exit code 2.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fires-network-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn fires(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_fires"))
        .args(args)
        .output()
        .expect("run fires")
}

fn ok(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout.clone()).unwrap();
    assert_eq!(text.lines().count(), 1, "{text}");
    serde_json::from_str(&text).unwrap()
}

fn simulate(dir: &Path) -> PathBuf {
    let rec = dir.join("rec");
    ok_status(&fires(&[
        "sim".as_ref(),
        "--scenario".as_ref(),
        "fires-v1".as_ref(),
        "--duration".as_ref(),
        "25".as_ref(),
        "--no-images".as_ref(),
        "--out".as_ref(),
        rec.as_os_str(),
    ]));
    rec.join("truth/strokes.json")
}

fn ok_status(out: &Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn true_strokes_make_the_planned_network_and_its_journal_replays_it() {
    let dir = temp("truth");
    let strokes = simulate(&dir);
    let truth: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&strokes).unwrap()).unwrap();
    // A stroke cut off by the end of the session may be trimmed at its last crossing and used: the
    // count below is for the complete ones, so only they go in.
    let complete: Vec<serde_json::Value> = truth
        .as_array()
        .unwrap()
        .iter()
        .filter(|s| s["complete"] == true)
        .cloned()
        .collect();
    let strokes = dir.join("complete.json");
    std::fs::write(&strokes, serde_json::to_vec(&complete).unwrap()).unwrap();
    // The boundary's disc plus one face per piece of every complete crossing stroke.
    let implied = 1 + complete
        .iter()
        .filter(|s| s["kind"] == "crossing")
        .map(|s| s["crosses"].as_array().unwrap().len() + 1)
        .sum::<usize>();

    let (net, png, journal) = (
        dir.join("net.json"),
        dir.join("net.png"),
        dir.join("j.json"),
    );
    let v = ok(&fires(&[
        "network".as_ref(),
        strokes.as_os_str(),
        "-o".as_ref(),
        net.as_os_str(),
        "--png".as_ref(),
        png.as_os_str(),
        "--journal-out".as_ref(),
        journal.as_os_str(),
    ]));
    assert_eq!(v["faces"].as_u64(), Some(implied as u64), "{v}");
    assert_eq!(
        v["used_strokes"].as_u64(),
        Some(complete.len() as u64),
        "{v}"
    );
    assert_eq!(v["boundaries"].as_u64(), Some(1));
    assert_eq!(v["euler"].as_i64(), Some(1));
    assert!(v["ms"].as_f64().is_some_and(|ms| ms > 0.0));
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);

    // Replaying the journal over the same strokes gives the same file, byte for byte.
    let again = dir.join("again.json");
    ok(&fires(&[
        "network".as_ref(),
        strokes.as_os_str(),
        "--journal".as_ref(),
        journal.as_os_str(),
        "-o".as_ref(),
        again.as_os_str(),
    ]));
    assert_eq!(std::fs::read(&net).unwrap(), std::fs::read(&again).unwrap());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_broken_strokes_file_is_one_error_line() {
    let dir = temp("broken");
    let bad = dir.join("strokes.json");
    std::fs::write(
        &bad,
        "{\"format\": \"fires-strokes\", \"version\": \"1.0\", \"strokes\": [",
    )
    .unwrap();
    let out = fires(&[
        "network".as_ref(),
        bad.as_os_str(),
        "-o".as_ref(),
        dir.join("n.json").as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("strokes.json"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
