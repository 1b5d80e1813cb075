//! The two primitive edits every sketching tool is made of (FIRES thesis §5.2.1): splitting an edge at a
//! point of its polyline, and splitting a face by a new edge between two of its vertices.
//! Both keep invariants 1–4; callers run them inside a transaction.

use super::geom::{dist, lerp};
use super::handles::{EdgeId, FaceId, VertexId};
use super::mesh::{EdgeUse, Network, PolylineAttrs, Vertex};

/// Points closer than this are one point when a polyline is cut, metres.
pub(crate) const SAME_POINT_M: f64 = 1e-9;

/// Where a face split would go: the loop positions of the two vertices.
pub(crate) struct FaceCut {
    pub(crate) i: usize,
    pub(crate) j: usize,
    pub(crate) len: usize,
}

impl FaceCut {
    /// Number of face uses from `a` to `b` and from `b` to `a`.
    pub(crate) fn sides(&self) -> (usize, usize) {
        let ab = (self.j + self.len - self.i) % self.len;
        (ab, self.len - ab)
    }
}

impl Network {
    /// Splits edge `e` at parameter `t` of polyline segment `seg`; the new vertex lies exactly on the old
    /// polyline, so existing curves do not move. Returns the vertex and the two halves (`from → v`,
    /// `v → to`). Cutting at an end point returns that end's vertex and no halves.
    pub(crate) fn split_edge(
        &mut self,
        e: EdgeId,
        seg: usize,
        t: f64,
    ) -> Option<(VertexId, Option<(EdgeId, EdgeId)>)> {
        let ed = self.edge(e)?.clone();
        let poly = self.polyline(ed.polyline)?.clone();
        let n = poly.points.len();
        let seg = seg.min(n - 2);
        let p = lerp(poly.points[seg], poly.points[seg + 1], t.clamp(0.0, 1.0));
        let mut first: Vec<[f64; 3]> = poly.points[..=seg].to_vec();
        if dist(p, poly.points[seg]) > SAME_POINT_M {
            first.push(p);
        } else if let Some(last) = first.last_mut() {
            *last = p;
        }
        let mut second = vec![p];
        let rest = &poly.points[seg + 1..];
        let skip = usize::from(dist(p, rest[0]) <= SAME_POINT_M);
        second.extend_from_slice(&rest[skip..]);
        if first.len() < 2 {
            return Some((ed.from, None));
        }
        if second.len() < 2 {
            return Some((ed.to, None));
        }
        let v = self.push_vertex(Vertex {
            position: p,
            edges: Vec::new(),
        });
        for end in [ed.from, ed.to] {
            if let Some(mut vx) = self.vertex(end).cloned() {
                if let Some(k) = vx.edges.iter().position(|&x| x == e) {
                    vx.edges.remove(k);
                }
                self.set_vertex(end, Some(vx));
            }
        }
        let e1 = self.add_edge(ed.from, v, first, poly.attrs);
        let e2 = self.add_edge(v, ed.to, second, poly.attrs);
        let mut faces = ed.faces.clone();
        faces.sort_unstable();
        faces.dedup();
        for f in faces {
            let Some(mut face) = self.face(f).cloned() else {
                continue;
            };
            let mut uses = Vec::with_capacity(face.uses.len() + 1);
            for u in &face.uses {
                if u.edge != e {
                    uses.push(*u);
                } else if u.reversed {
                    uses.push(EdgeUse {
                        edge: e2,
                        reversed: true,
                    });
                    uses.push(EdgeUse {
                        edge: e1,
                        reversed: true,
                    });
                } else {
                    uses.push(EdgeUse {
                        edge: e1,
                        reversed: false,
                    });
                    uses.push(EdgeUse {
                        edge: e2,
                        reversed: false,
                    });
                }
            }
            face.uses = uses;
            self.set_face(f, Some(face));
            for half in [e1, e2] {
                if let Some(mut h) = self.edge(half).cloned() {
                    h.faces.extend(ed.faces.iter().filter(|&&x| x == f));
                    self.set_edge(half, Some(h));
                }
            }
        }
        self.set_edge(e, None);
        self.set_polyline(ed.polyline, None);
        Some((v, Some((e1, e2))))
    }

    /// Where `a` and `b` sit on the loop of face `f` (first occurrences), if both do and differ.
    pub(crate) fn face_cut(&self, f: FaceId, a: VertexId, b: VertexId) -> Option<FaceCut> {
        if a == b {
            return None;
        }
        let face = self.face(f)?;
        let pos = |v| face.uses.iter().position(|u| self.use_start(*u) == Some(v));
        Some(FaceCut {
            i: pos(a)?,
            j: pos(b)?,
            len: face.uses.len(),
        })
    }

    /// Splits face `f` by a new edge `a → b` with geometry `points`; returns the edge and the two faces
    /// (the one bounded by the old loop from `a` to `b`, then the one from `b` to `a`).
    pub(crate) fn split_face(
        &mut self,
        f: FaceId,
        cut: &FaceCut,
        points: Vec<[f64; 3]>,
        attrs: PolylineAttrs,
    ) -> Option<(EdgeId, FaceId, FaceId)> {
        let face = self.face(f)?.clone();
        let a = self.use_start(face.uses[cut.i])?;
        let b = self.use_start(face.uses[cut.j])?;
        let (ab, ba) = cut.sides();
        let n = cut.len;
        let mut loop1: Vec<EdgeUse> = (0..ab).map(|k| face.uses[(cut.i + k) % n]).collect();
        let mut loop2: Vec<EdgeUse> = (0..ba).map(|k| face.uses[(cut.j + k) % n]).collect();
        let e = self.add_edge(a, b, points, attrs);
        self.remove_face(f);
        loop1.push(EdgeUse {
            edge: e,
            reversed: true,
        });
        loop2.push(EdgeUse {
            edge: e,
            reversed: false,
        });
        let f1 = self.add_face(loop1);
        let f2 = self.add_face(loop2);
        Some((e, f1, f2))
    }
}
