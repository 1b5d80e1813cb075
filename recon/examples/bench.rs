//! Measures the issue-6 figures until the `fires` CLI wires them up.
//!
//! ```text
//! cargo run --release -p fires-recon --example bench -- solve MATRIX.mtx [--runs N] [--threads T]
//!     [--mode auto|simplicial|supernodal] [--kernel auto|faer]
//! cargo run --release -p fires-recon --example bench -- laplacian MESH [--subdivide K] [--runs N] [--threads T] [--export OUT.mtx]
//! cargo run --release -p fires-recon --example bench -- ply-read MESH [--subdivide K] [--runs N]
//!     (a `.ply` MESH with K = 0 is timed as is)
//! ```

use std::fs::File;
use std::io::{BufReader, BufWriter, Write};
use std::num::NonZeroUsize;
use std::time::Instant;

use faer::Par;
use fires_recon::bench::{bench_solve_matrix_with, laplacian_system, load_subdivided, BenchError};
use fires_recon::io::{
    read_matrix_market, read_ply, write_matrix_market_lower, write_ply, PlyEncoding, PolygonSoup,
};
use fires_recon::solve::{CholeskyOptions, FactorMode, SolveKernel};

fn flag(args: &[String], name: &str) -> Option<String> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
}

fn number(args: &[String], name: &str, default: usize) -> usize {
    flag(args, name)
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn par(args: &[String]) -> Par {
    match NonZeroUsize::new(number(args, "--threads", 1)) {
        Some(t) if t.get() > 1 => Par::rayon(t.get()),
        _ => Par::Seq,
    }
}

fn options(args: &[String]) -> CholeskyOptions {
    let mode = match flag(args, "--mode").as_deref() {
        Some("simplicial") => FactorMode::Simplicial,
        Some("supernodal") => FactorMode::Supernodal,
        _ => FactorMode::Auto,
    };
    let kernel = match flag(args, "--kernel").as_deref() {
        Some("faer") => SolveKernel::Faer,
        _ => SolveKernel::Auto,
    };
    CholeskyOptions {
        par: par(args),
        mode,
        kernel,
        ..Default::default()
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(cmd), Some(path)) = (args.first(), args.get(1)) else {
        eprintln!("usage: bench solve MATRIX.mtx | laplacian MESH [--subdivide K] | ply-read MESH [--subdivide K]");
        std::process::exit(2);
    };
    let runs = number(&args, "--runs", 5);
    let k = number(&args, "--subdivide", 0) as u32;
    match cmd.as_str() {
        "solve" => {
            let mtx = read_matrix_market(BufReader::new(File::open(path)?))?;
            println!(
                "{}",
                bench_solve_matrix_with(&mtx.lower_triangle()?, runs, options(&args))?
                    .to_json_line()
            );
        }
        "laplacian" => {
            let mesh = load_subdivided(path, k)?;
            eprintln!(
                "mesh: {} vertices, {} faces",
                mesh.n_vertices(),
                mesh.n_faces()
            );
            let a = laplacian_system(&mesh)?;
            if let Some(out) = flag(&args, "--export") {
                let mut w = BufWriter::new(File::create(out)?);
                write_matrix_market_lower(&mut w, &a)?;
                w.flush()?;
            }
            println!(
                "{}",
                bench_solve_matrix_with(&a, runs, options(&args))?.to_json_line()
            );
        }
        "ply-read" => ply_read(path, k, runs)?,
        _ => return Err(Box::new(BenchError::NotSquare(0, 0))),
    }
    Ok(())
}

/// Times reading a binary PLY: `path` itself if it is a `.ply` file and `k == 0`,
/// otherwise the (subdivided) mesh written to a temporary binary PLY first.
fn ply_read(path: &str, k: u32, runs: usize) -> Result<(), Box<dyn std::error::Error>> {
    let given = k == 0 && path.ends_with(".ply");
    let file = if given {
        std::path::PathBuf::from(path)
    } else {
        let soup = PolygonSoup::from_mesh(&load_subdivided(path, k)?);
        let file = std::env::temp_dir().join(format!("fires-bench-{}.ply", std::process::id()));
        let mut w = BufWriter::new(File::create(&file)?);
        write_ply(&mut w, &soup, PlyEncoding::BinaryLittleEndian)?;
        w.flush()?;
        file
    };
    let soup = read_ply(BufReader::with_capacity(1 << 16, File::open(&file)?))?;
    let bytes = std::fs::metadata(&file)?.len() as f64;
    let mut times = Vec::new();
    for _ in 0..runs.max(1) {
        let t = Instant::now();
        let back = read_ply(BufReader::with_capacity(1 << 16, File::open(&file)?))?;
        times.push(t.elapsed().as_secs_f64());
        assert_eq!(back.n_faces(), soup.n_faces());
    }
    if !given {
        std::fs::remove_file(&file)?;
    }
    times.sort_by(f64::total_cmp);
    let med = times[times.len() / 2];
    println!(
        "{{\"faces\":{},\"vertices\":{},\"bytes\":{},\"read_ms\":{:.2},\"mb_per_s\":{:.1}}}",
        soup.n_faces(),
        soup.points.len(),
        bytes,
        med * 1e3,
        bytes / med / 1e6
    );
    Ok(())
}
