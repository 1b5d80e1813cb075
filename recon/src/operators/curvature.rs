//! Curvatures (FIRES thesis, Part I §1.5): mean curvature normal `H⃗ = −ΔX` (cotangent
//! Laplacian, mixed Voronoi areas), signed mean curvature, angle-defect Gaussian curvature
//! and principal curvatures `κ = H ± √(max(H² − K, 0))` (the square root's argument is
//! clamped at 0, Meyer et al.).
//!
//! Boundary vertices: the defect uses π instead of 2π; their mean curvature normal
//! includes the boundary term and is not a curvature estimate.

use std::f64::consts::PI;

use super::cotan::cotan_matrix;
use super::mass::{vertex_areas, MassKind};
use super::normals::{vertex_normals, NormalWeighting};
use super::{triangles_for, OperatorError};
use crate::geometry::{triangle_angles, Vec3};
use crate::mesh::SurfaceMesh;
use crate::solve::sparse_triplets;

const MIN_AREA: f64 = 1e-300;

/// `H⃗_i = −(1/A_i) Σ_j C_ij (X_j − X_i)`, with length 2|H| (FIRES thesis, Part I §1.5).
pub fn mean_curvature_normals(mesh: &SurfaceMesh) -> Result<Vec<Vec3>, OperatorError> {
    let c = cotan_matrix(mesh)?;
    let area = vertex_areas(mesh, MassKind::MixedVoronoi)?;
    let p = mesh.positions();
    let mut h = vec![Vec3::ZERO; p.len()];
    for (i, j, w) in sparse_triplets(c.as_ref()) {
        if i != j {
            h[i] -= (p[j] - p[i]) * w;
        }
    }
    for (hi, a) in h.iter_mut().zip(&area) {
        *hi = *hi / a.max(MIN_AREA);
    }
    Ok(h)
}

/// Signed mean curvature `H = (κ1 + κ2)/2 = ½ sign(H⃗·N) ‖H⃗‖`, `N` the area-weighted vertex
/// normal (positive on a sphere with outward orientation).
pub fn mean_curvature(mesh: &SurfaceMesh) -> Result<Vec<f64>, OperatorError> {
    let hn = mean_curvature_normals(mesh)?;
    let n = vertex_normals(mesh, NormalWeighting::Area);
    Ok(hn
        .iter()
        .zip(&n)
        .map(|(h, n)| 0.5 * h.norm().copysign(h.dot(*n)))
        .collect())
}

/// Angle defect of every vertex: `2π − Σθ` inside, `π − Σθ` on the boundary, 0 if
/// isolated. On a closed mesh the sum is exactly `2πχ` up to rounding (Gauss–Bonnet).
pub fn angle_defects(mesh: &SurfaceMesh) -> Result<Vec<f64>, OperatorError> {
    let tris = triangles_for(mesh, "angle defects")?;
    let p = mesh.positions();
    let mut sum = vec![0.0; p.len()];
    for &[a, b, c] in &tris {
        let ang = triangle_angles(p[a], p[b], p[c]);
        sum[a] += ang[0];
        sum[b] += ang[1];
        sum[c] += ang[2];
    }
    Ok(mesh
        .vertices()
        .map(|v| {
            if mesh.is_isolated(v) {
                0.0
            } else if mesh.is_boundary_vertex(v) {
                PI - sum[v.idx()]
            } else {
                2.0 * PI - sum[v.idx()]
            }
        })
        .collect())
}

/// Gaussian curvature `K_i = defect_i / A_i` (mixed Voronoi area).
pub fn gaussian_curvature(mesh: &SurfaceMesh) -> Result<Vec<f64>, OperatorError> {
    let d = angle_defects(mesh)?;
    let area = vertex_areas(mesh, MassKind::MixedVoronoi)?;
    Ok(d.iter()
        .zip(&area)
        .map(|(d, a)| d / a.max(MIN_AREA))
        .collect())
}

/// Principal curvatures `(κ_max, κ_min)` per vertex from `H` and `K`.
pub fn principal_curvatures(mesh: &SurfaceMesh) -> Result<Vec<(f64, f64)>, OperatorError> {
    let h = mean_curvature(mesh)?;
    let k = gaussian_curvature(mesh)?;
    Ok(h.iter()
        .zip(&k)
        .map(|(&h, &k)| {
            let s = (h * h - k).max(0.0).sqrt();
            (h + s, h - s)
        })
        .collect())
}
