//! The skinning tool (FIRES thesis §5.1.4 and §5.2.4): n ≥ 2 closed profile curves and two spine curves
//! that cross the same sequence of profiles become a tube, one section of two faces between each pair of
//! consecutive profiles, as a new component of the network.
//!
//! * **Crossings.** Each spine meets each profile where the two come closest (within `intersect_mm`); the
//!   vertex goes at the point on the profile. A spine must meet the profiles in their order along it (a
//!   spine drawn from the last profile to the first is reversed); what lies before the first profile and
//!   after the last is dropped.
//! * **Halves.** The spines cut profile i at s₁ᵢ and s₂ᵢ into two halves, two edges. Consecutive profiles
//!   are paired half to half by [`pair_halves`](super::pair_halves) (the thesis's largest dot product of the
//!   half directions d = (p_start + p_end)/2 − p_middle, valid while consecutive profile planes meet at a
//!   dihedral angle below 90°); the pairing is carried along the chain so every profile knows which of its
//!   halves lies on side 0. The report gives each section's margin (best straight minus best crossed dot
//!   product, or the reverse): a margin near 0 means the assumption is failing there.
//! * **Faces.** Section (i, j) gets face a = side-0 half of i, spine-2 piece, side-0 half of j backwards,
//!   spine-1 piece backwards, and face b = the same on side 1 (spine pieces traversed opposite to a), so the
//!   tube is consistently oriented.
//! * **Caps** (optional; the thesis leaves end caps open): a face on each end profile.
//!
//! Bookkeeping for n profiles: ΔV = 2n, ΔE = 2n + 2(n − 1), ΔF = 2(n − 1): χ = 0, two boundaries, genus 0
//! (with caps ΔF = 2n: χ = 2, no boundary).

use super::border::border_loop;
use super::{half_direction, widened_m, CurveInput, ToolError};
use crate::network::geom::{
    arc_lengths, bbox, boxes_overlap, dist, dot, lerp, segment_segment, P3,
};
use crate::network::mesh::{EdgeUse, Network, PolylineAttrs, Vertex};
use crate::network::ops::SAME_POINT_M;
use crate::network::{EdgeId, FaceId, Transaction, VertexId};

/// Options of [`skin_profiles`] (millimetres).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct SkinOptions {
    /// A spine crosses a profile where they come closer than this.
    pub intersect_mm: f64,
    /// A profile's ends must be this close.
    pub close_mm: f64,
    /// The two spines must cross a profile at least this far apart.
    pub vertex_snap_mm: f64,
    /// Distances are widened to this many times the strokes' σ when that is larger.
    pub sigma_factor: f64,
    /// Close both end profiles with a face each.
    pub caps: bool,
}

impl Default for SkinOptions {
    fn default() -> Self {
        SkinOptions {
            intersect_mm: 5.0,
            close_mm: 10.0,
            vertex_snap_mm: 4.0,
            sigma_factor: 3.0,
            caps: false,
        }
    }
}

/// What [`skin_profiles`] made.
#[derive(Clone, Debug, PartialEq)]
pub struct SkinReport {
    /// Per profile, the vertices where spine 1 and spine 2 cross it.
    pub vertices: Vec<[VertexId; 2]>,
    /// Per profile, its two half edges `[s₁ → s₂, s₂ → s₁]` in drawing order.
    pub halves: Vec<[EdgeId; 2]>,
    /// Per profile, whether its second half (`halves[i][1]`) lies on side 0.
    pub swapped: Vec<bool>,
    /// Per section, its two faces (side 0, side 1).
    pub faces: Vec<[FaceId; 2]>,
    /// Per section, the pairing margin (winning minus losing dot product, ≥ 0).
    pub margins: Vec<f64>,
    /// The cap faces, when asked for.
    pub caps: Vec<FaceId>,
}

/// Where a spine crosses a profile.
#[derive(Clone, Copy, Debug)]
struct Crossing {
    /// Arc length along the spine.
    sigma: f64,
    /// Arc length along the profile (from its first point, in drawing order).
    tau: f64,
    /// The point on the profile.
    point: P3,
}

/// The closest approach of `spine` to the closed polyline `profile` (last point = first), looking only at
/// spine segments whose box comes within `margin` of the profile's box (all of them when that finds none
/// closer than `margin`, so a refusal reports the true distance).
fn crossing(
    spine: &[P3],
    sarc: &[f64],
    profile: &[P3],
    parc: &[f64],
    margin: f64,
) -> (Crossing, f64) {
    let pbox = bbox(profile);
    let near = crossing_in(spine, sarc, profile, parc, |i| {
        boxes_overlap(pbox, bbox(&spine[i..=i + 1]), margin)
    });
    if near.1 <= margin {
        return near;
    }
    crossing_in(spine, sarc, profile, parc, |_| true)
}

