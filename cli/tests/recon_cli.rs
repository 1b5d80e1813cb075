//! `fires recon` as a user runs it: a simulated session's true strokes in, a quad surface (OBJ), its curves
//! (OBJ lines), a picture and one summary line out, with both methods, compared with the session's true object;
//! a journal without its strokes is one error line with exit code 2.

use std::path::PathBuf;
use std::process::{Command, Output};

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fires-recon-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn fires<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_fires"))
        .args(args)
        .output()
        .expect("run fires")
}

fn json_line(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout.clone()).unwrap();
    assert_eq!(text.lines().count(), 1, "{text}");
    serde_json::from_str(&text).unwrap()
}

#[test]
fn both_methods_rebuild_the_true_object_from_the_true_strokes() {
    let dir = temp("methods");
    let rec = dir.join("rec");
    let out = fires(&[
        "sim",
        "--scenario",
        "fires-v2",
        "--seed",
        "2",
        "--duration",
        "45",
        "--no-images",
        "--out",
        rec.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let strokes = rec.join("truth/strokes.json");
    for method in ["v1", "v2"] {
        let obj = dir.join(format!("{method}.obj"));
        let png = dir.join(format!("{method}.png"));
        let v = json_line(&fires(&[
            "recon",
            strokes.to_str().unwrap(),
            "-o",
            obj.to_str().unwrap(),
            "--method",
            method,
            "--png",
            png.to_str().unwrap(),
            "--truth",
            rec.to_str().unwrap(),
        ]));
        assert_eq!(v["method"], method);
        assert!(v["network_faces"].as_u64().unwrap() >= 10, "{v}");
        // The drawn curves are the measurement: the surface keeps them.
        assert!(v["curve_rms_mm"].as_f64().unwrap() <= 0.1, "{v}");
        let t = &v["truth"];
        // The surface issue's figure for a reconstruction from the true strokes (0.3% of the drawn region's
        // diagonal), and the region covered.
        assert!(t["rms_pct_diag"].as_f64().unwrap() <= 0.3, "{v}");
        assert!(t["completeness_3mm"].as_f64().unwrap() >= 0.95, "{v}");
        // Quads only, and the curves as OBJ line elements beside the mesh.
        let text = std::fs::read_to_string(&obj).unwrap();
        let faces: Vec<&str> = text.lines().filter(|l| l.starts_with("f ")).collect();
        assert_eq!(faces.len() as u64, v["faces"].as_u64().unwrap());
        assert!(faces.iter().all(|f| f.split_whitespace().count() == 5));
        let curves = std::fs::read_to_string(dir.join(format!("{method}.curves.obj"))).unwrap();
        assert!(curves.lines().filter(|l| l.starts_with("l ")).count() >= 10);
        assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_journal_without_its_strokes_is_one_error_line() {
    let dir = temp("journal");
    let j = dir.join("j.json");
    std::fs::write(
        &j,
        r#"{"format": "fires-sketch-journal", "version": "1.0", "steps": []}"#,
    )
    .unwrap();
    let out = fires(&[
        "recon",
        j.to_str().unwrap(),
        "-o",
        dir.join("s.obj").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("--strokes"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
