//! Local frames of handles given as explicit positions (Yu, Zhou, Xu, Shi, Bao, Guo, Shum
//! 2004, *Mesh Editing with Poisson-Based Gradient Field Manipulation*, §3.3 "generalized
//! boundary conditions" and §4.1, editing individual vertices of a boundary curve).
//!
//! A boundary condition carries one local frame per vertex (normal, tangent, binormal); an
//! edit's frame change at a constrained vertex is one rotation (a quaternion) and one scale
//! ratio, which Poisson editing propagates to the free vertices. When a handle is given as
//! explicit positions, the frame changes are not given; they are derived here in two parts.
//!
//! 1. **Global part**: the handle's best-fit similarity `F` from rest to target
//!    ([`fit_similarity`]: least squares, rotation from the polar decomposition of the
//!    cross-covariance). It settles what a curve alone cannot: the rotation about the curve's
//!    own tangent, the ambiguity the paper holds against WIRE (§4.1).
//! 2. **Local part**: the residual `r = F⁻¹(target)`, the handle's non-rigid change in the
//!    rest frame, gives each handle vertex `i` a rotation `ΔR_i` and scale `Δs_i`:
//!    * a *region* vertex, one with incident faces whose three vertices are all on the
//!      handle: `ΔR_i` is the polar factor of `Σ_j e'_j e_jᵀ + w n'_i n_iᵀ` over its handle
//!      neighbours `j` (`e = x_j − x_i` at rest, `e'` the same in the residual), where `n`
//!      and `n'` are the area-weighted normals of those faces and `w` is the mean `|e|²`, so
//!      the frame's normal axis counts like one more edge;
//!    * a *curve* vertex, with handle neighbours but no handle face: its frame is the
//!      tangent (central difference along the curve: the two handle neighbours whose edges
//!      are most nearly opposite, or the one edge at a curve end), the normal and the
//!      binormal. `ΔR_i` is the minimal rotation of the tangent, which carries the normal
//!      along (a rotation-minimising frame); the twist about the tangent is the global part;
//!    * an isolated handle vertex: the identity;
//!    * `Δs_i` is the ratio of the RMS lengths of the vertex's edges to its handle neighbours.
//!
//! A vertex's frame change is then `R_F ΔR_i` with scale `s_F Δs_i`. The paper obtains the
//! frames of individually moved curve vertices from an intermediate WIRE deformation; the
//! residual frames above need no intermediate solve and give a rigid (or similarity) motion
//! of the handle exactly the boundary condition of the equivalent `transform`: then `r` is
//! the rest shape, `ΔR_i = I` and `Δs_i = 1` to round-off.

use nalgebra::UnitQuaternion;

use super::similarity::{minimal_rotation, polar_rotation, Mat3, Similarity};
use super::EditError;
use crate::geometry::{triangle_normal, Vec3};

/// A handle given as explicit positions: its targets and per-vertex frame changes, in the
/// order of the handle's local vertices.
#[derive(Debug, Clone, PartialEq)]
pub struct HandleShape {
    /// Target position of each handle vertex (as given).
    pub positions: Vec<Vec3>,
    /// Residual offset `F⁻¹(target) − rest` of each handle vertex: the non-rigid part.
    pub offset: Vec<Vec3>,
    /// Per handle vertex: the local frame change `ΔR_i` and `ln Δs_i` on top of the fitted
    /// similarity.
    pub frames: Vec<(UnitQuaternion<f64>, f64)>,
}