fn crossing_in(
    spine: &[P3],
    sarc: &[f64],
    profile: &[P3],
    parc: &[f64],
    keep: impl Fn(usize) -> bool,
) -> (Crossing, f64) {
    let mut best = (
        Crossing {
            sigma: 0.0,
            tau: 0.0,
            point: profile[0],
        },
        f64::INFINITY,
    );
    for i in (0..spine.len() - 1).filter(|&i| keep(i)) {
        for j in 0..profile.len() - 1 {
            let (s, t, d) = segment_segment(spine[i], spine[i + 1], profile[j], profile[j + 1]);
            if d < best.1 {
                best = (
                    Crossing {
                        sigma: sarc[i] + s * (sarc[i + 1] - sarc[i]),
                        tau: parc[j] + t * (parc[j + 1] - parc[j]),
                        point: lerp(profile[j], profile[j + 1], t),
                    },
                    d,
                );
            }
        }
    }
    best
}

/// The part of the closed polyline `loop_pts` (with arc lengths `arc`, total `len`) from arc length `a`
/// to `b` in drawing order (wrapping), with exact end points `pa`, `pb`.
fn piece(loop_pts: &[P3], arc: &[f64], a: f64, b: f64, pa: P3, pb: P3) -> Vec<P3> {
    let len = arc[arc.len() - 1];
    let b = if b <= a { b + len } else { b };
    let mut out = vec![pa];
    for lap in 0..2 {
        for (k, p) in loop_pts.iter().enumerate().take(loop_pts.len() - 1) {
            let s = arc[k] + lap as f64 * len;
            if s > a && s < b && dist(*p, pa) > SAME_POINT_M && dist(*p, pb) > SAME_POINT_M {
                out.push(*p);
            }
        }
    }
    out.push(pb);
    out
}

