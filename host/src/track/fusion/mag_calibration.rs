//! Online hard-iron calibration of the magnetometer: a sphere fit to the raw readings
//! (psmoveapi's "Possible Yaw Drift", issue #442, was fixed by magnetometer
//! calibration; there the user runs `psmove calibrate`, here the session's own motion is used).
//!
//! The pen's board (battery, Bluetooth module, traces) adds a constant field `h` to the Earth's
//! field, so the readings `m_i` lie on a sphere `|m_i - h| = B` around `h` instead of the origin;
//! uncorrected, the heading error changes with the pen's orientation (up to `asin(|h| / B_h)`,
//! `B_h` the horizontal field). The fit is linear in `p = (h, B² - |h|²)`:
//! `|m_i|² = 2 m_iᵀ h + (B² - |h|²)`, so it runs on running sums (normal equations) in constant
//! memory. The offset is accepted only when the readings span the sphere well: drawing moves
//! the pen within a cone, which leaves the sphere's centre along the cone's axis undetermined,
//! and a soft-iron distortion would then bias it; so the least-varied direction of the readings
//! must spread by `min_spread` of `B`, and the offset must be known to `target_sigma` of `B`.
//! Soft iron (a few per cent) is not modelled.

use nalgebra::{Matrix3, Matrix4, SymmetricEigen, Vector3, Vector4};

/// When the offset is estimated and accepted.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MagCalibrationConfig {
    /// Run the calibration (otherwise readings are used as they are).
    pub enabled: bool,
    /// Smallest standard deviation of the readings along their least-varied direction, as a
    /// fraction of the field magnitude.
    pub min_spread: f64,
    /// Required standard deviation of the offset along its worst direction, as a fraction of
    /// the field magnitude.
    pub target_sigma: f64,
    /// Fewest readings before a fit.
    pub min_samples: usize,
    /// Readings between two fits.
    pub solve_every: usize,
}

impl Default for MagCalibrationConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            min_spread: 0.25,
            target_sigma: 0.02,
            min_samples: 300,
            solve_every: 100,
        }
    }
}

/// An accepted hard-iron offset.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MagOffset {
    /// The offset `h`, in the readings' unit.
    pub hard_iron: [f64; 3],
    /// Field magnitude `B` after removing the offset.
    pub field: f64,
    /// Standard deviation of `h` along its worst direction, as a fraction of `B`.
    pub sigma: f64,
    /// Readings behind the fit.
    pub samples: usize,
}

impl MagOffset {
    /// A reading with the offset removed.
    pub fn correct(&self, m: &Vector3<f64>) -> Vector3<f64> {
        m - Vector3::from(self.hard_iron)
    }
}

/// Running sums of the sphere fit and the accepted offset.
#[derive(Debug, Clone)]
pub struct MagCalibrator {
    config: MagCalibrationConfig,
    n: usize,
    /// `Σ r rᵀ`, `Σ r y`, `Σ y²` with `r = (2m, 1)`, `y = |m|²`.
    normal: Matrix4<f64>,
    rhs: Vector4<f64>,
    yy: f64,
    /// `Σ m`, `Σ m mᵀ` for the spread of the readings.
    sum: Vector3<f64>,
    scatter: Matrix3<f64>,
    since_fit: usize,
    offset: Option<MagOffset>,
}

impl MagCalibrator {
    /// A calibrator with no readings.
    pub fn new(config: MagCalibrationConfig) -> Self {
        Self {
            config,
            n: 0,
            normal: Matrix4::zeros(),
            rhs: Vector4::zeros(),
            yy: 0.0,
            sum: Vector3::zeros(),
            scatter: Matrix3::zeros(),
            since_fit: 0,
            offset: None,
        }
    }

    /// The accepted offset, if any.
    pub fn offset(&self) -> Option<&MagOffset> {
        self.offset.as_ref()
    }

    /// Adds a raw reading; returns the offset when this reading made the first one acceptable.
    pub fn push(&mut self, m: &Vector3<f64>) -> Option<MagOffset> {
        if !self.config.enabled || !m.iter().all(|v| v.is_finite()) || self.offset.is_some() {
            return None;
        }
        let y = m.norm_squared();
        let r = Vector4::new(2.0 * m.x, 2.0 * m.y, 2.0 * m.z, 1.0);
        self.normal += r * r.transpose();
        self.rhs += r * y;
        self.yy += y * y;
        self.sum += m;
        self.scatter += m * m.transpose();
        self.n += 1;
        self.since_fit += 1;
        if self.n < self.config.min_samples || self.since_fit < self.config.solve_every {
            return None;
        }
        self.since_fit = 0;
        self.offset = self.solve();
        self.offset
    }

