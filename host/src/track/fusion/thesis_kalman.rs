//! The thesis's Kalman fusion model, exactly as eqs. 4.18-4.21 (FIRES thesis, §4.1.4,
//! corrected so that eq. 4.21 measures the state at time t, as its text says).
//!
//! State `x = [α_θ, α_γ, ω_θ, ω_γ]` (eq. 4.20): two pen-direction angles and their rates, with
//! `A = [[1,0,dt,0],[0,1,0,dt],[0,0,1,0],[0,0,0,1]]` (constant angular rate, eq. 4.18) and
//! measurement `z = [α^v_θ, α^v_γ, α^a_θ, α^a_γ]` with `H = [[1,0,0,0],[0,1,0,0],[1,0,0,0],[0,1,0,0]]`
//! (eqs. 4.19, 4.21): the direction seen by vision and the direction from the inertial sensors.
//! The standard predict/update equations are used; the vision rows and the inertial rows can be
//! applied separately (partial H) because the camera and the IMU are asynchronous.
//!
//! Decisions the thesis leaves open, and ours: the angles are elevation
//! `θ = asin(v·up)` and azimuth `γ` about "up" from magnetic north (azimuth innovations wrap);
//! the inertial direction comes from accelerometer + magnetometer (TRIAD); the gyroscope is not a
//! measurement (as in the thesis, ω is inferred through the dynamics only); `Q = diag(q_α dt,
//! q_α dt, q_ω dt, q_ω dt)`. The model has no timestamps of its own: a late vision measurement is
//! applied at the filter's current time, as the thesis pipeline would.

use super::imu::{ImuSample, WorldReference};
use super::DirectionFilter;
use nalgebra::{Matrix2, Matrix2x4, Matrix4, Vector2, Vector3, Vector4};
use std::f64::consts::PI;

/// Noise parameters of the thesis filter.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ThesisKalmanConfig {
    /// Angle process noise density `Q_α`, rad^2/s.
    pub q_angle: f64,
    /// Rate process noise density `Q_ω`, rad^2/s^3.
    pub q_rate: f64,
    /// Vision angle measurement variance `R_v`, rad^2.
    pub r_vision: f64,
    /// Inertial (accelerometer + magnetometer) angle measurement variance `R_a`, rad^2.
    pub r_inertial: f64,
    /// Initial (diffuse) state variance.
    pub initial_variance: f64,
}

impl Default for ThesisKalmanConfig {
    fn default() -> Self {
        Self {
            q_angle: 1e-4,
            q_rate: 4.0,
            r_vision: 1e-4,
            r_inertial: 3e-3,
            initial_variance: 1e6,
        }
    }
}

/// The 4-state filter of eqs. 4.18-4.21.
#[derive(Debug, Clone)]
pub struct ThesisKalman {
    /// Configuration.
    pub config: ThesisKalmanConfig,
    world: WorldReference,
    x: Vector4<f64>,
    p: Matrix4<f64>,
    t_ns: Option<u64>,
    updated: bool,
}

/// `H` of eq. 4.21 restricted to one measurement pair: both pairs observe the two angles.
fn h_pair() -> Matrix2x4<f64> {
    Matrix2x4::new(1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0)
}

fn wrap(a: f64) -> f64 {
    (a + PI).rem_euclid(2.0 * PI) - PI
}

impl ThesisKalman {
    /// A filter with a diffuse prior.
    pub fn new(config: ThesisKalmanConfig, world: WorldReference) -> Self {
        Self {
            config,
            world,
            x: Vector4::zeros(),
            p: Matrix4::identity() * config.initial_variance,
            t_ns: None,
            updated: false,
        }
    }

    /// The state `[α_θ, α_γ, ω_θ, ω_γ]`.
    pub fn state(&self) -> &Vector4<f64> {
        &self.x
    }

    /// The state covariance.
    pub fn covariance(&self) -> &Matrix4<f64> {
        &self.p
    }

    /// The transition matrix `A` of eq. 4.20.
    pub fn transition(dt: f64) -> Matrix4<f64> {
        let mut a = Matrix4::identity();
        a[(0, 2)] = dt;
        a[(1, 3)] = dt;
        a
    }

    /// Predict step: `x = A x`, `P = A P A^T + Q`.
    pub fn predict(&mut self, dt: f64) {
        if dt.is_nan() || dt <= 0.0 {
            return;
        }
        let a = Self::transition(dt);
        self.x = a * self.x;
        self.x[1] = wrap(self.x[1]);
        let c = &self.config;
        let q =
            Matrix4::from_diagonal(&Vector4::new(c.q_angle, c.q_angle, c.q_rate, c.q_rate)) * dt;
        self.p = a * self.p * a.transpose() + q;
    }

    /// Update with the vision rows and/or the inertial rows of `H` (eq. 4.21).
    pub fn update(&mut self, vision: Option<[f64; 2]>, inertial: Option<[f64; 2]>) {
        if let Some(z) = vision {
            self.update_pair(z, self.config.r_vision);
        }
        if let Some(z) = inertial {
            self.update_pair(z, self.config.r_inertial);
        }
    }

    /// One 2-row update; sequential updates equal the joint 4-row update because the two
    /// measurement noises are independent.
    fn update_pair(&mut self, z: [f64; 2], r: f64) {
        if !(z[0].is_finite() && z[1].is_finite()) {
            return;
        }
        let h = h_pair();
        let mut innovation = Vector2::from(z) - h * self.x;
        innovation[1] = wrap(innovation[1]);
        let s = h * self.p * h.transpose() + Matrix2::identity() * r;
        let Some(s_inv) = s.try_inverse() else { return };
        let k = self.p * h.transpose() * s_inv;
        self.x += k * innovation;
        self.x[1] = wrap(self.x[1]);
        self.p = (Matrix4::identity() - k * h) * self.p;
        self.p = 0.5 * (self.p + self.p.transpose());
        self.updated = true;
    }

