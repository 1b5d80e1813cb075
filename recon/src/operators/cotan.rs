//! The cotangent matrix `C_ij = ½(cot α_ij + cot β_ij)`, `C_ii = −Σ_j C_ij`
//! (FIRES thesis, Part I §1.4 Meyer row; symmetric, negative semidefinite).

use super::{face_triangles, OperatorError};
use crate::geometry::cot_of_angle_between;
use crate::mesh::SurfaceMesh;
use crate::solve::{sparse_from_triplets, sparse_triplets, SparseMatrix};

/// Half-cotangents of the three corners of every triangle: `[½cot at a, ½cot at b, ½cot at c]`.
pub(crate) fn half_cotangents(mesh: &SurfaceMesh, tris: &[[usize; 3]]) -> Vec<[f64; 3]> {
    let p = mesh.positions();
    tris.iter()
        .map(|&[a, b, c]| {
            let (pa, pb, pc) = (p[a], p[b], p[c]);
            [
                0.5 * cot_of_angle_between(pb - pa, pc - pa),
                0.5 * cot_of_angle_between(pc - pb, pa - pb),
                0.5 * cot_of_angle_between(pa - pc, pb - pc),
            ]
        })
        .collect()
}

/// The cotangent matrix (`n_vertices × n_vertices`); rows sum to 0. Polygon faces are
/// triangulated first ([`super::face_triangles`]).
pub fn cotan_matrix(mesh: &SurfaceMesh) -> Result<SparseMatrix, OperatorError> {
    let tris = face_triangles(mesh)?;
    let cots = half_cotangents(mesh, &tris);
    let mut t = Vec::with_capacity(tris.len() * 12);
    for (tri, cot) in tris.iter().zip(&cots) {
        for k in 0..3 {
            // The corner k is opposite the edge (k+1, k+2).
            let (i, j) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
            let w = cot[k];
            t.extend([(i, j, w), (j, i, w), (i, i, -w), (j, j, -w)]);
        }
    }
    let n = mesh.vertices_size();
    Ok(sparse_from_triplets(n, n, &t)?)
}

/// Replaces negative off-diagonal weights of a Laplacian-like matrix (`C_ij ≥ 0` off
/// the diagonal, diagonal = −row sum) by 0 and recomputes the diagonal, giving an
/// M-matrix at the cost of linear precision.
pub fn clamp_negative_offdiagonal(c: &SparseMatrix) -> Result<SparseMatrix, OperatorError> {
    let n = c.nrows();
    let mut t = Vec::new();
    for (i, j, v) in sparse_triplets(c.as_ref()) {
        if i != j {
            let w = v.max(0.0);
            t.extend([(i, j, w), (i, i, -w)]);
        }
    }
    Ok(sparse_from_triplets(n, n, &t)?)
}
