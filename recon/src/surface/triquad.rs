//! Triquadrification (FIRES thesis §6.1): every face with five or more sides is split into quads and at
//! most one triangle by new polylines sampled from a Coons patch.
//!
//! For an n-gon (n ≥ 5):
//! 1. **Q'** (§6.1): its four corners are the four vertices with the smallest interior angles, measured
//!    between the tangents of the two polylines meeting there (chords to the point a small arc fraction
//!    along each polyline, see [`TriquadOptions::tangent_fraction`]), signed in the face's least-squares
//!    plane so reflex corners measure more than π; ties go to the lower loop index. Its sides concatenate
//!    the polylines between consecutive corners, and each vertex of the face gets (u, v) on Q''s border
//!    from the chord length along its side.
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

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

use super::control::{ControlMesh, Curve};
use super::coons::{chord_params, halfedge_polyline, CoonsPatch, Side};
use super::error::SurfaceError;
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

/// The unit normal of the least-squares plane of `pts`, oriented like the loop's Newell normal `hint`.
pub(crate) fn lsq_normal(pts: &[Vec3], hint: Vec3) -> Option<Vec3> {
    if pts.len() < 3 {
        return None;
    }
    let n = pts.len() as f64;
    let c = pts.iter().fold(Vec3::ZERO, |a, &p| a + p) / n;
    let mut m = Matrix3::zeros();
    for p in pts {
        let d = Vector3::new(p.x - c.x, p.y - c.y, p.z - c.z);
        m += d * d.transpose();
    }
    let eig = SymmetricEigen::new(m);
    let (mut k, mut best) = (0, f64::INFINITY);
    for i in 0..3 {
        if eig.eigenvalues[i] < best {
            best = eig.eigenvalues[i];
            k = i;
        }
    }
    let col = eig.eigenvectors.column(k);
    let nrm = Vec3::new(col[0], col[1], col[2]).try_normalize()?;
    Some(if nrm.dot(hint) < 0.0 { -nrm } else { nrm })
}

/// The Newell normal (twice the vector area) of the closed loop `pts`.
pub(crate) fn newell(pts: &[Vec3]) -> Vec3 {
    let n = pts.len();
    let mut a = Vec3::ZERO;
    for i in 0..n {
        a += pts[i].cross(pts[(i + 1) % n]);
    }
    a
}

/// The interior angle at a vertex between the incoming polyline `inc` (ending there) and the outgoing
/// `out` (starting there), signed about `normal`, in [0, 2π).
fn interior_angle(inc: &Side, out: &Side, normal: Vec3, frac: f64) -> f64 {
    let v = out.first();
    let d_in = inc.at(1.0 - frac) - v;
    let d_out = out.at(frac) - v;
    let a = normal.dot(d_out.cross(d_in)).atan2(d_out.dot(d_in));
    if a < 0.0 {
        a + std::f64::consts::TAU
    } else {
        a
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
    let all: Vec<Vec3> = sides
        .iter()
        .flat_map(|s| s[..s.len() - 1].iter().copied())
        .collect();
    let hint = newell(&all);
    let normal = lsq_normal(&all, hint).ok_or("its points span no plane")?;
    // 1. Q': the four smallest interior angles.
    let side_obj: Vec<Side> = sides.iter().map(|s| Side::new(s.clone())).collect();
    let frac = opts.tangent_fraction.clamp(1e-6, 0.5);
    let mut order: Vec<(f64, usize)> = (0..n)
        .map(|k| {
            let inc = &side_obj[(k + n - 1) % n];
            (interior_angle(inc, &side_obj[k], normal, frac), k)
        })
        .collect();
    order.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
    let mut c: Vec<usize> = order[..4].iter().map(|x| x.1).collect();
    c.sort_unstable();
    // Q' sides and the (u, v) of every vertex.
    let mut qsides: Vec<Vec<Vec3>> = Vec::with_capacity(4);
    let mut uv = vec![(0.0, 0.0); n];
    let mut on_side: Vec<[bool; 4]> = vec![[false; 4]; n];
    for j in 0..4 {
        let (start, end) = (c[j], c[(j + 1) % 4]);
        let count = (end + n - start) % n;
        let mut pts: Vec<Vec3> = Vec::new();
        let mut at_vertex = Vec::with_capacity(count + 1);
        for i in 0..count {
            let s = &sides[(start + i) % n];
            at_vertex.push(pts.len());
            pts.extend_from_slice(&s[..s.len() - 1]);
        }
        at_vertex.push(pts.len());
        pts.push(corners_pos[end]);
        let kn = chord_params(&pts);
        for (i, &ix) in at_vertex.iter().enumerate() {
            let k = (start + i) % n;
            on_side[k][j] = true;
            if i == count {
                continue; // the next side's corner
            }
            let t = kn[ix];
            uv[k] = match j {
                0 => (t, 0.0),
                1 => (1.0, t),
                2 => (1.0 - t, 1.0),
                _ => (0.0, 1.0 - t),
            };
        }
        qsides.push(pts);
    }
    let [q0, q1, q2, q3]: [Vec<Vec3>; 4] = qsides.try_into().map_err(|_| "no Q'")?;
    let patch = CoonsPatch::from_loop([q0, q1, q2, q3]);
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
