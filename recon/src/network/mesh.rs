//! The polyline mesh M = (V, E, F, P) of the FIRES thesis (§3.3, "Polyline Mesh").
//!
//! * a [`Vertex`] is a point with the unordered list of its edges;
//! * a [`Polyline`] is a sequence of points with the attributes the surfaces need;
//! * an [`Edge`] is a vertex pair plus exactly one polyline, so several edges may join the same two
//!   vertices (multi-edges, needed by border gluing); it knows its at most two faces;
//! * a [`Face`] is a closed ordered loop of edge uses, each with its traversal direction (adjacent faces
//!   traverse a shared edge in opposite directions; with multi-edges and self-loops the direction cannot be
//!   inferred from the vertices).
//!
//! Positions are in metres (the project's convention); tool thresholds are given in millimetres.
//! All edits go through the setters below, which record the previous slot value while a transaction is
//! open (see `txn.rs`), so a failed tool restores the network bit for bit.

use serde::{Deserialize, Serialize};

use super::handles::{EdgeId, FaceId, PolylineId, VertexId};
use super::txn::Change;

/// A network vertex.
#[derive(Clone, Debug, PartialEq)]
pub struct Vertex {
    /// Position, metres.
    pub position: [f64; 3],
    /// The edges that start or end here (a self-loop is listed twice), unordered.
    pub edges: Vec<EdgeId>,
}

/// Whether the surface must pass through a polyline or only near it (FIRES thesis §5.3: NULISSmod
/// interpolates characteristic curves and approximates control curves).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Fit {
    /// The surface interpolates the polyline.
    #[default]
    Interpolate,
    /// The surface approximates the polyline.
    Approximate,
}

/// Who made a polyline.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Origin {
    /// Drawn by the user (a stroke or part of one).
    #[default]
    User,
    /// Made by a tool (hole spokes, a short-stop extension, ...).
    Generated,
}

/// Per-polyline attributes (FIRES thesis §3.3 and §5.4).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PolylineAttrs {
    /// Crease sharpness, 0 (smooth) .. 1 (sharp).
    pub sharpness: f64,
    /// Interpolate or approximate.
    pub fit: Fit,
    /// User-drawn or generated.
    pub origin: Origin,
    /// The stroke id this polyline comes from (kept by every piece of a split stroke).
    pub stroke: Option<u32>,
}

impl Default for PolylineAttrs {
    fn default() -> Self {
        PolylineAttrs {
            sharpness: 0.0,
            fit: Fit::Interpolate,
            origin: Origin::User,
            stroke: None,
        }
    }
}

/// A polyline: at least two points joined by segments, metres.
#[derive(Clone, Debug, PartialEq)]
pub struct Polyline {
    /// Points in order; the first is the edge's `from` vertex, the last its `to` vertex.
    pub points: Vec<[f64; 3]>,
    /// Attributes.
    pub attrs: PolylineAttrs,
}

/// A network edge.
#[derive(Clone, Debug, PartialEq)]
pub struct Edge {
    /// Start vertex (the polyline's first point).
    pub from: VertexId,
    /// End vertex (the polyline's last point).
    pub to: VertexId,
    /// The edge's geometry.
    pub polyline: PolylineId,
    /// The faces using this edge (at most two; a face using the edge twice is listed twice).
    pub faces: Vec<FaceId>,
}

/// One edge of a face loop with its traversal direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct EdgeUse {
    /// The edge.
    pub edge: EdgeId,
    /// Traversed `to → from` instead of `from → to`.
    pub reversed: bool,
}

/// A network face: a closed loop of edge uses.
#[derive(Clone, Debug, PartialEq)]
pub struct Face {
    /// The loop, in traversal order.
    pub uses: Vec<EdgeUse>,
}

/// The curve network (polyline mesh).
#[derive(Clone, Debug, Default)]
pub struct Network {
    pub(crate) vertices: Vec<Option<Vertex>>,
    pub(crate) polylines: Vec<Option<Polyline>>,
    pub(crate) edges: Vec<Option<Edge>>,
    pub(crate) faces: Vec<Option<Face>>,
    /// The open transaction's change log (`None` outside a transaction).
    pub(crate) log: Option<super::txn::Log>,
    /// Bounding boxes of each polyline slot (derived; empty slots hold empty boxes).
    pub(crate) boxes: Vec<super::geom::PolyBoxes>,
    /// The edge last written with each polyline (derived; exact for live polylines).
    pub(crate) owner: Vec<EdgeId>,
}

