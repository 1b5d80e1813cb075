//! Euler operations (after pmp-library): edge split, edge flip, halfedge collapse with
//! the link-condition check, face split. Each keeps the halfedge invariants; edge split
//! and face split on triangles, flips and valid collapses keep χ = V − E + F unchanged.

use super::error::MeshError;
use super::handles::{Edge, Face, Halfedge, Vertex};
use super::SurfaceMesh;
use crate::geometry::Vec3;

impl SurfaceMesh {
    /// Splits edge `e` of a triangle mesh at point `p`: adds a vertex and connects it to
    /// the opposite vertex of each adjacent triangle. Returns the new vertex.
    pub fn split_edge(&mut self, e: Edge, p: Vec3) -> Result<Vertex, MeshError> {
        if self.is_deleted_edge(e) {
            return Err(MeshError::EdgeOperationRejected(e));
        }
        let tri = |h: Halfedge| self.face(h).is_none_or(|f| self.face_valence(f) == 3);
        if !tri(e.halfedge(0)) || !tri(e.halfedge(1)) {
            return Err(MeshError::EdgeOperationRejected(e));
        }
        let v = self.add_vertex(p);
        self.split_edge_at(e, v);
        Ok(v)
    }

    fn split_edge_at(&mut self, e: Edge, v: Vertex) {
        let h0 = e.halfedge(0);
        let o0 = e.halfedge(1);
        let v2 = self.to_vertex(o0);
        let e1 = self.new_edge(v, v2);
        let t1 = e1.opposite();
        self.set_vertex_halfedge(v, Some(h0));
        self.set_to_vertex(o0, v);
        self.split_side_h(h0, t1);
        self.split_side_o(o0, e1, v);
        if self.vertex_halfedge(v2) == Some(h0) {
            self.set_vertex_halfedge(v2, Some(t1));
        }
    }

    fn split_side_h(&mut self, h0: Halfedge, t1: Halfedge) {
        let v = self.from_vertex(h0);
        let Some(f0) = self.face(h0) else {
            let p = self.prev_halfedge(h0);
            self.set_next(p, t1);
            self.set_next(t1, h0);
            return;
        };
        let h1 = self.next_halfedge(h0);
        let h2 = self.next_halfedge(h1);
        let e0 = self.new_edge(v, self.to_vertex(h1));
        let t0 = e0.opposite();
        let f1 = self.new_face();
        self.set_face_halfedge(f0, h0);
        self.set_face_halfedge(f1, h2);
        for h in [h1, t0, h0] {
            self.set_face(h, Some(f0));
        }
        for h in [h2, t1, e0] {
            self.set_face(h, Some(f1));
        }
        self.link_loop(&[h0, h1, t0]);
        self.link_loop(&[e0, h2, t1]);
    }

    fn split_side_o(&mut self, o0: Halfedge, e1: Halfedge, v: Vertex) {
        let Some(f3) = self.face(o0) else {
            let n = self.next_halfedge(o0);
            self.set_next(e1, n);
            self.set_next(o0, e1);
            self.set_vertex_halfedge(v, Some(e1));
            return;
        };
        let o1 = self.next_halfedge(o0);
        let o2 = self.next_halfedge(o1);
        let e2 = self.new_edge(v, self.to_vertex(o1));
        let t2 = e2.opposite();
        let f2 = self.new_face();
        self.set_face_halfedge(f2, o1);
        self.set_face_halfedge(f3, o0);
        for h in [o1, t2, e1] {
            self.set_face(h, Some(f2));
        }
        for h in [o2, o0, e2] {
            self.set_face(h, Some(f3));
        }
        self.link_loop(&[e1, o1, t2]);
        self.link_loop(&[o0, e2, o2]);
    }

    fn link_loop(&mut self, hs: &[Halfedge]) {
        for k in 0..hs.len() {
            self.set_next(hs[k], hs[(k + 1) % hs.len()]);
        }
    }

