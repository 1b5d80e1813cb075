//! The base control mesh of a curve network: one polygon per network face (FIRES thesis §6.1, the input
//! of triquadrification).
//!
//! Every network vertex used by a face becomes a mesh vertex tagged [`VertexTag::Corner`]; every network
//! edge used by a face becomes a [`Curve`] (its polyline, `sharp` when the polyline's sharpness is ≥ ½,
//! `source` = the polyline's slot) followed by one mesh edge end to end. The faces keep the network loops'
//! orientation.
//!
//! A halfedge mesh cannot hold two edges between the same two vertices nor an edge from a vertex to
//! itself, both of which the network allows (multi-edges from border gluing, closed strokes). So:
//! * of several network edges joining the same two vertices, the first (in handle order) stays one mesh
//!   edge and each other one gets a vertex at its arc-length midpoint (its curve span split in two);
//! * a self-loop gets two vertices, at a third and two thirds of its arc length.
//!
//! The inserted vertices are tagged [`VertexTag::OnCurve`]. A 2-sided face between two multi-edges thus
//! becomes a triangle and a 1-sided face a triangle, so every face has at least three sides.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use super::control::{ControlMesh, Curve, CurvePoint, CurveSpan, VertexTag};
use super::error::SurfaceError;
use crate::geometry::Vec3;
use crate::mesh::SurfaceMesh;
use crate::network::{EdgeId, Network, VertexId};

/// A fast hasher for integer keys (vertex pairs): multiply-rotate, as rustc's FxHash. Not DoS-resistant,
/// which does not matter for keys the stages make themselves.
#[derive(Default, Clone, Copy)]
pub(crate) struct IntHasher(u64);

impl Hasher for IntHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_usize(&mut self, x: usize) {
        self.write_u64(x as u64);
    }
}

/// A map keyed by directed vertex pairs.
pub(crate) type PairMap<V> = HashMap<(usize, usize), V, BuildHasherDefault<IntHasher>>;

/// A control mesh under construction: polygons as vertex-index lists, with the curve span of each directed
/// vertex pair that follows a curve (`t0` at the first vertex).
#[derive(Default)]
pub(crate) struct Builder {
    /// Vertex positions.
    pub points: Vec<Vec3>,
    /// Vertex tags, one per point.
    pub tags: Vec<VertexTag>,
    /// Polygons.
    pub faces: Vec<Vec<usize>>,
    /// Curve spans of directed vertex pairs (one direction is enough).
    pub spans: PairMap<CurveSpan>,
    /// The curves.
    pub curves: Vec<Curve>,
}

impl Builder {
    /// A builder holding `cm`'s vertices, tags, curves and curve spans, without its faces.
    pub fn from_control(cm: &ControlMesh) -> Self {
        let mut b = Self::from_control_without_spans(cm);
        let m = &cm.mesh;
        b.spans.reserve(m.n_edges());
        for e in m.edges() {
            if let Some(s) = cm.span(e) {
                let (a, z) = m.edge_vertices(e);
                b.spans.insert((a.idx(), z.idx()), s);
            }
        }
        b
    }

    /// [`Self::from_control`] without the spans (for stages that split every edge).
    pub fn from_control_without_spans(cm: &ControlMesh) -> Self {
        let m = &cm.mesh;
        let mut tags = cm.vertex_tag.clone();
        tags.resize(m.vertices_size(), VertexTag::Free);
        Builder {
            points: m.positions().to_vec(),
            tags,
            faces: Vec::new(),
            spans: PairMap::default(),
            curves: cm.curves.clone(),
        }
    }

    /// Adds a vertex and returns its index.
    pub fn vertex(&mut self, p: Vec3, tag: VertexTag) -> usize {
        self.points.push(p);
        self.tags.push(tag);
        self.points.len() - 1
    }

    /// Records that the edge `a → b` follows `curve` from `t0` (at `a`) to `t1` (at `b`).
    pub fn span(&mut self, a: usize, b: usize, curve: usize, t0: f64, t1: f64) {
        self.spans.insert((a, b), CurveSpan { curve, t0, t1 });
    }

    /// The span of the directed pair `a → b`, whichever direction it was recorded in.
    pub fn span_of(&self, a: usize, b: usize) -> Option<CurveSpan> {
        if let Some(s) = self.spans.get(&(a, b)) {
            return Some(*s);
        }
        self.spans.get(&(b, a)).map(|s| CurveSpan {
            curve: s.curve,
            t0: s.t1,
            t1: s.t0,
        })
    }

    /// Builds the mesh and attaches the spans and tags.
    pub fn finish(self) -> Result<ControlMesh, SurfaceError> {
        let mesh = SurfaceMesh::from_faces(&self.points, &self.faces)?;
        let mut edge_curve = vec![None; mesh.edges_size()];
        for e in mesh.edges() {
            let (a, b) = mesh.edge_vertices(e);
            edge_curve[e.idx()] = self.span_of(a.idx(), b.idx());
        }
        Ok(ControlMesh {
            mesh,
            curves: self.curves,
            edge_curve,
            vertex_tag: self.tags,
        })
    }
}

/// One network edge as a chain of mesh vertices along its curve.
struct Chain {
    verts: Vec<usize>,
}