impl PartialEq for Network {
    /// Two networks are equal when every slot is equal (the transaction state is not compared).
    fn eq(&self, other: &Self) -> bool {
        self.vertices == other.vertices
            && self.polylines == other.polylines
            && self.edges == other.edges
            && self.faces == other.faces
    }
}

macro_rules! arena_access {
    ($get:ident, $iter:ident, $count:ident, $set:ident, $push:ident, $field:ident, $id:ident, $ty:ident, $change:ident) => {
        /// The element, if it exists.
        pub fn $get(&self, id: $id) -> Option<&$ty> {
            self.$field.get(id.idx()).and_then(|s| s.as_ref())
        }
        /// All live elements with their handles, in handle order.
        pub fn $iter(&self) -> impl Iterator<Item = ($id, &$ty)> + '_ {
            self.$field
                .iter()
                .enumerate()
                .filter_map(|(i, s)| s.as_ref().map(|x| ($id(i as u32), x)))
        }
        /// Number of live elements.
        pub fn $count(&self) -> usize {
            self.$field.iter().filter(|s| s.is_some()).count()
        }
        pub(crate) fn $set(&mut self, id: $id, value: Option<$ty>) {
            let old = std::mem::replace(&mut self.$field[id.idx()], value);
            self.slot_written(Change::$change(id, None));
            if let Some(log) = &mut self.log {
                log.changes.push(Change::$change(id, old));
            }
        }
        pub(crate) fn $push(&mut self, value: $ty) -> $id {
            let id = $id(self.$field.len() as u32);
            self.$field.push(None);
            self.$set(id, Some(value));
            id
        }
    };
}

impl Network {
    /// An empty network.
    pub fn new() -> Self {
        Self::default()
    }

    arena_access!(
        vertex,
        vertices,
        n_vertices,
        set_vertex,
        push_vertex,
        vertices,
        VertexId,
        Vertex,
        Vertex
    );
    arena_access!(edge, edges, n_edges, set_edge, push_edge, edges, EdgeId, Edge, Edge);
    arena_access!(face, faces, n_faces, set_face, push_face, faces, FaceId, Face, Face);
    arena_access!(
        polyline,
        polylines,
        n_polylines,
        set_polyline,
        push_polyline,
        polylines,
        PolylineId,
        Polyline,
        Polyline
    );

    /// Keeps the derived polyline boxes in step with a slot write.
    pub(crate) fn slot_written(&mut self, c: Change) {
        if let Change::Edge(id, _) = c {
            if let Some(e) = &self.edges[id.idx()] {
                let p = e.polyline.idx();
                if self.owner.len() <= p {
                    self.owner.resize(p + 1, EdgeId(u32::MAX));
                }
                self.owner[p] = id;
            }
        }
        if let Change::Polyline(id, _) = c {
            let b = super::geom::PolyBoxes::new(
                self.polylines[id.idx()]
                    .as_ref()
                    .map_or(&[][..], |p| &p.points[..]),
            );
            if self.boxes.len() < self.polylines.len() {
                self.boxes
                    .resize(self.polylines.len(), super::geom::PolyBoxes::default());
            }
            self.boxes[id.idx()] = b;
        }
    }

    /// Recomputes every polyline box (after slots were written directly).
    pub(crate) fn rebuild_boxes(&mut self) {
        self.boxes = self
            .polylines
            .iter()
            .map(|p| super::geom::PolyBoxes::new(p.as_ref().map_or(&[][..], |p| &p.points[..])))
            .collect();
        self.owner = vec![EdgeId(u32::MAX); self.polylines.len()];
        for (i, e) in self.edges.iter().enumerate() {
            if let Some(e) = e {
                if let Some(o) = self.owner.get_mut(e.polyline.idx()) {
                    *o = EdgeId(i as u32);
                }
            }
        }
    }

