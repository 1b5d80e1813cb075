//! `validate()`: the four invariants of the polyline mesh (FIRES thesis §3.3), reference symmetry and
//! polyline end points on their vertices.
//!
//! 1. every edge joins two existing vertices and is used by at most two faces;
//! 2. every edge has exactly one polyline (of at least two points), no other edge shares it, and its first
//!    and last points equal the edge's vertices to [`ENDPOINT_TOLERANCE_M`];
//! 3. every vertex has at least two edges (no dangling vertices);
//! 4. every face is a closed loop: each use ends where the next starts, the last where the first starts.
//!
//! Reference symmetry: a vertex lists exactly the edges that name it (a self-loop twice), an edge lists a
//! face as often as the face uses it. Orientation: a face using an edge twice, or two faces sharing an
//! edge, traverse it in opposite directions.

use super::handles::{EdgeId, FaceId, PolylineId, VertexId};
use super::mesh::Network;

/// How far a polyline end may be from its vertex, metres.
pub const ENDPOINT_TOLERANCE_M: f64 = 1e-12;

/// A broken invariant.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InvariantError {
    /// Invariant 1: an edge names a vertex that does not exist.
    #[error("invariant 1: edge {0} names a missing vertex")]
    EdgeVertexMissing(EdgeId),
    /// Invariant 1: an edge is used by more than two faces.
    #[error("invariant 1: edge {0} is used by {1} faces")]
    TooManyFaces(EdgeId, usize),
    /// Invariant 2: an edge's polyline is missing, too short or shared.
    #[error("invariant 2: edge {0} has a missing, shared or one-point polyline {1}")]
    BadPolyline(EdgeId, PolylineId),
    /// Invariant 2: a polyline end is not on its vertex.
    #[error("invariant 2: edge {edge} polyline end is {distance_m:e} m from vertex {vertex}")]
    EndpointOff {
        /// The edge.
        edge: EdgeId,
        /// The vertex.
        vertex: VertexId,
        /// Distance, metres.
        distance_m: f64,
    },
    /// A polyline that no edge uses.
    #[error("invariant 2: polyline {0} belongs to no edge")]
    OrphanPolyline(PolylineId),
    /// Invariant 3: a vertex with fewer than two edges.
    #[error("invariant 3: vertex {0} has {1} edges")]
    DanglingVertex(VertexId, usize),
    /// Invariant 4: a face is empty or its loop is not closed.
    #[error("invariant 4: face {0} is not a closed loop")]
    OpenFace(FaceId),
    /// Reference symmetry between vertices and edges is broken.
    #[error("vertex {0} and its edges disagree")]
    VertexEdgeAsymmetry(VertexId),
    /// Reference symmetry between edges and faces is broken.
    #[error("edge {0} and its faces disagree")]
    EdgeFaceAsymmetry(EdgeId),
    /// A face names an edge that does not exist.
    #[error("face {0} names a missing edge")]
    FaceEdgeMissing(FaceId),
    /// Two uses of one edge traverse it in the same direction.
    #[error("edge {0} is traversed twice in the same direction")]
    InconsistentOrientation(EdgeId),
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

impl Network {
    /// Checks invariants 1–4, reference symmetry and orientation; the first failure found is returned.
    pub fn validate(&self) -> Result<(), InvariantError> {
        let mut polyline_owner = vec![0usize; self.polylines.len()];
        let mut vertex_refs = vec![Vec::new(); self.vertices.len()];
        for (e, ed) in self.edges() {
            let (Some(a), Some(b)) = (self.vertex(ed.from), self.vertex(ed.to)) else {
                return Err(InvariantError::EdgeVertexMissing(e));
            };
            if ed.faces.len() > 2 {
                return Err(InvariantError::TooManyFaces(e, ed.faces.len()));
            }
            let p = match self.polyline(ed.polyline) {
                Some(p) if p.points.len() >= 2 => p,
                _ => return Err(InvariantError::BadPolyline(e, ed.polyline)),
            };
            polyline_owner[ed.polyline.idx()] += 1;
            if polyline_owner[ed.polyline.idx()] > 1 {
                return Err(InvariantError::BadPolyline(e, ed.polyline));
            }
            let ends = [
                (ed.from, a.position, p.points[0]),
                (ed.to, b.position, p.points[p.points.len() - 1]),
            ];
            for (vertex, vp, pp) in ends {
                let d = dist(vp, pp);
                if d > ENDPOINT_TOLERANCE_M || d.is_nan() {
                    return Err(InvariantError::EndpointOff {
                        edge: e,
                        vertex,
                        distance_m: d,
                    });
                }
            }
            vertex_refs[ed.from.idx()].push(e);
            vertex_refs[ed.to.idx()].push(e);
            for &f in &ed.faces {
                let Some(face) = self.face(f) else {
                    return Err(InvariantError::EdgeFaceAsymmetry(e));
                };
                let uses = face.uses.iter().filter(|u| u.edge == e).count();
                let listed = ed.faces.iter().filter(|&&x| x == f).count();
                if uses != listed {
                    return Err(InvariantError::EdgeFaceAsymmetry(e));
                }
            }
        }
        for (p, _) in self.polylines() {
            if polyline_owner[p.idx()] == 0 {
                return Err(InvariantError::OrphanPolyline(p));
            }
        }
        for (v, vx) in self.vertices() {
            if vx.edges.len() < 2 {
                return Err(InvariantError::DanglingVertex(v, vx.edges.len()));
            }
            let mut listed = vx.edges.clone();
            listed.sort_unstable();
            let mut refs = std::mem::take(&mut vertex_refs[v.idx()]);
            refs.sort_unstable();
            if listed != refs {
                return Err(InvariantError::VertexEdgeAsymmetry(v));
            }
        }
        // Edges named by no live vertex (vertex slot empty) were caught above as missing vertices.
        let mut traversals: std::collections::HashMap<EdgeId, [usize; 2]> = Default::default();
        for (f, face) in self.faces() {
            if face.uses.is_empty() {
                return Err(InvariantError::OpenFace(f));
            }
            for (k, u) in face.uses.iter().enumerate() {
                let Some(ed) = self.edge(u.edge) else {
                    return Err(InvariantError::FaceEdgeMissing(f));
                };
                if !ed.faces.contains(&f) {
                    return Err(InvariantError::EdgeFaceAsymmetry(u.edge));
                }
                let next = face.uses[(k + 1) % face.uses.len()];
                if self.use_end(*u) != self.use_start(next) {
                    return Err(InvariantError::OpenFace(f));
                }
                let t = traversals.entry(u.edge).or_default();
                t[u.reversed as usize] += 1;
                if t[u.reversed as usize] > 1 {
                    return Err(InvariantError::InconsistentOrientation(u.edge));
                }
            }
        }
        Ok(())
    }
}
