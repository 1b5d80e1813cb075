//! Hole creation with crossings (FIRES thesis §5.2.2, Fig. 5.3c–d): the closed hole curve splits the
//! faces it runs through as curve insertion with multiple crossings does, then the faces inside it are
//! removed.
//!
//! **Insertion.** The meeting points are curve insertion's (`crossings.rs`: the closest pair per
//! approach within the intersection threshold, the new vertex on the old polyline), snapped onto an end
//! vertex of their edge within `vertex_snap_mm`. The loop is split at them into pieces, each splitting one
//! face. Rule 1 does not apply: a hole crosses a curve twice, and the piece between the two crossings
//! bounds a two-sided face with the curve's piece between them; that face is inside and is removed.
//! The face a piece splits must hold both its ends and, projected onto the face's Newell plane, the piece's
//! middle point (so a piece outside the surface is refused by rule 2); of several, the one whose boundary
//! centroid is nearest that point.
//!
//! **Inside** (the thesis leaves it open): the hole curve's edges split the faces next to it into two
//! sides: the faces traversing a hole edge forward and those traversing one backwards. Each side is grown
//! across every edge that is not a hole edge. The two regions must be disjoint (else the curve does not
//! separate the surface: refused). The inside is the region that does not reach the network's border
//! (an edge with one face) when exactly one of them does; otherwise (both or neither reach it: a closed
//! surface, or a hole round an earlier hole) the region of smaller area (the sum of the faces' Newell
//! vector areas).
//!
//! Then the inside faces are removed, every edge left with no face is removed with its polyline, and
//! every vertex left with no edge; a vertex left with a single edge is refused (the network is restored),
//! and so is a hole whose border shares a vertex with another border (its loop snapped onto a border
//! vertex: two border loops through one vertex are not a surface).

use std::collections::BTreeSet;

use super::crossings::Hit;
use super::hole::{refuse, HoleKind, HoleReport, HoleRule};
use super::hole_spokes::inside as in_polygon;
use super::ToolError;
use crate::network::geom::{dist, dot, lerp, sub, P3};
use crate::network::mesh::{Network, Origin, PolylineAttrs};
use crate::network::ops::SAME_POINT_M;
use crate::network::{EdgeId, FaceId, VertexId};

#[derive(Clone, Copy, Debug, PartialEq)]
enum Anchor {
    Vertex(VertexId),
    Edge { edge: EdgeId, seg: usize, t: f64 },
}

fn newell(p: &[P3]) -> P3 {
    let n = p.len();
    let mut a = [0.0; 3];
    for i in 0..n {
        let (x, y) = (p[i], p[(i + 1) % n]);
        a[0] += x[1] * y[2] - x[2] * y[1];
        a[1] += x[2] * y[0] - x[0] * y[2];
        a[2] += x[0] * y[1] - x[1] * y[0];
    }
    a
}

