//! The Coons patch of an n-sided face (FIRES thesis §6.1 and §6.1.2), used by triquadrification and by
//! hole creation (§5.2.2).
//!
//! **Q'**: its four corners are the four face vertices with the smallest interior angles, measured
//! between the tangents of the two polylines meeting there (chords to the point `tangent_fraction` of
//! the polyline's arc length along each), signed in the face's least-squares plane so reflex corners
//! measure more than π; ties go to the lower loop index. Its sides concatenate the polylines between
//! consecutive corners, and each face vertex gets (u, v) on Q''s border from the chord length along its
//! side. Q' runs counter-clockwise in the (u, v) domain: side 0 is v = 0, side 1 u = 1, side 2 v = 1,
//! side 3 u = 0.
//!
//! A face of fewer than four sides (the thesis only patches n-gons with n ≥ 4) first gets pseudo-corners:
//! the longest side (by arc length, ties to the lower index) is cut at its arc-length midpoint until there
//! are four; the pseudo-corners are not face vertices and get no (u, v).

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

use super::coons::{chord_params, CoonsPatch, Side};
use crate::geometry::Vec3;

/// The Coons patch of Q' and where the face's vertices sit in its domain.
#[derive(Clone, Debug)]
pub struct FacePatch {
    /// The patch.
    pub patch: CoonsPatch,
    /// (u, v) of each face vertex, in loop order.
    pub uv: Vec<(f64, f64)>,
    /// Which of Q''s sides each face vertex lies on (a corner is on two).
    pub on_side: Vec<[bool; 4]>,
    /// The unit normal of the face's least-squares plane, oriented like the loop.
    pub normal: Vec3,
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

fn arc_length(p: &[Vec3]) -> f64 {
    p.windows(2).map(|w| (w[1] - w[0]).norm()).sum()
}

/// `side` cut at its arc-length midpoint.
fn halve(side: &[Vec3]) -> (Vec<Vec3>, Vec<Vec3>) {
    let half = arc_length(side) / 2.0;
    let mut s = 0.0;
    for i in 0..side.len().saturating_sub(1) {
        let l = (side[i + 1] - side[i]).norm();
        if s + l >= half && l > 0.0 {
            let w = (half - s) / l;
            let m = side[i] * (1.0 - w) + side[i + 1] * w;
            let mut a = side[..=i].to_vec();
            a.push(m);
            let mut b = vec![m];
            b.extend_from_slice(&side[i + 1..]);
            return (a, b);
        }
        s += l;
    }
    let m = side.first().copied().unwrap_or(Vec3::ZERO);
    (vec![m, m], side.to_vec())
}

/// The Coons patch of the face whose loop is `sides` (side k runs from vertex k to vertex k + 1, each
/// with at least two points); see the module docs.
pub fn face_patch(sides: &[Vec<Vec3>], tangent_fraction: f64) -> Result<FacePatch, String> {
    if sides.is_empty() || sides.iter().any(|s| s.len() < 2) {
        return Err("a face side has fewer than two points".into());
    }
    // Pseudo-corners for faces of fewer than four sides; `real[k]` is the face vertex at refined vertex k.
    let mut sides: Vec<Vec<Vec3>> = sides.to_vec();
    let mut real: Vec<Option<usize>> = (0..sides.len()).map(Some).collect();
    while sides.len() < 4 {
        let mut k = 0;
        for i in 1..sides.len() {
            if arc_length(&sides[i]) > arc_length(&sides[k]) {
                k = i;
            }
        }
        let (a, b) = halve(&sides[k]);
        sides.splice(k..=k, [a, b]);
        real.insert(k + 1, None);
    }
    let n = sides.len();
    let corners_pos: Vec<Vec3> = sides.iter().map(|s| s[0]).collect();
    let all: Vec<Vec3> = sides
        .iter()
        .flat_map(|s| s[..s.len() - 1].iter().copied())
        .collect();
    let hint = newell(&all);
    let normal = lsq_normal(&all, hint).ok_or("its points span no plane")?;
    // The four smallest interior angles.
    let side_obj: Vec<Side> = sides.iter().map(|s| Side::new(s.clone())).collect();
    let frac = tangent_fraction.clamp(1e-6, 0.5);
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
    let keep = |k: usize| real[k].is_some();
    Ok(FacePatch {
        patch,
        uv: (0..n).filter(|&k| keep(k)).map(|k| uv[k]).collect(),
        on_side: (0..n).filter(|&k| keep(k)).map(|k| on_side[k]).collect(),
        normal,
    })
}
