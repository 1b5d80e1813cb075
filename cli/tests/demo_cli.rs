//! `fires demo` on a short session: the summary it prints carries the stroke figures of a report with
//! ground truth (docs/report.md): distances, coverage and length of the worst stroke, the vision
//! fraction and the display's lag and jitter.

use std::process::Command;

#[test]
fn the_demo_summary_names_every_stroke_figure() {
    let out = std::env::temp_dir().join(format!("fires-demo-cli-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let run = Command::new(env!("CARGO_BIN_EXE_fires"))
        .arg("demo")
        .arg("--out")
        .arg(&out)
        .args(["--scenario", "fires-v1", "--duration", "6"])
        .output()
        .expect("run fires");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let line = |start: &str| {
        stdout
            .lines()
            .find(|l| l.starts_with(start))
            .unwrap_or_else(|| panic!("no line starting {start:?} in\n{stdout}"))
            .to_string()
    };
    let tracked = line("tracked ");
    assert!(tracked.contains(" mm (median stroke)"), "{tracked}");
    // Numbers, not placeholders: the session has a drawn stroke and truth.
    let worst = line("worst stroke: ");
    assert!(worst.contains("% of its true path within 3 mm"), "{worst}");
    assert!(!worst.contains(" - "), "{worst}");
    let vision = line("vision tips from ");
    assert!(vision.contains("% of the stereo pairs"), "{vision}");
    assert!(
        vision.contains(" ms, jitter at rest ") && vision.ends_with(" mm"),
        "{vision}"
    );
    let _ = std::fs::remove_dir_all(&out);
}
