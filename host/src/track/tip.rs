//! Pen-tip estimation (FIRES thesis, §4.1.2, eqs. 4.11-4.13).
//!
//! For each of the 11 visibility patterns (`Σδ_i >= 2`) the scalar centroid
//! `C = Σ l_i δ_i / Σ δ_i` (eq. 4.12) is precomputed. Per frame,
//! `p_tip = C' + v_pen (C + T)` (eq. 4.13) with `C'` the 3D centroid of the identified LEDs and
//! `v_pen` the unit pen direction towards the tip: the normalised difference for two LEDs, the
//! least-squares (principal) axis for three or four ([`super::line_fit`]), its sign fixed by the
//! labels. A fused direction can replace `v_pen` ([`TipEstimator::estimate_with_direction`]).

use super::line_fit::{labelled_direction, principal_axis};
use super::pen::{PenGeometry, LED_COUNT};
use nalgebra::Vector3;
use thiserror::Error;

/// Why no tip could be computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum TipError {
    /// Fewer than two LEDs identified.
    #[error("fewer than two identified LEDs")]
    TooFewLeds,
    /// The identified points coincide or the direction is not finite.
    #[error("degenerate LED configuration")]
    Degenerate,
}

/// One tip estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TipEstimate {
    /// Tip position, world frame, metres.
    pub tip: Vector3<f64>,
    /// Unit pen direction used (towards the tip).
    pub direction: Vector3<f64>,
    /// 3D centroid `C'` of the identified LEDs.
    pub centroid: Vector3<f64>,
    /// Visibility pattern (bit i = LED i+1).
    pub pattern: u8,
}

/// Tip estimator with the per-pattern constants of eq. 4.12 precomputed.
#[derive(Debug, Clone)]
pub struct TipEstimator {
    /// `C + T` per pattern mask (None for patterns with < 2 LEDs).
    offsets: [Option<f64>; 16],
    centroids: [Option<f64>; 16],
}

impl TipEstimator {
    /// Precomputes `C` (eq. 4.12) and `C + T` for the 11 patterns.
    pub fn new(pen: &PenGeometry) -> Self {
        let mut offsets = [None; 16];
        let mut centroids = [None; 16];
        for mask in 0u8..16 {
            let n = mask.count_ones();
            if n < 2 {
                continue;
            }
            let sum: f64 = (0..LED_COUNT)
                .filter(|i| mask & (1 << i) != 0)
                .map(|i| pen.led_offsets[i])
                .sum();
            let c = sum / f64::from(n);
            centroids[mask as usize] = Some(c);
            offsets[mask as usize] = Some(c + pen.tip_offset);
        }
        Self { offsets, centroids }
    }

    /// The precomputed scalar centroid `C` for a pattern (metres along the axis from LED 1).
    pub fn pattern_centroid(&self, mask: u8) -> Option<f64> {
        self.centroids.get(mask as usize).copied().flatten()
    }

    /// Eq. 4.13 with the least-squares pen axis.
    pub fn estimate(
        &self,
        pts: &[Option<Vector3<f64>>; LED_COUNT],
    ) -> Result<TipEstimate, TipError> {
        let (mask, centroid) = centroid_of(pts)?;
        let sign_ref = labelled_direction(pts).ok_or(TipError::Degenerate)?;
        let direction = if mask.count_ones() == 2 {
            sign_ref
        } else {
            let axis = principal_axis(pts, &centroid).ok_or(TipError::Degenerate)?;
            if axis.dot(&sign_ref) < 0.0 {
                -axis
            } else {
                axis
            }
        };
        self.finish(mask, centroid, direction)
    }

    /// Eq. 4.13 with an externally supplied (e.g. fused) direction; it is normalised and its sign
    /// aligned with the labels.
    pub fn estimate_with_direction(
        &self,
        pts: &[Option<Vector3<f64>>; LED_COUNT],
        direction: &Vector3<f64>,
    ) -> Result<TipEstimate, TipError> {
        let (mask, centroid) = centroid_of(pts)?;
        let mut v = direction.try_normalize(1e-12).ok_or(TipError::Degenerate)?;
        if let Some(s) = labelled_direction(pts) {
            if v.dot(&s) < 0.0 {
                v = -v;
            }
        }
        self.finish(mask, centroid, v)
    }

    fn finish(
        &self,
        mask: u8,
        centroid: Vector3<f64>,
        direction: Vector3<f64>,
    ) -> Result<TipEstimate, TipError> {
        let offset = self.offsets[mask as usize].ok_or(TipError::TooFewLeds)?;
        let tip = centroid + direction * offset;
        if !tip.iter().all(|v| v.is_finite()) {
            return Err(TipError::Degenerate);
        }
        Ok(TipEstimate {
            tip,
            direction,
            centroid,
            pattern: mask,
        })
    }
}

fn centroid_of(pts: &[Option<Vector3<f64>>; LED_COUNT]) -> Result<(u8, Vector3<f64>), TipError> {
    let mut mask = 0u8;
    let mut sum = Vector3::zeros();
    for (i, p) in pts.iter().enumerate() {
        if let Some(p) = p {
            mask |= 1 << i;
            sum += p;
        }
    }
    let n = mask.count_ones();
    if n < 2 {
        return Err(TipError::TooFewLeds);
    }
    Ok((mask, sum / f64::from(n)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::synth::{PenPose, SplitMix64};

    #[test]
    fn stored_centroids_match_the_thesis_table() {
        let est = TipEstimator::new(&PenGeometry::thesis());
        let table = [
            (0b0011, 35.0),
            (0b0101, 55.0),
            (0b1001, 80.0),
            (0b0110, 90.0),
            (0b1010, 115.0),
            (0b1100, 135.0),
            (0b0111, 60.0),
            (0b1011, 76.666_666_666),
            (0b1101, 90.0),
            (0b1110, 113.333_333_333),
            (0b1111, 85.0),
        ];
        for (mask, c) in table {
            assert!(
                (est.pattern_centroid(mask).unwrap() * 1000.0 - c).abs() < 1e-6,
                "{mask:b}"
            );
        }
        assert!(est.pattern_centroid(0b0100).is_none());
    }

    #[test]
    fn exact_on_noise_free_data_for_all_patterns() {
        let mut rng = SplitMix64::new(5);
        let pen = PenGeometry {
            led_offsets: [0.0, 0.07, 0.11, 0.16],
            tip_offset: 0.021,
        };
        let est = TipEstimator::new(&pen);
        for _ in 0..50 {
            let pose = PenPose::random(&mut rng, 0.3, 1.5, 1.5);
            let leds = pen.led_positions(&pose.led1, &pose.rotation);
            let truth = pen.tip_position(&pose.led1, &pose.rotation);
            for mask in 3u8..16 {
                if mask.count_ones() < 2 {
                    continue;
                }
                let pts = std::array::from_fn(|i| (mask & (1 << i) != 0).then_some(leds[i]));
                let e = est.estimate(&pts).unwrap();
                assert!((e.tip - truth).norm() < 1e-9, "{mask:b}");
                assert!((e.direction - pose.direction()).norm() < 1e-9);
                let f = est
                    .estimate_with_direction(&pts, &-pose.direction())
                    .unwrap();
                assert!((f.tip - truth).norm() < 1e-9);
            }
        }
        assert_eq!(
            est.estimate(&[None, Some(Vector3::x()), None, None]),
            Err(TipError::TooFewLeds)
        );
        assert_eq!(
            est.estimate(&[Some(Vector3::x()), Some(Vector3::x()), None, None]),
            Err(TipError::Degenerate)
        );
    }
}