/// The base control mesh of `net`: one polygon per network face, each side following a whole network edge
/// polyline (see the module doc for multi-edges and self-loops).
pub fn base_mesh(net: &Network) -> Result<ControlMesh, SurfaceError> {
    if net.n_faces() == 0 {
        return Err(SurfaceError::EmptyNetwork);
    }
    // The network edges the faces use, in handle order.
    let mut used: Vec<EdgeId> = net
        .faces()
        .flat_map(|(_, f)| f.uses.iter().map(|u| u.edge))
        .collect();
    used.sort_unstable();
    used.dedup();

    let mut b = Builder::default();
    let mut vmap: HashMap<VertexId, usize> = HashMap::new();
    let mut pair_seen: HashMap<(VertexId, VertexId), usize> = HashMap::new();
    let mut chains: HashMap<EdgeId, Chain> = HashMap::new();
    for &e in &used {
        let ed = net.edge(e).ok_or_else(|| SurfaceError::UnsupportedFace {
            face: "?".into(),
            reason: format!("it uses the missing edge {e}"),
        })?;
        let pl = net
            .polyline(ed.polyline)
            .ok_or_else(|| SurfaceError::Degenerate(format!("edge {e} has no polyline")))?;
        let points: Vec<Vec3> = pl.points.iter().map(|&p| Vec3::from_array(p)).collect();
        if points.len() < 2 || points.iter().any(|p| !p.is_finite()) {
            return Err(SurfaceError::Degenerate(format!(
                "edge {e}'s polyline has {} points or a non-finite one",
                points.len()
            )));
        }
        let mut curve = Curve::new(points, pl.attrs.sharpness >= 0.5);
        curve.source = Some(ed.polyline.idx());
        let len = curve.length();
        if len.is_nan() || len <= 0.0 {
            return Err(SurfaceError::Degenerate(format!(
                "edge {e}'s polyline has zero length"
            )));
        }
        let ci = b.curves.len();
        let mut corner = |b: &mut Builder, v: VertexId| -> Result<usize, SurfaceError> {
            if let Some(&i) = vmap.get(&v) {
                return Ok(i);
            }
            let vx = net.vertex(v).ok_or_else(|| {
                SurfaceError::Degenerate(format!("edge {e} ends at the missing vertex {v}"))
            })?;
            let p = Vec3::from_array(vx.position);
            if !p.is_finite() {
                return Err(SurfaceError::Degenerate(format!(
                    "vertex {v} is not finite"
                )));
            }
            let i = b.vertex(p, VertexTag::Corner);
            vmap.insert(v, i);
            Ok(i)
        };
        let a = corner(&mut b, ed.from)?;
        let z = corner(&mut b, ed.to)?;
        let key = if ed.from <= ed.to {
            (ed.from, ed.to)
        } else {
            (ed.to, ed.from)
        };
        let count = pair_seen.entry(key).or_insert(0);
        let cuts: &[f64] = if ed.from == ed.to {
            &[1.0 / 3.0, 2.0 / 3.0]
        } else if *count > 0 {
            &[0.5]
        } else {
            &[]
        };
        *count += 1;
        let mut verts = vec![a];
        let mut ts = vec![0.0];
        for &c in cuts {
            let t = c * len;
            let v = b.vertex(
                curve.point_at(t),
                VertexTag::OnCurve(CurvePoint { curve: ci, t }),
            );
            verts.push(v);
            ts.push(t);
        }
        verts.push(z);
        ts.push(len);
        for k in 0..verts.len() - 1 {
            b.span(verts[k], verts[k + 1], ci, ts[k], ts[k + 1]);
        }
        b.curves.push(curve);
        chains.insert(e, Chain { verts });
    }

    for (fid, face) in net.faces() {
        let mut poly: Vec<usize> = Vec::new();
        for u in &face.uses {
            let ch = chains
                .get(&u.edge)
                .ok_or_else(|| SurfaceError::UnsupportedFace {
                    face: fid.to_string(),
                    reason: format!("it uses the missing edge {}", u.edge),
                })?;
            let n = ch.verts.len();
            for k in 0..n - 1 {
                poly.push(if u.reversed {
                    ch.verts[n - 1 - k]
                } else {
                    ch.verts[k]
                });
            }
        }
        // The loop must close: each use's end is the next use's start.
        for (k, u) in face.uses.iter().enumerate() {
            let next = face.uses[(k + 1) % face.uses.len()];
            if net.use_end(*u) != net.use_start(next) {
                return Err(SurfaceError::UnsupportedFace {
                    face: fid.to_string(),
                    reason: format!("its loop is broken after edge {}", u.edge),
                });
            }
        }
        let mut sorted = poly.clone();
        sorted.sort_unstable();
        if sorted.windows(2).any(|w| w[0] == w[1]) {
            return Err(SurfaceError::UnsupportedFace {
                face: fid.to_string(),
                reason: "its loop visits a vertex twice".into(),
            });
        }
        if poly.len() < 3 {
            return Err(SurfaceError::UnsupportedFace {
                face: fid.to_string(),
                reason: format!("it has {} corners", poly.len()),
            });
        }
        b.faces.push(poly);
    }
    b.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn span_of_reverses() {
        let mut b = Builder::default();
        b.span(1, 2, 0, 0.5, 1.5);
        assert_eq!(
            b.span_of(2, 1),
            Some(CurveSpan {
                curve: 0,
                t0: 1.5,
                t1: 0.5
            })
        );
        assert_eq!(b.span_of(1, 3), None);
    }
}
