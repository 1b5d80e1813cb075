//! `fires mesh info` as a user runs it: one JSON line of counts and topology, repairs named, and a broken file
//! as one error line with exit code 2.

use std::path::PathBuf;
use std::process::Command;

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fires-mesh-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn info(path: &std::path::Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_fires"))
        .args(["mesh", "info"])
        .arg(path)
        .output()
        .expect("run fires")
}

#[test]
fn a_quad_cube_and_a_flipped_face_are_described_in_one_line() {
    let cube = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../recon/tests/data/quad_cube.off");
    let out = info(&cube);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert_eq!(text.lines().count(), 1);
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(
        (
            v["vertices"].as_u64(),
            v["faces"].as_u64(),
            v["quads"].as_u64()
        ),
        (Some(8), Some(6), Some(6))
    );
    assert_eq!(
        (
            v["genus"].as_i64(),
            v["closed"].as_bool(),
            v["orientable"].as_bool()
        ),
        (Some(0), Some(true), Some(true))
    );

    // The same cube with one face written the other way round: read, oriented, and the flip reported.
    let dir = temp("flip");
    let text = std::fs::read_to_string(&cube).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let face = lines
        .iter()
        .position(|l| l.trim_start().starts_with("4 "))
        .unwrap();
    let mut idx: Vec<&str> = lines[face].split_whitespace().collect();
    idx[1..].reverse();
    lines[face] = idx.join(" ");
    let flipped = dir.join("flipped.off");
    std::fs::write(&flipped, lines.join("\n") + "\n").unwrap();
    let out = info(&flipped);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["closed"].as_bool(), Some(true), "{v}");
    assert!(
        v["repairs"].to_string().contains('1'),
        "the flip is reported: {v}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_vertex_index_out_of_range_is_one_error_line_and_exit_code_2() {
    let dir = temp("bad");
    let bad = dir.join("bad.off");
    std::fs::write(&bad, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n").unwrap();
    let out = info(&bad);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("fires: error:"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
