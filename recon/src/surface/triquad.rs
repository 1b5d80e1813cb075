//! Triquadrification (FIRES thesis §6.1): every face with five or more sides is split into quads and at
//! most one triangle by new polylines sampled from a Coons patch.
//!
//! For an n-gon (n ≥ 5):
//! 1. **Q'** (§6.1): its four corners are the four vertices with the smallest interior angles, measured
//!    between the tangents of the two polylines meeting there (chords to the point a small arc fraction
//!    along each polyline, see [`TriquadOptions::tangent_fraction`]), signed in the face's least-squares
//!    plane so reflex corners measure more than π; ties go to the lower loop index. Its sides concatenate
//!    the polylines between consecutive corners, and each vertex of the face gets (u, v) on Q''s border
//!    from the chord length along its side (face_patch.rs, shared with hole creation).
//! 2. **Greedy planarity splitting** (§6.1.1): among the runs of four consecutive vertices of the
//!    remaining polygon (excluding runs whose four vertices lie on one side of Q', and cuts between vertices
//!    already joined by an edge), cut off the quad whose least-squares plane (over its polylines' points)
//!    is closest in angle (unsigned, 0–90°) to the n-gon's; repeat on the n − 2 remainder until it has three
//!    or four sides. An n-gon thus gives (n − 1)/2 faces for odd n, one of them a triangle, and (n − 2)/2
//!    quads for even n.
//! 3. **New polylines** (§6.1.2): a cut from a to b is the Coons patch of Q' sampled along the straight
//!    segment from (u_a, v_a) to (u_b, v_b) in its parameter domain, with the mean sample spacing of the
//!    face's polylines (at least [`TriquadOptions::min_segments`] segments). Each becomes a [`Curve`] with
//!    `generated = true`, not sharp.

use super::control::{ControlMesh, Curve};
use super::coons::halfedge_polyline;
use super::error::SurfaceError;
use super::face_patch::{face_patch, lsq_normal, newell, FacePatch};
use super::from_network::Builder;
use crate::geometry::Vec3;

/// Options of [`triquadrify`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriquadOptions {
    /// The tangent at a vertex is the chord to the point this fraction of the polyline's arc length away
    /// (default 0.05: robust to sampling noise, close to the tangent).
    pub tangent_fraction: f64,
    /// Fewest segments of a generated polyline (default 2).
    pub min_segments: usize,
}

impl Default for TriquadOptions {
    fn default() -> Self {
        TriquadOptions {
            tangent_fraction: 0.05,
            min_segments: 2,
        }
    }
}

/// Splits every face of `cm` with five or more sides into quads and at most one triangle (module doc).
/// Triangles and quads are kept as they are; the result has only triangles and quads.
pub fn triquadrify(cm: &ControlMesh, opts: &TriquadOptions) -> Result<ControlMesh, SurfaceError> {
    let m = &cm.mesh;
    let mut b = Builder::from_control(cm);
    for f in m.faces() {
        let hs: Vec<_> = m.face_halfedges(f).collect();
        let verts: Vec<usize> = hs.iter().map(|&h| m.from_vertex(h).idx()).collect();
        let n = hs.len();
        if n <= 4 {
            b.faces.push(verts);
            continue;
        }
        let sides: Vec<Vec<Vec3>> = hs.iter().map(|&h| halfedge_polyline(cm, h)).collect();
        split_face(&mut b, &verts, &sides, opts)
            .map_err(|r| SurfaceError::Degenerate(format!("face {f} ({n} sides): {r}")))?;
    }
    b.finish()
}

