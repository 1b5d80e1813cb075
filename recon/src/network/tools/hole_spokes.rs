//! Hole creation without crossings (FIRES thesis §5.2.2): a closed curve inside one n-sided face is
//! joined to the face's n vertices by n generated spokes.
//!
//! 1. **The face.** Candidate faces are those whose boundary box, grown by `max_distance_mm`, meets the
//!    hole's. Each gets the Coons patch of its Q' (`surface::face_patch`: the four smallest-angle
//!    vertices, pseudo-corners at side midpoints for faces of fewer than four sides). Those whose box
//!    holds the hole's arc-length centroid C̄ are tried first, ordered by the distance of C̄'s foot point
//!    (`surface::foot_point`: grid guess then hybrid Newton); then the others by the distance from C̄ to
//!    their box. The first whose patch holds every hole point's foot point strictly inside (0, 1)² and
//!    within `max_distance_mm` is the face.
//! 2. **The hole in the domain.** Each hole point's foot point (warm-started from the previous one, the
//!    grid guess where that ends on the domain's border) gives the hole as a polygon in (u, v); it is
//!    oriented counter-clockwise like the face loop, and (ū, v̄) must lie inside it.
//! 3. **Spokes.** The straight segment from (ū, v̄) to each face vertex's (u_k, v_k) meets the hole
//!    polygon; its crossing nearest the vertex splits the hole (the new vertex is put on the drawn curve,
//!    the hole's own points never move). The spoke is the patch sampled along the segment from
//!    (u_k, v_k) to that crossing, at the mean sample spacing of the face's polylines (at least
//!    `min_segments` segments); its ends are the face vertex and the hole vertex exactly. In the domain the
//!    spokes cannot cross each other or the face's border, so the new faces are simple loops.
//! 4. **Faces.** The crossings must follow the face's vertex order round the hole (else the hole is not
//!    convex enough: refused). Face k is old edge k (w_k → w_{k+1}), spoke k+1, hole arc k backwards,
//!    spoke k backwards. ΔV = n, ΔE = 2n, ΔF = n − 1.
//!
//! Spokes are `generated` polylines carrying the hole's stroke id; the hole arcs are `user` polylines of
//! the stroke.

use super::hole::{refuse, HoleKind, HoleOptions, HoleReport, HoleRule};
use super::ToolError;
use crate::geometry::Vec3;
use crate::network::geom::{bbox, boxes_overlap, dist, lerp, P3};
use crate::network::mesh::{EdgeUse, Network, Origin, PolylineAttrs, Vertex};
use crate::network::ops::SAME_POINT_M;
use crate::network::FaceId;
use crate::surface::{face_patch, FacePatch, FootPointOptions, FootPointSolver};

/// Margin inside the unit square a hole's foot point must keep.
const DOMAIN_MARGIN: f64 = 1e-9;

/// What the transaction applies.
pub(super) struct Plan {
    face: FaceId,
    hole_points: Vec<P3>,
    spokes: Vec<Vec<P3>>,
    arcs: Vec<Vec<P3>>,
    kind: HoleKind,
}

fn v3(p: P3) -> Vec3 {
    Vec3::from_array(p)
}

/// The sides of face `f`, each oriented along its use.
fn face_sides(net: &Network, f: FaceId) -> Option<Vec<Vec<Vec3>>> {
    let face = net.face(f)?;
    let mut out = Vec::with_capacity(face.uses.len());
    for u in &face.uses {
        let p = net.edge_polyline(u.edge)?;
        let mut pts: Vec<Vec3> = p.points.iter().map(|&q| v3(q)).collect();
        if u.reversed {
            pts.reverse();
        }
        out.push(pts);
    }
    Some(out)
}

/// Arc-length-weighted centroid of the closed loop `pts`.
fn centroid(pts: &[P3]) -> P3 {
    let (mut c, mut w) = ([0.0; 3], 0.0);
    for i in 0..pts.len() {
        let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
        let l = dist(a, b);
        for k in 0..3 {
            c[k] += l * (a[k] + b[k]) / 2.0;
        }
        w += l;
    }
    if w > 0.0 {
        [c[0] / w, c[1] / w, c[2] / w]
    } else {
        pts[0]
    }
}

/// Twice the signed area of the closed polygon `q`.
fn signed_area2(q: &[(f64, f64)]) -> f64 {
    (0..q.len())
        .map(|i| {
            let (a, b) = (q[i], q[(i + 1) % q.len()]);
            a.0 * b.1 - b.0 * a.1
        })
        .sum()
}

