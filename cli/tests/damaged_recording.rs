//! `fires replay` on a damaged simulated recording: link.bin cut mid-record, one frame image deleted, one cut
//! short. The replay succeeds, tracks the rest, and report.json's `damaged` counts what was skipped. A
//! `meta.json` describing an impossible rig or pen is refused, naming the field.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use fires_record::salvage::scan_link;
use fires_sim::{run_scenario, SimOptions};

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fires-damaged-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn replay(rec: &Path, out: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_fires"))
        .arg("replay")
        .arg(rec)
        .arg("--out")
        .arg(out)
        .args(["--world", "truth"])
        .output()
        .expect("run fires")
}

fn report(out: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(out.join("report.json")).expect("report")).expect("json")
}

fn lines(path: &Path) -> usize {
    std::fs::read_to_string(path)
        .expect("frames")
        .lines()
        .count()
}

#[test]
fn damaged_recording_replays_what_is_whole_and_reports_the_rest() {
    let rec = temp("rec");
    run_scenario("fires-v2", 3, 2.0, &rec, SimOptions::default()).expect("simulate");
    let clean_out = temp("clean-out");
    let clean = replay(&rec, &clean_out);
    assert!(
        clean.status.success(),
        "{}",
        String::from_utf8_lossy(&clean.stderr)
    );
    let clean_report = report(&clean_out);
    assert_eq!(clean_report["damaged"]["warnings"], serde_json::json!([]));
    assert!(!String::from_utf8_lossy(&clean.stderr).contains("warning"));

    // Cut link.bin in the middle of the record two thirds of the way through.
    let link = rec.join("link.bin");
    let bytes = std::fs::read(&link).expect("link.bin");
    let chunks = scan_link(&bytes).chunks;
    let k = chunks.len() * 2 / 3;
    let start: usize = chunks[..k].iter().map(|c| 12 + c.bytes.len()).sum();
    let cut = start + 12 + chunks[k].bytes.len() / 2;
    assert!(cut < start + 12 + chunks[k].bytes.len(), "mid-record");
    std::fs::write(&link, &bytes[..cut]).expect("truncate");
    let kept_bytes: usize = chunks[..k].iter().map(|c| c.bytes.len()).sum();
    // One image deleted, one cut short.
    std::fs::remove_file(rec.join("cam1").join("000005.pgm.zst")).expect("delete");
    let short = rec.join("cam0").join("000010.pgm.zst");
    let img = std::fs::read(&short).expect("image");
    std::fs::write(&short, &img[..img.len() - 100]).expect("cut short");

    let out = temp("out");
    let run = replay(&rec, &out);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let r = report(&out);
    let d = &r["damaged"];
    assert_eq!(d["torn_bytes"]["link.bin"], (cut - start) as u64, "{d}");
    assert_eq!(d["frames_missing"], 1, "{d}");
    assert_eq!(d["frames_unreadable"], 1, "{d}");
    assert_eq!(d["skipped_records"], serde_json::json!({}));
    assert_eq!(d["unread_bytes"], serde_json::json!({}));
    // One warning per kind, on stderr and in the report.
    assert_eq!(d["warnings"].as_array().map(Vec::len), Some(3), "{d}");
    let warnings: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("warning:"))
        .collect();
    assert_eq!(warnings.len(), 3, "{stderr}");
    assert!(warnings
        .iter()
        .any(|w| w.contains("link.bin") && w.contains("torn")));
    assert!(warnings
        .iter()
        .any(|w| w.contains("cam1/000005.pgm.zst") && w.contains("missing")));
    assert!(warnings
        .iter()
        .any(|w| w.contains("cam0/000010.pgm.zst") && w.contains("unreadable")));
    // The kept link bytes are all decoded; every listed frame is counted; the rest is tracked.
    assert_eq!(r["link"]["bytes"], kept_bytes as u64);
    let listed = [
        lines(&rec.join("cam0").join("frames.jsonl")),
        lines(&rec.join("cam1").join("frames.jsonl")),
    ];
    assert_eq!(r["camera_frames"], serde_json::json!(listed));
    let tracked = r["frames_vision"].as_u64().expect("frames_vision");
    let clean_tracked = clean_report["frames_vision"]
        .as_u64()
        .expect("frames_vision");
    assert!(
        tracked + 4 >= clean_tracked && tracked > clean_tracked / 2,
        "tracked {tracked} of the intact recording's {clean_tracked}"
    );
    for d in [&rec, &out, &clean_out] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// Replays `rec` after `edit` changed its meta.json; returns the failure message.
fn refused(rec: &Path, edit: impl FnOnce(&mut serde_json::Value)) -> String {
    let path = rec.join("meta.json");
    let original = std::fs::read(&path).expect("meta");
    let mut meta: serde_json::Value = serde_json::from_slice(&original).expect("json");
    edit(&mut meta);
    std::fs::write(&path, serde_json::to_vec(&meta).expect("json")).expect("write");
    let out = temp("refused-out");
    let run = replay(rec, &out);
    std::fs::write(&path, original).expect("restore");
    let _ = std::fs::remove_dir_all(&out);
    assert!(!run.status.success(), "accepted");
    String::from_utf8_lossy(&run.stderr).into_owned()
}

#[test]
fn impossible_calibration_or_pen_is_refused_naming_the_field() {
    let rec = temp("meta");
    run_scenario("fires-v1", 4, 0.3, &rec, SimOptions::default()).expect("simulate");
    let fx = refused(&rec, |m| {
        m["rig"]["cameras"][1]["intrinsics"]["fx"] = (-1.0).into()
    });
    assert!(
        fx.contains(
            "meta.json: rig.cameras[1].intrinsics.fx = -1.0: focal length must be positive"
        ),
        "{fx}"
    );
    let baseline = refused(&rec, |m| {
        m["rig"]["cameras"][1]["extrinsics"] = m["rig"]["cameras"][0]["extrinsics"].clone();
    });
    assert!(
        baseline.contains("rig.cameras[1].extrinsics.translation_m")
            && baseline.contains("baseline"),
        "{baseline}"
    );
    // Distances 40 and 45 mm: closer than twice the identification's 4.5 mm tolerance.
    let pen = refused(&rec, |m| {
        m["pen"]["led_positions_m"] = serde_json::json!([0.0, 0.04, 0.085, 0.16]);
    });
    assert!(
        pen.contains("pen.led_positions_m = [0.0, 0.04, 0.085, 0.16]") && pen.contains("tolerance"),
        "{pen}"
    );
    let _ = std::fs::remove_dir_all(&rec);
}
