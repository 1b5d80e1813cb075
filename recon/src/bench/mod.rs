//! Solver timing behind `fires bench solve MATRIX.mtx` and
//! `fires bench laplacian MESH [--subdivide K]` (issue 6, item 6).
//!
//! Each run times the three steps separately — symbolic analysis, numeric factorisation,
//! and one solve with three right-hand sides — and the medians over the runs are
//! reported. Everything is single-threaded (`Par::Seq`) unless a caller passes another
//! [`faer::Par`] to [`bench_solve_matrix`]. The same matrix can be written with
//! [`laplacian_system`] + [`crate::io::write_matrix_market_lower`] and timed with the
//! CHOLMOD harness in `recon/tools/cholmod-bench/`.

use std::fs::File;
use std::io::BufReader;
use std::path::Path;
use std::time::Instant;

use faer::{Mat, Par, Side};

use crate::io::{read_matrix_market, read_mesh_file, IoError};
use crate::mesh::SurfaceMesh;
use crate::operators::{cotan_matrix, OperatorError};
use crate::solve::{
    sparse_from_triplets, sparse_triplets, CholeskyOptions, CholeskySolver, SolveError,
    SparseMatrix,
};
use crate::subdivide::loop_subdivision_n;

/// Median timings of one benchmark, serialised as the one-line JSON the CLI prints.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SolveTimings {
    /// Matrix dimension.
    pub n: usize,
    /// Stored entries of the lower triangle of the matrix.
    pub nnz: usize,
    /// Stored entries of the Cholesky factor `L`.
    pub l_nnz: usize,
    /// Symbolic analysis (ordering, elimination tree, supernodes), ms.
    pub analyze_ms: f64,
    /// Numeric factorisation, ms.
    pub factor_ms: f64,
    /// One solve with three right-hand sides, ms.
    pub solve_ms: f64,
    /// Number of runs the medians are taken over.
    pub runs: usize,
    /// Threads used (1 = sequential).
    pub threads: usize,
}

impl SolveTimings {
    /// The JSON line (no trailing newline).
    pub fn to_json_line(&self) -> String {
        serde_json::to_string(self).unwrap_or_else(|e| format!("{{\"error\":\"{e}\"}}"))
    }
}

/// Errors of the benchmarks.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// Reading the matrix or mesh failed.
    #[error(transparent)]
    Io(#[from] IoError),
    /// Building the operator failed.
    #[error(transparent)]
    Operator(#[from] OperatorError),
    /// Factorisation or solve failed (e.g. the matrix is not positive definite).
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// The matrix is not square.
    #[error("matrix is {0}x{1}, not square")]
    NotSquare(usize, usize),
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => 0.0,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Times analysis, factorisation and a 3-column solve of an SPD matrix given by its lower
/// triangle, `runs` times (at least once), and returns the medians.
pub fn bench_solve_matrix(
    lower: &SparseMatrix,
    runs: usize,
    par: Par,
) -> Result<SolveTimings, BenchError> {
    let options = CholeskyOptions {
        side: Side::Lower,
        par,
        ..Default::default()
    };
    bench_solve_matrix_with(lower, runs, options)
}

/// [`bench_solve_matrix`] with explicit solver options (parallelism, factor mode).
pub fn bench_solve_matrix_with(
    lower: &SparseMatrix,
    runs: usize,
    options: CholeskyOptions,
) -> Result<SolveTimings, BenchError> {
    let par = options.par;
    let n = lower.nrows();
    if lower.ncols() != n {
        return Err(BenchError::NotSquare(n, lower.ncols()));
    }
    let rhs = Mat::from_fn(n, 3, |i, j| 1.0 + ((i * (j + 3)) % 17) as f64);
    let (mut a, mut f, mut s) = (Vec::new(), Vec::new(), Vec::new());
    let mut l_nnz = 0;
    for _ in 0..runs.max(1) {
        let t = Instant::now();
        let mut chol = CholeskySolver::analyze(lower.as_ref(), options)?;
        a.push(ms(t));
        let t = Instant::now();
        chol.factorize(lower.as_ref())?;
        f.push(ms(t));
        let mut x = rhs.clone();
        let t = Instant::now();
        chol.solve_in_place(x.as_mut())?;
        s.push(ms(t));
        l_nnz = chol.factor_len();
    }
    Ok(SolveTimings {
        n,
        nnz: lower.compute_nnz(),
        l_nnz,
        analyze_ms: median(a),
        factor_ms: median(f),
        solve_ms: median(s),
        runs: runs.max(1),
        threads: match par {
            Par::Seq => 1,
            Par::Rayon(t) => t.get(),
        },
    })
}

/// `fires bench solve MATRIX.mtx`: reads a symmetric positive-definite Matrix Market file
/// (coordinate, real, symmetric, either triangle stored) and times it single-threaded.
pub fn bench_solve_matrix_market(
    path: impl AsRef<Path>,
    runs: usize,
) -> Result<SolveTimings, BenchError> {
    let file = File::open(path.as_ref()).map_err(IoError::from)?;
    let mtx = read_matrix_market(BufReader::with_capacity(1 << 16, file))?;
    if mtx.nrows != mtx.ncols {
        return Err(BenchError::NotSquare(mtx.nrows, mtx.ncols));
    }
    bench_solve_matrix(&mtx.lower_triangle()?, runs, Par::Seq)
}

/// Reads a mesh file and applies `subdivide` steps of Loop subdivision.
pub fn load_subdivided(
    mesh_path: impl AsRef<Path>,
    subdivide: u32,
) -> Result<SurfaceMesh, BenchError> {
    let mesh = read_mesh_file(mesh_path)?.to_mesh()?;
    Ok(loop_subdivision_n(&mesh, subdivide)?)
}

/// The benchmark system of a mesh: the cotangent stiffness `−C` restricted to the free
/// vertices when every 20th vertex (5%) is fixed, as its lower triangle (SPD for a
/// connected mesh).
pub fn laplacian_system(mesh: &SurfaceMesh) -> Result<SparseMatrix, BenchError> {
    let c = cotan_matrix(mesh)?;
    let n = c.nrows();
    let mut slot = vec![usize::MAX; n];
    let mut free = 0;
    for (i, s) in slot.iter_mut().enumerate() {
        if i % 20 != 0 {
            *s = free;
            free += 1;
        }
    }
    let t: Vec<_> = sparse_triplets(c.as_ref())
        .into_iter()
        .filter(|&(i, j, _)| i >= j && slot[i] != usize::MAX && slot[j] != usize::MAX)
        .map(|(i, j, v)| (slot[i], slot[j], -v))
        .collect();
    Ok(sparse_from_triplets(free, free, &t)?)
}

/// `fires bench laplacian MESH [--subdivide K]`: Loop-subdivides the mesh `subdivide`
/// times, builds [`laplacian_system`] and times it single-threaded.
pub fn bench_laplacian(
    mesh_path: impl AsRef<Path>,
    subdivide: u32,
    runs: usize,
) -> Result<SolveTimings, BenchError> {
    let mesh = load_subdivided(mesh_path, subdivide)?;
    bench_solve_matrix(&laplacian_system(&mesh)?, runs, Par::Seq)
}
