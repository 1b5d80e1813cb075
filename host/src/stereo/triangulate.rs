//! The thesis's three triangulation methods (§4.1.1), selectable, on undistorted
//! normalised image coordinates `m_l`, `m_r`:
//!
//! - [`TriangulationMethod::NormalEquations`]: eqs. 4.1-4.5 with the corrected 3x2 matrix
//!   `A = [m_r, -R m_l]`, `A z = t`, solved through the 2x2 normal equations; `p = z_l m_l`.
//! - [`TriangulationMethod::Linear`]: the DLT of eq. 4.6 on the normalised projection matrices
//!   `[I|0]`, `[R|t]`, null vector by SVD.
//! - [`TriangulationMethod::Midpoint`]: eqs. 4.7-4.10, the midpoint of the common perpendicular.
//!
//! Every method also returns the ray gap `|p1 - p2|` (length of the common perpendicular of the two
//! viewing rays, eqs. 4.9/4.10), used to reject wrong pairs. Degenerate geometry (parallel rays,
//! points behind a camera, ill-conditioned systems, non-finite input) is an error value, never NaN.

use super::rig::StereoRig;
use nalgebra::{Matrix2, Matrix3, Matrix4, Vector2, Vector3, SVD};
use thiserror::Error;

/// Which triangulation equations to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum TriangulationMethod {
    /// Eqs. 4.1-4.5: depths from 2x2 normal equations.
    NormalEquations,
    /// Eq. 4.6: linear (DLT) triangulation by SVD.
    Linear,
    /// Eqs. 4.7-4.10: midpoint of the common perpendicular (the thesis pipeline's choice).
    #[default]
    Midpoint,
}

/// Why a pair could not be triangulated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum TriangulationError {
    /// The two viewing rays are (numerically) parallel: no finite intersection.
    #[error("viewing rays are parallel")]
    ParallelRays,
    /// The solution lies behind one of the cameras (non-positive depth).
    #[error("point lies behind a camera")]
    BehindCamera,
    /// The linear system is too ill-conditioned to trust.
    #[error("ill-conditioned triangulation")]
    IllConditioned,
    /// An input was NaN or infinite.
    #[error("non-finite input")]
    NonFinite,
}

/// A triangulated point with its consistency measures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Triangulated {
    /// The 3D point in the world (left camera) frame, metres.
    pub point: Vector3<f64>,
    /// Length of the common perpendicular between the two viewing rays, metres.
    pub ray_gap: f64,
    /// Depth along the left optical axis (z in the left frame).
    pub depth_left: f64,
    /// Depth along the right optical axis (z in the right frame).
    pub depth_right: f64,
}

/// Precomputed rig quantities for fast repeated triangulation.
#[derive(Debug, Clone)]
pub struct Triangulator {
    r: Matrix3<f64>,
    rt: Matrix3<f64>,
    t: Vector3<f64>,
    c_r: Vector3<f64>,
    /// Selected method.
    pub method: TriangulationMethod,
    /// Rays whose angle has a sine below this are treated as parallel.
    pub min_ray_sine: f64,
}

impl Triangulator {
    /// Precomputes the rig terms for `method`.
    pub fn new(rig: &StereoRig, method: TriangulationMethod) -> Self {
        let r = rig.r_right_from_left;
        Self {
            r,
            rt: r.transpose(),
            t: rig.t_right_from_left,
            c_r: rig.right_center(),
            method,
            min_ray_sine: 1e-7,
        }
    }

    /// Triangulates one pair of normalised image points with the selected method.
    pub fn triangulate(
        &self,
        m_l: [f64; 2],
        m_r: [f64; 2],
    ) -> Result<Triangulated, TriangulationError> {
        if !m_l.iter().chain(m_r.iter()).all(|v| v.is_finite()) {
            return Err(TriangulationError::NonFinite);
        }
        let ml = Vector3::new(m_l[0], m_l[1], 1.0);
        let mr = Vector3::new(m_r[0], m_r[1], 1.0);
        let l = ml;
        let r = self.rt * mr;
        let d = l.cross(&r);
        if d.norm() <= self.min_ray_sine * l.norm() * r.norm() {
            return Err(TriangulationError::ParallelRays);
        }
        let ray_gap = self.c_r.dot(&d).abs() / d.norm();
        let point = match self.method {
            TriangulationMethod::NormalEquations => self.normal_equations(&ml, &mr)?,
            TriangulationMethod::Linear => self.linear(m_l, m_r)?,
            TriangulationMethod::Midpoint => self.midpoint(&l, &r, &d)?,
        };
        self.finish(point, ray_gap)
    }

