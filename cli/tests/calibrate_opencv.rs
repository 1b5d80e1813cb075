//! Stereo calibration against a rig known in closed form: chessboard views rendered through two distorted
//! pinhole cameras, calibrated back with OpenCV (needs `--features opencv`).
#![cfg(feature = "opencv")]

use fires_host::calibrate::chessboard::{calibrate_stereo, Chessboard, GrayView};

type V3 = [f64; 3];
type M3 = [[f64; 3]; 3];

const W: usize = 640;
const H: usize = 480;

#[derive(Clone, Copy)]
struct Cam {
    f: f64,
    cx: f64,
    cy: f64,
    k1: f64,
    k2: f64,
}

fn mul(m: &M3, v: V3) -> V3 {
    [0, 1, 2].map(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
}
fn matmul(a: &M3, b: &M3) -> M3 {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}
fn rot(axis: usize, a: f64) -> M3 {
    let (s, c) = a.sin_cos();
    match axis {
        0 => [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]],
        1 => [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]],
        _ => [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
    }
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Normalised coordinates of a distorted pixel (fixed-point inversion of the radial model).
fn undistort(cam: &Cam, u: f64, v: f64) -> (f64, f64) {
    let (xd, yd) = ((u - cam.cx) / cam.f, (v - cam.cy) / cam.f);
    let (mut x, mut y) = (xd, yd);
    for _ in 0..8 {
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (cam.k1 + r2 * cam.k2);
        x = xd / radial;
        y = yd / radial;
    }
    (x, y)
}

/// Renders the board (pose `r_b`, `t_b` in this camera's frame) with 3x3 supersampling.
fn render(cam: &Cam, board: &Chessboard, r_b: &M3, t_b: V3) -> Vec<u8> {
    let n = [r_b[0][2], r_b[1][2], r_b[2][2]];
    let s = board.square_m;
    let shade = |u: f64, v: f64| -> f64 {
        let (x, y) = undistort(cam, u, v);
        let d = [x, y, 1.0];
        let lambda = dot(n, t_b) / dot(n, d);
        let p = [
            lambda * d[0] - t_b[0],
            lambda * d[1] - t_b[1],
            lambda * d[2] - t_b[2],
        ];
        let (bx, by) = (
            dot([r_b[0][0], r_b[1][0], r_b[2][0]], p),
            dot([r_b[0][1], r_b[1][1], r_b[2][1]], p),
        );
        let (i, j) = ((bx / s).floor() as i64, (by / s).floor() as i64);
        let inside =
            (-1..i64::from(board.cols)).contains(&i) && (-1..i64::from(board.rows)).contains(&j);
        let margin =
            (-2..=i64::from(board.cols)).contains(&i) && (-2..=i64::from(board.rows)).contains(&j);
        if inside {
            if (i + j).rem_euclid(2) == 0 {
                20.0
            } else {
                235.0
            }
        } else if margin {
            235.0
        } else {
            90.0
        }
    };
    let mut img = vec![0u8; W * H];
    for v in 0..H {
        for u in 0..W {
            let mut sum = 0.0;
            for a in [-1.0 / 3.0, 0.0, 1.0 / 3.0] {
                for b in [-1.0 / 3.0, 0.0, 1.0 / 3.0] {
                    sum += shade(u as f64 + a, v as f64 + b);
                }
            }
            img[v * W + u] = (sum / 9.0).round() as u8;
        }
    }
    img
}

#[test]
fn recovers_a_known_distorted_stereo_rig() {
    let board = Chessboard {
        cols: 9,
        rows: 6,
        square_m: 0.025,
    };
    let left = Cam {
        f: 700.0,
        cx: 321.0,
        cy: 238.0,
        k1: -0.08,
        k2: 0.0,
    };
    let right = Cam {
        f: 690.0,
        cx: 318.0,
        cy: 242.0,
        k1: -0.06,
        k2: 0.0,
    };
    let r_lr = rot(1, 3.0f64.to_radians());
    let t_lr = [-0.08, 0.002, 0.003];
    let poses: Vec<(M3, V3)> = [
        (-20.0, 15.0, 3.0),
        (15.0, -20.0, -5.0),
        (25.0, 10.0, 8.0),
        (-10.0, -25.0, 0.0),
        (5.0, 25.0, -10.0),
        (-25.0, -5.0, 12.0),
        (20.0, 20.0, 0.0),
        (0.0, 0.0, 20.0),
    ]
    .iter()
    .enumerate()
    .map(|(k, &(ax, ay, az))| {
        let r = matmul(
            &rot(2, f64::to_radians(az)),
            &matmul(&rot(1, f64::to_radians(ay)), &rot(0, f64::to_radians(ax))),
        );
        // Board centre near the optical axes, 0.45-0.6 m away; origin at the first inner corner.
        let centre = [
            -0.02 + 0.05 * (k % 3) as f64,
            -0.04 + 0.08 * (k % 2) as f64,
            0.55 + 0.02 * k as f64,
        ];
        let half = mul(&r, [4.0 * board.square_m, 2.5 * board.square_m, 0.0]);
        (
            r,
            [
                centre[0] - half[0],
                centre[1] - half[1],
                centre[2] - half[2],
            ],
        )
    })
    .collect();
    let images: Vec<(Vec<u8>, Vec<u8>)> = poses
        .iter()
        .map(|(r, t)| {
            let r_r = matmul(&r_lr, r);
            let t_r = mul(&r_lr, *t);
            (
                render(&left, &board, r, *t),
                render(
                    &right,
                    &board,
                    &r_r,
                    [t_r[0] + t_lr[0], t_r[1] + t_lr[1], t_r[2] + t_lr[2]],
                ),
            )
        })
        .collect();
    let dir = std::env::temp_dir().join(format!("fires-calib-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    for (k, (l, r)) in images.iter().enumerate() {
        for (name, img) in [("left", l), ("right", r)] {
            let mut pgm = format!("P5\n{W} {H}\n255\n").into_bytes();
            pgm.extend_from_slice(img);
            std::fs::write(dir.join(format!("{name}_{k}.pgm")), pgm).expect("write view");
        }
    }
    check_cli(&dir, &t_lr);
    let _ = std::fs::remove_dir_all(&dir);
    let views: Vec<(GrayView<'_>, GrayView<'_>)> = images
        .iter()
        .map(|(l, r)| {
            (
                GrayView {
                    width: W,
                    height: H,
                    pixels: l,
                },
                GrayView {
                    width: W,
                    height: H,
                    pixels: r,
                },
            )
        })
        .collect();
    let cal = calibrate_stereo(&views, &board).expect("calibration");
    assert_eq!(cal.views, poses.len());
    for (got, want) in [(&cal.left, &left), (&cal.right, &right)] {
        let (rms_px, got) = (got.rms_px, &got.model);
        assert!(
            (got.fx / want.f - 1.0).abs() < 0.005,
            "fx {} vs {}",
            got.fx,
            want.f
        );
        assert!(
            (got.fy / want.f - 1.0).abs() < 0.005,
            "fy {} vs {}",
            got.fy,
            want.f
        );
        assert!(
            (got.cx - want.cx).abs() < 2.0 && (got.cy - want.cy).abs() < 2.0,
            "{got:?}"
        );
        assert!((got.k1 - want.k1).abs() < 0.02, "k1 {}", got.k1);
        assert!(rms_px < 0.3, "rms {rms_px}");
    }
    let dt: f64 = (0..3)
        .map(|i| (cal.translation_m[i] - t_lr[i]).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(
        dt < 0.0015,
        "baseline error {dt} m: {:?}",
        cal.translation_m
    );
    let trace: f64 = (0..3)
        .map(|i| (0..3).map(|k| cal.rotation[k][i] * r_lr[k][i]).sum::<f64>())
        .sum();
    let angle = ((trace - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees();
    assert!(angle < 0.2, "rotation error {angle} deg");
    assert!(cal.stereo_rms_px < 0.3, "stereo rms {}", cal.stereo_rms_px);
    println!("{cal:?}");
}

/// `fires calibrate` on the same views as image files writes a rig that recordings can read.
fn check_cli(dir: &std::path::Path, t_lr: &V3) {
    let out_json = dir.join("rig.json");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_fires"))
        .args([
            "calibrate",
            "--board",
            "9x6",
            "--square-mm",
            "25",
            "--images",
        ])
        .arg(dir)
        .arg("--out")
        .arg(&out_json)
        .output()
        .expect("run fires");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON report");
    assert_eq!(report["views"], 8);
    let rig: fires_record::RigCalibration =
        serde_json::from_str(&std::fs::read_to_string(&out_json).expect("rig.json"))
            .expect("rig parses");
    assert_eq!(rig.cameras.len(), 2);
    let t = rig.cameras[1].extrinsics.translation_m;
    let dt: f64 = (0..3).map(|i| (t[i] - t_lr[i]).powi(2)).sum::<f64>().sqrt();
    assert!(dt < 0.0015, "baseline error {dt} m");
}

#[test]
fn too_few_views_is_a_typed_error() {
    let board = Chessboard {
        cols: 9,
        rows: 6,
        square_m: 0.025,
    };
    let blank = vec![128u8; W * H];
    let views = vec![
        (
            GrayView {
                width: W,
                height: H,
                pixels: &blank
            },
            GrayView {
                width: W,
                height: H,
                pixels: &blank
            }
        );
        3
    ];
    let err = calibrate_stereo(&views, &board).expect_err("no board anywhere");
    assert!(err.to_string().contains("only 0 view"), "{err}");
}
