//! Mirroring (FIRES thesis §5.1): a drawn open curve is projected onto its own least-squares plane and
//! reflected, within that plane, across the line through its two (projected) end points; the curve and its
//! mirror image form one closed curve (the telephone receiver of the thesis was drawn this way). The result
//! is a plain curve, to be used as a boundary or inserted like a stroke.

use super::ToolError;
use crate::network::geom::{dist, dot, sub, P3};

/// A mirrored, closed curve.
#[derive(Clone, Debug, PartialEq)]
pub struct Mirrored {
    /// The projected curve from its first to its last point, then its mirror image back to the first
    /// point (which is repeated at the end), metres.
    pub points: Vec<P3>,
    /// Unit normal of the least-squares plane.
    pub normal: P3,
    /// The symmetry axis: a point on it (the projected first point) and its unit direction.
    pub axis: (P3, P3),
}

/// Eigenvector of the smallest eigenvalue of a symmetric 3×3 matrix (cyclic Jacobi rotations).
#[allow(clippy::needless_range_loop)] // rows p and q are updated together
fn smallest_eigenvector(mut a: [[f64; 3]; 3]) -> P3 {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..50 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        if off < 1e-300 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q].abs() < 1e-300 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for k in 0..3 {
                let (akp, akq) = (a[k][p], a[k][q]);
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let (apk, aqk) = (a[p][k], a[q][k]);
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let k = (0..3)
        .min_by(|&i, &j| a[i][i].total_cmp(&a[j][j]))
        .unwrap_or(0);
    let e = [v[0][k], v[1][k], v[2][k]];
    let n = dot(e, e).sqrt();
    [e[0] / n, e[1] / n, e[2] / n]
}

/// Mirrors an open curve about its end-point axis in its least-squares plane.
pub fn mirror_curve(points: &[P3]) -> Result<Mirrored, ToolError> {
    if points.len() < 3 || !points.iter().flatten().all(|c| c.is_finite()) {
        return Err(ToolError::BadCurve(
            "mirroring needs at least 3 finite points".into(),
        ));
    }
    let n = points.len() as f64;
    let c = points.iter().fold([0.0; 3], |s, p| {
        [s[0] + p[0] / n, s[1] + p[1] / n, s[2] + p[2] / n]
    });
    let mut cov = [[0.0; 3]; 3];
    for p in points {
        let d = sub(*p, c);
        for (i, row) in cov.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x += d[i] * d[j];
            }
        }
    }
    let normal = smallest_eigenvector(cov);
    let project = |p: P3| {
        let h = dot(sub(p, c), normal);
        [
            p[0] - h * normal[0],
            p[1] - h * normal[1],
            p[2] - h * normal[2],
        ]
    };
    let proj: Vec<P3> = points.iter().map(|&p| project(p)).collect();
    let (a, b) = (proj[0], proj[proj.len() - 1]);
    let len = dist(a, b);
    if len < 1e-9 {
        return Err(ToolError::BadCurve(
            "the curve's ends coincide: no symmetry axis".into(),
        ));
    }
    let u = [
        (b[0] - a[0]) / len,
        (b[1] - a[1]) / len,
        (b[2] - a[2]) / len,
    ];
    let reflect = |q: P3| {
        let s = dot(sub(q, a), u);
        let f = [a[0] + s * u[0], a[1] + s * u[1], a[2] + s * u[2]];
        [2.0 * f[0] - q[0], 2.0 * f[1] - q[1], 2.0 * f[2] - q[2]]
    };
    let mut out = proj.clone();
    out.extend(proj[1..proj.len() - 1].iter().rev().map(|&q| reflect(q)));
    out.push(a);
    Ok(Mirrored {
        points: out,
        normal,
        axis: (a, u),
    })
}
