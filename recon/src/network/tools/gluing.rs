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

use super::border::{border_end, border_loop, is_border};
use super::glue_paths::glue_paths;
use super::{widened_m, CurveInput, End, ToolError};
use crate::network::geom::{dist, P3};
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
