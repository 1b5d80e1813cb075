//! Similarity transforms, rotations and the small dense kernels the editing methods share:
//! quaternion slerp and weighted averaging (Yu et al. 2004, *Mesh Editing with
//! Poisson-Based Gradient Field Manipulation*, §3.3 footnote 3), the polar/Kabsch rotation
//! of a 3×3 matrix (Fu, *Differential Methods for Intuitive 3D Shape Modeling*, §2.4.4),
//! and the minimal rotation between two directions (Yu et al. §4.3).

use nalgebra::{Matrix3, Quaternion, Unit, UnitQuaternion, Vector3};

use crate::geometry::Vec3;

/// 3×3 matrix type of the editing code.
pub type Mat3 = Matrix3<f64>;

/// `x ↦ about + s·R·(x − about) + t`: scale, then rotation, both about `about`, then a
/// translation (the edit specification's transform).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Similarity {
    /// Uniform scale `s > 0`.
    pub scale: f64,
    /// Rotation `R`.
    pub rotation: UnitQuaternion<f64>,
    /// Fixed point of scale and rotation.
    pub about: Vec3,
    /// Translation applied last.
    pub translate: Vec3,
}

impl Default for Similarity {
    fn default() -> Self {
        Self::identity()
    }
}

impl Similarity {
    /// The identity.
    pub fn identity() -> Self {
        Self {
            scale: 1.0,
            rotation: UnitQuaternion::identity(),
            about: Vec3::ZERO,
            translate: Vec3::ZERO,
        }
    }

    /// A rigid motion `x ↦ R x + t` (about the origin).
    pub fn rigid(rotation: UnitQuaternion<f64>, translate: Vec3) -> Self {
        Self {
            rotation,
            translate,
            ..Self::identity()
        }
    }

    /// Image of a point.
    pub fn apply(&self, p: Vec3) -> Vec3 {
        self.about + rotate(&self.rotation, p - self.about) * self.scale + self.translate
    }

    /// The linear part `s·R`.
    pub fn linear(&self) -> Mat3 {
        self.rotation.to_rotation_matrix().into_inner() * self.scale
    }

    /// `self ∘ other` (apply `other` first).
    pub fn compose(&self, other: &Similarity) -> Similarity {
        // self(other(x)) = A_s(A_o x + c_o) + c_s with A = sR, c = about − A·about + t.
        let rotation = self.rotation * other.rotation;
        let scale = self.scale * other.scale;
        let origin = self.apply(other.apply(Vec3::ZERO));
        Similarity {
            scale,
            rotation,
            about: Vec3::ZERO,
            translate: origin,
        }
    }

    /// The inverse transform.
    pub fn inverse(&self) -> Similarity {
        // x = about + sR(y' ...) solved: y = A x + c → x = A⁻¹(y − c).
        let inv_rot = self.rotation.inverse();
        let c = self.apply(Vec3::ZERO);
        let back = rotate(&inv_rot, -c) / self.scale;
        Similarity {
            scale: 1.0 / self.scale,
            rotation: inv_rot,
            about: Vec3::ZERO,
            translate: back,
        }
    }

    /// `g ∘ self ∘ g⁻¹`: the same edit expressed after the whole scene moved by `g`.
    pub fn conjugate_by(&self, g: &Similarity) -> Similarity {
        g.compose(&self.compose(&g.inverse()))
    }
}

/// `R v` for a unit quaternion.
pub fn rotate(q: &UnitQuaternion<f64>, v: Vec3) -> Vec3 {
    from_na(q.transform_vector(&to_na(v)))
}

/// `M v`.
pub fn mat_vec(m: &Mat3, v: Vec3) -> Vec3 {
    from_na(m * to_na(v))
}

/// Vec3 → nalgebra.
pub fn to_na(v: Vec3) -> Vector3<f64> {
    Vector3::new(v.x, v.y, v.z)
}

/// nalgebra → Vec3.
pub fn from_na(v: Vector3<f64>) -> Vec3 {
    Vec3::new(v.x, v.y, v.z)
}

/// Rotation about `axis` (need not be unit; `None` when it is zero) by `deg` degrees.
pub fn axis_angle(axis: Vec3, deg: f64) -> Option<UnitQuaternion<f64>> {
    let a = axis.try_normalize()?;
    Some(UnitQuaternion::from_axis_angle(
        &Unit::new_unchecked(to_na(a)),
        deg.to_radians(),
    ))
}

/// Spherical linear interpolation from `a` (t = 0) to `b` (t = 1) along the shorter arc
/// (`b` is flipped into `a`'s hemisphere first).
pub fn slerp(a: &UnitQuaternion<f64>, b: &UnitQuaternion<f64>, t: f64) -> UnitQuaternion<f64> {
    let (qa, mut qb) = (a.into_inner(), b.into_inner());
    if qa.dot(&qb) < 0.0 {
        qb = -qb;
    }
    let cos = qa.dot(&qb).clamp(-1.0, 1.0);
    if cos > 1.0 - 1e-12 {
        // Nearly equal: normalised linear interpolation is exact to round-off.
        return UnitQuaternion::new_normalize(qa * (1.0 - t) + qb * t);
    }
    let theta = cos.acos();
    let s = theta.sin();
    let q: Quaternion<f64> = qa * (((1.0 - t) * theta).sin() / s) + qb * ((t * theta).sin() / s);
    UnitQuaternion::new_normalize(q)
}

