//! `fires pivot` on a simulated pivot gesture: the tip offset and the pivot point come back, and a recording
//! that is not of a four-LED pen, or not of a pivot, is refused with a one-line error.

use std::path::PathBuf;
use std::process::{Command, Output};

use fires_sim::{run_scenario, SimOptions};

/// Simulates `scenario` (blob lists, with truth) and runs `fires pivot` on it.
fn pivot_on(scenario: &str, seed: u64, seconds: f64) -> Output {
    let rec: PathBuf =
        std::env::temp_dir().join(format!("fires-pivot-cli-{scenario}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&rec);
    let opts = SimOptions {
        images: false,
        ..SimOptions::default()
    };
    run_scenario(scenario, seed, seconds, &rec, opts).expect("simulate");
    let out = Command::new(env!("CARGO_BIN_EXE_fires"))
        .arg("pivot")
        .arg(&rec)
        .output()
        .expect("run fires");
    let _ = std::fs::remove_dir_all(&rec);
    out
}

/// The one-line error of a refused run.
fn refusal(out: &Output) -> String {
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("fires: error:"), "{err}");
    err
}

#[test]
fn the_tip_offset_is_fitted_from_the_pivot_gesture() {
    let out = pivot_on("pivot", 3, 6.0);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let fit: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON line");
    let num = |k: &str| fit[k].as_f64().unwrap_or(f64::NAN);
    // The simulated pen's tip is 20 mm ahead of LED 1; the pivot is at (0.10, 0.05, 0.70) m.
    // Per-pose noise is about 1 mm (0.5 px at 0.7 m) over hundreds of poses.
    assert!((num("tip_offset_mm") - 20.0).abs() < 0.5, "{fit}");
    let p = &fit["pivot_m"];
    let d = [0.10, 0.05, 0.70]
        .iter()
        .enumerate()
        .map(|(i, t)| (p[i].as_f64().unwrap_or(f64::NAN) - t).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(d < 0.001, "pivot {d} m off: {fit}");
    assert!(num("rms_mm") < 1.5, "{fit}");
    assert!(num("spread_deg") > 20.0, "{fit}");
}

#[test]
fn a_two_led_recording_is_refused() {
    let err = refusal(&pivot_on("bar", 1, 0.5));
    assert!(err.contains("2 LED"), "{err}");
}

#[test]
fn a_drawing_session_is_not_taken_for_a_pivot() {
    let err = refusal(&pivot_on("fires-v1", 1, 4.0));
    assert!(err.contains("did not stay on one point"), "{err}");
}
