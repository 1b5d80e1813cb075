//! The [`SurfaceMesh`] type: storage, element queries and low-level setters.

use super::handles::{Edge, Face, Halfedge, Vertex, INVALID};
use super::properties::PropertyContainer;
use crate::geometry::Vec3;

#[derive(Debug, Clone, Copy)]
pub(crate) struct HalfedgeConn {
    pub(crate) to: u32,
    pub(crate) next: u32,
    pub(crate) prev: u32,
    pub(crate) face: u32,
}

/// A halfedge mesh of polygons with per-element properties.
///
/// `clone()` copies connectivity and positions but not the (type-erased) properties.
#[derive(Debug, Clone, Default)]
pub struct SurfaceMesh {
    pub(crate) points: Vec<Vec3>,
    pub(crate) vertex_out: Vec<u32>,
    pub(crate) hconn: Vec<HalfedgeConn>,
    pub(crate) face_he: Vec<u32>,
    pub(crate) vdeleted: Vec<bool>,
    pub(crate) edeleted: Vec<bool>,
    pub(crate) fdeleted: Vec<bool>,
    pub(crate) n_deleted: [usize; 3],
    /// Per-vertex properties.
    pub vertex_props: PropertyContainer,
    /// Per-edge properties.
    pub edge_props: PropertyContainer,
    /// Per-face properties.
    pub face_props: PropertyContainer,
}

fn opt<T>(i: u32, f: impl FnOnce(u32) -> T) -> Option<T> {
    (i != INVALID).then(|| f(i))
}

impl SurfaceMesh {
    /// An empty mesh.
    pub fn new() -> Self {
        Self::default()
    }

    // ----- sizes -------------------------------------------------------------------

    /// Number of vertex slots, deleted ones included (the bound for vertex indices).
    pub fn vertices_size(&self) -> usize {
        self.points.len()
    }
    /// Number of halfedge slots, deleted ones included.
    pub fn halfedges_size(&self) -> usize {
        self.hconn.len()
    }
    /// Number of edge slots, deleted ones included.
    pub fn edges_size(&self) -> usize {
        self.hconn.len() / 2
    }
    /// Number of face slots, deleted ones included.
    pub fn faces_size(&self) -> usize {
        self.face_he.len()
    }
    /// Number of live vertices.
    pub fn n_vertices(&self) -> usize {
        self.vertices_size() - self.n_deleted[0]
    }
    /// Number of live edges.
    pub fn n_edges(&self) -> usize {
        self.edges_size() - self.n_deleted[1]
    }
    /// Number of live faces.
    pub fn n_faces(&self) -> usize {
        self.faces_size() - self.n_deleted[2]
    }
    /// True when deleted elements wait for [`Self::garbage_collection`].
    pub fn has_garbage(&self) -> bool {
        self.n_deleted.iter().any(|&n| n > 0)
    }
    /// Euler characteristic χ = V − E + F of the live elements.
    pub fn euler_characteristic(&self) -> i64 {
        self.n_vertices() as i64 - self.n_edges() as i64 + self.n_faces() as i64
    }

    // ----- iteration over live elements -------------------------------------------