/// Whether `p` is inside the closed polygon `q` (non-zero winding number).
pub(super) fn inside(q: &[(f64, f64)], p: (f64, f64)) -> bool {
    let mut w = 0i32;
    for i in 0..q.len() {
        let (a, b) = (q[i], q[(i + 1) % q.len()]);
        let cross = (b.0 - a.0) * (p.1 - a.1) - (p.0 - a.0) * (b.1 - a.1);
        if a.1 <= p.1 {
            if b.1 > p.1 && cross > 0.0 {
                w += 1;
            }
        } else if b.1 <= p.1 && cross < 0.0 {
            w -= 1;
        }
    }
    w != 0
}

/// Parameters (s, t) where segments p0→p1 and q0→q1 cross, both in [0, 1].
fn cross2(p0: (f64, f64), p1: (f64, f64), q0: (f64, f64), q1: (f64, f64)) -> Option<(f64, f64)> {
    let d = (p1.0 - p0.0, p1.1 - p0.1);
    let e = (q1.0 - q0.0, q1.1 - q0.1);
    let den = d.0 * e.1 - d.1 * e.0;
    if den == 0.0 || !den.is_finite() {
        return None;
    }
    let r = (q0.0 - p0.0, q0.1 - p0.1);
    let s = (r.0 * e.1 - r.1 * e.0) / den;
    let t = (r.0 * d.1 - r.1 * d.0) / den;
    ((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t)).then_some((s, t))
}

struct Projected {
    uv: Vec<(f64, f64)>,
    max_distance: f64,
    iterations: usize,
}

/// Foot points of every hole point, or `None` when one leaves the domain or the distance limit.
fn project(solver: &FootPointSolver<'_>, pts: &[P3], limit: f64) -> Result<Projected, f64> {
    let mut uv = Vec::with_capacity(pts.len());
    let (mut max_distance, mut iterations) = (0.0f64, 0);
    let on_border = |u: f64, v: f64| {
        u <= DOMAIN_MARGIN
            || v <= DOMAIN_MARGIN
            || u >= 1.0 - DOMAIN_MARGIN
            || v >= 1.0 - DOMAIN_MARGIN
    };
    for &p in pts {
        let c = v3(p);
        let mut fp = match uv.last() {
            Some(&(u, v)) => solver.solve_from(c, u, v),
            None => solver.solve(c),
        };
        if on_border(fp.u, fp.v) || !fp.converged {
            let g = solver.solve(c);
            if g.distance < fp.distance || on_border(fp.u, fp.v) {
                fp = g;
            }
        }
        max_distance = max_distance.max(fp.distance);
        iterations = iterations.max(fp.iterations);
        if on_border(fp.u, fp.v) || fp.distance > limit || !fp.distance.is_finite() {
            return Err(fp.distance);
        }
        uv.push((fp.u, fp.v));
    }
    Ok(Projected {
        uv,
        max_distance,
        iterations,
    })
}

/// Finds the face and the spokes (read-only).
pub(super) fn plan(net: &Network, pts: &[P3], options: &HoleOptions) -> Result<Plan, ToolError> {
    let limit = options.max_distance_mm * 1e-3;
    let c = centroid(pts);
    let hole_box = bbox(pts);
    let foot = FootPointOptions {
        grid: options.newton_grid.max(2),
        max_iterations: options.newton_iterations.max(1),
        ..FootPointOptions::default()
    };
    // Candidate faces by the distance from C̄ to their boundary box (within the distance limit).
    let box_gap = |(lo, hi): (P3, P3)| {
        let d: f64 = (0..3)
            .map(|k| (lo[k] - c[k]).max(c[k] - hi[k]).max(0.0).powi(2))
            .sum();
        d.sqrt()
    };
    let mut by_box: Vec<(f64, FaceId)> = Vec::new();
    for (f, _) in net.faces() {
        let fp = net.face_points(f);
        if fp.is_empty() {
            continue;
        }
        let b = bbox(&fp);
        if boxes_overlap(hole_box, b, limit) {
            by_box.push((box_gap(b), f));
        }
    }
    by_box.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    // The faces whose box holds C̄ are tried first, nearest patch first; then the others by box distance.
    let holding = by_box.iter().take_while(|x| x.0 == 0.0).count();
    let patch_of = |f: FaceId| {
        face_sides(net, f).and_then(|sides| face_patch(&sides, options.tangent_fraction).ok())
    };
    let mut first: Vec<(f64, FaceId, FacePatch)> = by_box[..holding]
        .iter()
        .filter_map(|&(_, f)| {
            let p = patch_of(f)?;
            let d = FootPointSolver::new(&p.patch, &foot).solve(v3(c)).distance;
            Some((d, f, p))
        })
        .collect();
    first.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let rest = by_box[holding..]
        .iter()
        .filter_map(|&(d, f)| patch_of(f).map(|p| (d, f, p)));
    let mut nearest = f64::INFINITY;
    for (_, f, fpatch) in first.into_iter().chain(rest) {
        let solver = FootPointSolver::new(&fpatch.patch, &foot);
        let proj = match project(&solver, pts, limit) {
            Ok(p) => p,
            Err(d) => {
                nearest = nearest.min(d);
                continue;
            }
        };
        return spokes(net, f, &fpatch, &solver, pts, c, proj, options);
    }
    Err(refuse(
        HoleRule::InsideOneFace,
        format!(
            "no face's Coons patch holds every hole point within {:.1} mm (nearest miss {:.2} mm)",
            options.max_distance_mm,
            nearest * 1e3
        ),
        Some(nearest * 1e3),
    ))
}

