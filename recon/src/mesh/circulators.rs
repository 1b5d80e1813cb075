//! Circulators: halfedges, vertices and faces around a vertex or a face.
//!
//! Every circulator stops after visiting as many halfedges as the mesh has, so a corrupted
//! mesh (which `validate()` would reject) cannot make it loop forever.

use super::handles::{Face, Halfedge, Vertex};
use super::SurfaceMesh;

/// Outgoing halfedges of a vertex, clockwise.
#[derive(Debug, Clone)]
pub struct VertexHalfedges<'a> {
    mesh: &'a SurfaceMesh,
    start: Option<Halfedge>,
    current: Option<Halfedge>,
    budget: usize,
}

impl Iterator for VertexHalfedges<'_> {
    type Item = Halfedge;
    fn next(&mut self) -> Option<Halfedge> {
        let h = self.current?;
        if self.budget == 0 {
            return None;
        }
        self.budget -= 1;
        let n = self.mesh.cw_rotated_halfedge(h);
        self.current = (Some(n) != self.start).then_some(n);
        Some(h)
    }
}

/// Halfedges of a face (or boundary loop), in order.
#[derive(Debug, Clone)]
pub struct FaceHalfedges<'a> {
    mesh: &'a SurfaceMesh,
    start: Halfedge,
    current: Option<Halfedge>,
    budget: usize,
}

impl Iterator for FaceHalfedges<'_> {
    type Item = Halfedge;
    fn next(&mut self) -> Option<Halfedge> {
        let h = self.current?;
        if self.budget == 0 {
            return None;
        }
        self.budget -= 1;
        let n = self.mesh.next_halfedge(h);
        self.current = (n != self.start).then_some(n);
        Some(h)
    }
}

impl SurfaceMesh {
    /// Outgoing halfedges of `v` (clockwise, starting at the stored one; empty if isolated).
    pub fn vertex_halfedges(&self, v: Vertex) -> VertexHalfedges<'_> {
        let start = self.vertex_halfedge(v);
        VertexHalfedges {
            mesh: self,
            start,
            current: start,
            budget: self.halfedges_size(),
        }
    }
    /// Neighbouring vertices of `v` (its 1-ring).
    pub fn vertex_vertices(&self, v: Vertex) -> impl Iterator<Item = Vertex> + '_ {
        self.vertex_halfedges(v).map(move |h| self.to_vertex(h))
    }
    /// Faces around `v` (each once; boundary gaps skipped).
    pub fn vertex_faces(&self, v: Vertex) -> impl Iterator<Item = Face> + '_ {
        self.vertex_halfedges(v).filter_map(move |h| self.face(h))
    }
    /// Halfedges of the loop starting at `h` (a face or a boundary loop).
    pub fn loop_halfedges(&self, h: Halfedge) -> FaceHalfedges<'_> {
        FaceHalfedges {
            mesh: self,
            start: h,
            current: Some(h),
            budget: self.halfedges_size(),
        }
    }
    /// Halfedges of face `f`, in order.
    pub fn face_halfedges(&self, f: Face) -> FaceHalfedges<'_> {
        self.loop_halfedges(self.face_halfedge(f))
    }
    /// Boundary loops, each as the list of its halfedges (which have no face).
    pub fn boundary_loops(&self) -> Vec<Vec<Halfedge>> {
        let mut seen = vec![false; self.halfedges_size()];
        let mut loops = Vec::new();
        for h in self.halfedges() {
            if seen[h.idx()] || !self.is_boundary_halfedge(h) {
                continue;
            }
            let l: Vec<Halfedge> = self.loop_halfedges(h).collect();
            for x in &l {
                seen[x.idx()] = true;
            }
            loops.push(l);
        }
        loops
    }
}
