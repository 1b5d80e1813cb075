//! Gluing two boundary paths into one curve (the identification step of border gluing, see `gluing.rs`):
//! both paths are split where the other has a vertex (normalised arc length; breakpoints closer than the
//! vertex snapping distance are one), then edge i of one and edge i of the other become one edge with the
//! surviving geometry and their end vertices one vertex.

use std::collections::HashMap;

use super::ToolError;
use crate::network::geom::{arc_lengths, dist, lerp, P3};
use crate::network::mesh::{EdgeUse, Network};
use crate::network::VertexId;

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
pub(crate) fn glue_paths(
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