#[allow(clippy::too_many_arguments)]
fn spokes(
    net: &Network,
    f: FaceId,
    fpatch: &FacePatch,
    solver: &FootPointSolver<'_>,
    pts: &[P3],
    c: P3,
    proj: Projected,
    options: &HoleOptions,
) -> Result<Plan, ToolError> {
    let internal = |what: &str| ToolError::BadCurve(format!("internal: {what}"));
    let n = fpatch.uv.len();
    if n < 2 {
        return Err(refuse(
            HoleRule::FaceSides,
            format!("face {f} has {n} side(s); a hole needs two spokes at least"),
            None,
        ));
    }
    let centre = solver.solve(v3(c));
    let cuv = (centre.u, centre.v);
    // The hole counter-clockwise in the domain, like the face loop.
    let (mut hole, mut q) = (pts.to_vec(), proj.uv);
    if signed_area2(&q) < 0.0 {
        hole.reverse();
        q.reverse();
    }
    if !inside(&q, cuv) {
        return Err(refuse(
            HoleRule::Convex,
            format!(
                "the hole's centroid (u, v) = ({:.3}, {:.3}) is outside the hole in face {f}'s patch domain",
                cuv.0, cuv.1
            ),
            None,
        ));
    }
    let m = hole.len();
    let mut arc = vec![0.0; m + 1];
    for i in 0..m {
        arc[i + 1] = arc[i] + dist(hole[i], hole[(i + 1) % m]);
    }
    let total = arc[m];
    // The crossing nearest each face vertex: (sigma along the hole, point, domain point).
    let mut meets: Vec<(f64, P3, (f64, f64))> = Vec::with_capacity(n);
    for (k, &w) in fpatch.uv.iter().enumerate() {
        let mut best: Option<(f64, usize, f64)> = None;
        for j in 0..m {
            if let Some((s, t)) = cross2(cuv, w, q[j], q[(j + 1) % m]) {
                if best.is_none_or(|b| s > b.0) {
                    best = Some((s, j, t));
                }
            }
        }
        let Some((s, j, t)) = best else {
            return Err(refuse(
                HoleRule::Convex,
                format!("the spoke to vertex {k} of face {f} does not meet the hole"),
                None,
            ));
        };
        let p = lerp(hole[j], hole[(j + 1) % m], t);
        let d = (cuv.0 + s * (w.0 - cuv.0), cuv.1 + s * (w.1 - cuv.1));
        meets.push((arc[j] + t * (arc[j + 1] - arc[j]), p, d));
    }
    // Round the hole in the face's order, at distinct points.
    let rel = |k: usize| (meets[k].0 - meets[0].0).rem_euclid(total);
    for k in 0..n {
        let next = (k + 1) % n;
        let ordered = next == 0 || rel(next) > rel(k);
        if !ordered || dist(meets[k].1, meets[next].1) <= SAME_POINT_M {
            return Err(refuse(
                HoleRule::Convex,
                format!(
                    "the spokes of face {f} meet the hole out of the face's vertex order (vertex {next})"
                ),
                None,
            ));
        }
    }
    // Spokes, from the face vertex to the hole.
    let face = net.face(f).ok_or_else(|| internal("face"))?;
    let (len, segs) = face.uses.iter().fold((0.0, 0usize), |(l, s), u| {
        net.edge_polyline(u.edge).map_or((l, s), |p| {
            let pl: f64 = p.points.windows(2).map(|w| dist(w[0], w[1])).sum();
            (l + pl, s + p.points.len() - 1)
        })
    });
    let spacing = (len / segs.max(1) as f64).max(f64::MIN_POSITIVE);
    let mut spokes = Vec::with_capacity(n);
    for (k, u) in face.uses.iter().enumerate() {
        let wv = net
            .use_start(*u)
            .and_then(|v| net.vertex(v))
            .ok_or_else(|| internal("vertex"))?
            .position;
        let (a, b) = (fpatch.uv[k], meets[k].2);
        let nseg = (dist(wv, meets[k].1) / spacing)
            .round()
            .max(options.min_segments.max(1) as f64)
            .min(1e4) as usize;
        let mut sp: Vec<P3> = (0..=nseg)
            .map(|i| {
                let w = i as f64 / nseg as f64;
                fpatch
                    .patch
                    .eval(a.0 + w * (b.0 - a.0), a.1 + w * (b.1 - a.1))
                    .to_array()
            })
            .collect();
        sp[0] = wv;
        sp[nseg] = meets[k].1;
        if sp.iter().any(|p| !p.iter().all(|x| x.is_finite())) {
            return Err(internal("a spoke is not finite"));
        }
        sp.dedup_by(|b, a| dist(*a, *b) <= SAME_POINT_M);
        if sp.len() < 2 {
            return Err(refuse(
                HoleRule::InsideOneFace,
                format!("vertex {k} of face {f} is on the hole"),
                Some(0.0),
            ));
        }
        spokes.push(sp);
    }
    // Hole arcs between consecutive crossings.
    let mut arcs = Vec::with_capacity(n);
    for k in 0..n {
        let (s0, p0) = (meets[k].0, meets[k].1);
        let (mut s1, p1) = (meets[(k + 1) % n].0, meets[(k + 1) % n].1);
        if s1 <= s0 {
            s1 += total;
        }
        let mut a = vec![p0];
        for i in 0..2 * m {
            let s = arc[i % m] + (i / m) as f64 * total;
            let p = hole[i % m];
            if s > s0 && s < s1 && dist(p, p0) > SAME_POINT_M && dist(p, p1) > SAME_POINT_M {
                a.push(p);
            }
        }
        a.push(p1);
        arcs.push(a);
    }
    Ok(Plan {
        face: f,
        hole_points: meets.iter().map(|m| m.1).collect(),
        spokes,
        arcs,
        kind: HoleKind::Spokes {
            face: f,
            sides: n,
            centroid_uv: cuv,
            max_distance_mm: proj.max_distance * 1e3,
            newton_iterations: proj.iterations.max(centre.iterations),
        },
    })
}