    fn finish(
        &self,
        point: Vector3<f64>,
        ray_gap: f64,
    ) -> Result<Triangulated, TriangulationError> {
        if !(point.iter().all(|v| v.is_finite()) && ray_gap.is_finite()) {
            return Err(TriangulationError::IllConditioned);
        }
        let depth_left = point.z;
        let depth_right = (self.r * point + self.t).z;
        if depth_left <= 0.0 || depth_right <= 0.0 {
            return Err(TriangulationError::BehindCamera);
        }
        Ok(Triangulated {
            point,
            ray_gap,
            depth_left,
            depth_right,
        })
    }

    /// Eqs. 4.3-4.5: `A = [m_r, -R m_l]`, `b = t`, `A^T A z = A^T b`, `p = z_l m_l`.
    fn normal_equations(
        &self,
        ml: &Vector3<f64>,
        mr: &Vector3<f64>,
    ) -> Result<Vector3<f64>, TriangulationError> {
        let rml = self.r * ml;
        let (a0, a1) = (*mr, -rml);
        let ata = Matrix2::new(a0.dot(&a0), a0.dot(&a1), a1.dot(&a0), a1.dot(&a1));
        let atb = Vector2::new(a0.dot(&self.t), a1.dot(&self.t));
        let det = ata.determinant();
        if det.is_nan() || det.abs() <= 1e-14 * ata[(0, 0)] * ata[(1, 1)] {
            return Err(TriangulationError::IllConditioned);
        }
        let z = ata
            .try_inverse()
            .ok_or(TriangulationError::IllConditioned)?
            * atb;
        let (z_r, z_l) = (z.x, z.y);
        if z_l <= 0.0 || z_r <= 0.0 {
            return Err(TriangulationError::BehindCamera);
        }
        Ok(ml * z_l)
    }

    /// Eq. 4.6 with `P_l = [I|0]`, `P_r = [R|t]`: the smallest right singular vector of `A`.
    fn linear(&self, m_l: [f64; 2], m_r: [f64; 2]) -> Result<Vector3<f64>, TriangulationError> {
        let mut a = Matrix4::zeros();
        let p_l = |row: usize, col: usize| -> f64 {
            if col < 3 {
                f64::from(u8::from(row == col))
            } else {
                0.0
            }
        };
        let p_r = |row: usize, col: usize| -> f64 {
            if col < 3 {
                self.r[(row, col)]
            } else {
                self.t[row]
            }
        };
        for c in 0..4 {
            a[(0, c)] = m_l[0] * p_l(2, c) - p_l(0, c);
            a[(1, c)] = m_l[1] * p_l(2, c) - p_l(1, c);
            a[(2, c)] = m_r[0] * p_r(2, c) - p_r(0, c);
            a[(3, c)] = m_r[1] * p_r(2, c) - p_r(1, c);
        }
        let svd = SVD::new(a, false, true);
        let v_t = svd.v_t.ok_or(TriangulationError::IllConditioned)?;
        let (mut best, mut best_s) = (0, f64::INFINITY);
        for (i, s) in svd.singular_values.iter().enumerate() {
            if *s < best_s {
                best_s = *s;
                best = i;
            }
        }
        let h = v_t.row(best);
        let w = h[3];
        let scale = h[0].abs().max(h[1].abs()).max(h[2].abs());
        if w.is_nan() || w.abs() <= 1e-12 * scale {
            return Err(TriangulationError::IllConditioned);
        }
        Ok(Vector3::new(h[0] / w, h[1] / w, h[2] / w))
    }

