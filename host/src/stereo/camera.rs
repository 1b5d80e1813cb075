//! One camera: the recording format's pinhole model with OpenCV's 5-coefficient distortion
//! ([`fires_record::CameraModel`], docs/recording.md), seen from the tracker: projection of camera-frame
//! points with a typed error, and undistortion of pixels to the normalised image coordinates
//! `m = K^-1 [u, v, 1]^T` that the triangulation equations 4.1-4.10 expect (FIRES thesis, §4.1.1).

pub use fires_record::CameraModel;
use nalgebra::Vector3;
use thiserror::Error;

/// Errors of projection and undistortion.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum ProjectionError {
    /// The point is on or behind the image plane (z <= 0).
    #[error("point is behind the camera")]
    BehindCamera,
    /// The iterative undistortion did not converge (pixel far outside the calibrated field).
    #[error("undistortion did not converge")]
    UndistortDiverged,
    /// An input coordinate was NaN or infinite.
    #[error("non-finite input")]
    NonFinite,
}

impl From<fires_record::UndistortError> for ProjectionError {
    fn from(e: fires_record::UndistortError) -> Self {
        match e {
            fires_record::UndistortError::NonFinite => ProjectionError::NonFinite,
            fires_record::UndistortError::Diverged => ProjectionError::UndistortDiverged,
        }
    }
}

/// Projects a camera-frame point to distorted pixel coordinates.
pub fn project(cam: &CameraModel, p: &Vector3<f64>) -> Result<[f64; 2], ProjectionError> {
    if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
        return Err(ProjectionError::NonFinite);
    }
    if p.z <= 0.0 {
        return Err(ProjectionError::BehindCamera);
    }
    let [xd, yd] = cam.distort_normalized(p.x / p.z, p.y / p.z);
    Ok([cam.fx * xd + cam.cx, cam.fy * yd + cam.cy])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> CameraModel {
        CameraModel {
            k1: -0.2,
            k2: 0.05,
            p1: 0.001,
            p2: -0.0005,
            ..CameraModel::from_hfov(640, 480, 60f64.to_radians())
        }
    }

    #[test]
    fn undistort_inverts_project() {
        let c = cam();
        for &(x, y) in &[(0.0, 0.0), (0.3, -0.2), (-0.45, 0.3), (0.5, 0.35)] {
            let p = Vector3::new(x, y, 1.0);
            let px = project(&c, &p).unwrap();
            let m = c.undistort(px).unwrap();
            assert!(
                (m[0] - x).abs() < 1e-9 && (m[1] - y).abs() < 1e-9,
                "{m:?} vs {x},{y}"
            );
        }
    }

    #[test]
    fn behind_camera_is_an_error() {
        assert_eq!(
            project(&cam(), &Vector3::new(0.0, 0.0, -1.0)),
            Err(ProjectionError::BehindCamera)
        );
        assert_eq!(
            cam()
                .undistort([f64::NAN, 0.0])
                .map_err(ProjectionError::from),
            Err(ProjectionError::NonFinite)
        );
    }
}
