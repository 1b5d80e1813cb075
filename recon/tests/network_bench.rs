//! Speed of the curve network tools (release build: `cargo test --release -p fires-recon --test
//! network_bench -- --ignored --nocapture`), plus a debug-speed check of the grid drawing's counts.

mod common;

use std::time::Instant;

use common::disc::grid_drawing;
use fires_recon::network::tools::{
    align_curves, delete_stroke, insert_curve, mirror_curve, tag_sharp, transform_network,
    AlignOptions, Alignment, CurveInput, InsertOptions,
};
use fires_recon::network::{build_network, BuildOptions, Network, StrokeInput};

fn strokes(drawing: Vec<common::disc::Drawn>) -> Vec<StrokeInput> {
    drawing
        .into_iter()
        .enumerate()
        .map(|(id, (points, closed))| StrokeInput {
            id: id as u32,
            points,
            closed,
            sigma_mm: None,
            mode: 0,
            untracked_mm: [0.0; 2],
        })
        .collect()
}

/// This thread's CPU time in ms (Linux `/proc/thread-self/schedstat`, updated at scheduler ticks, so
/// only meaningful over tens of ms), so a loaded machine does not inflate the figure; `None` elsewhere.
fn cpu_ms() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    Some(s.split_whitespace().next()?.parse::<f64>().ok()? * 1e-6)
}

