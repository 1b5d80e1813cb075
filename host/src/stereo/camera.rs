//! One camera: pinhole intrinsics with OpenCV's 5-coefficient distortion (k1, k2, p1, p2, k3).
//!
//! `project` maps a camera-frame point to pixels; `undistort` maps a pixel back to normalised
//! image coordinates `m = K^-1 [u, v, 1]^T` after removing distortion, which is what the
//! triangulation equations 4.1-4.10 expect (digest §2.1(a): "normalised homogeneous image coordinates").

use nalgebra::Vector3;
use thiserror::Error;

/// OpenCV radial-tangential distortion coefficients (the `k1, k2, p1, p2, k3` order of OpenCV).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Distortion {
    /// Radial coefficient r^2.
    pub k1: f64,
    /// Radial coefficient r^4.
    pub k2: f64,
    /// Tangential coefficient p1.
    pub p1: f64,
    /// Tangential coefficient p2.
    pub p2: f64,
    /// Radial coefficient r^6.
    pub k3: f64,
}

impl Distortion {
    /// True when every coefficient is zero (pure pinhole).
    pub fn is_zero(&self) -> bool {
        self.k1 == 0.0 && self.k2 == 0.0 && self.p1 == 0.0 && self.p2 == 0.0 && self.k3 == 0.0
    }

    /// Applies the distortion model to normalised undistorted coordinates.
    pub fn distort(&self, x: f64, y: f64) -> (f64, f64) {
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (self.k1 + r2 * (self.k2 + r2 * self.k3));
        let xd = x * radial + 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x);
        let yd = y * radial + self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y;
        (xd, yd)
    }
}

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

/// Pinhole intrinsics (pixels) plus distortion, for an image of `width` x `height` pixels.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CameraIntrinsics {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Focal length along x in pixels.
    pub fx: f64,
    /// Focal length along y in pixels.
    pub fy: f64,
    /// Principal point x in pixels.
    pub cx: f64,
    /// Principal point y in pixels.
    pub cy: f64,
    /// Lens distortion.
    pub distortion: Distortion,
}

impl CameraIntrinsics {
    /// An ideal camera with square pixels, the principal point at the image centre and the given
    /// horizontal field of view (radians).
    pub fn from_hfov(width: u32, height: u32, hfov: f64) -> Self {
        let f = 0.5 * f64::from(width) / (0.5 * hfov).tan();
        Self {
            width,
            height,
            fx: f,
            fy: f,
            cx: 0.5 * f64::from(width),
            cy: 0.5 * f64::from(height),
            distortion: Distortion::default(),
        }
    }

    /// Mean focal length in pixels (converts normalised distances to pixels).
    pub fn focal_px(&self) -> f64 {
        0.5 * (self.fx + self.fy)
    }

    /// Projects a camera-frame point to distorted pixel coordinates.
    pub fn project(&self, p: &Vector3<f64>) -> Result<[f64; 2], ProjectionError> {
        if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
            return Err(ProjectionError::NonFinite);
        }
        if p.z <= 0.0 {
            return Err(ProjectionError::BehindCamera);
        }
        let (xd, yd) = self.distortion.distort(p.x / p.z, p.y / p.z);
        Ok([self.fx * xd + self.cx, self.fy * yd + self.cy])
    }

    /// Pixel to distorted normalised coordinates (no distortion removal).
    pub fn pixel_to_distorted(&self, px: [f64; 2]) -> (f64, f64) {
        ((px[0] - self.cx) / self.fx, (px[1] - self.cy) / self.fy)
    }

    /// Pixel to undistorted normalised coordinates, by fixed-point iteration as OpenCV's
    /// `undistortPoints`, checked by re-distorting (error value if it does not converge).
    pub fn undistort(&self, px: [f64; 2]) -> Result<[f64; 2], ProjectionError> {
        if !(px[0].is_finite() && px[1].is_finite()) {
            return Err(ProjectionError::NonFinite);
        }
        let (xd, yd) = self.pixel_to_distorted(px);
        if self.distortion.is_zero() {
            return Ok([xd, yd]);
        }
        let d = &self.distortion;
        let (mut x, mut y) = (xd, yd);
        for _ in 0..30 {
            let r2 = x * x + y * y;
            let radial = 1.0 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
            let dx = 2.0 * d.p1 * x * y + d.p2 * (r2 + 2.0 * x * x);
            let dy = d.p1 * (r2 + 2.0 * y * y) + 2.0 * d.p2 * x * y;
            if radial.abs() < 1e-12 {
                return Err(ProjectionError::UndistortDiverged);
            }
            x = (xd - dx) / radial;
            y = (yd - dy) / radial;
        }
        let (rx, ry) = d.distort(x, y);
        let err = ((rx - xd).powi(2) + (ry - yd).powi(2)).sqrt() * self.focal_px();
        if !(x.is_finite() && y.is_finite()) || err > 1e-3 {
            return Err(ProjectionError::UndistortDiverged);
        }
        Ok([x, y])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> CameraIntrinsics {
        let mut c = CameraIntrinsics::from_hfov(640, 480, 60f64.to_radians());
        c.distortion = Distortion {
            k1: -0.2,
            k2: 0.05,
            p1: 0.001,
            p2: -0.0005,
            k3: 0.0,
        };
        c
    }

    #[test]
    fn undistort_inverts_project() {
        let c = cam();
        for &(x, y) in &[(0.0, 0.0), (0.3, -0.2), (-0.45, 0.3), (0.5, 0.35)] {
            let p = Vector3::new(x, y, 1.0);
            let px = c.project(&p).unwrap();
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
            cam().project(&Vector3::new(0.0, 0.0, -1.0)),
            Err(ProjectionError::BehindCamera)
        );
        assert_eq!(
            cam().undistort([f64::NAN, 0.0]),
            Err(ProjectionError::NonFinite)
        );
    }
}