/// Whether `q` projected onto the Newell plane of the loop `p` is inside it.
fn face_holds(p: &[P3], q: P3) -> bool {
    let n = newell(p);
    let len = dot(n, n).sqrt();
    if p.len() < 3 || len.is_nan() || len <= 0.0 {
        return false;
    }
    let n = [n[0] / len, n[1] / len, n[2] / len];
    let a = if n[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let e1 = sub(a, [n[0] * dot(a, n), n[1] * dot(a, n), n[2] * dot(a, n)]);
    let l1 = dot(e1, e1).sqrt();
    let e1 = [e1[0] / l1, e1[1] / l1, e1[2] / l1];
    let e2 = [
        n[1] * e1[2] - n[2] * e1[1],
        n[2] * e1[0] - n[0] * e1[2],
        n[0] * e1[1] - n[1] * e1[0],
    ];
    let proj = |x: P3| (dot(x, e1), dot(x, e2));
    let poly: Vec<(f64, f64)> = p.iter().map(|&x| proj(x)).collect();
    in_polygon(&poly, proj(q))
}

/// Inserts the closed loop `pts` (last point = first, off the network) at its meeting points `hits`
/// (inside a transaction); returns the loop's edges and vertices in order.
pub(super) fn insert_loop(
    net: &mut Network,
    pts: &[P3],
    hits: &[Hit],
    vertex_snap: f64,
    thr: f64,
    stroke: Option<u32>,
) -> Result<(Vec<EdgeId>, Vec<VertexId>), ToolError> {
    let internal = |what: &str| ToolError::BadCurve(format!("internal: {what}"));
    let anchors: Vec<Anchor> = hits
        .iter()
        .map(|h| {
            let pos = |v| {
                net.vertex(v)
                    .map_or(f64::INFINITY, |x| dist(x.position, h.point))
            };
            match net.edge(h.edge) {
                Some(ed) if pos(ed.from) <= vertex_snap && pos(ed.from) <= pos(ed.to) => {
                    Anchor::Vertex(ed.from)
                }
                Some(ed) if pos(ed.to) <= vertex_snap => Anchor::Vertex(ed.to),
                _ => Anchor::Edge {
                    edge: h.edge,
                    seg: h.seg,
                    t: h.t,
                },
            }
        })
        .collect();
    // Split each edge at its meeting points, last parameter first, so the first half keeps the
    // parameterisation of the remaining cuts (a cut on the same segment as the previous one is rescaled
    // to the shortened segment).
    let mut vs: Vec<Option<VertexId>> = anchors
        .iter()
        .map(|a| match a {
            Anchor::Vertex(v) => Some(*v),
            Anchor::Edge { .. } => None,
        })
        .collect();
    let mut cuts: Vec<(EdgeId, usize, f64, usize)> = anchors
        .iter()
        .enumerate()
        .filter_map(|(k, a)| match *a {
            Anchor::Edge { edge, seg, t } => Some((edge, seg, t, k)),
            Anchor::Vertex(_) => None,
        })
        .collect();
    cuts.sort_by(|a, b| a.0.cmp(&b.0).then(b.1.cmp(&a.1)).then(b.2.total_cmp(&a.2)));
    let mut prev: Option<(EdgeId, EdgeId, usize, f64, VertexId)> = None;
    for (edge, seg, t, k) in cuts {
        let (target, t) = match prev {
            Some((orig, _, ps, pt, pv)) if orig == edge && ps == seg && pt == t => {
                vs[k] = Some(pv);
                continue;
            }
            Some((orig, half, ps, pt, _)) if orig == edge && ps == seg => {
                (half, if pt > 0.0 { t / pt } else { 0.0 })
            }
            Some((orig, half, ..)) if orig == edge => (half, t),
            _ => (edge, t),
        };
        let (v, halves) = net
            .split_edge(target, seg, t)
            .ok_or_else(|| internal("split edge"))?;
        vs[k] = Some(v);
        let orig_t = match prev {
            Some((orig, _, ps, pt, _)) if orig == edge && ps == seg => t * pt,
            _ => t,
        };
        prev = Some((edge, halves.map_or(target, |h| h.0), seg, orig_t, v));
    }
    // The loop's vertices in order, one per run of equal ones.
    let mut path: Vec<(VertexId, f64)> = Vec::with_capacity(hits.len());
    for (k, h) in hits.iter().enumerate() {
        let v = vs[k].ok_or_else(|| internal("unresolved meeting point"))?;
        if path.last().is_none_or(|l| l.0 != v) {
            path.push((v, h.sigma));
        }
    }
    if path.len() > 1 && path[0].0 == path[path.len() - 1].0 {
        path.pop();
    }
    if path.len() < 2 {
        return Err(refuse(
            HoleRule::Separates,
            "the closed curve meets the network at one point only".into(),
            None,
        ));
    }
    let body = &pts[..pts.len() - 1];
    let m = body.len();
    let mut arc = vec![0.0; m + 1];
    for i in 0..m {
        arc[i + 1] = arc[i] + dist(body[i], body[(i + 1) % m]);
    }
    let total = arc[m];
    let attrs = PolylineAttrs {
        stroke,
        origin: Origin::User,
        ..PolylineAttrs::default()
    };
    let mut edges = Vec::with_capacity(path.len());
    for k in 0..path.len() {
        let (a, sa) = path[k];
        let (b, mut sb) = path[(k + 1) % path.len()];
        if sb <= sa {
            sb += total;
        }
        let pa = net.vertex(a).ok_or_else(|| internal("vertex"))?.position;
        let pb = net.vertex(b).ok_or_else(|| internal("vertex"))?.position;
        let mut points = vec![pa];
        for i in 0..2 * m {
            let s = arc[i % m] + (i / m) as f64 * total;
            let p = body[i % m];
            if s > sa && s < sb && dist(p, pa) > SAME_POINT_M && dist(p, pb) > SAME_POINT_M {
                points.push(p);
            }
        }
        points.push(pb);
        let mid = if points.len() > 2 {
            points[points.len() / 2]
        } else {
            lerp(pa, pb, 0.5)
        };
        let fa = net.vertex_faces(a);
        let fb = net.vertex_faces(b);
        let mut best: Option<(f64, FaceId)> = None;
        for f in fa.into_iter().filter(|f| fb.contains(f)) {
            if net.face_cut(f, a, b).is_none() {
                continue;
            }
            let fp = net.face_points(f);
            if !face_holds(&fp, mid) {
                continue;
            }
            let c = fp
                .iter()
                .fold([0.0; 3], |s, p| [s[0] + p[0], s[1] + p[1], s[2] + p[2]]);
            let n = fp.len().max(1) as f64;
            let d = dist([c[0] / n, c[1] / n, c[2] / n], mid);
            if best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, f));
            }
        }
        let Some((_, f)) = best else {
            return Err(ToolError::NoCommonFace {
                piece: k,
                threshold_mm: thr * 1e3,
            });
        };
        let cut = net.face_cut(f, a, b).ok_or_else(|| internal("cut"))?;
        let (e, _, _) = net
            .split_face(f, &cut, points, attrs)
            .ok_or_else(|| internal("split face"))?;
        edges.push(e);
    }
    Ok((edges, path.iter().map(|p| p.0).collect()))
}