    /// Elevation/azimuth of a direction in the world frame.
    pub fn angles(&self, v: &Vector3<f64>) -> Option<[f64; 2]> {
        let v = v.try_normalize(1e-12)?;
        let (up, north, east) = self.horizontal_basis();
        let theta = v.dot(&up).clamp(-1.0, 1.0).asin();
        let gamma = v.dot(&east).atan2(v.dot(&north));
        Some([theta, gamma])
    }

    /// Direction of elevation/azimuth angles.
    pub fn direction(&self, angles: [f64; 2]) -> Vector3<f64> {
        let (up, north, east) = self.horizontal_basis();
        let (st, ct) = angles[0].sin_cos();
        let (sg, cg) = angles[1].sin_cos();
        up * st + (north * cg + east * sg) * ct
    }

    fn horizontal_basis(&self) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
        let up = self.world.up();
        let m = self.world.magnetic();
        let north = (m - up * m.dot(&up))
            .try_normalize(1e-9)
            .unwrap_or_else(|| up.cross(&Vector3::x()).normalize());
        (up, north, up.cross(&north))
    }

    fn advance_to(&mut self, t_ns: u64) {
        match self.t_ns {
            Some(t0) if t_ns > t0 => self.predict((t_ns - t0) as f64 * 1e-9),
            Some(_) => return,
            None => {}
        }
        self.t_ns = Some(t_ns);
    }
}

impl DirectionFilter for ThesisKalman {
    fn imu(&mut self, s: &ImuSample) {
        self.advance_to(s.t_ns);
        let Some(q) = self
            .world
            .triad(&Vector3::from(s.accel), &Vector3::from(s.mag))
        else {
            return;
        };
        let z = self.angles(&(q * Vector3::x()));
        self.update(None, z);
    }

    fn vision(&mut self, t_ns: u64, direction: &Vector3<f64>, variance: Option<f64>) {
        self.advance_to(t_ns);
        let Some(z) = self.angles(direction) else {
            return;
        };
        // The measured variance (when given) replaces R_v, so both filters see the same noise.
        let r = variance
            .filter(|v| v.is_finite() && *v > 0.0)
            .unwrap_or(self.config.r_vision);
        self.update_pair(z, r);
    }

    fn direction_at(&self, t_ns: u64) -> Option<Vector3<f64>> {
        if !self.updated {
            return None;
        }
        let dt = self
            .t_ns
            .map_or(0.0, |t0| (t_ns as f64 - t0 as f64) * 1e-9)
            .clamp(-0.1, 0.1);
        Some(self.direction([self.x[0] + self.x[2] * dt, self.x[1] + self.x[3] * dt]))
    }

    fn orientation_at(&self, _t_ns: u64) -> Option<nalgebra::UnitQuaternion<f64>> {
        None
    }

    /// The angle state is defined by the world's horizontal basis: a new frame restarts it (the
    /// next IMU sample reinitialises it); a refined reference in the same frame is just taken.
    fn rebase(&mut self, new_from_old: &nalgebra::UnitQuaternion<f64>, world: WorldReference) {
        if new_from_old.angle() > 1e-9 {
            *self = Self::new(self.config, world);
        } else {
            self.world = world;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matrices_are_those_of_eq_4_20_and_4_21() {
        let a = ThesisKalman::transition(0.01);
        let expect = Matrix4::new(
            1.0, 0.0, 0.01, 0.0, 0.0, 1.0, 0.0, 0.01, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        );
        assert_eq!(a, expect);
        assert_eq!(
            h_pair(),
            Matrix2x4::new(1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0)
        );
    }

    #[test]
    fn two_equal_measurements_halve_the_variance() {
        let cfg = ThesisKalmanConfig {
            r_vision: 0.01,
            r_inertial: 0.01,
            ..Default::default()
        };
        let mut kf = ThesisKalman::new(cfg, WorldReference::default());
        kf.update(Some([0.2, 0.1]), Some([0.2, 0.1]));
        let var = kf.covariance()[(0, 0)];
        assert!((var - 0.005).abs() < 0.005 * 0.01, "{var}");
        // Static pen with Q > 0: steady-state variance below r/2.
        for _ in 0..2000 {
            kf.predict(0.01);
            kf.update(Some([0.2, 0.1]), Some([0.2, 0.1]));
        }
        assert!(kf.covariance()[(0, 0)] < 0.005);
    }

    #[test]
    fn constant_rate_is_tracked_without_lag() {
        let mut kf = ThesisKalman::new(ThesisKalmanConfig::default(), WorldReference::default());
        let rate = 0.5;
        let mut err = 0.0;
        for k in 0..3000 {
            let t = k as f64 * 0.01;
            kf.predict(0.01);
            let z = [0.1 + rate * t * 0.2, wrap(rate * t)];
            if k % 3 == 0 {
                kf.update(Some(z), None);
            } else {
                kf.update(None, Some(z));
            }
            err = (kf.state()[1] - z[1])
                .abs()
                .min(2.0 * PI - (kf.state()[1] - z[1]).abs());
        }
        assert!(err < 1e-6, "{err}");
        assert!((kf.state()[3] - rate).abs() < 1e-6);
    }

    #[test]
    fn angles_round_trip() {
        let kf = ThesisKalman::new(ThesisKalmanConfig::default(), WorldReference::default());
        let v = Vector3::new(0.3, -0.5, 0.8).normalize();
        let a = kf.angles(&v).unwrap();
        assert!((kf.direction(a) - v).norm() < 1e-12);
    }
}