/// Weighted quaternion average as a sequence of slerps in the given order (Yu et al.
/// 2004, footnote 3): `q ← slerp(q, q_k; w_k / W_k)` with `W_k` the cumulative weight.
/// Zero total weight gives the identity.
pub fn weighted_average(items: &[(UnitQuaternion<f64>, f64)]) -> UnitQuaternion<f64> {
    let mut acc = UnitQuaternion::identity();
    let mut total = 0.0;
    for &(q, w) in items {
        if w <= 0.0 {
            continue;
        }
        total += w;
        acc = if total == w {
            q
        } else {
            slerp(&acc, &q, w / total)
        };
    }
    acc
}

/// Closest proper rotation to `m` (polar factor `U Vᵀ` of its SVD, with the column of the
/// smallest singular value flipped when `det < 0`) and the scale `‖m‖_F/√3`
/// (Fu §2.4.4: `s = √((σ₁² + σ₂² + σ₃²)/3)`).
pub fn polar_rotation(m: &Mat3) -> (Mat3, f64) {
    let svd = m.svd(true, true);
    let scale = (m.norm_squared() / 3.0).sqrt();
    let (Some(mut u), Some(v_t)) = (svd.u, svd.v_t) else {
        return (Mat3::identity(), scale);
    };
    if (u * v_t).determinant() < 0.0 {
        let k = (0..3)
            .min_by(|&a, &b| svd.singular_values[a].total_cmp(&svd.singular_values[b]))
            .unwrap_or(2);
        for r in 0..3 {
            u[(r, k)] = -u[(r, k)];
        }
    }
    (u * v_t, scale)
}

/// The rotation of smallest angle taking unit `n` to unit `m` (axis `n × m`); the
/// antipodal case turns by π about any axis perpendicular to `n`.
pub fn minimal_rotation(n: Vec3, m: Vec3) -> UnitQuaternion<f64> {
    let (a, b) = (to_na(n), to_na(m));
    UnitQuaternion::rotation_between(&a, &b).unwrap_or_else(|| {
        let helper = if n.x.abs() < 0.9 {
            Vec3::new(1.0, 0.0, 0.0)
        } else {
            Vec3::new(0.0, 1.0, 0.0)
        };
        let axis = n.cross(helper).normalize_or_zero();
        UnitQuaternion::from_axis_angle(&Unit::new_normalize(to_na(axis)), std::f64::consts::PI)
    })
}

/// The skew exponential as a rotation matrix: `exp([h]×)` of a rotation vector `h`
/// (Rodrigues; Sorkine et al. 2004, *Laplacian Surface Editing*, appendix A).
pub fn rotation_from_vector(h: Vec3) -> Mat3 {
    UnitQuaternion::from_scaled_axis(to_na(h))
        .to_rotation_matrix()
        .into_inner()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_and_conjugate_round_trip() {
        let t = Similarity {
            scale: 1.7,
            rotation: axis_angle(Vec3::new(0.2, 0.9, 0.1), 70.0).unwrap(),
            about: Vec3::new(1.0, -2.0, 0.5),
            translate: Vec3::new(0.3, 0.1, -1.0),
        };
        let p = Vec3::new(0.4, 0.8, -0.3);
        assert!(t.inverse().apply(t.apply(p)).distance(p) < 1e-14);
        let g = Similarity::rigid(
            axis_angle(Vec3::new(1.0, 1.0, 0.0), 33.0).unwrap(),
            Vec3::new(5.0, 0.0, 1.0),
        );
        let c = t.conjugate_by(&g);
        assert!(c.apply(g.apply(p)).distance(g.apply(t.apply(p))) < 1e-13);
    }

    #[test]
    fn averaging_and_polar() {
        let q = axis_angle(Vec3::new(0.0, 0.0, 1.0), 40.0).unwrap();
        let neg = UnitQuaternion::new_unchecked(-q.into_inner());
        let avg = weighted_average(&[(q, 1.0), (neg, 2.0)]);
        assert!(avg.angle_to(&q) < 1e-12);
        let m = q.to_rotation_matrix().into_inner() * 2.5;
        let (r, s) = polar_rotation(&m);
        assert!((r - q.to_rotation_matrix().into_inner()).norm() < 1e-12);
        assert!((s - 2.5).abs() < 1e-12);
        let mr = minimal_rotation(Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 0.0, -1.0));
        assert!(rotate(&mr, Vec3::new(0.0, 0.0, 1.0)).distance(Vec3::new(0.0, 0.0, -1.0)) < 1e-12);
    }
}
