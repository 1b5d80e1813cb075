//! Border gluing (FIRES thesis §5.1.3 and §5.2.3): two boundary curves of one surface, or of two
//! surfaces, become one curve. As in the thesis the user draws the minimal information as curves: a first
//! curve from a point a₁ of border A to the point b₁ of border B that goes with it, and (where needed) a
//! second curve a₂ → b₂ that cuts the borders into halves. The drawn curves are markers only; they are not
//! inserted.
//!
//! * **Two different loops**: with one curve, the whole loops are glued with a₁ ≡ b₁; with two curves, the
//!   halves a₁ → a₂ and b₁ → b₂ are glued to each other and a₂ → a₁ to b₂ → b₁ (`GluePart::Whole`), or
//!   only the first (`FirstHalf`) or the second (`SecondHalf`) pair — the thesis's choice of which
//!   half-curves belong together; gluing one pair leaves the other two halves as one boundary loop.
//! * **One loop** (e.g. the two opposite sides of a strip): the two curves give the two paths between the
//!   a's and between the b's. Going round the loop in the closing direction the order must be a₁, a₂, b₂, b₁
//!   (or b₁, b₂, a₂, a₁); crossed curves would glue a Möbius band and are refused.
//!
//! A path on A is glued to the path on B in the direction that keeps the surface orientable: the face on A
//! and the face on B traverse the glued curve in opposite directions. Points correspond by normalised arc
//! length: each path is split where the other has a vertex (breakpoints closer than `vertex_snap_mm` are one),
//! then edge i of A's path and edge i of B's become one edge and their end vertices one vertex. Which
//! geometry survives is [`Survivor`]: A's half-curve, B's, or their average point by point (vertices too;
//! the curves ending at a moved vertex follow it).
//!
//! Bookkeeping, after the splits: gluing two closed loops of m edges gives ΔV = ΔE = −m, ΔF = 0, two
//! boundaries fewer: Δχ = 0, genus +1 on one surface (a cylinder becomes a torus; two holes on a disk give
//! genus 1). Gluing two open paths of m edges gives ΔV = −(m + 1), ΔE = −m: Δχ = −1 (a strip becomes a
//! cylinder: one boundary becomes two, genus 0).

use std::collections::HashMap;

use super::border::{border_end, border_loop, is_border};
use super::{widened_m, CurveInput, End, ToolError};
use crate::network::geom::{arc_lengths, dist, lerp, P3};
use crate::network::mesh::{EdgeUse, Network};
use crate::network::{Transaction, VertexId};

/// Which geometry the glued curve keeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Survivor {
    /// The half-curve of border A (where the first curve starts).
    #[default]
    First,
    /// The half-curve of border B (where the first curve ends).
    Second,
    /// The point-by-point average of the two.
    Average,
}

/// Which halves of two different loops are glued (with two curves).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GluePart {
    /// Both pairs of halves: the whole loops.
    #[default]
    Whole,
    /// Only a₁ → a₂ with b₁ → b₂.
    FirstHalf,
    /// Only a₂ → a₁ with b₂ → b₁.
    SecondHalf,
}

/// Options of [`glue_borders`] (millimetres).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct GlueOptions {
    /// The curves' ends must be this close to a boundary.
    pub snap_mm: f64,
    /// An end this close to a vertex of its boundary edge goes onto the vertex; breakpoints of the two
    /// paths this close (along the path) are one.
    pub vertex_snap_mm: f64,
    /// Distances are widened to this many times the strokes' σ when that is larger.
    pub sigma_factor: f64,
    /// Which geometry the glued curve keeps.
    pub survivor: Survivor,
    /// Which halves of two loops are glued.
    pub part: GluePart,
}

impl Default for GlueOptions {
    fn default() -> Self {
        GlueOptions {
            snap_mm: 8.0,
            vertex_snap_mm: 4.0,
            sigma_factor: 3.0,
            survivor: Survivor::First,
            part: GluePart::Whole,
        }
    }
}

/// What [`glue_borders`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct GlueReport {
    /// Edges of the glued curve (each made of one edge of A and one of B).
    pub glued_edges: usize,
    /// Vertices removed by identification.
    pub merged_vertices: usize,
    /// Both paths were on one boundary loop.
    pub same_loop: bool,
}