    /// Splits face `f` (any polygon) at point `p`, joining a new vertex to every corner.
    pub fn split_face(&mut self, f: Face, p: Vec3) -> Result<Vertex, MeshError> {
        if self.is_deleted_face(f) {
            return Err(MeshError::FaceOperationRejected(f));
        }
        let v = self.add_vertex(p);
        let hend = self.face_halfedge(f);
        let mut h = self.next_halfedge(hend);
        let first = self.new_edge(self.to_vertex(hend), v);
        self.set_next(hend, first);
        self.set_face(first, Some(f));
        let mut hold = first.opposite();
        while h != hend {
            let hnext = self.next_halfedge(h);
            let fnew = self.new_face();
            self.set_face_halfedge(fnew, h);
            let hnew = self.new_edge(self.to_vertex(h), v);
            self.link_loop(&[hnew, hold, h]);
            for x in [hnew, hold, h] {
                self.set_face(x, Some(fnew));
            }
            hold = hnew.opposite();
            h = hnext;
        }
        self.set_next(hold, hend);
        self.set_next(first, hold);
        self.set_face(hold, Some(f));
        self.set_vertex_halfedge(v, Some(hold));
        Ok(v)
    }

    /// True if edge `e` is interior, between two triangles, and flipping it does not
    /// create an edge that already exists.
    pub fn is_flip_ok(&self, e: Edge) -> bool {
        if self.is_deleted_edge(e) || self.is_boundary_edge(e) {
            return false;
        }
        let (h0, h1) = (e.halfedge(0), e.halfedge(1));
        let tri = |h: Halfedge| self.face(h).is_some_and(|f| self.face_valence(f) == 3);
        if !tri(h0) || !tri(h1) {
            return false;
        }
        let v0 = self.to_vertex(self.next_halfedge(h0));
        let v1 = self.to_vertex(self.next_halfedge(h1));
        v0 != v1 && self.find_halfedge(v0, v1).is_none()
    }

    /// Flips edge `e` inside the quad formed by its two triangles.
    pub fn flip(&mut self, e: Edge) -> Result<(), MeshError> {
        if !self.is_flip_ok(e) {
            return Err(MeshError::EdgeOperationRejected(e));
        }
        let (a0, b0) = (e.halfedge(0), e.halfedge(1));
        let (a1, b1) = (self.next_halfedge(a0), self.next_halfedge(b0));
        let (a2, b2) = (self.next_halfedge(a1), self.next_halfedge(b1));
        let (va0, va1) = (self.to_vertex(a0), self.to_vertex(a1));
        let (vb0, vb1) = (self.to_vertex(b0), self.to_vertex(b1));
        let (fa, fb) = (self.face(a0), self.face(b0));
        self.set_to_vertex(a0, va1);
        self.set_to_vertex(b0, vb1);
        self.link_loop(&[a0, a2, b1]);
        self.link_loop(&[b0, b2, a1]);
        self.set_face(a1, fb);
        self.set_face(b1, fa);
        if let (Some(fa), Some(fb)) = (fa, fb) {
            self.set_face_halfedge(fa, a0);
            self.set_face_halfedge(fb, b0);
        }
        if self.vertex_halfedge(va0) == Some(b0) {
            self.set_vertex_halfedge(va0, Some(a1));
        }
        if self.vertex_halfedge(vb0) == Some(a0) {
            self.set_vertex_halfedge(vb0, Some(b1));
        }
        Ok(())
    }

    /// True if collapsing `h` (moving its start vertex onto its end vertex) keeps the
    /// mesh a manifold of the same topology: the link condition on the two one-rings,
    /// plus the boundary cases of pmp-library's `is_collapse_ok`. Triangle meshes only.
    pub fn is_collapse_ok(&self, h: Halfedge) -> bool {
        if self.is_deleted_edge(h.edge()) {
            return false;
        }
        let o = h.opposite();
        let (v0, v1) = (self.to_vertex(o), self.to_vertex(h));
        let Some(vl) = self.collapse_side_vertex(h) else {
            return false;
        };
        let Some(vr) = self.collapse_side_vertex(o) else {
            return false;
        };
        if vl.is_some() && vl == vr || vl.is_none() && vr.is_none() {
            return false;
        }
        let interior = !self.is_boundary_halfedge(h) && !self.is_boundary_halfedge(o);
        if self.is_boundary_vertex(v0) && self.is_boundary_vertex(v1) && interior {
            return false;
        }
        self.vertex_vertices(v0)
            .filter(|&w| w != v1 && Some(w) != vl && Some(w) != vr)
            .all(|w| self.find_halfedge(w, v1).is_none())
    }

