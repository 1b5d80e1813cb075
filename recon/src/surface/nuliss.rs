//! The interpolatory quad subdivision of FIRESV1 with the NULISSmod rules (FIRES thesis §6.3).
//!
//! **Substitute scheme.** The thesis uses NULISS (Beccari, Casciola & Romani, non-uniform local
//! interpolatory subdivision), whose masks it does not give. In its place this module uses the
//! interpolatory scheme of L. Kobbelt, *Interpolatory subdivision on open quadrilateral nets with arbitrary
//! topology*, Computer Graphics Forum 15(3) (Eurographics 1996): a 1-to-4 split of every quad in which old
//! vertices keep their positions and each edge point is the four-point rule
//! `e = 9/16 (p1 + p2) − 1/16 (p0 + p3)` along the edge's mesh line. Where the line has no continuation
//! (p1 or p2 not a regular interior valence-4 vertex and the edge not a boundary edge continued by the
//! next boundary edge) the missing point is extrapolated linearly, `p0 = 2 p1 − p2`, Kobbelt's boundary
//! treatment, instead of his virtual-vertex construction at extraordinary vertices (a simplification:
//! the surface near extraordinary vertices is smooth in practice but not proven C1).
//!
//! **NULISSmod rules** (§6.3), applied on top:
//! * old vertices are kept (interpolation), with their tags;
//! * an edge point on a curve edge is replaced by the nearest point of the edge's curve span (kept inside
//!   the middle 80 % of the span so the children never collapse), tagged [`VertexTag::OnCurve`]; the two
//!   children of the edge get the two halves of its span, so at later levels the rule applies only to
//!   pieces of the original curves;
//! * a face point is the face's Coons patch, over its four sides through their edge points (curve spans,
//!   or the two-segment polyline `p, e, q` on an edge off the curves), evaluated at
//!   (½(t₀ + t₂), ½(t₁ + t₃)), t_k the chord-length parameter of the edge point on side k with opposite
//!   sides run in the same direction.
//!
//! Off the curves the Coons face point over `p, e, q` sides is `½ Σ e − ¼ Σ p` at the parameters' centre,
//! the bilinear tensor-product face rule, which replaces Kobbelt's face rule there.

use super::control::{ControlMesh, CurvePoint, VertexTag};
use super::coons::{chord_params, halfedge_span, span_points, CoonsPatch};
use super::error::SurfaceError;
use super::from_network::Builder;
use crate::geometry::Vec3;
use crate::mesh::Halfedge;

/// Options of [`nuliss_mod`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NulissOptions {
    /// Snap curve edge points to their curves (NULISSmod; default true). False gives the plain
    /// interpolatory scheme's edge points (face points still from the Coons patches).
    pub snap_to_curves: bool,
}

impl Default for NulissOptions {
    fn default() -> Self {
        NulissOptions {
            snap_to_curves: true,
        }
    }
}

/// The vertex continuing the mesh line of outgoing halfedge `h` backwards through its source, if any.
/// Creases (edges along sharp curves) act as boundaries: a line along a crease continues along the
/// crease's other edge, a line crossing one has no continuation (module doc, sharp rules).
fn continuation(cm: &ControlMesh, h: Halfedge) -> Option<Vec3> {
    let m = &cm.mesh;
    let v = m.from_vertex(h);
    let crease = |g: Halfedge| m.is_boundary_edge(g.edge()) || cm.is_sharp(g.edge());
    let creases = m.vertex_halfedges(v).filter(|&g| crease(g)).count();
    if creases > 0 {
        if creases != 2 || !crease(h) || (cm.tag(v) == VertexTag::Corner && cm.sharp_valence(v) > 0)
        {
            return None;
        }
        let other = m.vertex_halfedges(v).find(|&g| g != h && crease(g))?;
        return Some(m.position(m.to_vertex(other)));
    }
    if m.valence(v) != 4 {
        return None;
    }
    let g = m.cw_rotated_halfedge(m.cw_rotated_halfedge(h));
    Some(m.position(m.to_vertex(g)))
}

