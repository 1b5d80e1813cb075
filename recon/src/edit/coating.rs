//! Coating transfer between meshes of the same connectivity (Sorkine et al. 2004,
//! *Laplacian Surface Editing*, §5.1, Eqs. 13–16).
//!
//! The detail of `detailed` is the difference of uniform Laplacian coordinates between it
//! and its smoothed version `S̃`: `ξᵢ = δᵢ(S) − δᵢ(S̃)`. Each `ξᵢ` is rotated from the frame
//! of `S̃` into the frame of `base` at the same vertex (normal, the first ring edge
//! projected into the tangent plane, their cross product) and added to the base's own
//! coordinates; the result solves `L x = δ(base) + R ξ`.
//!
//! Choices the paper leaves open (documented): `S̃` is implicit umbrella fairing
//! `(D + λ(D − A)) x = D s`, repeated `smoothing_steps` times, with boundary vertices held
//! fixed; the reconstruction pins the boundary of an open mesh at the base's positions and
//! a closed mesh by its valence-weighted centroid (which the fairing preserves), so the
//! coating of a mesh put back onto its own smoothed base returns it exactly.

use faer::Mat;

use super::local::{from_mat, gather};
use super::EditError;
use crate::geometry::Vec3;
use crate::mesh::{SurfaceMesh, Vertex};
use crate::operators::{vertex_normals, NormalWeighting};
use crate::solve::{
    sparse_from_triplets, sparse_mul_dense, CholeskyOptions, FixedSolver, SparseMatrix,
};

/// Options of [`coat`] and [`smooth_base`].
#[derive(Debug, Clone, Copy)]
pub struct CoatingOptions {
    /// Fairing strength λ of one smoothing step.
    pub smoothing: f64,
    /// Number of smoothing steps (the detail band).
    pub smoothing_steps: usize,
}

impl Default for CoatingOptions {
    fn default() -> Self {
        Self {
            smoothing: 1.0,
            smoothing_steps: 10,
        }
    }
}

/// `D − A` of the mesh's edge graph and the valences.
fn graph_laplacian(mesh: &SurfaceMesh) -> Result<(SparseMatrix, Vec<f64>), EditError> {
    let n = mesh.vertices_size();
    let mut t = Vec::new();
    let mut d = vec![0.0; n];
    for e in mesh.edges() {
        let (a, b) = mesh.edge_vertices(e);
        let (a, b) = (a.idx(), b.idx());
        t.extend([(a, b, -1.0), (b, a, -1.0), (a, a, 1.0), (b, b, 1.0)]);
        d[a] += 1.0;
        d[b] += 1.0;
    }
    Ok((sparse_from_triplets(n, n, &t)?, d))
}

fn boundary(mesh: &SurfaceMesh) -> Vec<usize> {
    mesh.vertices()
        .filter(|&v| mesh.is_boundary_vertex(v))
        .map(Vertex::idx)
        .collect()
}

/// The smoothed base `S̃` of a mesh (implicit umbrella fairing, boundary fixed).
pub fn smooth_base(mesh: &SurfaceMesh, options: &CoatingOptions) -> Result<Vec<Vec3>, EditError> {
    let (k, d) = graph_laplacian(mesh)?;
    let n = d.len();
    let lam = options.smoothing;
    let mut t: Vec<(usize, usize, f64)> = crate::solve::sparse_triplets(k.as_ref())
        .into_iter()
        .map(|(i, j, v)| (i, j, lam * v))
        .collect();
    t.extend(d.iter().enumerate().map(|(i, &di)| (i, i, di.max(1.0))));
    let a = sparse_from_triplets(n, n, &t)?;
    let fixed = boundary(mesh);
    let solver = FixedSolver::precompute(a.as_ref(), &fixed, CholeskyOptions::default())?;
    let mut x: Vec<Vec3> = mesh.positions().to_vec();
    for _ in 0..options.smoothing_steps {
        let b = Mat::from_fn(n, 3, |i, c| d[i].max(1.0) * x[i][c]);
        let known = gather(&x, solver.known());
        x = from_mat(solver.solve(b.as_ref(), known.as_ref())?.as_ref());
    }
    Ok(x)
}

