//! Face areas, total area, enclosed volume, mean edge length.

use crate::geometry::{triangle_normal, Vec3};
use crate::mesh::{Face, SurfaceMesh};

/// Vector area `½ Σ pᵢ × pᵢ₊₁` of a polygon face (exact for planar polygons).
fn face_vector_area(mesh: &SurfaceMesh, f: Face) -> Vec3 {
    let pts: Vec<Vec3> = mesh.face_vertices(f).map(|v| mesh.position(v)).collect();
    let mut a = Vec3::ZERO;
    for k in 1..pts.len().saturating_sub(1) {
        a += triangle_normal(pts[0], pts[k], pts[k + 1]);
    }
    a * 0.5
}

/// Area of every face (indexed by face index; polygons use their vector area).
pub fn face_areas(mesh: &SurfaceMesh) -> Vec<f64> {
    let mut out = vec![0.0; mesh.faces_size()];
    for f in mesh.faces() {
        out[f.idx()] = face_vector_area(mesh, f).norm();
    }
    out
}

/// Total surface area.
pub fn total_area(mesh: &SurfaceMesh) -> f64 {
    mesh.faces().map(|f| face_vector_area(mesh, f).norm()).sum()
}

/// Signed enclosed volume `(1/6) Σ p₀ · (pₖ × pₖ₊₁)` over a fan triangulation of each face
/// (FIRES thesis, Part I §1.6, with the unnormalised normal). Exact for closed, consistently
/// oriented meshes; positive for outward orientation.
pub fn volume(mesh: &SurfaceMesh) -> f64 {
    let mut v = 0.0;
    for f in mesh.faces() {
        let pts: Vec<Vec3> = mesh.face_vertices(f).map(|x| mesh.position(x)).collect();
        for k in 1..pts.len().saturating_sub(1) {
            v += pts[0].dot(pts[k].cross(pts[k + 1]));
        }
    }
    v / 6.0
}

/// Mean length of the live edges (0 for a mesh without edges).
pub fn mean_edge_length(mesh: &SurfaceMesh) -> f64 {
    let (sum, n) = mesh
        .edges()
        .fold((0.0, 0usize), |(s, n), e| (s + mesh.edge_length(e), n + 1));
    if n == 0 {
        0.0
    } else {
        sum / n as f64
    }
}