/// One subdivision step (module doc); the mesh must be all quads.
pub fn nuliss_mod(cm: &ControlMesh, opts: &NulissOptions) -> Result<ControlMesh, SurfaceError> {
    let m = &cm.mesh;
    if let Some(f) = m.faces().find(|&f| m.face_valence(f) != 4) {
        return Err(SurfaceError::BadControlMesh(format!(
            "the interpolatory step takes quads, face {f} has {} sides",
            m.face_valence(f)
        )));
    }
    let mut b = Builder::from_control_without_spans(cm);
    // Edge points: vertex index and, on curves, the curve parameter.
    let mut ep: Vec<usize> = vec![usize::MAX; m.edges_size()];
    let mut ep_t: Vec<f64> = vec![f64::NAN; m.edges_size()];
    for e in m.edges() {
        let h = e.halfedge(0);
        let (a, z) = (m.from_vertex(h), m.to_vertex(h));
        let (p1, p2) = (m.position(a), m.position(z));
        let p0 = continuation(cm, h).unwrap_or(p1 * 2.0 - p2);
        let p3 = continuation(cm, h.opposite()).unwrap_or(p2 * 2.0 - p1);
        let four = (p1 + p2) * (9.0 / 16.0) - (p0 + p3) * (1.0 / 16.0);
        let span = cm
            .span(e)
            .filter(|_| opts.snap_to_curves)
            .and_then(|s| cm.curves.get(s.curve).map(|c| (s, c)));
        ep[e.idx()] = match span {
            Some((s, c)) => {
                let (lo, hi) = (s.t0.min(s.t1), s.t0.max(s.t1));
                let pad = 0.1 * (hi - lo);
                let t = c.closest_in(four, s.t0, s.t1).clamp(lo + pad, hi - pad);
                let p = c.point_at(t);
                ep_t[e.idx()] = t;
                let v = b.vertex(p, VertexTag::OnCurve(CurvePoint { curve: s.curve, t }));
                b.span(a.idx(), v, s.curve, s.t0, t);
                b.span(v, z.idx(), s.curve, t, s.t1);
                v
            }
            None => b.vertex(four, VertexTag::Free),
        };
    }
    for f in m.faces() {
        let hs: Vec<Halfedge> = m.face_halfedges(f).collect();
        let mut sides: Vec<Vec<Vec3>> = Vec::with_capacity(4);
        let mut tk = [0.0; 4];
        for (k, &h) in hs.iter().enumerate() {
            let e = h.edge();
            let epos = b.points[ep[e.idx()]];
            let (pts, at) =
                match halfedge_span(cm, h).and_then(|s| cm.curves.get(s.curve).map(|c| (s, c))) {
                    Some((s, c)) if opts.snap_to_curves => {
                        let t = ep_t[e.idx()];
                        let mut pts = span_points(c, s.t0, t);
                        let at = pts.len() - 1;
                        pts.extend(span_points(c, t, s.t1).into_iter().skip(1));
                        let n = pts.len();
                        pts[0] = m.position(m.from_vertex(h));
                        pts[n - 1] = m.position(m.to_vertex(h));
                        pts[at] = epos;
                        (pts, at)
                    }
                    _ => (
                        vec![
                            m.position(m.from_vertex(h)),
                            epos,
                            m.position(m.to_vertex(h)),
                        ],
                        1,
                    ),
                };
            tk[k] = chord_params(&pts)[at];
            sides.push(pts);
        }
        let [s0, s1, s2, s3]: [Vec<Vec3>; 4] = sides
            .try_into()
            .map_err(|_| SurfaceError::BadControlMesh(format!("face {f}")))?;
        let patch = CoonsPatch::from_loop([s0, s1, s2, s3]);
        let u = 0.5 * (tk[0] + 1.0 - tk[2]);
        let v = 0.5 * (tk[1] + 1.0 - tk[3]);
        let fp = patch.eval(u, v);
        if !fp.is_finite() {
            return Err(SurfaceError::Degenerate(format!("face {f}'s Coons patch")));
        }
        let c = b.vertex(fp, VertexTag::Free);
        let e: Vec<usize> = hs.iter().map(|h| ep[h.edge().idx()]).collect();
        for k in 0..4 {
            let p = m.from_vertex(hs[k]).idx();
            b.faces.push(vec![p, e[k], c, e[(k + 3) % 4]]);
        }
    }
    b.finish()
}

/// `levels` steps of [`nuliss_mod`].
pub fn nuliss_mod_n(
    cm: &ControlMesh,
    levels: usize,
    opts: &NulissOptions,
) -> Result<ControlMesh, SurfaceError> {
    let mut cur = cm.clone();
    for _ in 0..levels {
        cur = nuliss_mod(&cur, opts)?;
    }
    Ok(cur)
}