fn median_ms(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[test]
fn grid_drawing_has_one_face_per_cell_and_corner() {
    // 6 + 6 lines, 36 crossings, 10 corner cuts: F = 1 + Σ(crossings + 1) = 1 + 36 + 12 + 10.
    let (drawing, crossings) = grid_drawing(0.2, 6, 0.03, 10, 0.003);
    let s = strokes(drawing);
    let (net, report) = build_network(&s, &BuildOptions::default());
    net.validate().unwrap();
    assert!(report.rejected.is_empty(), "{:?}", report.rejected);
    assert_eq!(report.topology.faces, 1 + crossings + (s.len() - 1));
    assert_eq!((report.topology.euler, report.topology.genus), (1, 0));
}

/// A network of exactly 100 faces: a circle with 9 + 9 lines.
fn hundred_faces() -> Network {
    let (drawing, _) = grid_drawing(0.2, 9, 0.03, 0, 0.003);
    let (net, report) = build_network(&strokes(drawing), &BuildOptions::default());
    assert_eq!(report.topology.faces, 100);
    net
}

#[test]
#[ignore = "benchmark: run in release with --ignored --nocapture"]
fn bench_network_tools() {
    let net = hundred_faces();
    let opts = InsertOptions::default();
    // One corner cut (a single face split) and one diagonal across the whole grid.
    let corner = common::disc::line([-0.12, -0.105, 0.5], [-0.105, -0.09, 0.5], 0.002);
    let diagonal = common::disc::line([-0.13, -0.15, 0.5], [0.15, 0.13, 0.5], 0.003);
    let mut res = Vec::new();
    for (name, c) in [("corner", &corner), ("diagonal", &diagonal)] {
        let mut times = Vec::new();
        let mut crossings = 0;
        for _ in 0..51 {
            let mut n = net.clone();
            let t0 = Instant::now();
            let (r, _) = insert_curve(&mut n, CurveInput::new(c), &opts).unwrap();
            times.push(t0.elapsed().as_secs_f64() * 1e3);
            crossings = r.crossings;
        }
        res.push(format!(
            "{{\"tool\":\"insert_{name}\",\"faces\":100,\"crossings\":{crossings},\"points\":{},\"median_ms\":{:.4}}}",
            c.len(),
            median_ms(times)
        ));
    }
    // Curve delete of a grid line (9 crossings re-merged), sharp tag, moving the whole network.
    let mut times = [Vec::new(), Vec::new(), Vec::new()];
    for _ in 0..51 {
        let mut n = net.clone();
        let t0 = Instant::now();
        delete_stroke(&mut n, 5).unwrap();
        times[0].push(t0.elapsed().as_secs_f64() * 1e3);
        let mut n = net.clone();
        let t0 = Instant::now();
        tag_sharp(&mut n, 5, 1.0).unwrap();
        times[1].push(t0.elapsed().as_secs_f64() * 1e3);
        let mut n = net.clone();
        let a = Alignment {
            rotation: [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
            translation: [0.01, 0.0, 0.0],
            rms_m: 0.0,
            ambiguous: false,
        };
        let t0 = Instant::now();
        transform_network(&mut n, &a);
        times[2].push(t0.elapsed().as_secs_f64() * 1e3);
    }
    for (name, t) in ["delete_stroke", "tag_sharp", "transform_network"]
        .iter()
        .zip(times)
    {
        res.push(format!(
            "{{\"tool\":\"{name}\",\"faces\":100,\"median_ms\":{:.4}}}",
            median_ms(t)
        ));
    }
    // Mirroring a drawn curve and aligning a redrawn one (a bowed 133-point curve; alignment with up
    // to the default 30 ICP iterations), then moving the network by the result.
    let bowed: Vec<[f64; 3]> = diagonal
        .iter()
        .enumerate()
        .map(|(i, p)| [p[0], p[1], p[2] + 0.01 * (i as f64 / 20.0).sin()])
        .collect();
    // Redrawn on the object turned 90° and moved 10 mm, with 0.3 mm of drawing noise and other samples.
    let redrawn: Vec<[f64; 3]> = bowed
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let n = 3e-4 * ((i as f64 * 1.7).sin() + (i as f64 * 0.61).cos()) / 2.0;
            [-p[1] + 0.01 + n, p[0] - n, p[2] + n]
        })
        .collect();
    let mut times = [Vec::new(), Vec::new()];
    for _ in 0..51 {
        let t0 = Instant::now();
        std::hint::black_box(mirror_curve(&bowed).unwrap());
        times[0].push(t0.elapsed().as_secs_f64() * 1e3);
        let mut n = net.clone();
        let t0 = Instant::now();
        let a = align_curves(&bowed, &redrawn, &AlignOptions::default()).unwrap();
        transform_network(&mut n, &a);
        times[1].push(t0.elapsed().as_secs_f64() * 1e3);
    }
    for (name, t) in ["mirror_curve", "align_curves+transform_network"]
        .iter()
        .zip(times)
    {
        res.push(format!(
            "{{\"tool\":\"{name}\",\"faces\":100,\"points\":{},\"median_ms\":{:.4}}}",
            bowed.len(),
            median_ms(t)
        ));
    }
    // 400 strokes, 2025 crossings: 45 + 45 lines 25 mm apart and 310 corner cuts.
    let (drawing, crossings) = grid_drawing(0.85, 45, 0.025, 310, 0.003);
    let s = strokes(drawing);
    let points: usize = s.iter().map(|x| x.points.len()).sum();
    let mut times = Vec::new();
    let mut cpu = Vec::new();
    let mut faces = 0;
    for _ in 0..5 {
        let (t0, c0) = (Instant::now(), cpu_ms());
        let (net, report) = build_network(&s, &BuildOptions::default());
        times.push(t0.elapsed().as_secs_f64() * 1e3);
        cpu.push(cpu_ms().zip(c0).map_or(f64::NAN, |(a, b)| a - b));
        assert!(report.rejected.is_empty(), "{:?}", &report.rejected[..1]);
        faces = net.n_faces();
        assert_eq!(faces, 1 + crossings + (s.len() - 1));
    }
    res.push(format!(
        "{{\"tool\":\"build_network\",\"strokes\":{},\"crossings\":{crossings},\"points\":{points},\"faces\":{faces},\"median_ms\":{:.2},\"median_cpu_ms\":{:.2}}}",
        s.len(),
        median_ms(times),
        median_ms(cpu)
    ));
    for r in res {
        println!("{r}");
    }
}
