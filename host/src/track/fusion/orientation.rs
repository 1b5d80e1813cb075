//! The default direction filter: a Mahony-style nonlinear complementary filter on SO(3)
//! (as psmoveapi's complementary MARG filter and Monado's gravity-gated 3DoF tracker),
//! extended with vision corrections. It beats the thesis model (eqs. 4.18-4.21) because it
//! integrates the gyroscope instead of inferring the rate from the angle dynamics.
//!
//! State: world-from-pen quaternion `q` and gyro bias `b`. At every IMU sample (rate `ω`):
//! - gravity error `e_a = â × (q⁻¹ up)`, weighted down to zero as `|a|` departs from `g`
//!   (the hand's acceleration corrupts the gravity direction);
//! - heading error from the magnetometer, both vectors projected on the horizontal plane, so the
//!   magnetometer never tilts the estimate;
//! - `q ← q ⊗ exp((ω - b + k_a e_a + k_m e_m) dt)`, `b ← b - k_i e dt`.
//!
//! Vision: the pen direction `v` measured at the frame's exposure time `t_f` corrects the
//! orientation the filter had at `t_f` (from a short history), error `e_v = x̂ × (q(t_f)⁻¹ v)`
//! in the pen frame; the correction (a fraction `vision_gain` of it) is transported to the current
//! time and applied, and feeds the bias estimate. So late, out-of-order frames are handled
//! without rewinding the IMU (roll about the pen axis stays IMU-only, as it must with
//! collinear LEDs).

use super::imu::{ImuSample, WorldReference};
use super::DirectionFilter;
use nalgebra::{UnitQuaternion, Vector3};
use std::collections::VecDeque;

/// Gains of the complementary filter (a configuration that leaves a gain out gets its default).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct OrientationConfig {
    /// Gravity correction gain, 1/s.
    pub k_accel: f64,
    /// Magnetic heading correction gain, 1/s.
    pub k_mag: f64,
    /// Gyro bias integral gain, 1/s^2.
    pub k_bias: f64,
    /// Fraction of the vision direction error removed per frame when its variance is not given.
    pub vision_gain: f64,
    /// Growth of the axis variance between vision frames while the pen turns at `walk_rate` or
    /// faster, rad^2/s; with the vision variance it sets the vision gain (scalar Kalman filter).
    pub axis_random_walk: f64,
    /// The rate at which the axis variance grows at the full `axis_random_walk`, rad/s. Most of what
    /// that growth stands for grows with the rotation: the roll about the pen axis that vision cannot
    /// see (from gravity and the heading reference) turns the gyro's rates about the wrong axes, and
    /// scale and alignment errors scale with the rate. Below it the growth falls with the square of
    /// the rate to `rest_walk_fraction` of it, so a still pen averages its vision axes over longer:
    /// on `fires-v1` the tip at rest wandered 0.75 mm with the fused axis's frame-to-frame noise
    /// (seeds 1-5, the display's jitter at rest 0.21-0.35 mm; with this, 0.17-0.23 mm).
    pub walk_rate: f64,
    /// The fraction of `axis_random_walk` left at rest: 2e-6 rad^2/s, still twenty times the
    /// angle random walk of the simulated gyro's noise (0.003 rad/s per 10 ms sample, 9e-8 rad^2/s),
    /// for its bias error.
    pub rest_walk_fraction: f64,
    /// Variance of the axis that the gravity and heading corrections converge to, rad^2: once
    /// vision no longer owns the axis the filter's axis variance relaxes towards it at `k_mag`.
    /// The heading reference is the magnetometer's, which is off by its uncalibrated hard iron
    /// and the world estimate's heading error (8 degrees on the `webcam` rig's seed 1; 10 degrees
    /// of axis error at webcam seed 11's stroke 5): a filter that kept the gyro's small variance
    /// through such a stretch would take the next vision axis only in part and then refuse the
    /// frames after it by its own direction prior.
    pub reference_var: f64,
    /// Vision bias gain (rad/s of bias per rad of error per frame).
    pub vision_bias_gain: f64,
    /// Relative deviation of `|a|` from `g` at which the gravity correction reaches zero.
    pub accel_gate: f64,
    /// Larger gains for this long after start-up, seconds (fast convergence).
    pub startup_s: f64,
    /// Length of the orientation history for late vision, nanoseconds.
    pub history_ns: u64,
    /// Gyro samples further apart than this are treated as a gap (no integration), nanoseconds.
    pub max_gap_ns: u64,
    /// For this long after a vision correction the gravity and heading corrections act only about
    /// the pen axis (the roll vision cannot see), nanoseconds: vision owns the axis direction,
    /// which the magnetometer's soft iron and the hand's acceleration would otherwise pull away.
    pub vision_owns_axis_ns: u64,
}

impl Default for OrientationConfig {
    fn default() -> Self {
        Self {
            k_accel: 1.0,
            k_mag: 0.5,
            k_bias: 0.1,
            vision_gain: 0.15,
            vision_bias_gain: 0.02,
            axis_random_walk: 2e-4,
            walk_rate: 0.5,
            rest_walk_fraction: 0.01,
            // (10 degrees)^2.
            reference_var: 0.03,
            accel_gate: 0.2,
            startup_s: 1.0,
            history_ns: 250_000_000,
            max_gap_ns: 100_000_000,
            vision_owns_axis_ns: 300_000_000,
        }
    }
}