/// Glues border A to border B as marked by `first` (a₁ → b₁) and `second` (a₂ → b₂).
pub fn glue_borders(
    net: &mut Network,
    first: CurveInput<'_>,
    second: Option<CurveInput<'_>>,
    options: &GlueOptions,
) -> Result<(GlueReport, Transaction), ToolError> {
    let mut ends: Vec<P3> = Vec::new();
    let mut sigma: Option<f64> = None;
    for c in std::iter::once(first).chain(second) {
        let (Some(&a), Some(&b)) = (c.points.first(), c.points.last()) else {
            return Err(ToolError::BadCurve("a gluing curve has no points".into()));
        };
        if !c.points.iter().flatten().all(|x| x.is_finite()) {
            return Err(ToolError::BadCurve("a point is not finite".into()));
        }
        ends.extend([a, b]);
        sigma = match (sigma, c.sigma_mm) {
            (Some(x), Some(y)) => Some(x.max(y)),
            (x, y) => x.or(y),
        };
    }
    let r = widened_m(options.snap_mm, sigma, options.sigma_factor);
    let vsnap = widened_m(options.vertex_snap_mm, sigma, options.sigma_factor);
    for (k, p) in ends.iter().enumerate() {
        let end = if k % 2 == 0 { End::Start } else { End::End };
        border_end(net, *p, end, r)?;
    }
    net.transact(|net| {
        let mut vs = Vec::with_capacity(4);
        for (k, p) in ends.iter().enumerate() {
            let end = if k % 2 == 0 { End::Start } else { End::End };
            vs.push(anchor(net, *p, end, r, vsnap)?);
        }
        let (a1, b1) = (vs[0], vs[1]);
        let second = vs.get(2..4).map(|x| (x[0], x[1]));
        let loop_a = loop_at(net, a1)?;
        let same_loop = loop_vertices_of(net, &loop_a).contains(&b1);
        let (pairs, p_is_a) = if same_loop {
            let (a2, b2) = second.ok_or(ToolError::NeedsSecondCurve)?;
            same_loop_paths(net, &loop_a, a2, b1, b2)?
        } else {
            let loop_b = loop_at(net, b1)?;
            (
                two_loop_paths(net, &loop_a, &loop_b, second, options.part)?,
                true,
            )
        };
        let w = match (options.survivor, p_is_a) {
            (Survivor::Average, _) => 0.5,
            (Survivor::First, true) | (Survivor::Second, false) => 1.0,
            _ => 0.0,
        };
        let mut report = GlueReport {
            glued_edges: 0,
            merged_vertices: 0,
            same_loop,
        };
        for (p, q) in pairs {
            let (e, v) = glue_paths(net, p, q, w, vsnap)?;
            report.glued_edges += e;
            report.merged_vertices += v;
        }
        net.validate().map_err(|e| match e {
            crate::network::InvariantError::InconsistentOrientation(_) => ToolError::CrossedGluing,
            other => ToolError::BadCurve(format!("internal: gluing broke {other}")),
        })?;
        Ok(report)
    })
}

/// The vertex a curve end attaches to: an end vertex of the nearest boundary edge within `vsnap`, or a
/// new vertex splitting that edge.
pub(crate) fn anchor(
    net: &mut Network,
    p: P3,
    end: End,
    r: f64,
    vsnap: f64,
) -> Result<VertexId, ToolError> {
    let bp = border_end(net, p, end, r)?;
    let internal = || ToolError::BadCurve("internal: boundary edge vanished".into());
    let ed = net.edge(bp.edge).cloned().ok_or_else(internal)?;
    let d = |v: VertexId| {
        net.vertex(v)
            .map_or(f64::INFINITY, |x| dist(x.position, bp.point))
    };
    let (df, dt) = (d(ed.from), d(ed.to));
    if df <= vsnap && df <= dt {
        return Ok(ed.from);
    }
    if dt <= vsnap {
        return Ok(ed.to);
    }
    let (v, _) = net.split_edge(bp.edge, bp.seg, bp.t).ok_or_else(internal)?;
    Ok(v)
}

