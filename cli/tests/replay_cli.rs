//! `fires replay` on a short simulated session: its outputs (the tip-error plot, and the report and strokes
//! files through their typed readers).

use std::path::PathBuf;
use std::process::Command;

use fires_sim::{run_scenario, SimOptions};

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fires-replay-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn replay_writes_a_tip_error_png() {
    let rec = temp("rec");
    let out = temp("out");
    run_scenario("fires-v1", 5, 3.0, &rec, SimOptions::default()).expect("simulate");
    let status = Command::new(env!("CARGO_BIN_EXE_fires"))
        .arg("replay")
        .arg(&rec)
        .arg("--out")
        .arg(&out)
        // The simulated world reference: 3 s is about the time the online estimate needs, and
        // this test is about the plot of a full track.
        .args(["--world", "truth"])
        .output()
        .expect("run fires");
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let png = std::fs::read(out.join("tip_error.png")).expect("tip_error.png");
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&png[12..16], b"IHDR");
    let width = u32::from_be_bytes(png[16..20].try_into().expect("4 bytes"));
    let height = u32::from_be_bytes(png[20..24].try_into().expect("4 bytes"));
    assert_eq!(
        (width, height),
        fires_host::replay::plot::TIP_ERROR_SIZE,
        "dimensions"
    );
    assert!(png.len() > 2000, "a plot, not an empty image");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).expect("report"))
            .expect("json");
    let scale = &report["tip_error_plot"]["scale"];
    assert!(scale["points"].as_u64().expect("points") > 100, "{report}");
    assert!(scale["y_max_mm"].as_f64().expect("y max") >= 3.0);
    // Both files read back through their typed readers (docs/report.md, docs/strokes.md).
    let typed = fires_record::Report::from_json(&std::fs::read(out.join("report.json")).unwrap())
        .expect("typed report");
    let fires_record::Report::Replay(typed) = typed else {
        panic!("a pen session gives a replay report")
    };
    let strokes = fires_record::StrokesFile::read(&out.join("strokes.json")).expect("strokes");
    assert_eq!(typed.strokes, strokes.strokes.len());
    assert!(typed.accuracy.is_some() && typed.tip_error_plot.is_some());
    // The display follows the pen (One Euro by default), and every true stroke has its figures and its floor.
    let display = typed.display.as_ref().expect("display block");
    assert_eq!(display.filter, "one-euro");
    assert!(display.lag_ms.is_some_and(|l| l <= 50.0), "{display:?}");
    let vs = typed.strokes_vs_truth.as_ref().expect("strokes_vs_truth");
    assert_eq!(
        typed.strokes_summary.map(|s| s.true_strokes),
        Some(vs.len())
    );
    assert!(typed.strokes_floor.is_some() && typed.strokes_floor_summary.is_some());
    let _ = std::fs::remove_dir_all(&rec);
    let _ = std::fs::remove_dir_all(&out);
}