/// Applies `plan` (inside a transaction).
pub(super) fn apply(
    net: &mut Network,
    plan: &Plan,
    stroke: Option<u32>,
) -> Result<HoleReport, ToolError> {
    let internal = |what: &str| ToolError::BadCurve(format!("internal: {what}"));
    let uses = net
        .face(plan.face)
        .ok_or_else(|| internal("face"))?
        .uses
        .clone();
    let n = uses.len();
    let spoke_attrs = PolylineAttrs {
        origin: Origin::Generated,
        stroke,
        ..PolylineAttrs::default()
    };
    let arc_attrs = PolylineAttrs {
        origin: Origin::User,
        stroke,
        ..PolylineAttrs::default()
    };
    let hv: Vec<_> = plan
        .hole_points
        .iter()
        .map(|&p| {
            net.push_vertex(Vertex {
                position: p,
                edges: Vec::new(),
            })
        })
        .collect();
    let mut spokes = Vec::with_capacity(n);
    for (k, u) in uses.iter().enumerate() {
        let w = net.use_start(*u).ok_or_else(|| internal("vertex"))?;
        spokes.push(net.add_edge(w, hv[k], plan.spokes[k].clone(), spoke_attrs));
    }
    let hole_edges: Vec<_> = (0..n)
        .map(|k| net.add_edge(hv[k], hv[(k + 1) % n], plan.arcs[k].clone(), arc_attrs))
        .collect();
    net.remove_face(plan.face);
    let use_of = |edge, reversed| EdgeUse { edge, reversed };
    let faces = (0..n)
        .map(|k| {
            net.add_face(vec![
                uses[k],
                use_of(spokes[(k + 1) % n], false),
                use_of(hole_edges[k], true),
                use_of(spokes[k], true),
            ])
        })
        .collect();
    Ok(HoleReport {
        kind: plan.kind,
        hole_edges,
        spokes,
        faces,
        removed_faces: 1,
        removed_edges: 0,
        removed_vertices: 0,
    })
}