/// The least-squares similarity `x ↦ c' + s R (x − c)` taking `rest` to `target`
/// (centroids `c`, `c'`; `R` the polar factor of `Σ (t − c')(x − c)ᵀ`; `s` the least-squares
/// scale for that `R`, or the RMS ratio if that is not positive). One point, or all points
/// equal, gives the translation; collinear points give the minimal rotation of their line.
/// Fails when `target` collapses a handle of distinct points to one point.
pub fn fit_similarity(
    rest: &[Vec3],
    target: &[Vec3],
    handle: usize,
) -> Result<Similarity, EditError> {
    let n = rest.len().min(target.len()).max(1) as f64;
    let c = rest.iter().fold(Vec3::ZERO, |a, &p| a + p) / n;
    let ct = target.iter().fold(Vec3::ZERO, |a, &p| a + p) / n;
    let mut cov = Mat3::zeros();
    let (mut var, mut var_t) = (0.0, 0.0);
    for (&p, &t) in rest.iter().zip(target) {
        let (a, b) = (p - c, t - ct);
        var += a.dot(a);
        var_t += b.dot(b);
        for r in 0..3 {
            for k in 0..3 {
                cov[(r, k)] += b[r] * a[k];
            }
        }
    }
    let translation = Similarity {
        about: c,
        translate: ct - c,
        ..Similarity::identity()
    };
    let tiny = 1e-24 * rest.iter().map(|p| p.dot(*p)).fold(1e-300, f64::max);
    if var <= tiny {
        return Ok(translation);
    }
    if var_t <= 1e-24 * var {
        return Err(EditError::BadPositions {
            handle,
            reason: "the positions collapse the handle to one point".into(),
        });
    }
    let svd = cov.svd(true, true);
    let sv = svd.singular_values;
    let order = {
        let mut o = [0usize, 1, 2];
        o.sort_by(|&a, &b| sv[b].total_cmp(&sv[a]));
        o
    };
    let rotation = if sv[order[1]] <= 1e-12 * sv[order[0]] {
        // Collinear (rank one): turn the rest line onto the target line.
        match (svd.u, svd.v_t) {
            (Some(u), Some(vt)) => {
                let k = order[0];
                let a = Vec3::new(vt[(k, 0)], vt[(k, 1)], vt[(k, 2)]);
                let b = Vec3::new(u[(0, k)], u[(1, k)], u[(2, k)]);
                minimal_rotation(a, b)
            }
            _ => UnitQuaternion::identity(),
        }
    } else {
        rotation_of(&polar_rotation(&cov).0)
    };
    let r = rotation.to_rotation_matrix().into_inner();
    let fitted = (r.transpose() * cov).trace() / var;
    let scale = if fitted > 0.0 {
        fitted
    } else {
        (var_t / var).sqrt()
    };
    if !scale.is_finite() {
        return Err(EditError::BadPositions {
            handle,
            reason: "the positions give no finite scale".into(),
        });
    }
    Ok(Similarity {
        scale,
        rotation,
        ..translation
    })
}

fn rotation_of(m: &Mat3) -> UnitQuaternion<f64> {
    UnitQuaternion::from_rotation_matrix(&nalgebra::Rotation3::from_matrix_unchecked(*m))
}