/// The boundary loop through `v` (closing direction), rotated to start at `v`.
pub(crate) fn loop_at(net: &Network, v: VertexId) -> Result<Vec<EdgeUse>, ToolError> {
    let e = net
        .vertex(v)
        .and_then(|x| x.edges.iter().copied().find(|&e| is_border(net, e)))
        .ok_or(ToolError::NotOnBoundary {
            end: End::Start,
            distance_mm: f64::INFINITY,
            limit_mm: 0.0,
        })?;
    let uses = border_loop(net, e)?;
    let k = uses
        .iter()
        .position(|u| net.use_start(*u) == Some(v))
        .ok_or(ToolError::PinchedBoundary { vertex: v })?;
    Ok(uses[k..].iter().chain(&uses[..k]).copied().collect())
}

fn loop_vertices_of(net: &Network, uses: &[EdgeUse]) -> Vec<VertexId> {
    super::border::loop_vertices(net, uses)
}

fn flip(u: EdgeUse) -> EdgeUse {
    EdgeUse {
        edge: u.edge,
        reversed: !u.reversed,
    }
}

/// A closing-direction run reversed into the face direction.
fn face_direction(run: &[EdgeUse]) -> Vec<EdgeUse> {
    run.iter().rev().map(|u| flip(*u)).collect()
}

type Pair = (Vec<EdgeUse>, Vec<EdgeUse>);

/// One loop (rotated to start at a₁): the path a₁ → a₂ (closing direction) with b₁ → b₂ (face direction), or the b path with the
/// a path when the loop runs the other way. Returns the pair and whether the first path is A's.
fn same_loop_paths(
    net: &Network,
    loop_a: &[EdgeUse],
    a2: VertexId,
    b1: VertexId,
    b2: VertexId,
) -> Result<(Vec<Pair>, bool), ToolError> {
    let verts = loop_vertices_of(net, loop_a);
    let n = verts.len();
    let pos = |v: VertexId| verts.iter().position(|&x| x == v);
    let (Some(pa2), Some(pb1), Some(pb2)) = (pos(a2), pos(b1), pos(b2)) else {
        return Err(ToolError::DifferentBoundaries {
            first: loop_a[0].edge,
            second: loop_a[0].edge,
        });
    };
    // Positions from a₁ (at 0); b₁ = a₁ counts as the end of the loop.
    let pb1_end = if pb1 == 0 { n } else { pb1 };
    if pa2 > 0 && pa2 <= pb2 && pb2 < pb1_end {
        let p = loop_a[..pa2].to_vec();
        let q = face_direction(&loop_a[pb2..pb1_end]);
        return Ok((vec![(p, q)], true));
    }
    // The loop runs b₁, b₂, a₂, a₁: rotate to b₁.
    let rot: Vec<EdgeUse> = loop_a[pb1..]
        .iter()
        .chain(&loop_a[..pb1])
        .copied()
        .collect();
    let r = |k: usize| (k + n - pb1) % n;
    let (qb2, qa2, qa1) = (r(pb2), r(pa2), if pb1 == 0 { n } else { r(0) });
    if qb2 > 0 && qb2 <= qa2 && qa2 < qa1 {
        let p = rot[..qb2].to_vec();
        let q = face_direction(&rot[qa2..qa1]);
        return Ok((vec![(p, q)], false));
    }
    if pa2 == 0 || pb1 == pb2 {
        return Err(ToolError::DegenerateGluing);
    }
    Err(ToolError::CrossedGluing)
}