/// SO(3) complementary filter with gyro bias and time-stamped vision corrections.
#[derive(Debug, Clone)]
pub struct OrientationFilter {
    /// Gains.
    pub config: OrientationConfig,
    world: WorldReference,
    q: UnitQuaternion<f64>,
    bias: Vector3<f64>,
    t_ns: Option<u64>,
    t_start: u64,
    initialised: bool,
    history: VecDeque<(u64, UnitQuaternion<f64>)>,
    /// Variance of the pen-axis direction per perpendicular axis, rad^2.
    p_var: f64,
    last_vision_ns: Option<u64>,
    /// Bias-corrected angular rate of the last IMU sample (pen frame, rad/s): carries the
    /// orientation from that sample to a later camera time.
    rate: Vector3<f64>,
}

impl OrientationFilter {
    /// A filter that initialises from its first usable accelerometer/magnetometer sample.
    pub fn new(config: OrientationConfig, world: WorldReference) -> Self {
        Self {
            config,
            world,
            q: UnitQuaternion::identity(),
            bias: Vector3::zeros(),
            t_ns: None,
            t_start: 0,
            initialised: false,
            history: VecDeque::with_capacity(256),
            p_var: 1.0,
            last_vision_ns: None,
            rate: Vector3::zeros(),
        }
    }

    /// Current world-from-pen orientation.
    pub fn orientation(&self) -> &UnitQuaternion<f64> {
        &self.q
    }

    /// Current gyro bias estimate, rad/s.
    pub fn gyro_bias(&self) -> &Vector3<f64> {
        &self.bias
    }

    /// True once the filter has an orientation.
    pub fn is_initialised(&self) -> bool {
        self.initialised
    }

    fn boost(&self, t_ns: u64) -> f64 {
        let age = t_ns.saturating_sub(self.t_start) as f64 * 1e-9;
        if age < self.config.startup_s {
            10.0
        } else {
            1.0
        }
    }

    /// Growth of the axis variance at the current rate, rad^2/s (see [`OrientationConfig::walk_rate`]).
    fn axis_walk(&self) -> f64 {
        let c = &self.config;
        let m = if c.walk_rate > 0.0 {
            (self.rate.norm() / c.walk_rate).powi(2).min(1.0)
        } else {
            1.0
        };
        let rest = c.rest_walk_fraction.clamp(0.0, 1.0);
        c.axis_random_walk * (rest + (1.0 - rest) * m)
    }

    /// Gravity + heading error in the pen frame (rad), each weighted.
    fn imu_error(&self, s: &ImuSample) -> Vector3<f64> {
        let inv = self.q.inverse();
        let up_b = inv * self.world.up();
        let a = Vector3::from(s.accel);
        let mut e = Vector3::zeros();
        let norm = a.norm();
        let weight = 1.0
            - ((norm - self.world.gravity).abs() / (self.config.accel_gate * self.world.gravity));
        if weight > 0.0 {
            e += a.cross(&up_b) / norm * (self.config.k_accel * weight);
        }
        let m = Vector3::from(s.mag);
        let horizontal = |v: Vector3<f64>| (v - up_b * v.dot(&up_b)).try_normalize(1e-9);
        if let (Some(mh), Some(ph)) = (horizontal(m), horizontal(inv * self.world.magnetic())) {
            e += mh.cross(&ph) * self.config.k_mag;
        }
        e
    }

    fn record(&mut self, t_ns: u64) {
        self.history.push_back((t_ns, self.q));
        while self
            .history
            .front()
            .is_some_and(|(t, _)| t_ns.saturating_sub(*t) > self.config.history_ns)
        {
            self.history.pop_front();
        }
    }

    /// Orientation at `t_ns`: from the history (slerp) up to the last IMU sample, after it the
    /// last sample's rate carried on (for at most `max_gap_ns`). A camera frame is usually exposed
    /// after the last IMU sample that has arrived (one sample period, plus the link's latency):
    /// holding the last orientation would lag a pen turning at 3 rad/s by several degrees.
    fn orientation_at_time(&self, t_ns: u64) -> UnitQuaternion<f64> {
        match self.t_ns {
            Some(t) if t_ns > t => {
                let dt = (t_ns - t).min(self.config.max_gap_ns) as f64 * 1e-9;
                self.q * UnitQuaternion::from_scaled_axis(self.rate * dt)
            }
            _ => self.orientation_in_history(t_ns),
        }
    }

    /// Orientation at `t_ns` from the history (slerp), or the current one outside it.
    fn orientation_in_history(&self, t_ns: u64) -> UnitQuaternion<f64> {
        let i = self.history.partition_point(|(t, _)| *t <= t_ns);
        match (
            i.checked_sub(1).and_then(|k| self.history.get(k)),
            self.history.get(i),
        ) {
            (Some((t0, q0)), Some((t1, q1))) if t1 > t0 => {
                let f = (t_ns - t0) as f64 / (t1 - t0) as f64;
                q0.try_slerp(q1, f, 1e-9).unwrap_or(*q0)
            }
            (Some((_, q0)), _) => *q0,
            (None, Some((_, q1))) => *q1,
            (None, None) => self.q,
        }
    }
}

