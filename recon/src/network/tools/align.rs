//! Alignment of a moved object (FIRES thesis §5.3): the user redraws an existing curve C_ref on the
//! moved object (C_obj). Both curves' PCA frames (centroid and covariance eigenvectors, sorted by
//! eigenvalue) give M = F_obj · F_ref⁻¹. Eigenvector signs are unknown, so the candidates are tried and
//! the one with the smallest sum of squared closest-point distances of M·C_ref to C_obj wins; only the
//! four proper rotations are tried (b₃ = b₁ × b₂), so a reflection is never returned. An optional ICP
//! refinement (Besl & McKay, "A method for registration of 3-D shapes", with Horn's quaternion fit)
//! follows. [`transform_network`] then moves every point of the network.

use super::ToolError;
use crate::network::geom::{dist2, P3};
use crate::network::mesh::Network;
use crate::network::Transaction;

/// Options of [`align_curves`].
#[derive(Clone, Debug, PartialEq)]
pub struct AlignOptions {
    /// ICP iterations after the PCA guess (0: PCA only, as in the thesis).
    pub icp_iterations: usize,
}

impl Default for AlignOptions {
    fn default() -> Self {
        AlignOptions { icp_iterations: 30 }
    }
}

/// A rigid motion x ↦ R x + t (metres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Alignment {
    /// Rotation, row-major, det = +1.
    pub rotation: [[f64; 3]; 3],
    /// Translation, metres.
    pub translation: P3,
    /// RMS closest-point distance of the moved reference curve to the object curve, metres.
    pub rms_m: f64,
    /// The covariance has two nearly equal eigenvalues (ratio < 1.05): the PCA frame is ill-defined
    /// (circles, straight lines) and the result may be wrong.
    pub ambiguous: bool,
}

impl Alignment {
    /// Applies the motion to a point.
    pub fn apply(&self, p: P3) -> P3 {
        let r = &self.rotation;
        let mut out = self.translation;
        for (i, o) in out.iter_mut().enumerate() {
            *o += r[i][0] * p[0] + r[i][1] * p[1] + r[i][2] * p[2];
        }
        out
    }
}

/// Eigen-decomposition of a symmetric N×N matrix by cyclic Jacobi rotations: eigenvalues and the
/// eigenvectors as columns of the second matrix.
#[allow(clippy::needless_range_loop)] // rows p and q are updated together
fn jacobi<const N: usize>(mut a: [[f64; N]; N]) -> ([f64; N], [[f64; N]; N]) {
    let mut v = [[0.0; N]; N];
    for (i, row) in v.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for _ in 0..60 {
        let mut off = 0.0;
        for p in 0..N {
            for q in p + 1..N {
                off += a[p][q].abs();
            }
        }
        if off < 1e-300 {
            break;
        }
        for p in 0..N {
            for q in p + 1..N {
                if a[p][q].abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = if theta == 0.0 {
                    1.0
                } else {
                    theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt())
                };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..N {
                    let (akp, akq) = (a[k][p], a[k][q]);
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for k in 0..N {
                    let (apk, aqk) = (a[p][k], a[q][k]);
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for row in v.iter_mut() {
                    let (vp, vq) = (row[p], row[q]);
                    row[p] = c * vp - s * vq;
                    row[q] = s * vp + c * vq;
                }
            }
        }
    }
    let mut vals = [0.0; N];
    for (i, x) in vals.iter_mut().enumerate() {
        *x = a[i][i];
    }
    (vals, v)
}

fn centroid(p: &[P3]) -> P3 {
    let n = p.len() as f64;
    p.iter().fold([0.0; 3], |s, q| {
        [s[0] + q[0] / n, s[1] + q[1] / n, s[2] + q[2] / n]
    })
}

fn cross(a: P3, b: P3) -> P3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Centroid, eigenvectors by decreasing eigenvalue (b₁, b₂) and the eigenvalue ratios.
fn frame(p: &[P3]) -> (P3, P3, P3, f64) {
    let c = centroid(p);
    let mut cov = [[0.0; 3]; 3];
    for q in p {
        let d = [q[0] - c[0], q[1] - c[1], q[2] - c[2]];
        for i in 0..3 {
            for j in 0..3 {
                cov[i][j] += d[i] * d[j];
            }
        }
    }
    let (vals, vecs) = jacobi(cov);
    let mut order = [0, 1, 2];
    order.sort_by(|&i, &j| vals[j].total_cmp(&vals[i]));
    let col = |k: usize| [vecs[0][k], vecs[1][k], vecs[2][k]];
    let ratio = |i: usize, j: usize| vals[order[i]] / vals[order[j]].max(1e-300);
    let min_ratio = ratio(0, 1).min(ratio(1, 2));
    (c, col(order[0]), col(order[1]), min_ratio)
}

fn rotation_from_frames(obj: [P3; 3], r: [P3; 3]) -> [[f64; 3]; 3] {
    // R = B · Pᵀ with the frames' vectors as columns.
    let mut m = [[0.0; 3]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = (0..3).map(|k| obj[k][i] * r[k][j]).sum();
        }
    }
    m
}

fn motion(rotation: [[f64; 3]; 3], from: P3, to: P3) -> Alignment {
    let mut a = Alignment {
        rotation,
        translation: [0.0; 3],
        rms_m: 0.0,
        ambiguous: false,
    };
    let moved = a.apply(from);
    a.translation = [to[0] - moved[0], to[1] - moved[1], to[2] - moved[2]];
    a
}