/// Two loops: the whole loops (one curve) or their halves (two curves).
fn two_loop_paths(
    net: &Network,
    loop_a: &[EdgeUse],
    loop_b: &[EdgeUse],
    second: Option<(VertexId, VertexId)>,
    part: GluePart,
) -> Result<Vec<Pair>, ToolError> {
    // The face direction from b₁: the closing loop from b₁ reversed (it starts and ends at b₁).
    let qfull = face_direction(loop_b);
    let Some((a2, b2)) = second else {
        if part != GluePart::Whole {
            return Err(ToolError::NeedsSecondCurve);
        }
        return Ok(vec![(loop_a.to_vec(), qfull)]);
    };
    let va = loop_vertices_of(net, loop_a);
    let vb = loop_vertices_of(net, &qfull);
    let pa2 = va.iter().position(|&x| x == a2);
    let qb2 = vb.iter().position(|&x| x == b2);
    let (Some(pa2), Some(qb2)) = (pa2, qb2) else {
        return Err(ToolError::DifferentBoundaries {
            first: loop_a[0].edge,
            second: loop_b[0].edge,
        });
    };
    if pa2 == 0 || qb2 == 0 {
        return Err(ToolError::DegenerateGluing);
    }
    let first = (loop_a[..pa2].to_vec(), qfull[..qb2].to_vec());
    let second = (loop_a[pa2..].to_vec(), qfull[qb2..].to_vec());
    Ok(match part {
        GluePart::Whole => vec![first, second],
        GluePart::FirstHalf => vec![first],
        GluePart::SecondHalf => vec![second],
    })
}

/// A use's points in traversal order.
fn use_points(net: &Network, u: EdgeUse) -> Vec<P3> {
    let mut p = net
        .edge_polyline(u.edge)
        .map(|p| p.points.clone())
        .unwrap_or_default();
    if u.reversed {
        p.reverse();
    }
    p
}

fn use_length(net: &Network, u: EdgeUse) -> f64 {
    arc_lengths(&use_points(net, u))
        .last()
        .copied()
        .unwrap_or(0.0)
}

