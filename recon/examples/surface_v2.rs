//! FIRESV2 on a generated curve network and its timings.
//!
//! The network: strokes on a paraboloid cap z = 0.5 + 2(x² + y²) over a 0.2 m disc (its boundary ellipse
//! and a grid of chords), built with `build_network` as the sketching tools would. Prints one JSON line:
//! faces, the Refined Mesh's vertices and the time to it (wall clock and CPU, best of 5) (base mesh, tessellation, flow), the time of three
//! more Catmull-Clark levels and their vertices, and the height error to the paraboloid.
//!
//! `cargo run --release -p fires-recon --example surface_v2 -- [chords] [out.obj]`

use std::io::Write;
use std::time::Instant;

use fires_recon::network::{build_network, BuildOptions, StrokeInput};
use fires_recon::surface::{
    base_mesh, diffusion_options, interpolating_control, subdivide, tessellate, SurfaceDiffusion,
    V2Options,
};

const R: f64 = 0.1;
const B: f64 = 0.097;
const Z: f64 = 0.5;
const K: f64 = 2.0;

fn lift(x: f64, y: f64) -> f64 {
    Z + K * (x * x + y * y)
}

fn line(a: [f64; 2], b: [f64; 2]) -> Vec<[f64; 3]> {
    let d = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
    let n = (d / 0.002).ceil().max(1.0) as usize;
    (0..=n)
        .map(|i| {
            let t = i as f64 / n as f64;
            let (x, y) = (a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]));
            [x, y, lift(x, y)]
        })
        .collect()
}

/// CPU time of this thread in ms (Linux `/proc/thread-self/schedstat`), so a loaded machine does not
/// inflate the figures; `None` elsewhere.
fn cpu_ms() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace()
        .next()?
        .parse::<f64>()
        .ok()
        .map(|ns| ns * 1e-6)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let chords: usize = args.get(1).map_or(Ok(7), |s| s.parse())?;
    let mut strokes = vec![(0..=600)
        .map(|i| {
            let a = 2.0 * std::f64::consts::PI * i as f64 / 600.0;
            let (x, y) = (R * a.cos(), B * a.sin());
            [x, y, lift(x, y)]
        })
        .collect::<Vec<_>>()];
    for i in 0..chords {
        let c = -0.8 + 1.6 * (i as f64 + 0.5) / chords as f64;
        let (x, y) = (c * R, c * B * 0.97);
        let ye = B * (1.0 - (x / R).powi(2)).sqrt();
        strokes.push(line([x, ye], [x, -ye]));
        let xe = R * (1.0 - (y / B).powi(2)).sqrt();
        strokes.push(line([-xe, y], [xe, y]));
    }
    let inputs: Vec<StrokeInput> = strokes
        .into_iter()
        .enumerate()
        .map(|(k, points)| StrokeInput {
            id: k as u32,
            points,
            closed: k == 0,
            sigma_mm: None,
            mode: 0,
            untracked_mm: [0.0; 2],
        })
        .collect();
    let (net, _) = build_network(&inputs, &BuildOptions::default());
    let opts = V2Options::default();

    // Best of 5 runs, single-threaded: wall clock and this thread's CPU time.
    let mut best = (f64::INFINITY, f64::INFINITY);
    let mut best_cpu = (f64::INFINITY, f64::INFINITY);
    let mut out = None;
    let mut phases = [0.0; 4];
    for _ in 0..5 {
        let c0 = cpu_ms();
        let t0 = Instant::now();
        let base = base_mesh(&net)?;
        let tb = Instant::now();
        let tess = tessellate(&base, &opts.tessellate)?;
        let tt = Instant::now();
        let mut flow = SurfaceDiffusion::new(&tess, &diffusion_options(&base, &opts))?;
        let tp = Instant::now();
        let refined = flow.run()?;
        let t1 = Instant::now();
        let c1 = cpu_ms();
        phases = [
            (tb - t0).as_secs_f64() * 1e3,
            (tt - tb).as_secs_f64() * 1e3,
            (tp - tt).as_secs_f64() * 1e3,
            (t1 - tp).as_secs_f64() * 1e3,
        ];
        let control = interpolating_control(&refined, &opts.subdivision, opts.interpolate_sweeps);
        let fine = subdivide(&control, 3, &opts.subdivision)?;
        let t2 = Instant::now();
        if let (Some(c0), Some(c1), Some(c2)) = (c0, c1, cpu_ms()) {
            best_cpu.0 = best_cpu.0.min(c1 - c0);
            best_cpu.1 = best_cpu.1.min(c2 - c1);
        }
        best.0 = best.0.min((t1 - t0).as_secs_f64() * 1e3);
        best.1 = best.1.min((t2 - t1).as_secs_f64() * 1e3);
        out = Some((base.mesh.n_faces(), refined.mesh.n_vertices(), fine));
    }
    let Some((faces, refined_v, fine)) = out else {
        return Ok(());
    };
    let err: Vec<f64> = fine
        .mesh
        .vertices()
        .map(|v| {
            let p = fine.mesh.position(v);
            p.z - lift(p.x, p.y)
        })
        .collect();
    let rms = (err.iter().map(|e| e * e).sum::<f64>() / err.len() as f64).sqrt();
    println!(
        "{{\"faces\":{faces},\"refined_vertices\":{refined_v},\"v2_ms\":{:.1},\"cc3_vertices\":{},\"cc3_ms\":{:.1},\"v2_cpu_ms\":{:.1},\"cc3_cpu_ms\":{:.1},\"height_rms_mm\":{:.4},\"phases_ms\":{{\"base\":{:.1},\"tessellate\":{:.1},\"flow_setup\":{:.1},\"flow_run\":{:.1}}}}}",
        best.0,
        fine.mesh.n_vertices(),
        best.1,
        best_cpu.0,
        best_cpu.1,
        rms * 1e3,
        phases[0],
        phases[1],
        phases[2],
        phases[3]
    );
    if let Some(path) = args.get(2) {
        let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
        for p in fine.mesh.positions() {
            writeln!(w, "v {} {} {}", p.x, p.y, p.z)?;
        }
        for f in fine.mesh.faces() {
            write!(w, "f")?;
            for v in fine.mesh.face_vertices(f) {
                write!(w, " {}", v.idx() + 1)?;
            }
            writeln!(w)?;
        }
    }
    Ok(())
}