fn split_face(
    b: &mut Builder,
    verts: &[usize],
    sides: &[Vec<Vec3>],
    opts: &TriquadOptions,
) -> Result<(), String> {
    let n = verts.len();
    let corners_pos: Vec<Vec3> = verts.iter().map(|&v| b.points[v]).collect();
    // 1. Q' and its Coons patch (face_patch.rs).
    let FacePatch {
        patch,
        uv,
        on_side,
        normal,
    } = face_patch(sides, opts.tangent_fraction)?;
    // Sample spacing of the face's polylines.
    let (len, segs) = sides.iter().fold((0.0, 0usize), |(l, s), p| {
        let pl: f64 = p.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
        (l + pl, s + p.len() - 1)
    });
    let spacing = len / segs.max(1) as f64;

    // 2. Greedy splitting. `poly` holds face-local indices; `edge_pts(a, b)` the polyline a → b.
    let mut poly: Vec<usize> = (0..n).collect();
    let mut cuts: Vec<((usize, usize), Vec<Vec3>)> = Vec::new();
    let side_pts = |a: usize, bb: usize, cuts: &[((usize, usize), Vec<Vec3>)]| -> Vec<Vec3> {
        if (a + 1) % n == bb {
            return sides[a].clone();
        }
        for (k, p) in cuts {
            if *k == (a, bb) {
                return p.clone();
            }
            if *k == (bb, a) {
                return p.iter().rev().copied().collect();
            }
        }
        Vec::new()
    };
    while poly.len() >= 5 {
        let mlen = poly.len();
        let mut best: Option<(bool, f64, usize)> = None;
        for i in 0..mlen {
            let run = [0, 1, 2, 3].map(|d| poly[(i + d) % mlen]);
            let same_side = (0..4).any(|j| run.iter().all(|&k| on_side[k][j]));
            let (va, vb) = (verts[run[0]], verts[run[3]]);
            let joined = b.span_of(va, vb).is_some() || (run[3] + 1) % n == run[0];
            if joined {
                continue;
            }
            let mut pts: Vec<Vec3> = Vec::new();
            for d in 0..3 {
                let p = side_pts(run[d], run[d + 1], &cuts);
                pts.extend_from_slice(&p[..p.len().saturating_sub(1)]);
            }
            pts.push(corners_pos[run[3]]);
            let nq = lsq_normal(&pts, newell(&pts)).unwrap_or(normal);
            let angle = nq.dot(normal).abs().min(1.0).acos();
            // Candidates off a single side of Q' first; among them, the most coplanar.
            let key = (same_side, angle, i);
            if best.is_none_or(|bk| (key.0, key.1) < (bk.0, bk.1)) {
                best = Some(key);
            }
        }
        let (_, _, i) = best.ok_or("no admissible cut")?;
        let run = [0, 1, 2, 3].map(|d| poly[(i + d) % mlen]);
        // 3. The new polyline run[0] → run[3], from the Coons patch of Q'.
        let (pa, pb) = (corners_pos[run[0]], corners_pos[run[3]]);
        let (ua, ub) = (uv[run[0]], uv[run[3]]);
        let nseg = ((pa - pb).norm() / spacing.max(f64::MIN_POSITIVE))
            .round()
            .max(opts.min_segments.max(1) as f64)
            .min(1e5) as usize;
        let mut pts: Vec<Vec3> = (0..=nseg)
            .map(|s| {
                let w = s as f64 / nseg as f64;
                patch.eval(ua.0 + w * (ub.0 - ua.0), ua.1 + w * (ub.1 - ua.1))
            })
            .collect();
        pts[0] = pa;
        pts[nseg] = pb;
        if pts.iter().any(|p| !p.is_finite()) {
            return Err("a generated polyline is not finite".into());
        }
        let mut curve = Curve::new(pts.clone(), false);
        curve.generated = true;
        let ci = b.curves.len();
        let l = curve.length();
        if l.is_nan() || l <= 0.0 {
            return Err("two corners of a cut coincide".into());
        }
        b.curves.push(curve);
        b.span(verts[run[0]], verts[run[3]], ci, 0.0, l);
        cuts.push(((run[0], run[3]), pts));
        b.faces.push(run.iter().map(|&k| verts[k]).collect());
        // Remove run[1], run[2] from the polygon.
        let (r1, r2) = ((i + 1) % mlen, (i + 2) % mlen);
        poly = poly
            .iter()
            .enumerate()
            .filter(|&(j, _)| j != r1 && j != r2)
            .map(|(_, &k)| k)
            .collect();
    }
    b.faces.push(poly.iter().map(|&k| verts[k]).collect());
    Ok(())
}
