//! The image-evidence checks of [`Identifier::identify_with_images`]: the labelled pen predicts
//! where all four LEDs project in each camera; an unused blob on the predicted pen segment away
//! from every predicted LED, or four labelled blobs whose cross-ratio is not the pen's, contradict
//! the labelling.

use super::{Identification, Identifier, IdentifyError, IdentifyPrior};
use crate::stereo::Candidate;
use crate::track::line_fit::{labelled_direction, principal_axis};
use crate::track::pen::LED_COUNT;
use nalgebra::Vector3;

/// Rig terms for projecting predicted LEDs into normalised image coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct ImageGeometry {
    /// Rotation of the right camera from the left (world) frame.
    pub(super) r: nalgebra::Matrix3<f64>,
    /// Translation of the right camera from the left frame, metres.
    pub(super) t: Vector3<f64>,
    /// Focal lengths of the left and right camera, pixels.
    pub(super) focal: [f64; 2],
}

impl Identifier {
    /// As [`Self::identify`], then checks the labelling against all blobs of both images
    /// (undistorted normalised coordinates, indexed as in the candidates): the labelled pen predicts
    /// where all four LEDs project; an unused blob lying on the predicted pen segment but away from
    /// every predicted LED contradicts the labelling. This exposes "ghost pens" made of wrong
    /// left/right pairings of collinear LEDs (which share epipolar lines when the pen is parallel
    /// to the baseline).
    pub fn identify_with_images(
        &mut self,
        candidates: &[Candidate],
        prior: &IdentifyPrior,
        left: &[[f64; 2]],
        right: &[[f64; 2]],
    ) -> Result<Identification, IdentifyError> {
        let id = self.identify(candidates, prior)?;
        if self.image_consistent(candidates, &id, [left, right]) {
            Ok(id)
        } else {
            self.refused_by = Some(super::RefusedBy::ImageEvidence);
            Err(IdentifyError::ContradictedByImage)
        }
    }

    /// With four labelled LEDs, the cross-ratio of their blobs along the image line must match
    /// the pen's (a projective invariant, see `cross_ratio_fits`); checked when the pen spans at
    /// least 40 px in that image.
    #[allow(clippy::too_many_arguments)]
    fn image_cross_ratio_ok(
        &self,
        cands: &[Candidate],
        id: &Identification,
        cam: usize,
        blobs: &[[f64; 2]],
        origin: &[f64; 2],
        d: &[f64; 2],
        span_px: f64,
    ) -> bool {
        if id.count() < LED_COUNT || span_px < 40.0 {
            return true;
        }
        let mut s = [0.0; LED_COUNT];
        for (i, k) in id.assignment.iter().enumerate() {
            let Some(k) = k else { return true };
            let idx = if cam == 0 {
                cands[*k].left
            } else {
                cands[*k].right
            };
            let Some(b) = blobs.get(idx) else { return true };
            s[i] = (b[0] - origin[0]) * d[0] + (b[1] - origin[1]) * d[1];
        }
        self.cross_ratio_fits(s, self.config.image_cross_ratio_tolerance)
    }

    /// True when every unused finite blob near the labelled pen's predicted image line lies near
    /// a predicted LED and the image cross-ratio fits, in both cameras (true without a rig).
    fn image_consistent(
        &self,
        cands: &[Candidate],
        id: &Identification,
        blobs: [&[[f64; 2]]; 2],
    ) -> bool {
        let Some(g) = &self.geometry else { return true };
        let l = &self.pen.led_offsets;
        let n = id.count() as f64;
        let Some(centroid) = id
            .points
            .iter()
            .flatten()
            .copied()
            .reduce(|a, b| a + b)
            .map(|s| s / n)
        else {
            return true;
        };
        let Some(v) = principal_axis(&id.points, &centroid) else {
            return true;
        };
        let v = if labelled_direction(&id.points).is_some_and(|d| d.dot(&v) < 0.0) {
            -v
        } else {
            v
        };
        let labels = || (0..LED_COUNT).filter(|&i| id.assignment[i].is_some());
        let c_h = labels().map(|i| l[i]).sum::<f64>() / n;
        let spread = labels().map(|i| l[i]).fold(f64::NEG_INFINITY, f64::max)
            - labels().map(|i| l[i]).fold(f64::INFINITY, f64::min);
        let predicted: [Vector3<f64>; LED_COUNT] =
            std::array::from_fn(|i| centroid + v * (c_h - l[i]));
        for (cam, blob_list) in blobs.iter().enumerate() {
            let used = |b: usize| {
                id.assignment.iter().flatten().any(|&k| {
                    if cam == 0 {
                        cands[k].left == b
                    } else {
                        cands[k].right == b
                    }
                })
            };
            let proj: Option<Vec<[f64; 2]>> = predicted
                .iter()
                .map(|p| {
                    let q = if cam == 0 { *p } else { g.r * p + g.t };
                    (q.z > 1e-6).then(|| [q.x / q.z, q.y / q.z])
                })
                .collect();
            let Some(m) = proj else { continue };
            let f = g.focal[cam];
            let d = [m[3][0] - m[0][0], m[3][1] - m[0][1]];
            let len = d[0].hypot(d[1]);
            if len * f < 3.0 {
                continue;
            }
            if !self.image_cross_ratio_ok(cands, id, cam, blob_list, &m[0], &d, len * f) {
                return false;
            }
            for (b, blob) in blob_list.iter().enumerate() {
                if used(b) || !blob.iter().all(|v| v.is_finite()) {
                    continue;
                }
                let rel = [blob[0] - m[0][0], blob[1] - m[0][1]];
                let along = (rel[0] * d[0] + rel[1] * d[1]) / (len * len);
                let perp_px = (rel[0] * d[1] - rel[1] * d[0]).abs() / len * f;
                // The line is searched one pen length beyond either end (in units of the LED
                // 1-4 image segment): a labelling shifted by one LED leaves the real end LED
                // there, and perspective can put it past 1.6 when the pen recedes.
                if perp_px > self.config.image_line_px || !(-1.0..=2.0).contains(&along) {
                    continue;
                }
                let near_led = (0..LED_COUNT).any(|i| {
                    let radius =
                        self.config.image_match_px * (1.0 + (l[i] - c_h).abs() / spread.max(1e-6));
                    (blob[0] - m[i][0]).hypot(blob[1] - m[i][1]) * f <= radius
                });
                if !near_led {
                    return false;
                }
            }
        }
        true
    }
}
