//! The calibrated camera pair. World frame = left camera frame; the right camera is
//! `X_right = R X_left + t` (OpenCV `stereoCalibrate` convention). In the thesis's notation
//! (eq. 4.1) `M~_r = R (M~_l - C_r)`, so the right centre in the world is `C_r = -R^T t`.
//!
//! Precomputes the essential matrix `E = [t]x R` used by the epipolar gate and the
//! normalised projection matrices `[I | 0]`, `[R | t]` used by the linear method (eq. 4.6).

use super::camera::{project, CameraModel, ProjectionError};
use nalgebra::{Matrix3, Matrix3x4, Rotation3, Vector3};

/// A calibrated stereo pair.
#[derive(Debug, Clone, PartialEq)]
pub struct StereoRig {
    /// Left camera (defines the world frame).
    pub left: CameraModel,
    /// Right camera.
    pub right: CameraModel,
    /// Rotation taking left-frame vectors into the right frame.
    pub r_right_from_left: Matrix3<f64>,
    /// Translation of the right-from-left transform (metres): `X_r = R X_l + t`.
    pub t_right_from_left: Vector3<f64>,
    essential: Matrix3<f64>,
    right_center: Vector3<f64>,
}

/// Which of the two cameras.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum CameraId {
    /// The left camera (world frame).
    Left,
    /// The right camera.
    Right,
}

impl StereoRig {
    /// Builds the rig; the rotation is re-orthonormalised.
    pub fn new(
        left: CameraModel,
        right: CameraModel,
        r_right_from_left: Matrix3<f64>,
        t_right_from_left: Vector3<f64>,
    ) -> Self {
        let r = Rotation3::from_matrix(&r_right_from_left).into_inner();
        let t = t_right_from_left;
        let essential = t.cross_matrix() * r;
        let right_center = -(r.transpose() * t);
        Self {
            left,
            right,
            r_right_from_left: r,
            t_right_from_left: t,
            essential,
            right_center,
        }
    }

    /// The thesis/issue reference rig: two identical cameras with the given resolution and
    /// horizontal FOV, parallel axes, right camera `baseline` metres to the right (+x).
    pub fn parallel(width: u32, height: u32, hfov: f64, baseline: f64) -> Self {
        let cam = CameraModel::from_hfov(width, height, hfov);
        Self::new(
            cam,
            cam,
            Matrix3::identity(),
            Vector3::new(-baseline, 0.0, 0.0),
        )
    }

    /// Essential matrix `E = [t]x R`: `m_r^T E m_l = 0` for normalised coordinates.
    pub fn essential(&self) -> &Matrix3<f64> {
        &self.essential
    }

    /// Fundamental matrix `F = K_r^-T E K_l^-1` (pixel coordinates, undistorted).
    pub fn fundamental(&self) -> Matrix3<f64> {
        let k_inv = |c: &CameraModel| {
            Matrix3::new(
                1.0 / c.fx,
                0.0,
                -c.cx / c.fx,
                0.0,
                1.0 / c.fy,
                -c.cy / c.fy,
                0.0,
                0.0,
                1.0,
            )
        };
        k_inv(&self.right).transpose() * self.essential * k_inv(&self.left)
    }

    /// Right camera centre in the world (left) frame, `C_r = -R^T t`.
    pub fn right_center(&self) -> Vector3<f64> {
        self.right_center
    }

    /// Baseline length in metres.
    pub fn baseline(&self) -> f64 {
        self.t_right_from_left.norm()
    }

    /// Normalised left projection matrix `[I | 0]`.
    pub fn left_projection(&self) -> Matrix3x4<f64> {
        Matrix3x4::identity()
    }

    /// Normalised right projection matrix `[R | t]`.
    pub fn right_projection(&self) -> Matrix3x4<f64> {
        let mut p = Matrix3x4::zeros();
        p.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&self.r_right_from_left);
        p.fixed_view_mut::<3, 1>(0, 3)
            .copy_from(&self.t_right_from_left);
        p
    }

    /// World point expressed in the right camera frame.
    pub fn to_right(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.r_right_from_left * p + self.t_right_from_left
    }

    /// Projects a world point into the given camera (distorted pixels).
    pub fn project(&self, camera: CameraId, p: &Vector3<f64>) -> Result<[f64; 2], ProjectionError> {
        match camera {
            CameraId::Left => project(&self.left, p),
            CameraId::Right => project(&self.right, &self.to_right(p)),
        }
    }

    /// Intrinsics of one camera.
    pub fn camera(&self, camera: CameraId) -> &CameraModel {
        match camera {
            CameraId::Left => &self.left,
            CameraId::Right => &self.right,
        }
    }

    /// Distance (in right-image pixels) of normalised right point `m_r` from the epipolar line of
    /// normalised left point `m_l`. Infinite when the line is undefined.
    pub fn epipolar_distance_px(&self, m_l: [f64; 2], m_r: [f64; 2]) -> f64 {
        let line = self.essential * Vector3::new(m_l[0], m_l[1], 1.0);
        let norm = line.x.hypot(line.y);
        if norm.is_nan() || norm <= 1e-15 {
            return f64::INFINITY;
        }
        let d = (line.x * m_r[0] + line.y * m_r[1] + line.z).abs() / norm;
        d * self.right.focal_px()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    fn rig() -> StereoRig {
        let cam = CameraModel::from_hfov(1024, 768, 45f64.to_radians());
        let r = Rotation3::from_euler_angles(0.01, -0.12, 0.02).into_inner();
        StereoRig::new(cam, cam, r, Vector3::new(-0.25, 0.01, 0.02))
    }

    #[test]
    fn epipolar_constraint_holds_for_true_projections() {
        let rig = rig();
        let p = Vector3::new(0.1, -0.05, 0.9);
        let ml = rig
            .left
            .undistort(rig.project(CameraId::Left, &p).unwrap())
            .unwrap();
        let mr = rig
            .right
            .undistort(rig.project(CameraId::Right, &p).unwrap())
            .unwrap();
        assert!(rig.epipolar_distance_px(ml, mr) < 1e-9);
        let f = rig.fundamental();
        let pl = rig.project(CameraId::Left, &p).unwrap();
        let pr = rig.project(CameraId::Right, &p).unwrap();
        let v = Vector3::new(pr[0], pr[1], 1.0).transpose() * f * Vector3::new(pl[0], pl[1], 1.0);
        assert!(v[(0, 0)].abs() < 1e-9);
        let c = rig.right_center();
        assert!(rig.to_right(&c).norm() < 1e-12);
    }
}
