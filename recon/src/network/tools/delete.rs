//! Curve delete (FIRES thesis §5.1; its internals are ours): removes every edge made of one stroke. Each
//! removed edge merges its two faces into one; a vertex left with two edges of one stroke and equal
//! attributes is removed and its two edges re-merged into one polyline. Refused, leaving the network
//! unchanged: a stroke with no edges, an edge on the boundary (one face) or with the same face on both
//! sides (deleting it would not merge two faces), and anything that would leave a vertex with one edge.

use super::ToolError;
use crate::network::mesh::{EdgeUse, Network};
use crate::network::{EdgeId, Transaction, VertexId};

/// What [`delete_stroke`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct DeleteReport {
    /// Edges removed (the stroke's).
    pub removed_edges: usize,
    /// Vertices removed (ends and crossings that became plain points of a curve).
    pub removed_vertices: usize,
}

/// Deletes every edge whose polyline came from stroke `stroke`.
pub fn delete_stroke(
    net: &mut Network,
    stroke: u32,
) -> Result<(DeleteReport, Transaction), ToolError> {
    let edges: Vec<EdgeId> = net
        .edges()
        .filter(|(_, e)| {
            net.polyline(e.polyline)
                .is_some_and(|p| p.attrs.stroke == Some(stroke))
        })
        .map(|(id, _)| id)
        .collect();
    if edges.is_empty() {
        return Err(ToolError::NoSuchStroke { stroke });
    }
    net.transact(|net| {
        let mut touched: Vec<VertexId> = Vec::new();
        for &e in &edges {
            let ed = net
                .edge(e)
                .cloned()
                .ok_or(ToolError::NoSuchStroke { stroke })?;
            let (f1, f2) = match ed.faces[..] {
                [a, b] if a != b => (a, b),
                _ => return Err(ToolError::CannotDelete { edge: e }),
            };
            let l1 = net.face(f1).map(|f| f.uses.clone()).unwrap_or_default();
            let l2 = net.face(f2).map(|f| f.uses.clone()).unwrap_or_default();
            let rest = |l: &[EdgeUse]| -> Vec<EdgeUse> {
                let k = l.iter().position(|u| u.edge == e).unwrap_or(0);
                (1..l.len()).map(|i| l[(k + i) % l.len()]).collect()
            };
            let mut merged = rest(&l1);
            merged.extend(rest(&l2));
            net.remove_face(f1);
            net.remove_face(f2);
            net.remove_edge(e);
            if merged.is_empty() {
                return Err(ToolError::CannotDelete { edge: e });
            }
            net.add_face(merged);
            touched.extend([ed.from, ed.to]);
        }
        let mut removed_vertices = 0;
        touched.sort_unstable();
        touched.dedup();
        for v in touched {
            let Some(vx) = net.vertex(v).cloned() else {
                continue;
            };
            match vx.edges.len() {
                0 => {
                    net.set_vertex(v, None);
                    removed_vertices += 1;
                }
                1 => return Err(ToolError::CannotDelete { edge: vx.edges[0] }),
                2 if net.merge_at(v) => removed_vertices += 1,
                _ => {}
            }
        }
        Ok(DeleteReport {
            removed_edges: edges.len(),
            removed_vertices,
        })
    })
}

impl Network {
    /// Removes edge `e` (no face may use it) and its polyline.
    pub(crate) fn remove_edge(&mut self, e: EdgeId) {
        let Some(ed) = self.edge(e).cloned() else {
            return;
        };
        for v in [ed.from, ed.to] {
            if let Some(mut vx) = self.vertex(v).cloned() {
                if let Some(k) = vx.edges.iter().position(|&x| x == e) {
                    vx.edges.remove(k);
                }
                self.set_vertex(v, Some(vx));
            }
        }
        self.set_edge(e, None);
        self.set_polyline(ed.polyline, None);
    }

    /// Re-merges the two edges at degree-2 vertex `v` when they are different edges with the same
    /// attributes and the same faces; returns whether it did.
    pub(crate) fn merge_at(&mut self, v: VertexId) -> bool {
        let Some(vx) = self.vertex(v).cloned() else {
            return false;
        };
        let [a, b] = vx.edges[..] else {
            return false;
        };
        let (Some(ea), Some(eb)) = (self.edge(a).cloned(), self.edge(b).cloned()) else {
            return false;
        };
        if a == b || ea.from == ea.to || eb.from == eb.to {
            return false;
        }
        let (Some(pa), Some(pb)) = (
            self.polyline(ea.polyline).cloned(),
            self.polyline(eb.polyline).cloned(),
        ) else {
            return false;
        };
        let (mut fa, mut fb) = (ea.faces.clone(), eb.faces.clone());
        fa.sort_unstable();
        fb.sort_unstable();
        if pa.attrs != pb.attrs || fa != fb {
            return false;
        }
        // Orient both so the path runs x → v → y.
        let (x, mut first) = if ea.to == v {
            (ea.from, pa.points.clone())
        } else {
            (ea.to, pa.points.iter().rev().copied().collect())
        };
        let (y, second): (VertexId, Vec<[f64; 3]>) = if eb.from == v {
            (eb.to, pb.points.clone())
        } else {
            (eb.from, pb.points.iter().rev().copied().collect())
        };
        first.extend_from_slice(&second[1..]);
        let a_forward = ea.to == v;
        self.replace_pair_by_edge(v, a, b, a_forward, x, y, first, pa.attrs)
    }

    #[allow(clippy::too_many_arguments)]
    fn replace_pair_by_edge(
        &mut self,
        v: VertexId,
        a: EdgeId,
        b: EdgeId,
        a_forward: bool,
        x: VertexId,
        y: VertexId,
        points: Vec<[f64; 3]>,
        attrs: crate::network::PolylineAttrs,
    ) -> bool {
        let faces = self.edge(a).map(|e| e.faces.clone()).unwrap_or_default();
        let mut faces_d = faces.clone();
        faces_d.sort_unstable();
        faces_d.dedup();
        // Detach the faces, drop the two edges and the vertex, add the merged edge, reattach.
        let mut loops = Vec::new();
        for &f in &faces_d {
            let Some(face) = self.face(f).cloned() else {
                return false;
            };
            loops.push((f, face.uses));
        }
        for &(f, _) in &loops {
            self.remove_face(f);
        }
        self.remove_edge(a);
        self.remove_edge(b);
        self.set_vertex(v, None);
        let m = self.add_edge(x, y, points, attrs);
        for (_, uses) in loops {
            // A use of `a` in its x → v direction is followed by `b`: both become `m` forward; the
            // opposite traversal (y → v → x) becomes `m` reversed.
            let mut out: Vec<EdgeUse> = Vec::with_capacity(uses.len());
            for u in &uses {
                if u.edge == a {
                    let forward = u.reversed != a_forward;
                    out.push(EdgeUse {
                        edge: m,
                        reversed: !forward,
                    });
                } else if u.edge != b {
                    out.push(*u);
                }
            }
            self.add_face(out);
        }
        true
    }
}
