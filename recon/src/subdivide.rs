//! Loop subdivision (Loop 1987) of triangle meshes, with the usual boundary rules
//! (boundary edges: midpoint; boundary vertices: ¾ v + ⅛ (b₀ + b₁)). Used to build the
//! 100k/400k-vertex benchmark meshes from `bunny00.off`.

use std::f64::consts::PI;

use crate::geometry::Vec3;
use crate::mesh::{SurfaceMesh, Vertex};
use crate::operators::{triangles_for, OperatorError};

/// Loop's interior weight β(n) = (1/n)(5/8 − (3/8 + ¼ cos(2π/n))²).
fn loop_beta(n: usize) -> f64 {
    let n = n as f64;
    let c = 3.0 / 8.0 + 0.25 * (2.0 * PI / n).cos();
    (5.0 / 8.0 - c * c) / n
}

fn even_position(mesh: &SurfaceMesh, v: Vertex) -> Vec3 {
    let p = mesh.position(v);
    if mesh.is_isolated(v) {
        return p;
    }
    if mesh.is_boundary_vertex(v) {
        let ends: Vec<Vec3> = mesh
            .vertex_halfedges(v)
            .filter(|&h| mesh.is_boundary_halfedge(h) || mesh.is_boundary_halfedge(h.opposite()))
            .map(|h| mesh.position(mesh.to_vertex(h)))
            .collect();
        if ends.len() == 2 {
            return p * 0.75 + (ends[0] + ends[1]) * 0.125;
        }
        return p;
    }
    let n = mesh.valence(v);
    let beta = loop_beta(n);
    let sum = mesh
        .vertex_vertices(v)
        .fold(Vec3::ZERO, |s, w| s + mesh.position(w));
    p * (1.0 - n as f64 * beta) + sum * beta
}

fn odd_position(mesh: &SurfaceMesh, e: crate::mesh::Edge) -> Vec3 {
    let (a, b) = mesh.edge_vertices(e);
    let (pa, pb) = (mesh.position(a), mesh.position(b));
    if mesh.is_boundary_edge(e) {
        return (pa + pb) * 0.5;
    }
    let apex = |h: crate::mesh::Halfedge| mesh.position(mesh.to_vertex(mesh.next_halfedge(h)));
    (pa + pb) * 0.375 + (apex(e.halfedge(0)) + apex(e.halfedge(1))) * 0.125
}

/// One step of Loop subdivision: every triangle becomes four. The mesh must be a compact
/// triangle mesh (no garbage). Vertices keep their indices; edge `e` gets vertex
/// `n_vertices + e`.
pub fn loop_subdivision(mesh: &SurfaceMesh) -> Result<SurfaceMesh, OperatorError> {
    let tris = triangles_for(mesh, "Loop subdivision")?;
    let nv = mesh.vertices_size();
    let mut points: Vec<Vec3> = mesh.vertices().map(|v| even_position(mesh, v)).collect();
    points.extend(mesh.edges().map(|e| odd_position(mesh, e)));
    let mut faces = Vec::with_capacity(4 * tris.len());
    for f in mesh.faces() {
        let hs: Vec<_> = mesh.face_halfedges(f).collect();
        // Corner k is the end of hs[k]; the edge vertices of hs[k] and hs[k+1] flank it.
        let corner = |k: usize| mesh.to_vertex(hs[k]).idx();
        let mid = |k: usize| nv + hs[k].edge().idx();
        for k in 0..3 {
            faces.push([mid(k), corner(k), mid((k + 1) % 3)]);
        }
        faces.push([mid(0), mid(1), mid(2)]);
    }
    Ok(SurfaceMesh::from_faces(&points, &faces)?)
}

/// Applies [`loop_subdivision`] `k` times.
pub fn loop_subdivision_n(mesh: &SurfaceMesh, k: u32) -> Result<SurfaceMesh, OperatorError> {
    let mut m = mesh.clone();
    for _ in 0..k {
        m = loop_subdivision(&m)?;
    }
    Ok(m)
}
