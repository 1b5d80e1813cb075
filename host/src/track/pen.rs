//! Pen geometry (FIRES thesis, §4.1.2, eq. 4.11 and Fig. 4.3): four collinear LEDs at axial positions
//! `l = (0, d1, d1+d2, d1+d2+d3)` measured from LED 1 (nearest the tip) towards the back, and the
//! tip `T` metres ahead of LED 1. In the pen frame +x points from the back towards the tip, so LED `i`
//! sits at `x = -l_i` and the tip at `x = +T`.

use nalgebra::{UnitQuaternion, Vector3};
use thiserror::Error;

/// Number of LEDs on the pen.
pub const LED_COUNT: usize = 4;

/// Invalid pen geometry.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum PenError {
    /// An LED offset or the tip offset is not a finite number.
    #[error("LED and tip offsets must be finite numbers")]
    NotFinite,
    /// LED offsets must start at 0 and increase strictly.
    #[error("LED offsets must be 0 followed by strictly increasing values")]
    NotIncreasing,
    /// Two of the six pairwise LED distances differ by less than twice the matching tolerance:
    /// identification by distances (FIRES thesis, §4.1.2, which needs all six to differ) would be
    /// ambiguous.
    #[error("pairwise LED distances {0} m and {1} m are closer than twice the tolerance")]
    DistancesTooClose(f64, f64),
}

/// LED layout and tip offset of the pen, metres.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PenGeometry {
    /// Axial LED positions from LED 1 towards the back (`l_1 = 0`).
    pub led_offsets: [f64; LED_COUNT],
    /// Distance from LED 1 to the physical tip, towards the tip (`T`; 0 in the thesis experiment).
    pub tip_offset: f64,
}

impl Default for PenGeometry {
    fn default() -> Self {
        Self::thesis()
    }
}

impl PenGeometry {
    /// The thesis pen: spacings 70/40/50 mm, tip at LED 1.
    pub fn thesis() -> Self {
        Self {
            led_offsets: [0.0, 0.070, 0.110, 0.160],
            tip_offset: 0.0,
        }
    }

    /// Distance between LEDs `a` and `b` (0-based).
    pub fn distance(&self, a: usize, b: usize) -> f64 {
        (self.led_offsets[a] - self.led_offsets[b]).abs()
    }

    /// The six LED pairs `(a, b)` with `a < b`.
    pub fn pairs() -> [(usize, usize); 6] {
        [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    }

    /// Checks the geometry can be identified by distances with matching tolerance `tolerance`
    /// ([`super::identify::IdentifyConfig::tolerance`]): finite offsets, LED offsets 0 then strictly
    /// increasing, and no two of the six pairwise distances closer than `2 * tolerance`.
    pub fn validate(&self, tolerance: f64) -> Result<(), PenError> {
        let l = &self.led_offsets;
        if !self.tip_offset.is_finite() || l.iter().any(|v| !v.is_finite()) {
            return Err(PenError::NotFinite);
        }
        if l[0] != 0.0 || !l.windows(2).all(|w| w[1] > w[0]) {
            return Err(PenError::NotIncreasing);
        }
        let pairs = Self::pairs();
        for (i, &(a, b)) in pairs.iter().enumerate() {
            for &(c, d) in &pairs[i + 1..] {
                let (x, y) = (self.distance(a, b), self.distance(c, d));
                if (x - y).abs() < 2.0 * tolerance {
                    return Err(PenError::DistancesTooClose(x, y));
                }
            }
        }
        Ok(())
    }

    /// The projective cross-ratio of the four LED positions, `((l3-l1)(l4-l2)) / ((l3-l2)(l4-l1))`.
    pub fn cross_ratio(&self) -> f64 {
        cross_ratio_1d(self.led_offsets)
    }

    /// World positions of the four LEDs for a pen whose LED 1 is at `led1` with world-from-pen rotation `q`.
    pub fn led_positions(
        &self,
        led1: &Vector3<f64>,
        q: &UnitQuaternion<f64>,
    ) -> [Vector3<f64>; LED_COUNT] {
        let v = q * Vector3::x();
        self.led_offsets.map(|l| led1 - v * l)
    }

    /// World position of the tip for a pen whose LED 1 is at `led1` with world-from-pen rotation `q`.
    pub fn tip_position(&self, led1: &Vector3<f64>, q: &UnitQuaternion<f64>) -> Vector3<f64> {
        led1 + (q * Vector3::x()) * self.tip_offset
    }
}

/// Cross-ratio `((s3-s1)(s4-s2)) / ((s3-s2)(s4-s1))` of four ordered collinear coordinates.
pub fn cross_ratio_1d(s: [f64; 4]) -> f64 {
    ((s[2] - s[0]) * (s[3] - s[1])) / ((s[2] - s[1]) * (s[3] - s[0]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thesis_pen_is_identifiable_below_5mm() {
        let pen = PenGeometry::thesis();
        assert!(pen.validate(0.0049).is_ok());
        let mut inf = pen;
        inf.led_offsets[3] = f64::INFINITY;
        assert_eq!(inf.validate(0.0049), Err(PenError::NotFinite));
        assert!(matches!(
            pen.validate(0.0051),
            Err(PenError::DistancesTooClose(..))
        ));
        let mut d: Vec<f64> = PenGeometry::pairs()
            .iter()
            .map(|&(a, b)| pen.distance(a, b) * 1000.0)
            .collect();
        d.sort_by(f64::total_cmp);
        let expect = [40.0, 50.0, 70.0, 90.0, 110.0, 160.0];
        assert!(d.iter().zip(expect).all(|(a, b)| (a - b).abs() < 1e-9));
    }
}