    /// Live vertices.
    pub fn vertices(&self) -> impl Iterator<Item = Vertex> + '_ {
        (0..self.vertices_size())
            .filter(|&i| !self.vdeleted[i])
            .map(Vertex::new)
    }
    /// Live edges.
    pub fn edges(&self) -> impl Iterator<Item = Edge> + '_ {
        (0..self.edges_size())
            .filter(|&i| !self.edeleted[i])
            .map(Edge::new)
    }
    /// Live halfedges.
    pub fn halfedges(&self) -> impl Iterator<Item = Halfedge> + '_ {
        (0..self.halfedges_size())
            .filter(|&i| !self.edeleted[i / 2])
            .map(Halfedge::new)
    }
    /// Live faces.
    pub fn faces(&self) -> impl Iterator<Item = Face> + '_ {
        (0..self.faces_size())
            .filter(|&i| !self.fdeleted[i])
            .map(Face::new)
    }

    /// True if the vertex was deleted (and not yet collected).
    pub fn is_deleted_vertex(&self, v: Vertex) -> bool {
        self.vdeleted[v.idx()]
    }
    /// True if the edge was deleted.
    pub fn is_deleted_edge(&self, e: Edge) -> bool {
        self.edeleted[e.idx()]
    }
    /// True if the face was deleted.
    pub fn is_deleted_face(&self, f: Face) -> bool {
        self.fdeleted[f.idx()]
    }

    // ----- geometry ----------------------------------------------------------------

    /// Position of a vertex.
    pub fn position(&self, v: Vertex) -> Vec3 {
        self.points[v.idx()]
    }
    /// Sets the position of a vertex.
    pub fn set_position(&mut self, v: Vertex, p: Vec3) {
        self.points[v.idx()] = p;
    }
    /// All vertex positions, indexed by vertex index (deleted slots included).
    pub fn positions(&self) -> &[Vec3] {
        &self.points
    }
    /// Mutable vertex positions.
    pub fn positions_mut(&mut self) -> &mut [Vec3] {
        &mut self.points
    }

    // ----- connectivity queries ----------------------------------------------------

    /// An outgoing halfedge of `v` (a boundary one if `v` is on the boundary), or `None`
    /// for an isolated vertex.
    pub fn vertex_halfedge(&self, v: Vertex) -> Option<Halfedge> {
        opt(self.vertex_out[v.idx()], Halfedge)
    }
    /// The vertex a halfedge points to.
    pub fn to_vertex(&self, h: Halfedge) -> Vertex {
        Vertex(self.hconn[h.idx()].to)
    }
    /// The vertex a halfedge starts from.
    pub fn from_vertex(&self, h: Halfedge) -> Vertex {
        self.to_vertex(h.opposite())
    }
    /// Next halfedge in the same face (or boundary loop).
    pub fn next_halfedge(&self, h: Halfedge) -> Halfedge {
        Halfedge(self.hconn[h.idx()].next)
    }
    /// Previous halfedge in the same face (or boundary loop).
    pub fn prev_halfedge(&self, h: Halfedge) -> Halfedge {
        Halfedge(self.hconn[h.idx()].prev)
    }
    /// The face of a halfedge, `None` for a boundary halfedge.
    pub fn face(&self, h: Halfedge) -> Option<Face> {
        opt(self.hconn[h.idx()].face, Face)
    }
    /// One halfedge of a face.
    pub fn face_halfedge(&self, f: Face) -> Halfedge {
        Halfedge(self.face_he[f.idx()])
    }
    /// The two vertices of an edge.
    pub fn edge_vertices(&self, e: Edge) -> (Vertex, Vertex) {
        let h = e.halfedge(0);
        (self.from_vertex(h), self.to_vertex(h))
    }
    /// Rotates an outgoing halfedge clockwise around its start vertex.
    pub fn cw_rotated_halfedge(&self, h: Halfedge) -> Halfedge {
        self.next_halfedge(h.opposite())
    }
    /// Rotates an outgoing halfedge counter-clockwise around its start vertex.
    pub fn ccw_rotated_halfedge(&self, h: Halfedge) -> Halfedge {
        self.prev_halfedge(h).opposite()
    }

    /// True for a halfedge without a face.
    pub fn is_boundary_halfedge(&self, h: Halfedge) -> bool {
        self.hconn[h.idx()].face == INVALID
    }
    /// True for an edge with a boundary halfedge.
    pub fn is_boundary_edge(&self, e: Edge) -> bool {
        self.is_boundary_halfedge(e.halfedge(0)) || self.is_boundary_halfedge(e.halfedge(1))
    }
    /// True for a vertex on the boundary (or isolated).
    pub fn is_boundary_vertex(&self, v: Vertex) -> bool {
        self.vertex_halfedge(v)
            .is_none_or(|h| self.is_boundary_halfedge(h))
    }
    /// True for a vertex without incident edges.
    pub fn is_isolated(&self, v: Vertex) -> bool {
        self.vertex_out[v.idx()] == INVALID
    }
    /// True for a face with a boundary edge.
    pub fn is_boundary_face(&self, f: Face) -> bool {
        self.face_halfedges(f)
            .any(|h| self.is_boundary_halfedge(h.opposite()))
    }
    /// True when every face has three vertices.
    pub fn is_triangle_mesh(&self) -> bool {
        self.faces().all(|f| self.face_valence(f) == 3)
    }
    /// True when the mesh has no boundary edge.
    pub fn is_closed(&self) -> bool {
        self.halfedges().all(|h| !self.is_boundary_halfedge(h))
    }

    /// Number of edges incident to a vertex.
    pub fn valence(&self, v: Vertex) -> usize {
        self.vertex_halfedges(v).count()
    }
    /// Number of vertices of a face.
    pub fn face_valence(&self, f: Face) -> usize {
        self.face_halfedges(f).count()
    }
    /// The halfedge from `a` to `b`, if they are joined by an edge.
    pub fn find_halfedge(&self, a: Vertex, b: Vertex) -> Option<Halfedge> {
        self.vertex_halfedges(a).find(|&h| self.to_vertex(h) == b)
    }
    /// The edge joining `a` and `b`, if any.
    pub fn find_edge(&self, a: Vertex, b: Vertex) -> Option<Edge> {
        self.find_halfedge(a, b).map(Halfedge::edge)
    }
    /// The vertices of a face in order.
    pub fn face_vertices(&self, f: Face) -> impl Iterator<Item = Vertex> + '_ {
        self.face_halfedges(f).map(move |h| self.to_vertex(h))
    }
    /// The three vertices of a triangle face (the first three for a polygon).
    pub fn triangle(&self, f: Face) -> [Vertex; 3] {
        let h0 = self.face_halfedge(f);
        let h1 = self.next_halfedge(h0);
        let h2 = self.next_halfedge(h1);
        [self.to_vertex(h0), self.to_vertex(h1), self.to_vertex(h2)]
    }
    /// Length of an edge.
    pub fn edge_length(&self, e: Edge) -> f64 {
        let (a, b) = self.edge_vertices(e);
        self.position(a).distance(self.position(b))
    }

    /// All faces as vertex-index lists (live elements only, indices as stored; call
    /// [`Self::garbage_collection`] first for dense indices).
    pub fn face_index_lists(&self) -> Vec<Vec<usize>> {
        self.faces()
            .map(|f| self.face_vertices(f).map(Vertex::idx).collect())
            .collect()
    }

    // ----- low-level construction --------------------------------------------------

    /// Adds an isolated vertex.
    pub fn add_vertex(&mut self, p: Vec3) -> Vertex {
        self.points.push(p);
        self.vertex_out.push(INVALID);
        self.vdeleted.push(false);
        self.vertex_props.push();
        Vertex::new(self.points.len() - 1)
    }

    /// Adds an edge `a → b` as two halfedges with no face and no links; returns `a → b`.
    pub(crate) fn new_edge(&mut self, a: Vertex, b: Vertex) -> Halfedge {
        let blank = HalfedgeConn {
            to: INVALID,
            next: INVALID,
            prev: INVALID,
            face: INVALID,
        };
        let h = self.hconn.len();
        self.hconn.push(HalfedgeConn { to: b.0, ..blank });
        self.hconn.push(HalfedgeConn { to: a.0, ..blank });
        self.edeleted.push(false);
        self.edge_props.push();
        Halfedge::new(h)
    }

    pub(crate) fn new_face(&mut self) -> Face {
        self.face_he.push(INVALID);
        self.fdeleted.push(false);
        self.face_props.push();
        Face::new(self.face_he.len() - 1)
    }

    pub(crate) fn set_next(&mut self, h: Halfedge, n: Halfedge) {
        self.hconn[h.idx()].next = n.0;
        self.hconn[n.idx()].prev = h.0;
    }
    pub(crate) fn set_to_vertex(&mut self, h: Halfedge, v: Vertex) {
        self.hconn[h.idx()].to = v.0;
    }
    pub(crate) fn set_face(&mut self, h: Halfedge, f: Option<Face>) {
        self.hconn[h.idx()].face = f.map_or(INVALID, |f| f.0);
    }
    pub(crate) fn set_vertex_halfedge(&mut self, v: Vertex, h: Option<Halfedge>) {
        self.vertex_out[v.idx()] = h.map_or(INVALID, |h| h.0);
    }
    pub(crate) fn set_face_halfedge(&mut self, f: Face, h: Halfedge) {
        self.face_he[f.idx()] = h.0;
    }

    /// Makes the stored outgoing halfedge of `v` a boundary one if `v` is on the boundary.
    pub(crate) fn adjust_outgoing_halfedge(&mut self, v: Vertex) {
        let boundary = self
            .vertex_halfedges(v)
            .find(|&h| self.is_boundary_halfedge(h));
        if let Some(h) = boundary {
            self.set_vertex_halfedge(v, Some(h));
        }
    }
}
