//! `fires bench`: the solver benchmarks of the geometry core (issue figures), one JSON line each.

use std::path::PathBuf;

use anyhow::Context;
use fires_recon::bench::{bench_laplacian_report, bench_solve_matrix_market};

/// Arguments of `fires bench`.
#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    #[command(subcommand)]
    what: BenchKind,
}

#[derive(Debug, clap::Subcommand)]
enum BenchKind {
    /// Time analysis, factorisation and a 3-column solve of an SPD Matrix Market file (single-threaded).
    Solve {
        /// Coordinate, real, symmetric matrix (either triangle stored).
        matrix: PathBuf,
        /// Runs the medians are taken over.
        #[arg(long, default_value_t = 5)]
        runs: usize,
    },
    /// Build a mesh's cotangent system with 5% of the vertices fixed and time the same steps
    /// (the mesh is repaired on reading, polygons triangulated; repairs are warned about).
    Laplacian {
        /// Mesh file (OBJ, OFF, PLY, STL).
        mesh: PathBuf,
        /// Loop subdivision steps applied first (each multiplies the vertex count by about 4).
        #[arg(long, default_value_t = 0)]
        subdivide: u32,
        /// Runs the medians are taken over.
        #[arg(long, default_value_t = 5)]
        runs: usize,
    },
    /// Factor one editing ROI and time repeated handle moves against the ROI's plain cotangent solve.
    Edit {
        /// Triangle mesh (OBJ, OFF, PLY, STL).
        mesh: PathBuf,
        /// Editing method.
        #[arg(long, value_enum)]
        method: super::edit::MethodArg,
        /// Fraction of the vertices in the ROI (a geodesic ball around vertex 0).
        #[arg(long, default_value_t = 0.5)]
        roi_fraction: f64,
        /// Handle moves timed after the factorisation.
        #[arg(long, default_value_t = 10)]
        moves: usize,
    },
}

/// Runs the benchmark and prints its JSON line.
pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
    if let BenchKind::Edit {
        mesh,
        method,
        roi_fraction,
        moves,
    } = &args.what
    {
        let m = super::edit::load_mesh(mesh)?;
        let r = fires_recon::edit::bench_edit(&m, method.method(), *roi_fraction, *moves)
            .with_context(|| format!("edit benchmark of {}", mesh.display()))?;
        println!("{}", serde_json::to_string(&r)?);
        return Ok(());
    }
    let timings = match &args.what {
        BenchKind::Solve { matrix, runs } => bench_solve_matrix_market(matrix, *runs)
            .with_context(|| format!("benchmark of {}", matrix.display()))?,
        BenchKind::Laplacian {
            mesh,
            subdivide,
            runs,
        } => {
            let (timings, repairs) = bench_laplacian_report(mesh, *subdivide, *runs)
                .with_context(|| format!("benchmark of {}", mesh.display()))?;
            let summary = repairs.summary();
            if !summary.is_empty() {
                eprintln!("fires: warning: {}: {summary}", mesh.display());
            }
            timings
        }
        BenchKind::Edit { .. } => anyhow::bail!("edit benchmark handled above"),
    };
    println!("{}", timings.to_json_line());
    Ok(())
}
