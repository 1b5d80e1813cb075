//! Vertex areas and the lumped mass matrix (FIRES thesis, Part I §1.1: barycentric cells and
//! Meyer et al.'s mixed Voronoi cells).

use super::{face_triangles, OperatorError};
use crate::geometry::{cot_of_angle_between, triangle_area};
use crate::mesh::SurfaceMesh;
use crate::solve::{sparse_from_triplets, SparseMatrix};

/// Which dual cell gives a vertex its area.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MassKind {
    /// A third of the area of every incident triangle.
    Barycentric,
    /// Voronoi cells, with Meyer's fix for obtuse triangles (half the area to the obtuse
    /// corner, a quarter to the others). Default, as FIRES thesis, Part I §1.1 decides.
    #[default]
    MixedVoronoi,
}

/// Area of every vertex's dual cell (indexed by vertex index); sums to the total area.
/// Polygon faces are triangulated first ([`super::face_triangles`]).
pub fn vertex_areas(mesh: &SurfaceMesh, kind: MassKind) -> Result<Vec<f64>, OperatorError> {
    let tris = face_triangles(mesh)?;
    let p = mesh.positions();
    let mut area = vec![0.0; mesh.vertices_size()];
    for &t in &tris {
        let [a, b, c] = t.map(|i| p[i]);
        let contrib = match kind {
            MassKind::Barycentric => [triangle_area(a, b, c) / 3.0; 3],
            MassKind::MixedVoronoi => mixed_voronoi_parts(a, b, c),
        };
        for k in 0..3 {
            area[t[k]] += contrib[k];
        }
    }
    Ok(area)
}

fn mixed_voronoi_parts(a: crate::Vec3, b: crate::Vec3, c: crate::Vec3) -> [f64; 3] {
    let total = triangle_area(a, b, c);
    let obtuse = [(b - a).dot(c - a), (c - b).dot(a - b), (a - c).dot(b - c)];
    if let Some(k) = obtuse.iter().position(|&d| d < 0.0) {
        let mut out = [total / 4.0; 3];
        out[k] = total / 2.0;
        return out;
    }
    let cot_a = cot_of_angle_between(b - a, c - a);
    let cot_b = cot_of_angle_between(c - b, a - b);
    let cot_c = cot_of_angle_between(a - c, b - c);
    let (ab, bc, ca) = (
        (b - a).norm_squared(),
        (c - b).norm_squared(),
        (a - c).norm_squared(),
    );
    [
        (ab * cot_c + ca * cot_b) / 8.0,
        (ab * cot_c + bc * cot_a) / 8.0,
        (bc * cot_a + ca * cot_b) / 8.0,
    ]
}

/// Diagonal (lumped) mass matrix `M_ii = A_i`.
pub fn mass_matrix(mesh: &SurfaceMesh, kind: MassKind) -> Result<SparseMatrix, OperatorError> {
    let area = vertex_areas(mesh, kind)?;
    let n = area.len();
    let t: Vec<_> = area.iter().enumerate().map(|(i, &a)| (i, i, a)).collect();
    Ok(sparse_from_triplets(n, n, &t)?)
}