    /// The apex of the triangle of `h`: `Some(None)` for a boundary halfedge,
    /// `None` when the triangle's two other edges are both on the boundary (rejected).
    fn collapse_side_vertex(&self, h: Halfedge) -> Option<Option<Vertex>> {
        if self.is_boundary_halfedge(h) {
            return Some(None);
        }
        let h1 = self.next_halfedge(h);
        let h2 = self.next_halfedge(h1);
        let both =
            self.is_boundary_halfedge(h1.opposite()) && self.is_boundary_halfedge(h2.opposite());
        (!both).then_some(Some(self.to_vertex(h1)))
    }

    /// Collapses halfedge `h`: its start vertex is removed and merged into its end vertex.
    /// Checks [`Self::is_collapse_ok`] first.
    pub fn collapse(&mut self, h: Halfedge) -> Result<(), MeshError> {
        if !self.is_collapse_ok(h) {
            return Err(MeshError::HalfedgeOperationRejected(h));
        }
        let h1 = self.prev_halfedge(h);
        let o1 = self.next_halfedge(h.opposite());
        self.remove_edge_helper(h);
        if self.next_halfedge(self.next_halfedge(h1)) == h1 {
            self.remove_loop_helper(h1);
        }
        if self.next_halfedge(self.next_halfedge(o1)) == o1 {
            self.remove_loop_helper(o1);
        }
        Ok(())
    }

    fn remove_edge_helper(&mut self, h: Halfedge) {
        let (hn, hp) = (self.next_halfedge(h), self.prev_halfedge(h));
        let o = h.opposite();
        let (on, op) = (self.next_halfedge(o), self.prev_halfedge(o));
        let (fh, fo) = (self.face(h), self.face(o));
        let (vh, vo) = (self.to_vertex(h), self.to_vertex(o));
        let around: Vec<Halfedge> = self.vertex_halfedges(vo).collect();
        for hc in around {
            self.set_to_vertex(hc.opposite(), vh);
        }
        self.set_next(hp, hn);
        self.set_next(op, on);
        if let Some(f) = fh {
            self.set_face_halfedge(f, hn);
        }
        if let Some(f) = fo {
            self.set_face_halfedge(f, on);
        }
        if self.vertex_halfedge(vh) == Some(o) {
            self.set_vertex_halfedge(vh, Some(hn));
        }
        self.adjust_outgoing_halfedge(vh);
        self.set_vertex_halfedge(vo, None);
        self.delete_vertex_slot(vo);
        self.delete_edge_slot(h.edge());
    }

    fn remove_loop_helper(&mut self, h0: Halfedge) {
        let h1 = self.next_halfedge(h0);
        let (o0, o1) = (h0.opposite(), h1.opposite());
        let (v0, v1) = (self.to_vertex(h0), self.to_vertex(h1));
        let (fh, fo) = (self.face(h0), self.face(o0));
        let on = self.next_halfedge(o0);
        let op = self.prev_halfedge(o0);
        self.set_next(h1, on);
        self.set_next(op, h1);
        self.set_face(h1, fo);
        self.set_vertex_halfedge(v0, Some(h1));
        self.adjust_outgoing_halfedge(v0);
        self.set_vertex_halfedge(v1, Some(o1));
        self.adjust_outgoing_halfedge(v1);
        if let Some(f) = fo {
            if self.face_halfedge(f) == o0 {
                self.set_face_halfedge(f, h1);
            }
        }
        if let Some(f) = fh {
            self.delete_face_slot(f);
        }
        self.delete_edge_slot(h0.edge());
    }

    fn delete_vertex_slot(&mut self, v: Vertex) {
        if !self.vdeleted[v.idx()] {
            self.vdeleted[v.idx()] = true;
            self.n_deleted[0] += 1;
        }
    }
    fn delete_edge_slot(&mut self, e: Edge) {
        if !self.edeleted[e.idx()] {
            self.edeleted[e.idx()] = true;
            self.n_deleted[1] += 1;
        }
    }
    fn delete_face_slot(&mut self, f: Face) {
        if !self.fdeleted[f.idx()] {
            self.fdeleted[f.idx()] = true;
            self.n_deleted[2] += 1;
        }
    }
}