/// The faces reachable from `seeds` without crossing an edge of `wall`.
fn region(net: &Network, seeds: &[FaceId], wall: &BTreeSet<EdgeId>) -> BTreeSet<FaceId> {
    let mut out: BTreeSet<FaceId> = seeds.iter().copied().collect();
    let mut stack: Vec<FaceId> = seeds.to_vec();
    while let Some(f) = stack.pop() {
        let Some(face) = net.face(f) else { continue };
        for u in &face.uses {
            if wall.contains(&u.edge) {
                continue;
            }
            if let Some(ed) = net.edge(u.edge) {
                for &g in &ed.faces {
                    if out.insert(g) {
                        stack.push(g);
                    }
                }
            }
        }
    }
    out
}

/// Half the norm of the Newell vector of face `f`'s loop (its area when planar).
fn face_area(net: &Network, f: FaceId) -> f64 {
    let a = newell(&net.face_points(f));
    0.5 * dot(a, a).sqrt()
}

/// Removes the faces inside the inserted hole loop with edges `hole` and `crossings` vertices (inside a
/// transaction).
pub(super) fn remove_inside(
    net: &mut Network,
    hole: &[EdgeId],
    crossings: &[VertexId],
) -> Result<HoleReport, ToolError> {
    let wall: BTreeSet<EdgeId> = hole.iter().copied().collect();
    let (mut fwd, mut rev) = (Vec::new(), Vec::new());
    for &e in hole {
        let Some(ed) = net.edge(e) else { continue };
        for &f in &ed.faces {
            let Some(face) = net.face(f) else { continue };
            for u in face.uses.iter().filter(|u| u.edge == e) {
                if u.reversed {
                    rev.push(f);
                } else {
                    fwd.push(f);
                }
            }
        }
    }
    let (a, b) = (region(net, &fwd, &wall), region(net, &rev, &wall));
    if a.is_empty() || b.is_empty() || a.intersection(&b).next().is_some() {
        return Err(refuse(
            HoleRule::Separates,
            "the closed curve does not cut the surface into an inside and an outside".into(),
            None,
        ));
    }
    let on_border = |r: &BTreeSet<FaceId>| {
        r.iter().any(|&f| {
            net.face(f).is_some_and(|face| {
                face.uses
                    .iter()
                    .any(|u| net.edge(u.edge).is_some_and(|e| e.faces.len() == 1))
            })
        })
    };
    let area = |r: &BTreeSet<FaceId>| r.iter().map(|&f| face_area(net, f)).sum::<f64>();
    let inside_is_a = match (on_border(&a), on_border(&b)) {
        (false, true) => true,
        (true, false) => false,
        _ => area(&a) <= area(&b),
    };
    let (inside, outside) = if inside_is_a { (a, b) } else { (b, a) };
    let mut edges: BTreeSet<EdgeId> = BTreeSet::new();
    for &f in &inside {
        if let Some(face) = net.face(f) {
            edges.extend(face.uses.iter().map(|u| u.edge));
        }
        net.remove_face(f);
    }
    let mut verts: BTreeSet<VertexId> = BTreeSet::new();
    let mut removed_edges = 0;
    for &e in &edges {
        if let Some(ed) = net.edge(e).cloned() {
            if ed.faces.is_empty() {
                verts.extend([ed.from, ed.to]);
                net.remove_edge(e);
                removed_edges += 1;
            }
        }
    }
    let mut removed_vertices = 0;
    for &v in &verts {
        let Some(vx) = net.vertex(v) else { continue };
        match vx.edges.len() {
            0 => {
                net.set_vertex(v, None);
                removed_vertices += 1;
            }
            1 => {
                return Err(refuse(
                    HoleRule::NoDangling,
                    format!(
                        "removing the inside would leave vertex {v} with the single edge {}",
                        vx.edges[0]
                    ),
                    None,
                ))
            }
            _ => {}
        }
    }
    // The hole's border must not touch another border (its vertex snapped onto a border vertex).
    for &v in crossings {
        let border = net.vertex(v).map_or(0, |vx| {
            vx.edges
                .iter()
                .filter(|&&e| net.edge(e).is_some_and(|ed| ed.faces.len() == 1))
                .count()
        });
        if border > 2 {
            return Err(refuse(
                HoleRule::ClearOfBorder,
                format!("the hole's border meets another border at vertex {v}"),
                None,
            ));
        }
    }
    let faces: Vec<FaceId> = outside
        .iter()
        .copied()
        .filter(|&f| {
            net.face(f)
                .is_some_and(|face| face.uses.iter().any(|u| wall.contains(&u.edge)))
        })
        .collect();
    Ok(HoleReport {
        kind: HoleKind::Cut {
            crossings: crossings.len(),
        },
        hole_edges: hole.to_vec(),
        spokes: Vec::new(),
        faces,
        removed_faces: inside.len(),
        removed_edges,
        removed_vertices,
    })
}