/// Builds the skin of `profiles` along `spines` (see the module docs).
pub fn skin_profiles(
    net: &mut Network,
    profiles: &[CurveInput<'_>],
    spines: [CurveInput<'_>; 2],
    options: &SkinOptions,
) -> Result<(SkinReport, Transaction), ToolError> {
    if profiles.len() < 2 {
        return Err(ToolError::BadCurve(
            "skinning needs at least 2 profiles".into(),
        ));
    }
    let sigma = profiles
        .iter()
        .chain(&spines)
        .filter_map(|c| c.sigma_mm)
        .fold(None, |m: Option<f64>, s| Some(m.map_or(s, |m| m.max(s))));
    let thr = widened_m(options.intersect_mm, sigma, options.sigma_factor);
    let apart = widened_m(options.vertex_snap_mm, sigma, options.sigma_factor);
    let mut loops: Vec<Vec<P3>> = Vec::with_capacity(profiles.len());
    for c in profiles {
        let mut pts = super::distinct_points(c.points)?;
        if pts.len() < 3 {
            return Err(ToolError::BadCurve(
                "a profile needs at least 3 distinct points".into(),
            ));
        }
        let gap = dist(pts[0], pts[pts.len() - 1]);
        if gap > options.close_mm * 1e-3 {
            return Err(ToolError::NotClosed {
                gap_mm: gap * 1e3,
                limit_mm: options.close_mm,
            });
        }
        if gap > SAME_POINT_M {
            pts.push(pts[0]);
        } else {
            let n = pts.len();
            pts[n - 1] = pts[0];
        }
        loops.push(pts);
    }
    let arcs: Vec<Vec<f64>> = loops.iter().map(|l| arc_lengths(l)).collect();
    let mut spine_pts: Vec<Vec<P3>> = Vec::with_capacity(2);
    let mut cross: Vec<Vec<Crossing>> = Vec::with_capacity(2);
    for (s, c) in spines.iter().enumerate() {
        let mut pts = super::distinct_points(c.points)?;
        if pts.len() < 2 {
            return Err(ToolError::BadCurve(
                "a spine needs at least 2 distinct points".into(),
            ));
        }
        let mut list = Vec::new();
        for reversed in [false, true] {
            if reversed {
                pts.reverse();
            }
            let sarc = arc_lengths(&pts);
            list.clear();
            for (i, (l, a)) in loops.iter().zip(&arcs).enumerate() {
                let (x, d) = crossing(&pts, &sarc, l, a, thr);
                if d > thr {
                    return Err(ToolError::SpineMissesProfile {
                        spine: s,
                        profile: i,
                        distance_mm: d * 1e3,
                        limit_mm: thr * 1e3,
                    });
                }
                list.push(x);
            }
            if list.windows(2).all(|w| w[0].sigma < w[1].sigma) {
                break;
            }
            if reversed {
                return Err(ToolError::SpineOrder { spine: s });
            }
        }
        spine_pts.push(pts);
        cross.push(list);
    }
    // The two halves of each profile, in drawing order: s₁ → s₂ and s₂ → s₁.
    let mut halves: Vec<[Vec<P3>; 2]> = Vec::with_capacity(loops.len());
    for (i, (l, a)) in loops.iter().zip(&arcs).enumerate() {
        let (c1, c2) = (cross[0][i], cross[1][i]);
        if dist(c1.point, c2.point) <= apart {
            return Err(ToolError::SpinesMeet {
                profile: i,
                distance_mm: dist(c1.point, c2.point) * 1e3,
            });
        }
        halves.push([
            piece(l, a, c1.tau, c2.tau, c1.point, c2.point),
            piece(l, a, c2.tau, c1.tau, c2.point, c1.point),
        ]);
    }
    // Pair consecutive profiles and carry the pairing along the chain.
    let mut swapped = vec![false; loops.len()];
    let mut margins = Vec::with_capacity(loops.len() - 1);
    for i in 0..loops.len() - 1 {
        let d = |h: &[P3]| half_direction(h);
        let (a0, a1) = (d(&halves[i][0])?, d(&halves[i][1])?);
        let (b0, b1) = (d(&halves[i + 1][0])?, d(&halves[i + 1][1])?);
        let straight = dot(a0, b0).max(dot(a1, b1));
        let crossed = dot(a0, b1).max(dot(a1, b0));
        swapped[i + 1] = swapped[i] != (straight < crossed);
        margins.push((straight - crossed).abs());
    }
    let spine_piece = |s: usize, i: usize| -> Vec<P3> {
        let sarc = arc_lengths(&spine_pts[s]);
        let (a, b) = (cross[s][i], cross[s][i + 1]);
        let mut out = vec![a.point];
        for (k, p) in spine_pts[s].iter().enumerate() {
            if sarc[k] > a.sigma
                && sarc[k] < b.sigma
                && dist(*p, a.point) > SAME_POINT_M
                && dist(*p, b.point) > SAME_POINT_M
            {
                out.push(*p);
            }
        }
        out.push(b.point);
        out
    };
    let attrs = |c: &CurveInput<'_>| PolylineAttrs {
        stroke: c.stroke,
        ..PolylineAttrs::default()
    };
    net.transact(|net| {
        let mut report = SkinReport {
            vertices: Vec::new(),
            halves: Vec::new(),
            swapped: swapped.clone(),
            faces: Vec::new(),
            margins: margins.clone(),
            caps: Vec::new(),
        };
        for (i, h) in halves.iter().enumerate() {
            let mut v = |p: P3| {
                net.push_vertex(Vertex {
                    position: p,
                    edges: Vec::new(),
                })
            };
            let (v1, v2) = (v(cross[0][i].point), v(cross[1][i].point));
            let e0 = net.add_edge(v1, v2, h[0].clone(), attrs(&profiles[i]));
            let e1 = net.add_edge(v2, v1, h[1].clone(), attrs(&profiles[i]));
            report.vertices.push([v1, v2]);
            report.halves.push([e0, e1]);
        }
        let fwd = |edge| EdgeUse {
            edge,
            reversed: false,
        };
        let rev = |edge| EdgeUse {
            edge,
            reversed: true,
        };
        // Side-0 and side-1 halves of profile i as uses from s₁ to s₂.
        let sides = |i: usize, r: &SkinReport| {
            let [e0, e1] = r.halves[i];
            if swapped[i] {
                (rev(e1), fwd(e0))
            } else {
                (fwd(e0), rev(e1))
            }
        };
        for i in 0..halves.len() - 1 {
            let [a1, a2] = report.vertices[i];
            let [b1, b2] = report.vertices[i + 1];
            let sp1 = net.add_edge(a1, b1, spine_piece(0, i), attrs(&spines[0]));
            let sp2 = net.add_edge(a2, b2, spine_piece(1, i), attrs(&spines[1]));
            let (zi, oi) = sides(i, &report);
            let (zj, oj) = sides(i + 1, &report);
            let flip = |u: EdgeUse| EdgeUse {
                edge: u.edge,
                reversed: !u.reversed,
            };
            let fa = net.add_face(vec![zi, fwd(sp2), flip(zj), rev(sp1)]);
            let fb = net.add_face(vec![flip(oi), fwd(sp1), oj, rev(sp2)]);
            report.faces.push([fa, fb]);
        }
        if options.caps {
            for i in [0, halves.len() - 1] {
                let uses = border_loop(net, report.halves[i][0])?;
                report.caps.push(net.add_face(uses));
            }
        }
        Ok(report)
    })
}
