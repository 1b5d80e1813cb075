//! Stereo correspondence (FIRES thesis, §4.1.2, made robust): every left blob is
//! paired with every right blob (at most 16 pairs for 4+4 LEDs), each pair is gated by its epipolar
//! distance and triangulated; pairs with a large ray gap, out of the depth range or with degenerate
//! geometry are dropped. The surviving candidates go to LED identification, which picks a
//! consistent subset with distinct left and right blobs.

use super::rig::StereoRig;
use super::triangulate::{Triangulated, Triangulator};
use nalgebra::{Matrix3, Vector3};

/// Gates for candidate pairs.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CorrespondenceConfig {
    /// Maximum distance of the right point from the left point's epipolar line, right-image pixels.
    pub max_epipolar_px: f64,
    /// Maximum ray gap (common perpendicular length), metres.
    pub max_ray_gap: f64,
    /// Accepted depth range along the left optical axis, metres.
    pub min_depth: f64,
    /// Accepted depth range along the left optical axis, metres.
    pub max_depth: f64,
    /// At most this many blobs per camera are considered (the brightest first is the caller's job).
    pub max_blobs_per_camera: usize,
    /// Blob-centroid noise in pixels; when positive each candidate gets a 3D covariance by
    /// propagating it through the triangulation (numerical Jacobian, 4 extra solves).
    pub pixel_sigma: f64,
}

impl Default for CorrespondenceConfig {
    fn default() -> Self {
        Self {
            max_epipolar_px: 3.0,
            max_ray_gap: 0.008,
            min_depth: 0.1,
            max_depth: 5.0,
            max_blobs_per_camera: 8,
            pixel_sigma: 0.5,
        }
    }
}

/// One surviving left/right pairing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// Index of the left blob.
    pub left: usize,
    /// Index of the right blob.
    pub right: usize,
    /// Triangulated point (world frame).
    pub point: Vector3<f64>,
    /// Ray gap, metres.
    pub ray_gap: f64,
    /// Epipolar distance, pixels.
    pub epipolar_px: f64,
    /// Covariance of `point` from the blob noise (zero when not computed), m^2.
    pub covariance: Matrix3<f64>,
}

impl Candidate {
    /// A candidate at a known point with no measurement details (tests, synthetic input).
    pub fn at(left: usize, right: usize, point: Vector3<f64>) -> Self {
        Self {
            left,
            right,
            point,
            ray_gap: 0.0,
            epipolar_px: 0.0,
            covariance: Matrix3::zeros(),
        }
    }

    fn new(left: usize, right: usize, t: &Triangulated, epipolar_px: f64) -> Self {
        Self {
            left,
            right,
            point: t.point,
            ray_gap: t.ray_gap,
            epipolar_px,
            covariance: Matrix3::zeros(),
        }
    }
}

/// Covariance of the triangulated point for isotropic image noise `sigma` (normalised units,
/// left and right), by finite differences of the triangulation.
pub(crate) fn covariance(
    tr: &Triangulator,
    ml: [f64; 2],
    mr: [f64; 2],
    p: &Vector3<f64>,
    sigma: [f64; 2],
) -> Matrix3<f64> {
    let h = 1e-7;
    let mut cov = Matrix3::zeros();
    for k in 0..4 {
        let (mut l, mut r) = (ml, mr);
        if k < 2 {
            l[k] += h;
        } else {
            r[k - 2] += h;
        }
        let Ok(t) = tr.triangulate(l, r) else {
            continue;
        };
        let col = (t.point - p) / h * sigma[k / 2];
        cov += col * col.transpose();
    }
    cov
}

/// Reusable candidate list (no allocation per frame after warm-up).
#[derive(Debug, Clone, Default)]
pub struct Correspondences {
    /// The candidates of the last call.
    pub candidates: Vec<Candidate>,
}

impl Correspondences {
    /// Computes all gated candidates between normalised left and right points.
    pub fn compute(
        &mut self,
        rig: &StereoRig,
        triangulator: &Triangulator,
        config: &CorrespondenceConfig,
        left: &[[f64; 2]],
        right: &[[f64; 2]],
    ) -> &[Candidate] {
        self.candidates.clear();
        let n_l = left.len().min(config.max_blobs_per_camera);
        let n_r = right.len().min(config.max_blobs_per_camera);
        for (i, ml) in left.iter().enumerate().take(n_l) {
            for (j, mr) in right.iter().enumerate().take(n_r) {
                let epi = rig.epipolar_distance_px(*ml, *mr);
                if epi.is_nan() || epi > config.max_epipolar_px {
                    continue;
                }
                let Ok(t) = triangulator.triangulate(*ml, *mr) else {
                    continue;
                };
                if t.ray_gap > config.max_ray_gap
                    || t.depth_left < config.min_depth
                    || t.depth_left > config.max_depth
                {
                    continue;
                }
                let mut cand = Candidate::new(i, j, &t, epi);
                if config.pixel_sigma > 0.0 {
                    let sigma = [
                        config.pixel_sigma / rig.left.focal_px(),
                        config.pixel_sigma / rig.right.focal_px(),
                    ];
                    cand.covariance = covariance(triangulator, *ml, *mr, &t.point, sigma);
                }
                self.candidates.push(cand);
            }
        }
        &self.candidates
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stereo::{rig::CameraId, TriangulationMethod};

    #[test]
    fn true_pairs_survive_and_far_off_pairs_are_gated() {
        let rig = StereoRig::parallel(1024, 768, 45f64.to_radians(), 0.25);
        let tr = Triangulator::new(&rig, TriangulationMethod::Midpoint);
        let pts = [Vector3::new(0.0, -0.1, 0.8), Vector3::new(0.05, 0.1, 0.85)];
        let norm = |cam, p: &Vector3<f64>| {
            rig.camera(cam)
                .undistort(rig.project(cam, p).unwrap())
                .unwrap()
        };
        let left: Vec<_> = pts.iter().map(|p| norm(CameraId::Left, p)).collect();
        let right: Vec<_> = pts.iter().rev().map(|p| norm(CameraId::Right, p)).collect();
        let mut c = Correspondences::default();
        let cands = c.compute(&rig, &tr, &CorrespondenceConfig::default(), &left, &right);
        assert_eq!(cands.len(), 2);
        assert!(cands.iter().all(|c| c.left + c.right == 1));
        assert!(cands.iter().all(|c| c.ray_gap < 1e-9));
    }
}
