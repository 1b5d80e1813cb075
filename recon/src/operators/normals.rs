//! Face and vertex normals.

use crate::geometry::{triangle_angles, triangle_normal, Vec3};
use crate::mesh::SurfaceMesh;

/// How face normals are weighted when averaged at a vertex.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NormalWeighting {
    /// By face area (the sum of unnormalised face normals).
    #[default]
    Area,
    /// By the face's interior angle at the vertex (Thürmer–Wüthrich).
    Angle,
}

/// Unit normal of every face (Newell's vector area for polygons), indexed by face
/// index; zero for a degenerate face.
pub fn face_normals(mesh: &SurfaceMesh) -> Vec<Vec3> {
    let mut out = vec![Vec3::ZERO; mesh.faces_size()];
    for f in mesh.faces() {
        let pts: Vec<Vec3> = mesh.face_vertices(f).map(|v| mesh.position(v)).collect();
        let mut n = Vec3::ZERO;
        for k in 1..pts.len().saturating_sub(1) {
            n += triangle_normal(pts[0], pts[k], pts[k + 1]);
        }
        out[f.idx()] = n.normalize_or_zero();
    }
    out
}

/// Unit normal of every vertex, indexed by vertex index; zero for isolated vertices.
/// Polygon faces contribute per corner (the corner triangle `prev, v, next`).
pub fn vertex_normals(mesh: &SurfaceMesh, weighting: NormalWeighting) -> Vec<Vec3> {
    let mut out = vec![Vec3::ZERO; mesh.vertices_size()];
    let fnormals = face_normals(mesh);
    for f in mesh.faces() {
        let vs: Vec<usize> = mesh.face_vertices(f).map(|v| v.idx()).collect();
        let m = vs.len();
        for k in 0..m {
            let (p, c, n) = (
                mesh.positions()[vs[(k + m - 1) % m]],
                mesh.positions()[vs[k]],
                mesh.positions()[vs[(k + 1) % m]],
            );
            let w = match weighting {
                NormalWeighting::Area => triangle_normal(c, n, p).norm() / 2.0,
                NormalWeighting::Angle => triangle_angles(c, n, p)[0],
            };
            out[vs[k]] += fnormals[f.idx()] * w;
        }
    }
    out.into_iter().map(Vec3::normalize_or_zero).collect()
}