    /// Eqs. 4.7-4.10 with `C_l = 0`: feet `p1`, `p2` of the common perpendicular, `p = (p1+p2)/2`.
    fn midpoint(
        &self,
        l: &Vector3<f64>,
        r: &Vector3<f64>,
        d: &Vector3<f64>,
    ) -> Result<Vector3<f64>, TriangulationError> {
        let n_l = l.cross(d);
        let n_r = r.cross(d);
        let den_r = r.dot(&n_l);
        let den_l = l.dot(&n_r);
        if den_r.abs() < 1e-300 || den_l.abs() < 1e-300 {
            return Err(TriangulationError::ParallelRays);
        }
        let s_r = (-self.c_r).dot(&n_l) / den_r;
        let s_l = self.c_r.dot(&n_r) / den_l;
        if s_r <= 0.0 || s_l <= 0.0 {
            return Err(TriangulationError::BehindCamera);
        }
        let p1 = self.c_r + r * s_r;
        let p2 = l * s_l;
        Ok((p1 + p2) * 0.5)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stereo::{rig::CameraId, CameraModel};
    use nalgebra::Rotation3;
    use proptest::prelude::*;

    const METHODS: [TriangulationMethod; 3] = [
        TriangulationMethod::NormalEquations,
        TriangulationMethod::Linear,
        TriangulationMethod::Midpoint,
    ];

    fn rig(yaw: f64, baseline: f64) -> StereoRig {
        let cam = CameraModel::from_hfov(1024, 768, 45f64.to_radians());
        let r = Rotation3::from_euler_angles(0.01, yaw, -0.015).into_inner();
        StereoRig::new(cam, cam, r, Vector3::new(-baseline, 0.005, 0.01))
    }

    fn normalised(rig: &StereoRig, p: &Vector3<f64>) -> ([f64; 2], [f64; 2]) {
        let ml = rig
            .left
            .undistort(rig.project(CameraId::Left, p).unwrap())
            .unwrap();
        let mr = rig
            .right
            .undistort(rig.project(CameraId::Right, p).unwrap())
            .unwrap();
        (ml, mr)
    }

    #[test]
    fn all_methods_reproduce_noise_free_points() {
        let rig = rig(-0.1, 0.25);
        for p in [
            Vector3::new(0.0, 0.0, 0.3),
            Vector3::new(0.2, -0.1, 1.0),
            Vector3::new(-0.3, 0.2, 2.0),
        ] {
            let (ml, mr) = normalised(&rig, &p);
            for m in METHODS {
                let t = Triangulator::new(&rig, m).triangulate(ml, mr).unwrap();
                assert!(
                    (t.point - p).norm() <= 1e-6 * p.z,
                    "{m:?}: {} vs {}",
                    t.point,
                    p
                );
                assert!(t.ray_gap < 1e-9);
            }
        }
    }

    #[test]
    fn methods_agree_under_noise_and_gap_grows_with_mismatch() {
        let rig = rig(-0.05, 0.25);
        let p = Vector3::new(0.05, 0.02, 0.8);
        let (ml, mut mr) = normalised(&rig, &p);
        mr[1] += 0.5 / rig.right.fy; // half a pixel of vertical (epipolar) noise
        let pts: Vec<_> = METHODS
            .iter()
            .map(|&m| Triangulator::new(&rig, m).triangulate(ml, mr).unwrap())
            .collect();
        for t in &pts {
            assert!((t.point - p).norm() < 2e-3);
            assert!((t.point - pts[2].point).norm() < 1e-3);
            assert!(t.ray_gap > 1e-4);
        }
    }

    #[test]
    fn degenerate_geometry_is_an_error() {
        let rig = rig(0.0, 0.25);
        let tr = Triangulator::new(&rig, TriangulationMethod::Midpoint);
        // Identical normalised coordinates on a parallel rig: parallel rays.
        let par = StereoRig::parallel(640, 480, 1.0, 0.2);
        for m in METHODS {
            let t = Triangulator::new(&par, m);
            assert_eq!(
                t.triangulate([0.1, 0.1], [0.1, 0.1]),
                Err(TriangulationError::ParallelRays)
            );
            // Rays diverging: the intersection is behind the cameras.
            let e = t.triangulate([0.0, 0.0], [0.3, 0.0]).unwrap_err();
            assert!(
                matches!(
                    e,
                    TriangulationError::BehindCamera | TriangulationError::IllConditioned
                ),
                "{e:?}"
            );
        }
        assert_eq!(
            tr.triangulate([f64::NAN, 0.0], [0.0, 0.0]),
            Err(TriangulationError::NonFinite)
        );
    }

    proptest! {
        #[test]
        fn never_nan_and_exact_when_valid(
            yaw in -0.4f64..0.4, baseline in 0.05f64..0.6,
            x in -1.0f64..1.0, y in -1.0f64..1.0, z in -0.5f64..3.0,
            ul in -1.0f64..1.0, vl in -1.0f64..1.0, ur in -1.0f64..1.0, vr in -1.0f64..1.0,
        ) {
            let rig = rig(yaw, baseline);
            for m in METHODS {
                let t = Triangulator::new(&rig, m);
                // Arbitrary (mostly inconsistent) image points: finite result or error.
                if let Ok(r) = t.triangulate([ul, vl], [ur, vr]) {
                    prop_assert!(r.point.iter().all(|v| v.is_finite()) && r.ray_gap.is_finite());
                    prop_assert!(r.depth_left > 0.0 && r.depth_right > 0.0);
                }
                // A real point in front of both cameras is recovered.
                let p = Vector3::new(x, y, z);
                if z > 0.3 && rig.to_right(&p).z > 0.3 {
                    let ml = [p.x / p.z, p.y / p.z];
                    let q = rig.to_right(&p);
                    let mr = [q.x / q.z, q.y / q.z];
                    match t.triangulate(ml, mr) {
                        Ok(r) => prop_assert!((r.point - p).norm() <= 1e-6 * p.norm().max(1.0)),
                        Err(e) => prop_assert!(matches!(e, TriangulationError::ParallelRays | TriangulationError::IllConditioned)),
                    }
                }
            }
        }
    }
}