/// Builds a handle's shape: `vertices` are its local indices, `positions` their targets
/// (same order), `rest`, `neighbors` and `faces` the problem's local rest geometry. Returns
/// the fitted similarity (the handle's transform) and the shape.
pub fn handle_shape(
    vertices: &[usize],
    positions: Vec<Vec3>,
    rest: &[Vec3],
    neighbors: &[Vec<usize>],
    faces: &[[usize; 3]],
    handle: usize,
) -> Result<(Similarity, HandleShape), EditError> {
    let rest_h: Vec<Vec3> = vertices.iter().map(|&l| rest[l]).collect();
    let fit = fit_similarity(&rest_h, &positions, handle)?;
    let inv = fit.inverse();
    let residual: Vec<Vec3> = positions.iter().map(|&p| inv.apply(p)).collect();
    let offset = residual.iter().zip(&rest_h).map(|(r, p)| *r - *p).collect();
    let mut slot = vec![usize::MAX; rest.len()];
    for (k, &l) in vertices.iter().enumerate() {
        slot[l] = k;
    }
    // Area-weighted normals of the handle's own faces, at rest and in the residual.
    let mut normals = vec![(Vec3::ZERO, Vec3::ZERO); vertices.len()];
    for f in faces {
        let k = f.map(|l| slot.get(l).copied().unwrap_or(usize::MAX));
        if k.contains(&usize::MAX) {
            continue;
        }
        let n0 = triangle_normal(rest_h[k[0]], rest_h[k[1]], rest_h[k[2]]);
        let n1 = triangle_normal(residual[k[0]], residual[k[1]], residual[k[2]]);
        for &s in &k {
            normals[s].0 += n0;
            normals[s].1 += n1;
        }
    }
    let frames = vertices
        .iter()
        .enumerate()
        .map(|(k, &l)| {
            let nb: Vec<usize> = neighbors[l]
                .iter()
                .map(|&j| slot[j])
                .filter(|&s| s != usize::MAX)
                .collect();
            vertex_frame(k, &nb, &rest_h, &residual, normals[k])
        })
        .collect();
    Ok((
        fit,
        HandleShape {
            positions,
            offset,
            frames,
        },
    ))
}

/// Frame change of handle vertex `k` from its handle neighbours `nb` (see the module doc).
fn vertex_frame(
    k: usize,
    nb: &[usize],
    rest: &[Vec3],
    residual: &[Vec3],
    normals: (Vec3, Vec3),
) -> (UnitQuaternion<f64>, f64) {
    if nb.is_empty() {
        return (UnitQuaternion::identity(), 0.0);
    }
    let e: Vec<Vec3> = nb.iter().map(|&j| rest[j] - rest[k]).collect();
    let f: Vec<Vec3> = nb.iter().map(|&j| residual[j] - residual[k]).collect();
    let len0: f64 = e.iter().map(|v| v.dot(*v)).sum();
    let len1: f64 = f.iter().map(|v| v.dot(*v)).sum();
    let log_scale = if len0 > 0.0 && len1 > 0.0 {
        0.5 * (len1 / len0).ln()
    } else {
        0.0
    };
    let (n0, n1) = (normals.0.try_normalize(), normals.1.try_normalize());
    let rotation = if let (Some(n0), Some(n1)) = (n0, n1) {
        // Region vertex: best-fit rotation of the edges plus the normal axis.
        let w = len0 / e.len() as f64;
        let mut m = Mat3::zeros();
        let mut add = |a: Vec3, b: Vec3, s: f64| {
            for r in 0..3 {
                for c in 0..3 {
                    m[(r, c)] += s * b[r] * a[c];
                }
            }
        };
        for (a, b) in e.iter().zip(&f) {
            add(*a, *b, 1.0);
        }
        add(n0, n1, w);
        rotation_of(&polar_rotation(&m).0)
    } else {
        // Curve vertex: minimal rotation of the tangent.
        let (t0, t1) = tangent(&e, &f);
        match (t0.try_normalize(), t1.try_normalize()) {
            (Some(a), Some(b)) => minimal_rotation(a, b),
            _ => UnitQuaternion::identity(),
        }
    };
    (
        rotation,
        if log_scale.is_finite() {
            log_scale
        } else {
            0.0
        },
    )
}

/// The tangent at rest and in the residual: the difference of the two most nearly opposite
/// edges (central difference), or the single edge.
fn tangent(e: &[Vec3], f: &[Vec3]) -> (Vec3, Vec3) {
    if e.len() == 1 {
        return (e[0], f[0]);
    }
    let mut best = (f64::INFINITY, 0, 1);
    for a in 0..e.len() {
        for b in a + 1..e.len() {
            let d = e[a].dot(e[b]) / (e[a].norm() * e[b].norm()).max(1e-300);
            if d < best.0 {
                best = (d, a, b);
            }
        }
    }
    let (_, a, b) = best;
    (e[b] - e[a], f[b] - f[a])
}
