//! The Laplacian discretisations tabulated in FIRES thesis, Part I §1.4, as `L = D·L̄` with
//! `L̄_ij = w_ij` off the diagonal and `L̄_ii = −Σ_j w_ij` (negative semidefinite sign):
//!
//! | kind | w_ij | D_ii |
//! |---|---|---|
//! | `Cotan(mass)` | cot α + cot β | 1/(2A_i) |
//! | `CotanNormalized` | cot α + cot β | 1/Σ_j w_ij (corrected, FIX of §1.4) |
//! | `Umbrella` | 1 | 1/d_i |
//! | `ScaledUmbrella` | 1/‖X_i − X_j‖ | 2/Σ_j ‖X_i − X_j‖ |
//! | `MeanValue` | (tan(γ/2) + tan(η/2))/‖X_i − X_j‖ | 1 (not symmetric) |
//!
//! `(L f)_i ≈ Δf(X_i)`; every row sums to zero. Umbrella and scaled umbrella work on any
//! polygon mesh (they only use edges); the cotangent kinds triangulate polygons
//! ([`super::face_triangles`]); mean-value weights need triangles.

use super::cotan::cotan_matrix;
use super::mass::{vertex_areas, MassKind};
use super::{triangles_for, OperatorError};
use crate::mesh::SurfaceMesh;
use crate::solve::{sparse_from_triplets, sparse_triplets, SparseMatrix};

/// Smallest normaliser used before dividing (areas, weight sums).
const MIN_DENOMINATOR: f64 = 1e-300;

/// Which Laplacian of the table in the module docs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LaplacianKind {
    /// Cotangent weights, area-normalised with the given vertex areas (Meyer et al.).
    Cotan(MassKind),
    /// Cotangent weights normalised to sum to one per row.
    CotanNormalized,
    /// Uniform weights (Taubin).
    Umbrella,
    /// Inverse edge length weights (Fujiwara / Desbrun).
    ScaledUmbrella,
    /// Floater's mean-value weights (not symmetric).
    MeanValue,
}

/// Builds `L = D·L̄` of the chosen kind (`n_vertices × n_vertices`).
pub fn laplacian(mesh: &SurfaceMesh, kind: LaplacianKind) -> Result<SparseMatrix, OperatorError> {
    if mesh.has_garbage() {
        return Err(OperatorError::HasGarbage);
    }
    let n = mesh.vertices_size();
    let off = off_diagonal_weights(mesh, kind)?;
    let mut row_sum = vec![0.0; n];
    for &(i, _, w) in &off {
        row_sum[i] += w;
    }
    let d: Vec<f64> = match kind {
        LaplacianKind::Cotan(mass) => vertex_areas(mesh, mass)?
            .iter()
            .map(|a| 1.0 / (2.0 * a.max(MIN_DENOMINATOR)))
            .collect(),
        LaplacianKind::CotanNormalized => row_sum.iter().map(|s| 1.0 / floor_abs(*s)).collect(),
        LaplacianKind::Umbrella => mesh
            .vertices()
            .map(|v| 1.0 / mesh.valence(v).max(1) as f64)
            .collect(),
        LaplacianKind::ScaledUmbrella => edge_length_sums(mesh)
            .iter()
            .map(|s| 2.0 / s.max(MIN_DENOMINATOR))
            .collect(),
        LaplacianKind::MeanValue => vec![1.0; n],
    };
    let mut t: Vec<_> = off.iter().map(|&(i, j, w)| (i, j, d[i] * w)).collect();
    t.extend((0..n).map(|i| (i, i, -d[i] * row_sum[i])));
    Ok(sparse_from_triplets(n, n, &t)?)
}

fn floor_abs(s: f64) -> f64 {
    if s.abs() < MIN_DENOMINATOR {
        MIN_DENOMINATOR.copysign(s)
    } else {
        s
    }
}

/// `(i, j, w_ij)` for every ordered neighbour pair (duplicates summed later).
fn off_diagonal_weights(
    mesh: &SurfaceMesh,
    kind: LaplacianKind,
) -> Result<Vec<(usize, usize, f64)>, OperatorError> {
    let edge_weight = |f: &dyn Fn(f64) -> f64| {
        let mut t = Vec::new();
        for e in mesh.edges() {
            let (a, b) = mesh.edge_vertices(e);
            let w = f(mesh.edge_length(e));
            t.extend([(a.idx(), b.idx(), w), (b.idx(), a.idx(), w)]);
        }
        t
    };
    Ok(match kind {
        LaplacianKind::Cotan(_) | LaplacianKind::CotanNormalized => {
            let c = cotan_matrix(mesh)?;
            sparse_triplets(c.as_ref())
                .into_iter()
                .filter(|&(i, j, _)| i != j)
                .map(|(i, j, w)| (i, j, 2.0 * w))
                .collect()
        }
        LaplacianKind::Umbrella => edge_weight(&|_| 1.0),
        LaplacianKind::ScaledUmbrella => edge_weight(&|l| 1.0 / l.max(MIN_DENOMINATOR)),
        LaplacianKind::MeanValue => mean_value_weights(mesh)?,
    })
}

fn edge_length_sums(mesh: &SurfaceMesh) -> Vec<f64> {
    let mut s = vec![0.0; mesh.vertices_size()];
    for e in mesh.edges() {
        let (a, b) = mesh.edge_vertices(e);
        let l = mesh.edge_length(e);
        s[a.idx()] += l;
        s[b.idx()] += l;
    }
    s
}

/// For each triangle corner i with neighbours j, k: tan(θ_i/2)/‖X_j − X_i‖ goes to w_ij
/// and tan(θ_i/2)/‖X_k − X_i‖ to w_ik; tan(θ/2) = |u×v| / (|u||v| + u·v).
fn mean_value_weights(mesh: &SurfaceMesh) -> Result<Vec<(usize, usize, f64)>, OperatorError> {
    let p = mesh.positions();
    let mut t = Vec::new();
    for tri in triangles_for(mesh, "mean-value Laplacian")? {
        for k in 0..3 {
            let (i, j, l) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
            let (u, v) = (p[j] - p[i], p[l] - p[i]);
            let (nu, nv) = (u.norm(), v.norm());
            let half_tan = u.cross(v).norm() / (nu * nv + u.dot(v)).max(MIN_DENOMINATOR);
            t.push((i, j, half_tan / nu.max(MIN_DENOMINATOR)));
            t.push((i, l, half_tan / nv.max(MIN_DENOMINATOR)));
        }
    }
    Ok(t)
}