/// Nearest point of `set` to `p` (brute force: curves are a few hundred points).
fn nearest(set: &[P3], p: P3) -> P3 {
    let mut best = (f64::INFINITY, set[0]);
    for &q in set {
        let d = dist2(p, q);
        if d < best.0 {
            best = (d, q);
        }
    }
    best.1
}

fn score(a: &Alignment, reference: &[P3], object: &[P3]) -> f64 {
    reference
        .iter()
        .map(|&p| {
            let q = a.apply(p);
            dist2(q, nearest(object, q))
        })
        .sum()
}

/// Horn's closed-form rigid fit of pairs (p → q).
fn horn(pairs: &[(P3, P3)]) -> Alignment {
    let n = pairs.len() as f64;
    let cp = pairs.iter().fold([0.0; 3], |s, (p, _)| {
        [s[0] + p[0] / n, s[1] + p[1] / n, s[2] + p[2] / n]
    });
    let cq = pairs.iter().fold([0.0; 3], |s, (_, q)| {
        [s[0] + q[0] / n, s[1] + q[1] / n, s[2] + q[2] / n]
    });
    let mut s = [[0.0; 3]; 3];
    for (p, q) in pairs {
        for i in 0..3 {
            for j in 0..3 {
                s[i][j] += (p[i] - cp[i]) * (q[j] - cq[j]);
            }
        }
    }
    let [[sxx, sxy, sxz], [syx, syy, syz], [szx, szy, szz]] = s;
    let k = [
        [sxx + syy + szz, syz - szy, szx - sxz, sxy - syx],
        [syz - szy, sxx - syy - szz, sxy + syx, szx + sxz],
        [szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy],
        [sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz],
    ];
    let (vals, vecs) = jacobi(k);
    let m = (0..4)
        .max_by(|&i, &j| vals[i].total_cmp(&vals[j]))
        .unwrap_or(0);
    let r = quaternion_matrix([vecs[0][m], vecs[1][m], vecs[2][m], vecs[3][m]]);
    motion(r, cp, cq)
}

/// The rotation matrix of the unit quaternion `[w, x, y, z]` (row-major).
pub fn quaternion_matrix([w, x, y, z]: [f64; 4]) -> [[f64; 3]; 3] {
    [
        [
            w * w + x * x - y * y - z * z,
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            w * w - x * x + y * y - z * z,
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            w * w - x * x - y * y + z * z,
        ],
    ]
}

/// ICP stops when no entry of the rotation (or translation, metres) moves by more than this.
const ICP_CONVERGED: f64 = 1e-12;

/// The rigid motion that carries `reference` (a curve of the network) onto `object` (the same curve
/// drawn on the moved object). Point order and count may differ.
pub fn align_curves(
    reference: &[P3],
    object: &[P3],
    options: &AlignOptions,
) -> Result<Alignment, ToolError> {
    if reference.len() < 3 || object.len() < 3 {
        return Err(ToolError::BadCurve(
            "alignment needs curves of at least 3 points".into(),
        ));
    }
    if !reference
        .iter()
        .chain(object)
        .flatten()
        .all(|c| c.is_finite())
    {
        return Err(ToolError::BadCurve("a point is not finite".into()));
    }
    let (cr, r1, r2, ratio_r) = frame(reference);
    let (co, o1, o2, ratio_o) = frame(object);
    let rf = [r1, r2, cross(r1, r2)];
    let mut best: Option<(f64, Alignment)> = None;
    for (s1, s2) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
        let b1 = o1.map(|x| x * s1);
        let b2 = o2.map(|x| x * s2);
        let a = motion(rotation_from_frames([b1, b2, cross(b1, b2)], rf), cr, co);
        let sc = score(&a, reference, object);
        if best.is_none_or(|(b, _)| sc < b) {
            best = Some((sc, a));
        }
    }
    let Some((_, mut a)) = best else {
        return Err(ToolError::BadCurve("no alignment".into()));
    };
    for _ in 0..options.icp_iterations {
        let pairs: Vec<(P3, P3)> = reference
            .iter()
            .map(|&p| (p, nearest(object, a.apply(p))))
            .collect();
        let next = horn(&pairs);
        // Converged (Besl & McKay §III stop when the fit no longer changes): the same pairs again.
        let moved = (0..3)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .map(|(i, j)| (next.rotation[i][j] - a.rotation[i][j]).abs())
            .chain((0..3).map(|i| (next.translation[i] - a.translation[i]).abs()))
            .fold(0.0, f64::max);
        a = next;
        if moved < ICP_CONVERGED {
            break;
        }
    }
    a.rms_m = (score(&a, reference, object) / reference.len() as f64).sqrt();
    a.ambiguous = ratio_r.min(ratio_o) < 1.05;
    Ok(a)
}

/// Moves every vertex and polyline point of the network by `a` (a transaction).
pub fn transform_network(net: &mut Network, a: &Alignment) -> Transaction {
    let result: Result<((), Transaction), std::convert::Infallible> = net.transact(|net| {
        let vs: Vec<_> = net.vertices().map(|(id, _)| id).collect();
        for v in vs {
            if let Some(mut x) = net.vertex(v).cloned() {
                x.position = a.apply(x.position);
                net.set_vertex(v, Some(x));
            }
        }
        let ps: Vec<_> = net.polylines().map(|(id, _)| id).collect();
        for p in ps {
            if let Some(mut x) = net.polyline(p).cloned() {
                for q in &mut x.points {
                    *q = a.apply(*q);
                }
                net.set_polyline(p, Some(x));
            }
        }
        Ok(())
    });
    match result {
        Ok((_, t)) => t,
        Err(never) => match never {},
    }
}
