//! Per-face gradient and per-vertex (integrated) divergence (FIRES thesis, Part I §1.2–1.3).
//!
//! On a triangle `T = (i, j, k)` the gradient of the hat function of `i` is
//! `ω^i_T = N_T × (X_k − X_j) / (2|T|)` (§1.2 cross-check form), so
//! `∇_T f = Σ ω^k_T f_k`. The divergence of a per-face vector field `V` at vertex `i` is
//! the integrated `−Σ_T |T| ω^i_T · V_T`, i.e. `D = −Gᵀ·diag(|T|)`, which makes
//! `D·G = C` (the cotangent matrix) exactly.

use super::{triangles_for, OperatorError};
use crate::geometry::triangle_normal;
use crate::mesh::SurfaceMesh;
use crate::solve::{sparse_from_triplets, SparseMatrix};

/// Per-face area and hat-function gradients of every triangle, `None` for a degenerate one.
pub(crate) fn hat_gradients(
    mesh: &SurfaceMesh,
    tris: &[[usize; 3]],
) -> Vec<Option<(f64, [crate::Vec3; 3])>> {
    let p = mesh.positions();
    tris.iter()
        .map(|&[a, b, c]| {
            let n = triangle_normal(p[a], p[b], p[c]);
            let n2 = n.norm_squared();
            if !(n2 > 0.0 && n2.is_finite()) {
                return None;
            }
            let g = |from: usize, to: usize| n.cross(p[to] - p[from]) / n2;
            Some((0.5 * n2.sqrt(), [g(b, c), g(c, a), g(a, b)]))
        })
        .collect()
}

/// The `3F × V` gradient matrix: row `3f + c` is the `c`-th coordinate of the gradient on
/// face `f` (degenerate faces get zero rows).
pub fn gradient_matrix(mesh: &SurfaceMesh) -> Result<SparseMatrix, OperatorError> {
    let tris = triangles_for(mesh, "gradient matrix")?;
    let mut t = Vec::with_capacity(tris.len() * 9);
    for (f, (tri, g)) in tris.iter().zip(hat_gradients(mesh, &tris)).enumerate() {
        let Some((_, grads)) = g else { continue };
        for (&v, g) in tri.iter().zip(grads) {
            for (c, gc) in g.to_array().into_iter().enumerate() {
                t.push((3 * f + c, v, gc));
            }
        }
    }
    Ok(sparse_from_triplets(
        3 * tris.len(),
        mesh.vertices_size(),
        &t,
    )?)
}

/// The `V × 3F` integrated divergence `−Gᵀ·diag(|T|)` of per-face vector fields laid out as
/// in [`gradient_matrix`].
pub fn divergence_matrix(mesh: &SurfaceMesh) -> Result<SparseMatrix, OperatorError> {
    let tris = triangles_for(mesh, "divergence matrix")?;
    let mut t = Vec::with_capacity(tris.len() * 9);
    for (f, (tri, g)) in tris.iter().zip(hat_gradients(mesh, &tris)).enumerate() {
        let Some((area, grads)) = g else { continue };
        for (&v, g) in tri.iter().zip(grads) {
            for (c, gc) in g.to_array().into_iter().enumerate() {
                t.push((v, 3 * f + c, -area * gc));
            }
        }
    }
    Ok(sparse_from_triplets(
        mesh.vertices_size(),
        3 * tris.len(),
        &t,
    )?)
}

/// The thesis's per-vertex gradient `W = D_W·W^s` (FIRES thesis, Part I §1.2, eqs. 1.5, 1.9–1.10,
/// with the corrected (**FIX**) diagonal sign): the area-weighted average of the face gradients
/// around each vertex, as a `3V × V` matrix (row `3i + c`). Its transpose-free use
/// `div V ≈ Σ_c W_c V_c` (§1.3) and the 2-ring Laplacian `W·W` follow from it.
pub fn vertex_gradient_matrix(mesh: &SurfaceMesh) -> Result<SparseMatrix, OperatorError> {
    let tris = triangles_for(mesh, "vertex gradient matrix")?;
    let n = mesh.vertices_size();
    let grads = hat_gradients(mesh, &tris);
    let mut ring_area = vec![0.0; n];
    for (tri, g) in tris.iter().zip(&grads) {
        if let Some((area, _)) = g {
            for &v in tri {
                ring_area[v] += area;
            }
        }
    }
    let mut t = Vec::with_capacity(tris.len() * 27);
    for (tri, g) in tris.iter().zip(&grads) {
        let Some((area, w)) = g else { continue };
        for &i in tri {
            let scale = area / ring_area[i];
            for (&j, wj) in tri.iter().zip(w) {
                for (c, wc) in wj.to_array().into_iter().enumerate() {
                    t.push((3 * i + c, j, scale * wc));
                }
            }
        }
    }
    Ok(sparse_from_triplets(3 * n, n, &t)?)
}