    /// Live edges whose polyline's box meets `b` grown by `margin`, with their polyline and boxes.
    pub(crate) fn edges_near(
        &self,
        b: ([f64; 3], [f64; 3]),
        margin: f64,
    ) -> impl Iterator<Item = (EdgeId, &Polyline, &super::geom::PolyBoxes)> + '_ {
        self.boxes.iter().enumerate().filter_map(move |(p, bx)| {
            if !super::geom::boxes_overlap(b, bx.whole, margin) {
                return None;
            }
            let e = *self.owner.get(p)?;
            let ed = self.edge(e)?;
            if ed.polyline.idx() != p {
                return None;
            }
            Some((e, self.polylines[p].as_ref()?, bx))
        })
    }

    /// The polyline of edge `e`.
    pub fn edge_polyline(&self, e: EdgeId) -> Option<&Polyline> {
        self.edge(e).and_then(|x| self.polyline(x.polyline))
    }

    /// The vertex a face use starts at.
    pub fn use_start(&self, u: EdgeUse) -> Option<VertexId> {
        self.edge(u.edge)
            .map(|e| if u.reversed { e.to } else { e.from })
    }

    /// The vertex a face use ends at.
    pub fn use_end(&self, u: EdgeUse) -> Option<VertexId> {
        self.edge(u.edge)
            .map(|e| if u.reversed { e.from } else { e.to })
    }

    /// The faces around vertex `v` (each once, in handle order).
    pub fn vertex_faces(&self, v: VertexId) -> Vec<FaceId> {
        let mut out: Vec<FaceId> = Vec::new();
        if let Some(vx) = self.vertex(v) {
            for &e in &vx.edges {
                if let Some(ed) = self.edge(e) {
                    out.extend(ed.faces.iter().copied());
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// The points of a face's boundary in traversal order (each polyline oriented by its use; the shared
    /// vertex between consecutive uses appears once).
    pub fn face_points(&self, f: FaceId) -> Vec<[f64; 3]> {
        let mut out = Vec::new();
        if let Some(face) = self.face(f) {
            for u in &face.uses {
                if let Some(p) = self.edge_polyline(u.edge) {
                    let n = p.points.len();
                    for k in 0..n.saturating_sub(1) {
                        let i = if u.reversed { n - 1 - k } else { k };
                        out.push(p.points[i]);
                    }
                }
            }
        }
        out
    }

    /// Adds an edge from `from` to `to` with geometry `points` (whose ends are set to the vertex positions
    /// exactly) and registers it at both vertices.
    pub(crate) fn add_edge(
        &mut self,
        from: VertexId,
        to: VertexId,
        mut points: Vec<[f64; 3]>,
        attrs: PolylineAttrs,
    ) -> EdgeId {
        let (pa, pb) = (
            self.vertices[from.idx()].as_ref(),
            self.vertices[to.idx()].as_ref(),
        );
        if let (Some(a), Some(b), Some(first)) = (pa, pb, points.first_mut()) {
            *first = a.position;
            if let Some(last) = points.last_mut() {
                *last = b.position;
            }
        }
        let polyline = self.push_polyline(Polyline { points, attrs });
        let e = self.push_edge(Edge {
            from,
            to,
            polyline,
            faces: Vec::new(),
        });
        for v in [from, to] {
            if let Some(mut vx) = self.vertex(v).cloned() {
                vx.edges.push(e);
                self.set_vertex(v, Some(vx));
            }
        }
        e
    }

    /// Adds a face with loop `uses` and registers it at its edges.
    pub(crate) fn add_face(&mut self, uses: Vec<EdgeUse>) -> FaceId {
        let f = self.push_face(Face { uses: uses.clone() });
        for u in uses {
            if let Some(mut ed) = self.edge(u.edge).cloned() {
                ed.faces.push(f);
                self.set_edge(u.edge, Some(ed));
            }
        }
        f
    }

    /// Removes face `f` and its references from its edges.
    pub(crate) fn remove_face(&mut self, f: FaceId) {
        let Some(face) = self.face(f).cloned() else {
            return;
        };
        for u in &face.uses {
            if let Some(mut ed) = self.edge(u.edge).cloned() {
                if let Some(k) = ed.faces.iter().position(|&x| x == f) {
                    ed.faces.remove(k);
                    self.set_edge(u.edge, Some(ed));
                }
            }
        }
        self.set_face(f, None);
    }
}