/// Orthonormal frame `[t b n]` per vertex: normal, first ring edge projected, cross.
fn frames(mesh: &SurfaceMesh, x: &[Vec3]) -> Vec<nalgebra::Matrix3<f64>> {
    let mut m = mesh.clone();
    m.positions_mut().copy_from_slice(x);
    let normals = vertex_normals(&m, NormalWeighting::Area);
    (0..mesh.vertices_size())
        .map(|i| {
            let v = Vertex::new(i);
            let n = normals[i];
            let e = mesh
                .vertex_vertices(v)
                .next()
                .map_or(Vec3::ZERO, |w| x[w.idx()] - x[i]);
            let t = (e - n * e.dot(n)).normalize_or_zero();
            let b = n.cross(t);
            nalgebra::Matrix3::new(t.x, b.x, n.x, t.y, b.y, n.y, t.z, b.z, n.z)
        })
        .collect()
}

/// Puts the detail of `detailed` (over its smoothed base) onto `base` (same connectivity,
/// positions given per vertex); returns the coated positions.
pub fn coat(
    detailed: &SurfaceMesh,
    base: &[Vec3],
    options: &CoatingOptions,
) -> Result<Vec<Vec3>, EditError> {
    let n = detailed.vertices_size();
    if base.len() != n {
        return Err(EditError::Mismatch(format!(
            "base has {} vertices, the detailed mesh {n}",
            base.len()
        )));
    }
    let smooth = smooth_base(detailed, options)?;
    coat_with_base(detailed, &smooth, base)
}

/// [`coat`] with an explicit smoothed version `smooth` of `detailed`.
pub fn coat_with_base(
    detailed: &SurfaceMesh,
    smooth: &[Vec3],
    base: &[Vec3],
) -> Result<Vec<Vec3>, EditError> {
    let n = detailed.vertices_size();
    if smooth.len() != n || base.len() != n {
        return Err(EditError::Mismatch("position counts differ".into()));
    }
    let (k, d) = graph_laplacian(detailed)?;
    let lap =
        |x: &[Vec3]| sparse_mul_dense(k.as_ref(), Mat::from_fn(n, 3, |i, c| x[i][c]).as_ref());
    let ds = lap(detailed.positions())?;
    let dsm = lap(smooth)?;
    let du = lap(base)?;
    let fs = frames(detailed, smooth);
    let fu = frames(detailed, base);
    let mut b = Mat::<f64>::zeros(n, 3);
    for i in 0..n {
        let xi = nalgebra::Vector3::new(
            ds[(i, 0)] - dsm[(i, 0)],
            ds[(i, 1)] - dsm[(i, 1)],
            ds[(i, 2)] - dsm[(i, 2)],
        );
        let r = fu[i] * fs[i].transpose();
        let xr = r * xi;
        for c in 0..3 {
            b[(i, c)] = du[(i, c)] + xr[c];
        }
    }
    let mut fixed = boundary(detailed);
    let closed = fixed.is_empty();
    if closed {
        fixed = detailed.vertices().take(1).map(Vertex::idx).collect();
    }
    let solver = FixedSolver::precompute(k.as_ref(), &fixed, CholeskyOptions::default())?;
    let known = gather(base, solver.known());
    let mut x = from_mat(solver.solve(b.as_ref(), known.as_ref())?.as_ref());
    if closed {
        let wc = |p: &[Vec3]| {
            let s: f64 = d.iter().sum();
            p.iter().zip(&d).fold(Vec3::ZERO, |a, (q, w)| a + *q * *w) / s.max(1.0)
        };
        let shift = wc(base) - wc(&x);
        for p in &mut x {
            *p += shift;
        }
    }
    Ok(x)
}
