//! `fires edit` / `fires bench edit` / `fires denoise` end to end on a generated mesh.

use std::path::PathBuf;
use std::process::Command;

use fires_recon::generate::cylinder;
use fires_recon::io::{write_mesh_file, PolygonSoup};

fn dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("fires_edit_cli_{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn fires(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_fires"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn edit_writes_mesh_png_and_one_json_line() {
    let d = dir();
    let mesh = d.join("cyl.off");
    write_mesh_file(
        &mesh,
        &PolygonSoup::from_mesh(&cylinder(1.0, 3.0, 24, 16, false)),
    )
    .unwrap();
    let spec = d.join("spec.json");
    let top: Vec<usize> = (15 * 24..16 * 24).collect();
    std::fs::write(
        &spec,
        format!(
            r#"{{"roi": "all", "anchors": {{"vertices": [{}]}},
               "handles": [{{"select": {{"vertices": {top:?}}},
                            "transform": {{"rotate": {{"axis": [0, 0, 1], "deg": 45}}}}}}]}}"#,
            (0..24).map(|i| i.to_string()).collect::<Vec<_>>().join(",")
        ),
    )
    .unwrap();
    let out = d.join("out.obj");
    let png = d.join("out.png");
    let r = fires(&[
        "edit",
        "poisson",
        mesh.to_str().unwrap(),
        spec.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--png",
        png.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let line = String::from_utf8(r.stdout).unwrap();
    let v: serde_json::Value = serde_json::from_str(line.trim()).unwrap();
    for k in [
        "method",
        "roi_vertices",
        "build_ms",
        "factor_ms",
        "solve_ms",
        "detail_error",
    ] {
        assert!(v.get(k).is_some(), "missing {k} in {line}");
    }
    assert_eq!(v["roi_vertices"], 24 * 16);
    assert!(v["detail_error"].as_f64().unwrap() > 0.0);
    assert!(out.exists() && png.exists());

    let r = fires(&[
        "bench",
        "edit",
        mesh.to_str().unwrap(),
        "--method",
        "naive",
        "--roi-fraction",
        "0.5",
        "--moves",
        "3",
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let v: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert!(v["per_move_ms"].as_f64().is_some() && v["cotan_solve_ms"].as_f64().is_some());

    std::fs::write(&spec, r#"{"roi": "all", "handles": [], "colour": 1}"#).unwrap();
    let r = fires(&[
        "edit",
        "lse",
        mesh.to_str().unwrap(),
        spec.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(r.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&r.stderr).contains("unknown field `colour`"));
}

#[test]
fn edit_accepts_a_handle_given_as_positions() {
    let d = dir().join("positions");
    std::fs::create_dir_all(&d).unwrap();
    let mesh = d.join("cyl.off");
    write_mesh_file(
        &mesh,
        &PolygonSoup::from_mesh(&cylinder(1.0, 3.0, 24, 16, false)),
    )
    .unwrap();
    // The top ring (z = 3) lifted by 0.5 and squeezed to an ellipse.
    let top: Vec<usize> = (15 * 24..16 * 24).collect();
    let pos: Vec<String> = (0..24)
        .map(|j| {
            let phi = 2.0 * std::f64::consts::PI * j as f64 / 24.0;
            format!("[{}, {}, 3.5]", 1.2 * phi.cos(), 0.8 * phi.sin())
        })
        .collect();
    let write = |name: &str, extra: &str| {
        let spec = d.join(name);
        std::fs::write(
            &spec,
            format!(
                r#"{{"roi": "all", "anchors": {{"vertices": [{}]}},
                   "handles": [{{"select": {{"vertices": {top:?}}}, "positions": [{}]{extra}}}]}}"#,
                (0..24).map(|i| i.to_string()).collect::<Vec<_>>().join(","),
                pos.join(",")
            ),
        )
        .unwrap();
        spec
    };
    let out = d.join("out.off");
    let spec = write("spec.json", "");
    let r = fires(&[
        "edit",
        "poisson",
        mesh.to_str().unwrap(),
        spec.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let line = String::from_utf8(r.stdout).unwrap();
    let v: serde_json::Value = serde_json::from_str(line.trim()).unwrap();
    assert_eq!(v["method"], "poisson");
    assert!(v["detail_error"].as_f64().unwrap() > 0.0);
    let edited = fires_recon::io::read_mesh_file(&out)
        .unwrap()
        .to_mesh()
        .unwrap();
    let p = edited.positions()[15 * 24 + 6];
    assert!(
        (p.z - 3.5).abs() < 1e-9 && (p.y - 0.8).abs() < 1e-9,
        "{p:?}"
    );
    // Both a transform and positions: a named error, exit code 2.
    let bad = write("bad.json", r#", "transform": {"scale": 2}"#);
    let r = fires(&[
        "edit",
        "poisson",
        mesh.to_str().unwrap(),
        bad.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(r.status.code(), Some(2));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("handle 0 positions") && err.contains("not both"),
        "{err}"
    );
}
