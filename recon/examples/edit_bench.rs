//! Speed figures of issue 16 on a generated mesh: per-move solve time of each editing
//! method after one factorisation, against the same ROI's plain 3-RHS cotangent solve
//! measured in the same run (single-threaded; build with `--release`).
//!
//! ```text
//! cargo run --release -p fires-recon --example edit_bench -- ROI_VERTICES [MOVES] [METHOD ...]
//! ```
//!
//! The mesh is an icosphere with enough vertices; the ROI is the geodesic ball around
//! vertex 0 holding ROI_VERTICES vertices (see `fires_recon::edit::run::bench_spec`).

use fires_recon::edit::{bench_edit, Method};
use fires_recon::generate::icosphere;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let roi: usize = args.first().and_then(|a| a.parse().ok()).unwrap_or(30_000);
    let moves: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(10);
    let methods: Vec<Method> = if args.len() > 2 {
        args[2..].iter().filter_map(|m| m.parse().ok()).collect()
    } else {
        vec![
            Method::Naive,
            Method::Poisson,
            Method::Implicit,
            Method::Lse,
        ]
    };
    let mut level = 1;
    while 10 * 4usize.pow(level) + 2 < roi * 5 / 4 {
        level += 1;
    }
    let mesh = icosphere(level, 1.0);
    let fraction = roi as f64 / mesh.n_vertices() as f64;
    eprintln!(
        "icosphere level {level}: {} vertices, ROI fraction {fraction:.3}",
        mesh.n_vertices()
    );
    for m in methods {
        match bench_edit(&mesh, m, fraction, moves) {
            Ok(r) => println!(
                "{}",
                serde_json::to_string(&r).unwrap_or_else(|e| format!("{{\"error\":\"{e}\"}}"))
            ),
            Err(e) => println!("{{\"method\":\"{}\",\"error\":\"{e}\"}}", m.name()),
        }
    }
}