impl DirectionFilter for OrientationFilter {
    fn imu(&mut self, s: &ImuSample) {
        if !s
            .accel
            .iter()
            .chain(&s.gyro)
            .chain(&s.mag)
            .all(|v| v.is_finite())
        {
            return;
        }
        if !self.initialised {
            if let Some(q) = self
                .world
                .triad(&Vector3::from(s.accel), &Vector3::from(s.mag))
            {
                self.q = q;
                self.initialised = true;
                self.t_start = s.t_ns;
                self.t_ns = Some(s.t_ns);
                self.record(s.t_ns);
            }
            return;
        }
        let Some(t0) = self.t_ns else { return };
        if s.t_ns <= t0 {
            return;
        }
        let dt_ns = s.t_ns - t0;
        self.t_ns = Some(s.t_ns);
        if dt_ns > self.config.max_gap_ns {
            self.rate = Vector3::from(s.gyro) - self.bias;
            self.record(s.t_ns);
            return;
        }
        let dt = dt_ns as f64 * 1e-9;
        let boost = self.boost(s.t_ns);
        let mut e = self.imu_error(s) * boost;
        let vision_recent = self
            .last_vision_ns
            .is_some_and(|tv| s.t_ns.saturating_sub(tv) <= self.config.vision_owns_axis_ns);
        if vision_recent {
            e = Vector3::x() * e.x;
        }
        self.bias -= e * (self.config.k_bias * dt);
        self.rate = Vector3::from(s.gyro) - self.bias;
        let omega = self.rate + e;
        self.q *= UnitQuaternion::from_scaled_axis(omega * dt);
        self.p_var = (self.p_var + self.axis_walk() * dt).min(1.0);
        if !vision_recent && self.p_var < self.config.reference_var {
            let relax = 1.0 - (-self.config.k_mag * boost * dt).exp();
            self.p_var += (self.config.reference_var - self.p_var) * relax;
        }
        self.record(s.t_ns);
    }

    fn vision(&mut self, t_ns: u64, direction: &Vector3<f64>, variance: Option<f64>) {
        let Some(v) = direction
            .try_normalize(1e-12)
            .filter(|v| v.iter().all(|x| x.is_finite()))
        else {
            return;
        };
        if !self.initialised {
            return;
        }
        let q_f = self.orientation_at_time(t_ns);
        let measured = q_f.inverse() * v;
        let e = Vector3::x().cross(&measured);
        let angle = e.norm().asin().min(std::f64::consts::FRAC_PI_2);
        let axis_err = if measured.x < 0.0 {
            // Beyond 90 degrees; exactly opposite has no defined axis: use any perpendicular.
            e.try_normalize(1e-12).unwrap_or_else(Vector3::y) * (std::f64::consts::PI - angle)
        } else {
            e
        };
        // Scalar Kalman gain on the axis error: the orientation variance grows with the gyro random
        // walk between frames and shrinks with each vision update of known variance.
        let gain = match variance.filter(|v| v.is_finite() && *v > 0.0) {
            Some(r) => {
                let p = if self.boost(t_ns) > 1.0 {
                    self.p_var.max(1e-2)
                } else {
                    self.p_var
                };
                let k = p / (p + r);
                self.p_var = (1.0 - k) * p;
                k.min(0.8)
            }
            None => (self.config.vision_gain * self.boost(t_ns)).min(0.8),
        };
        // Transport the correction from t_f to now: q_now = q_f * d  =>  use d⁻¹ e.
        let d = q_f.inverse() * self.q;
        let now = d.inverse() * axis_err;
        let corrected = self.q * UnitQuaternion::from_scaled_axis(now * gain);
        // The same world-frame correction is applied to the history, so a later (or repeated)
        // frame is compared against orientations that already include this one.
        let world_fix = corrected * self.q.inverse();
        for (_, q) in self.history.iter_mut() {
            *q = world_fix * *q;
        }
        self.q = corrected;
        self.bias -= now * self.config.vision_bias_gain;
        self.last_vision_ns = Some(self.last_vision_ns.map_or(t_ns, |tv| tv.max(t_ns)));
    }

    fn direction_at(&self, t_ns: u64) -> Option<Vector3<f64>> {
        self.orientation_at(t_ns).map(|q| q * Vector3::x())
    }

    fn rebase(&mut self, new_from_old: &UnitQuaternion<f64>, world: WorldReference) {
        self.q = new_from_old * self.q;
        for (_, q) in self.history.iter_mut() {
            *q = new_from_old * *q;
        }
        self.world = world;
    }

    fn orientation_at(&self, t_ns: u64) -> Option<UnitQuaternion<f64>> {
        if !self.initialised {
            return None;
        }
        Some(self.orientation_at_time(t_ns))
    }
}