    /// The sphere fit, if it passes the spread and precision tests.
    fn solve(&self) -> Option<MagOffset> {
        let n = self.n as f64;
        let chol = self.normal.cholesky()?;
        let p = chol.solve(&self.rhs);
        let h = Vector3::new(p[0], p[1], p[2]);
        let b2 = p[3] + h.norm_squared();
        if !(b2.is_finite() && b2 > 0.0) {
            return None;
        }
        let field = b2.sqrt();
        let mean = self.sum / n;
        let covariance = self.scatter / n - mean * mean.transpose();
        let spread2 = SymmetricEigen::new(covariance).eigenvalues.min();
        if spread2 < (self.config.min_spread * field).powi(2) {
            return None;
        }
        // Residual variance of y and the covariance of p = σ² N⁻¹.
        let rss = (self.yy - 2.0 * p.dot(&self.rhs) + p.dot(&(self.normal * p))).max(0.0);
        let sigma2 = rss / (n - 4.0).max(1.0);
        let inverse = chol.inverse();
        let cov_h = inverse.fixed_view::<3, 3>(0, 0).into_owned() * sigma2;
        let worst = SymmetricEigen::new(cov_h).eigenvalues.max().max(0.0).sqrt() / field;
        (worst <= self.config.target_sigma).then_some(MagOffset {
            hard_iron: h.into(),
            field,
            sigma: worst,
            samples: self.n,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::synth::SplitMix64;
    use nalgebra::UnitQuaternion;

    /// Readings of a 47 µT field with a hard-iron offset and 0.25 µT noise, the pen's orientation
    /// drawn from `orientation`.
    fn feed(
        cal: &mut MagCalibrator,
        h: Vector3<f64>,
        samples: usize,
        rng: &mut SplitMix64,
        orientation: impl Fn(&mut SplitMix64) -> UnitQuaternion<f64>,
    ) -> Option<MagOffset> {
        let earth = Vector3::new(0.0, 23.5, 40.7);
        let mut accepted = None;
        for _ in 0..samples {
            let q = orientation(rng);
            let noise = Vector3::new(rng.gaussian(), rng.gaussian(), rng.gaussian()) * 0.25;
            let m = q.inverse() * earth + h + noise;
            if let Some(o) = cal.push(&m) {
                accepted = Some(o);
            }
        }
        accepted
    }

    #[test]
    fn a_pen_turned_every_way_gives_the_offset() {
        let h = Vector3::new(30.0, -12.0, 55.0);
        let mut cal = MagCalibrator::new(MagCalibrationConfig::default());
        let mut rng = SplitMix64::new(5);
        let o = feed(&mut cal, h, 2000, &mut rng, |r| r.rotation()).expect("accepted");
        let err = (Vector3::from(o.hard_iron) - h).norm();
        assert!(err < 0.5, "offset error {err} µT");
        assert!((o.field - 47.0).abs() < 0.5, "field {}", o.field);
        assert!(o.samples <= 400, "accepted early: {}", o.samples);
        let corrected = o.correct(&(Vector3::new(0.0, 47.0, 0.0) + h));
        assert!((corrected - Vector3::new(0.0, 47.0, 0.0)).norm() < 0.5);
    }

    #[test]
    fn a_pen_held_in_a_narrow_cone_gives_none() {
        // Drawing: the axis stays within 20 degrees of one direction with little roll: the
        // readings cover a small patch of the sphere.
        let mut cal = MagCalibrator::new(MagCalibrationConfig::default());
        let mut rng = SplitMix64::new(6);
        let cone = |r: &mut SplitMix64| {
            let tilt = UnitQuaternion::from_euler_angles(0.0, r.uniform(-0.35, 0.35), 0.0);
            tilt * UnitQuaternion::from_euler_angles(r.uniform(-0.1, 0.1), 0.0, 0.0)
        };
        let h = Vector3::new(10.0, 5.0, -8.0);
        assert!(feed(&mut cal, h, 5000, &mut rng, cone).is_none());
        assert!(cal.offset().is_none());
    }
}