/// Splits use `u` at arc length `l` from its start; returns the two uses in traversal order.
fn split_use(net: &mut Network, u: EdgeUse, l: f64) -> Option<(EdgeUse, EdgeUse)> {
    let pts = use_points(net, u);
    let arc = arc_lengths(&pts);
    let n = pts.len();
    let k = arc.partition_point(|&s| s <= l).clamp(1, n - 1) - 1;
    let span = arc[k + 1] - arc[k];
    let t = if span > 0.0 {
        ((l - arc[k]) / span).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (seg, t) = if u.reversed {
        (n - 2 - k, 1.0 - t)
    } else {
        (k, t)
    };
    let (_, halves) = net.split_edge(u.edge, seg, t)?;
    let (e1, e2) = halves?;
    Some(if u.reversed {
        (
            EdgeUse {
                edge: e2,
                reversed: true,
            },
            EdgeUse {
                edge: e1,
                reversed: true,
            },
        )
    } else {
        (
            EdgeUse {
                edge: e1,
                reversed: false,
            },
            EdgeUse {
                edge: e2,
                reversed: false,
            },
        )
    })
}

/// Splits a path at the normalised arc lengths `targets` (sorted, inside (0, 1)).
fn split_path(
    net: &mut Network,
    path: Vec<EdgeUse>,
    targets: &[f64],
) -> Result<Vec<EdgeUse>, ToolError> {
    let total: f64 = path.iter().map(|u| use_length(net, *u)).sum();
    let mut out = Vec::with_capacity(path.len() + targets.len());
    let mut s0 = 0.0;
    let mut k = 0;
    for mut u in path {
        let len = use_length(net, u);
        let s1 = s0 + len;
        let mut done = s0;
        while k < targets.len() && targets[k] * total < s1 {
            let l = targets[k] * total - done;
            k += 1;
            if l <= 0.0 {
                continue;
            }
            let (a, b) = split_use(net, u, l)
                .ok_or_else(|| ToolError::BadCurve("internal: path split".into()))?;
            out.push(a);
            done += use_length(net, a);
            u = b;
        }
        out.push(u);
        s0 = s1;
    }
    Ok(out)
}

/// Normalised arc lengths of a path's inner vertices.
fn breakpoints(net: &Network, path: &[EdgeUse]) -> (Vec<f64>, f64) {
    let lens: Vec<f64> = path.iter().map(|u| use_length(net, *u)).collect();
    let total: f64 = lens.iter().sum();
    let mut s = 0.0;
    let mut out = Vec::new();
    for l in &lens[..lens.len().saturating_sub(1)] {
        s += l;
        out.push(s / total);
    }
    (out, total)
}

/// Evaluates a polyline with normalised arc lengths `arc` at `s` in [0, 1].
fn at(pts: &[P3], arc: &[f64], s: f64) -> P3 {
    let n = pts.len();
    let k = arc.partition_point(|&x| x <= s).clamp(1, n - 1) - 1;
    let span = arc[k + 1] - arc[k];
    let t = if span > 0.0 {
        ((s - arc[k]) / span).clamp(0.0, 1.0)
    } else {
        0.0
    };
    lerp(pts[k], pts[k + 1], t)
}

fn blend(a: P3, b: P3, w: f64) -> P3 {
    [
        w * a[0] + (1.0 - w) * b[0],
        w * a[1] + (1.0 - w) * b[1],
        w * a[2] + (1.0 - w) * b[2],
    ]
}

/// The glued curve of two uses (both from the same vertex pair's sides, in traversal order).
fn glued_points(p: &[P3], q: &[P3], w: f64) -> Vec<P3> {
    if w == 1.0 {
        return p.to_vec();
    }
    if w == 0.0 {
        return q.to_vec();
    }
    let norm = |pts: &[P3]| {
        let a = arc_lengths(pts);
        let t = a[a.len() - 1];
        a.into_iter()
            .map(|x| if t > 0.0 { x / t } else { 0.0 })
            .collect::<Vec<_>>()
    };
    let (ap, aq) = (norm(p), norm(q));
    let mut s: Vec<f64> = ap.iter().chain(&aq).copied().collect();
    s.sort_by(f64::total_cmp);
    s.dedup_by(|b, a| (*b - *a).abs() < 1e-12);
    let mut out: Vec<P3> = s
        .iter()
        .map(|&x| blend(at(p, &ap, x), at(q, &aq, x), w))
        .collect();
    out.dedup_by(|b, a| dist(*a, *b) <= crate::network::ops::SAME_POINT_M);
    if out.len() < 2 {
        out = vec![
            blend(p[0], q[0], w),
            blend(p[p.len() - 1], q[q.len() - 1], w),
        ];
    }
    out
}

/// Glues path `p` (closing direction of its loop) to path `q` (face direction of its loop), keeping
/// weight `w` of `p`'s geometry; returns (glued edges, merged vertices).
fn glue_paths(
    net: &mut Network,
    p: Vec<EdgeUse>,
    q: Vec<EdgeUse>,
    w: f64,
    vsnap: f64,
) -> Result<(usize, usize), ToolError> {
    if p.is_empty() || q.is_empty() {
        return Err(ToolError::DegenerateGluing);
    }
    let (bp, lp) = breakpoints(net, &p);
    let (bq, lq) = breakpoints(net, &q);
    if !(lp > 0.0 && lq > 0.0) {
        return Err(ToolError::DegenerateGluing);
    }
    // Merge the two breakpoint lists: a breakpoint of one path closer than `vsnap` (along the shorter
    // path) to one of the other is the same point; every other one splits the other path.
    let tol = vsnap / lp.min(lq);
    let mut tagged: Vec<(f64, bool)> = bp
        .iter()
        .map(|&s| (s, true))
        .chain(bq.iter().map(|&s| (s, false)))
        .collect();
    tagged.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (mut split_p, mut split_q) = (Vec::new(), Vec::new());
    let mut i = 0;
    while i < tagged.len() {
        if i + 1 < tagged.len()
            && tagged[i].1 != tagged[i + 1].1
            && tagged[i + 1].0 - tagged[i].0 <= tol
        {
            i += 2;
            continue;
        }
        let (s, of_p) = tagged[i];
        if of_p {
            split_q.push(s);
        } else {
            split_p.push(s);
        }
        i += 1;
    }
    let p = split_path(net, p, &split_p)?;
    let q = split_path(net, q, &split_q)?;
    if p.len() != q.len() {
        return Err(ToolError::BadCurve(
            "internal: glued paths differ in length".into(),
        ));
    }
    let internal = || ToolError::BadCurve("internal: gluing".into());
    let pv: Vec<VertexId> = std::iter::once(net.use_start(p[0]))
        .chain(p.iter().map(|u| net.use_end(*u)))
        .collect::<Option<_>>()
        .ok_or_else(internal)?;
    let qv: Vec<VertexId> = std::iter::once(net.use_start(q[0]))
        .chain(q.iter().map(|u| net.use_end(*u)))
        .collect::<Option<_>>()
        .ok_or_else(internal)?;
    let pos = |net: &Network, v: VertexId| net.vertex(v).map(|x| x.position);
    let targets: Vec<P3> = pv
        .iter()
        .zip(&qv)
        .map(|(&a, &b)| Some(blend(pos(net, a)?, pos(net, b)?, w)))
        .collect::<Option<_>>()
        .ok_or_else(internal)?;
    // One edge per pair: P's edge keeps its handle and gets the glued geometry; Q's face uses it.
    for (up, uq) in p.iter().zip(&q) {
        let gp = glued_points(&use_points(net, *up), &use_points(net, *uq), w);
        let mut pl = net.edge_polyline(up.edge).cloned().ok_or_else(internal)?;
        let ql = net.edge_polyline(uq.edge).cloned().ok_or_else(internal)?;
        if w < 0.5 {
            pl.attrs = ql.attrs;
        }
        pl.points = if up.reversed {
            gp.into_iter().rev().collect()
        } else {
            gp
        };
        let mut eq = net.edge(uq.edge).cloned().ok_or_else(internal)?;
        let [fb] = eq.faces[..] else {
            return Err(ToolError::NotABoundaryEdge { edge: uq.edge });
        };
        let mut face = net.face(fb).cloned().ok_or_else(internal)?;
        for u in face.uses.iter_mut().filter(|u| u.edge == uq.edge) {
            *u = EdgeUse {
                edge: up.edge,
                reversed: up.reversed,
            };
        }
        net.set_face(fb, Some(face));
        eq.faces.clear();
        net.set_edge(uq.edge, Some(eq));
        net.remove_edge(uq.edge);
        let mut ep = net.edge(up.edge).cloned().ok_or_else(internal)?;
        ep.faces.push(fb);
        let pid = ep.polyline;
        net.set_edge(up.edge, Some(ep));
        net.set_polyline(pid, Some(pl));
    }
    // Identify the vertices (Q's into P's) and move the survivors.
    let mut map: HashMap<VertexId, VertexId> = HashMap::new();
    let find = |map: &HashMap<VertexId, VertexId>, mut v: VertexId| {
        while let Some(&n) = map.get(&v) {
            v = n;
        }
        v
    };
    let mut merged = 0;
    for (&a, &b) in pv.iter().zip(&qv) {
        let (a, b) = (find(&map, a), find(&map, b));
        if a == b {
            continue;
        }
        let vb = net.vertex(b).cloned().ok_or_else(internal)?;
        let mut seen = Vec::new();
        for &e in &vb.edges {
            if seen.contains(&e) {
                continue;
            }
            seen.push(e);
            let mut ed = net.edge(e).cloned().ok_or_else(internal)?;
            if ed.from == b {
                ed.from = a;
            }
            if ed.to == b {
                ed.to = a;
            }
            net.set_edge(e, Some(ed));
        }
        let mut va = net.vertex(a).cloned().ok_or_else(internal)?;
        va.edges.extend(vb.edges.iter().copied());
        net.set_vertex(a, Some(va));
        net.set_vertex(b, None);
        map.insert(b, a);
        merged += 1;
    }
    for (&a, target) in pv.iter().zip(&targets) {
        let a = find(&map, a);
        let mut va = net.vertex(a).cloned().ok_or_else(internal)?;
        va.position = *target;
        let edges = va.edges.clone();
        net.set_vertex(a, Some(va));
        for e in edges {
            let ed = net.edge(e).cloned().ok_or_else(internal)?;
            let mut pl = net.polyline(ed.polyline).cloned().ok_or_else(internal)?;
            let n = pl.points.len();
            let mut changed = false;
            if ed.from == a && pl.points[0] != *target {
                pl.points[0] = *target;
                changed = true;
            }
            if ed.to == a && pl.points[n - 1] != *target {
                pl.points[n - 1] = *target;
                changed = true;
            }
            if changed {
                net.set_polyline(ed.polyline, Some(pl));
            }
        }
    }
    Ok((p.len(), merged))
}
