//! `validate()`: checks every halfedge invariant and reports the first violation.

use super::error::MeshError;
use super::handles::{Halfedge, INVALID};
use super::SurfaceMesh;

impl SurfaceMesh {
    /// Checks the halfedge invariants on live elements:
    /// * `next`/`prev` are inverse and stay on live halfedges; `next(h)` starts where `h`
    ///   ends; `h` and `next(h)` share their face;
    /// * every face loop has ≥ 3 halfedges, all pointing to that face;
    /// * a vertex's stored halfedge starts at it, is live, and is a boundary halfedge when
    ///   the vertex is on the boundary; rotating around it visits all its outgoing
    ///   halfedges (one fan per vertex);
    /// * no live element refers to a deleted one.
    pub fn validate(&self) -> Result<(), MeshError> {
        self.validate_halfedges()?;
        self.validate_faces()?;
        self.validate_vertices()
    }

    fn bad(msg: String) -> Result<(), MeshError> {
        Err(MeshError::Invalid(msg))
    }

    fn validate_halfedges(&self) -> Result<(), MeshError> {
        let nh = self.halfedges_size() as u32;
        for h in self.halfedges() {
            let c = self.hconn[h.idx()];
            if c.next >= nh || c.prev >= nh || c.to as usize >= self.vertices_size() {
                return Self::bad(format!("{h} has a dangling link"));
            }
            let n = Halfedge(c.next);
            if self.edeleted[n.edge().idx()] || self.vdeleted[c.to as usize] {
                return Self::bad(format!("{h} links to a deleted element"));
            }
            if self.prev_halfedge(n) != h || self.next_halfedge(self.prev_halfedge(h)) != h {
                return Self::bad(format!("{h}: next/prev not inverse"));
            }
            if self.from_vertex(n) != self.to_vertex(h) {
                return Self::bad(format!("{h}: next does not start at its end"));
            }
            if self.face(n) != self.face(h) {
                return Self::bad(format!("{h}: next is in another face"));
            }
            if let Some(f) = self.face(h) {
                if f.idx() >= self.faces_size() || self.fdeleted[f.idx()] {
                    return Self::bad(format!("{h} refers to a missing face"));
                }
            }
            if self.to_vertex(h) == self.from_vertex(h) {
                return Self::bad(format!("{h} is a loop edge"));
            }
        }
        Ok(())
    }

    fn validate_faces(&self) -> Result<(), MeshError> {
        for f in self.faces() {
            let h0 = self.face_he[f.idx()];
            if h0 == INVALID || self.edeleted[(h0 >> 1) as usize] {
                return Self::bad(format!("{f} has no live halfedge"));
            }
            let mut count = 0;
            for h in self.face_halfedges(f) {
                if self.face(h) != Some(f) {
                    return Self::bad(format!("{f}: loop halfedge {h} has another face"));
                }
                count += 1;
            }
            let closed = self.next_halfedge(self.prev_halfedge(self.face_halfedge(f)));
            if count < 3 || closed != self.face_halfedge(f) {
                return Self::bad(format!("{f} has a loop of {count} halfedges"));
            }
        }
        Ok(())
    }

    fn validate_vertices(&self) -> Result<(), MeshError> {
        let mut outgoing = vec![0usize; self.vertices_size()];
        for h in self.halfedges() {
            outgoing[self.from_vertex(h).idx()] += 1;
        }
        for v in self.vertices() {
            let Some(h) = self.vertex_halfedge(v) else {
                if outgoing[v.idx()] > 0 {
                    return Self::bad(format!("{v} is marked isolated but has edges"));
                }
                continue;
            };
            if self.edeleted[h.edge().idx()] || self.from_vertex(h) != v {
                return Self::bad(format!("{v}: stored halfedge {h} does not start at it"));
            }
            let around: Vec<Halfedge> = self.vertex_halfedges(v).collect();
            if around.len() != outgoing[v.idx()] {
                return Self::bad(format!("{v} is not a single fan"));
            }
            let on_boundary = around.iter().any(|&x| self.is_boundary_halfedge(x));
            if on_boundary && !self.is_boundary_halfedge(h) {
                return Self::bad(format!("{v}: boundary vertex without boundary halfedge"));
            }
        }
        Ok(())
    }
}
