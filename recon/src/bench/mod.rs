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

use crate::geometry::is_degenerate_triangle;
use crate::io::{read_matrix_market, read_mesh_file_repaired, IoError};
use crate::mesh::{Repairs, SurfaceMesh};
use crate::operators::{cotan_matrix, face_triangles, triangulate, OperatorError};
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
    /// The Laplacian is not positive definite because the mesh has zero-area triangles.
    #[error("Laplacian not positive definite: the mesh has {count} zero-area (degenerate) triangles, the first in face {first_face}")]
    DegenerateTriangles {
        /// Degenerate triangles (after triangulating polygons).
        count: usize,
        /// Mesh face holding the first one.
        first_face: usize,
    },
    /// The Laplacian is singular because a connected component has no fixed vertex.
    #[error("Laplacian singular: the component of vertex {first_vertex} ({vertices} vertices) has no fixed vertex")]
    UnfixedComponent {
        /// Vertices of the component.
        vertices: usize,
        /// Its smallest vertex index.
        first_vertex: usize,
    },
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

/// Reads a mesh file (repairing it, [`read_mesh_file_repaired`]), triangulates it if it
/// has polygons and `subdivide > 0` (Loop subdivision needs triangles), and applies
/// `subdivide` steps of Loop subdivision. Returns the mesh and the repairs made on reading.
pub fn load_for_bench(
    mesh_path: impl AsRef<Path>,
    subdivide: u32,
) -> Result<(SurfaceMesh, Repairs), BenchError> {
    let (mesh, repairs) = read_mesh_file_repaired(mesh_path)?;
    if subdivide == 0 {
        return Ok((mesh, repairs));
    }
    let mesh = if mesh.is_triangle_mesh() {
        mesh
    } else {
        triangulate(&mesh)?
    };
    Ok((loop_subdivision_n(&mesh, subdivide)?, repairs))
}

/// [`load_for_bench`] without the repair report.
pub fn load_subdivided(
    mesh_path: impl AsRef<Path>,
    subdivide: u32,
) -> Result<SurfaceMesh, BenchError> {
    Ok(load_for_bench(mesh_path, subdivide)?.0)
}

/// The vertices the benchmark fixes: every 20th vertex (5%), every isolated vertex, and
/// the first vertex of every connected component that would otherwise have none (a
/// component without a fixed vertex makes the system singular).
pub fn laplacian_fixed_vertices(mesh: &SurfaceMesh) -> Vec<bool> {
    let n = mesh.vertices_size();
    let mut fixed: Vec<bool> = (0..n).map(|i| i % 20 == 0).collect();
    for v in mesh.vertices() {
        if mesh.is_isolated(v) {
            fixed[v.idx()] = true;
        }
    }
    for comp in vertex_components(mesh) {
        if !comp.iter().any(|&v| fixed[v]) {
            if let Some(&v) = comp.first() {
                fixed[v] = true;
            }
        }
    }
    fixed
}

/// Connected components (through edges) of the live vertices, each sorted by index.
fn vertex_components(mesh: &SurfaceMesh) -> Vec<Vec<usize>> {
    let n = mesh.vertices_size();
    let mut seen = vec![false; n];
    let mut comps = Vec::new();
    for s in mesh.vertices() {
        if seen[s.idx()] {
            continue;
        }
        seen[s.idx()] = true;
        let mut comp = vec![s.idx()];
        let mut k = 0;
        while k < comp.len() {
            let v = crate::mesh::Vertex::new(comp[k]);
            k += 1;
            for w in mesh.vertex_vertices(v) {
                if !seen[w.idx()] {
                    seen[w.idx()] = true;
                    comp.push(w.idx());
                }
            }
        }
        comp.sort_unstable();
        comps.push(comp);
    }
    comps
}

/// The benchmark system of a mesh: the cotangent stiffness `−C` (polygons triangulated)
/// restricted to the free vertices of [`laplacian_fixed_vertices`], as its lower
/// triangle (SPD unless the mesh has zero-area triangles).
pub fn laplacian_system(mesh: &SurfaceMesh) -> Result<SparseMatrix, BenchError> {
    laplacian_system_fixed(mesh, &laplacian_fixed_vertices(mesh))
}

/// [`laplacian_system`] with the given fixed vertices (`fixed[i]` for vertex index `i`).
pub fn laplacian_system_fixed(
    mesh: &SurfaceMesh,
    fixed: &[bool],
) -> Result<SparseMatrix, BenchError> {
    let c = cotan_matrix(mesh)?;
    let n = c.nrows();
    let mut slot = vec![usize::MAX; n];
    let mut free = 0;
    for (i, s) in slot.iter_mut().enumerate() {
        if !fixed.get(i).copied().unwrap_or(true) {
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

/// Why a Dirichlet cotangent system of `mesh` with these fixed vertices is not positive
/// definite, if the cause is in the input: zero-area triangles
/// ([`crate::geometry::is_degenerate_triangle`], polygons triangulated) or a connected
/// component without a fixed vertex. `None` when neither is found.
pub fn diagnose_laplacian_system(mesh: &SurfaceMesh, fixed: &[bool]) -> Option<BenchError> {
    let p = mesh.positions();
    let tris = face_triangles(mesh).ok()?;
    let mut faces = mesh.faces();
    let (mut left, mut face) = (0usize, None);
    let (mut count, mut first) = (0usize, None);
    for t in &tris {
        if left == 0 {
            face = faces.next();
            left = face.map_or(1, |f| mesh.face_valence(f) - 2);
        }
        left -= 1;
        if is_degenerate_triangle(p[t[0]], p[t[1]], p[t[2]]) {
            count += 1;
            first = first.or(face.map(|f| f.idx()));
        }
    }
    if count > 0 {
        return Some(BenchError::DegenerateTriangles {
            count,
            first_face: first.unwrap_or(0),
        });
    }
    vertex_components(mesh)
        .into_iter()
        .find(|c| !c.iter().any(|&v| fixed.get(v).copied().unwrap_or(false)))
        .map(|c| BenchError::UnfixedComponent {
            vertices: c.len(),
            first_vertex: c[0],
        })
}

/// `fires bench laplacian MESH [--subdivide K]`: [`load_for_bench`], then
/// [`laplacian_system`] timed single-threaded. A factorisation that fails because of the
/// input is reported as such ([`diagnose_laplacian_system`]).
pub fn bench_laplacian(
    mesh_path: impl AsRef<Path>,
    subdivide: u32,
    runs: usize,
) -> Result<SolveTimings, BenchError> {
    Ok(bench_laplacian_report(mesh_path, subdivide, runs)?.0)
}

/// [`bench_laplacian`], also returning the repairs made on reading the mesh.
pub fn bench_laplacian_report(
    mesh_path: impl AsRef<Path>,
    subdivide: u32,
    runs: usize,
) -> Result<(SolveTimings, Repairs), BenchError> {
    let (mesh, repairs) = load_for_bench(mesh_path, subdivide)?;
    let fixed = laplacian_fixed_vertices(&mesh);
    let system = laplacian_system_fixed(&mesh, &fixed)?;
    match bench_solve_matrix(&system, runs, Par::Seq) {
        Ok(t) => Ok((t, repairs)),
        Err(BenchError::Solve(
            e @ (SolveError::NotPositiveDefinite { .. } | SolveError::Singular { .. }),
        )) => Err(diagnose_laplacian_system(&mesh, &fixed).unwrap_or(BenchError::Solve(e))),
        Err(e) => Err(e),
    }
}
