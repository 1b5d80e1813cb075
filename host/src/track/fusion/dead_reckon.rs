//! Tip dead reckoning through short occlusions (integrating the pen acceleration
//! from the last vision-based position, which the FIRES thesis, §4.1.4, suggests but does not implement).
//!
//! While the tip is seen, its velocity comes from the tracker's Kalman tip filter
//! ([`TipDeadReckoner::observe_with_velocity`]) or, standing alone, from an alpha-beta filter
//! ([`TipDeadReckoner::observe`]). When it is lost, the tip is
//! extrapolated with that velocity, decaying exponentially, plus (optionally) the world-frame
//! linear acceleration `q a - g up` from the IMU. Drift is bounded by giving up after
//! `max_duration_ns` (default 0.3 s): the output is then "no tip", never a stale one.
//! [`TipDeadReckoner::propagate`] takes the accelerometer for the tip (no lever arm); the tracker
//! calls [`TipDeadReckoner::propagate_linear`] with the tip's own acceleration, the lever from the
//! accelerometer (12 cm behind the tip on the FIRES pen) included: a pen that turns as it stops
//! moves its accelerometer differently from its tip, and integrated as the tip's that motion carried
//! the display 17 mm off a resting pen in 0.2 s (`fires-v2` seed 3, the end of a stroke).

use super::imu::{ImuSample, WorldReference};
use nalgebra::{UnitQuaternion, Vector3};

/// Dead-reckoning settings.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DeadReckonConfig {
    /// Give up this long after the last vision tip, nanoseconds.
    pub max_duration_ns: u64,
    /// Velocity decay rate while occluded, 1/s.
    pub velocity_decay: f64,
    /// Alpha-beta filter gains while visible (position, velocity).
    pub alpha: f64,
    /// Velocity gain of the alpha-beta filter.
    pub beta: f64,
    /// Integrate the IMU's linear acceleration while occluded.
    pub use_accelerometer: bool,
    /// Fastest tip speed believed, m/s; faster velocity estimates are clamped (a hand-held pen).
    pub max_speed_mps: f64,
    /// A vision tip farther than this from the prediction restarts the tracker instead of updating its
    /// velocity (a re-acquisition, not motion), metres.
    pub max_innovation_m: f64,
    /// Farthest an extrapolated tip may move from the last vision tip before it is given up, metres.
    pub max_drift_m: f64,
    /// Shortest interval the velocity gain divides by, nanoseconds. The two cameras are not
    /// synchronised, so vision tips can come a fraction of a millisecond apart; their
    /// difference is then mostly noise (0.5 mm of tip noise over 0.1 ms reads as 7 m/s), which
    /// `beta / dt` would turn into the velocity the occlusions are then extrapolated with.
    /// 8 ms keeps that noise under 0.1 m/s for 0.5 mm tips (√2 σ / dt), about half a 60 Hz
    /// frame period.
    #[serde(default = "default_min_velocity_dt_ns")]
    pub min_velocity_dt_ns: u64,
}

fn default_min_velocity_dt_ns() -> u64 {
    8_000_000
}

impl Default for DeadReckonConfig {
    fn default() -> Self {
        Self {
            max_duration_ns: 300_000_000,
            velocity_decay: 3.0,
            alpha: 0.6,
            beta: 0.3,
            use_accelerometer: true,
            max_speed_mps: 3.0,
            max_innovation_m: 0.05,
            max_drift_m: 0.05,
            min_velocity_dt_ns: default_min_velocity_dt_ns(),
        }
    }
}

/// Alpha-beta tip tracker with bounded extrapolation.
#[derive(Debug, Clone)]
pub struct TipDeadReckoner {
    /// Settings.
    pub config: DeadReckonConfig,
    world: WorldReference,
    position: Option<Vector3<f64>>,
    velocity: Vector3<f64>,
    t_ns: u64,
    last_seen_ns: u64,
    last_seen: Vector3<f64>,
}

impl TipDeadReckoner {
    /// A reckoner with no tip yet.
    pub fn new(config: DeadReckonConfig, world: WorldReference) -> Self {
        Self {
            config,
            world,
            position: None,
            velocity: Vector3::zeros(),
            t_ns: 0,
            last_seen_ns: 0,
            last_seen: Vector3::zeros(),
        }
    }

    /// Replaces the world reference (gravity direction) used to remove gravity.
    pub fn set_world(&mut self, world: WorldReference) {
        self.world = world;
    }

    /// A vision tip at `t_ns` (updates position and velocity).
    pub fn observe(&mut self, t_ns: u64, tip: &Vector3<f64>) {
        if !tip.iter().all(|v| v.is_finite()) {
            return;
        }
        match self.innovation(t_ns, tip) {
            Some((predicted, r, dt)) if r.norm() <= self.config.max_innovation_m => {
                self.position = Some(predicted + r * self.config.alpha);
                let gain_dt = dt.max(self.config.min_velocity_dt_ns as f64 * 1e-9);
                self.velocity = clamp_norm(
                    self.velocity + r * (self.config.beta / gain_dt),
                    self.config.max_speed_mps,
                );
            }
            _ => self.restart(tip),
        }
        self.mark_seen(t_ns, tip);
    }

    /// A vision tip at `t_ns` with its velocity estimated elsewhere (the tracker's Kalman tip
    /// filter, which weighs each tip by its noise): the position is the tip, the velocity taken as
    /// given (clamped to the fastest speed believed), unless the tip is a jump from the prediction
    /// (a re-acquisition), which restarts at rest.
    pub fn observe_with_velocity(
        &mut self,
        t_ns: u64,
        tip: &Vector3<f64>,
        velocity: &Vector3<f64>,
    ) {
        if !tip.iter().all(|v| v.is_finite()) {
            return;
        }
        match self.innovation(t_ns, tip) {
            Some((_, r, _))
                if r.norm() <= self.config.max_innovation_m
                    && velocity.iter().all(|v| v.is_finite()) =>
            {
                self.position = Some(*tip);
                self.velocity = clamp_norm(*velocity, self.config.max_speed_mps);
            }
            _ => self.restart(tip),
        }
        self.mark_seen(t_ns, tip);
    }

    /// The prediction at `t_ns`, the tip's innovation from it and the step (s), when there is a
    /// prediction within the time limit to compare with.
    fn innovation(
        &self,
        t_ns: u64,
        tip: &Vector3<f64>,
    ) -> Option<(Vector3<f64>, Vector3<f64>, f64)> {
        let p = self.position?;
        if t_ns <= self.t_ns || t_ns - self.last_seen_ns >= self.config.max_duration_ns {
            return None;
        }
        let dt = (t_ns - self.t_ns) as f64 * 1e-9;
        let predicted = p + self.velocity * dt;
        Some((predicted, tip - predicted, dt))
    }

    /// Starts over at `tip`, at rest (a first tip, or a re-acquisition).
    fn restart(&mut self, tip: &Vector3<f64>) {
        self.position = Some(*tip);
        self.velocity = Vector3::zeros();
    }

    /// Records a vision tip at `t_ns` as the last one seen.
    fn mark_seen(&mut self, t_ns: u64, tip: &Vector3<f64>) {
        self.t_ns = t_ns.max(self.t_ns);
        self.last_seen_ns = self.t_ns;
        self.last_seen = *tip;
    }

    /// Advances through an occlusion with one IMU sample (world-from-pen orientation `q`);
    /// returns the dead-reckoned tip, or None once the time limit is exceeded. The sample's own
    /// acceleration is taken for the tip's (no lever arm); [`Self::propagate_linear`] takes the tip's.
    pub fn propagate(
        &mut self,
        sample: &ImuSample,
        q: Option<&UnitQuaternion<f64>>,
    ) -> Option<Vector3<f64>> {
        if !sample.accel.iter().all(|v| v.is_finite()) {
            return self.current(sample.t_ns);
        }
        let linear =
            q.map(|q| q * Vector3::from(sample.accel) - self.world.up() * self.world.gravity);
        self.propagate_linear(sample.t_ns, linear)
    }

    /// Advances through an occlusion to `t_ns` with the tip's world-frame linear acceleration
    /// there (gravity removed; None: velocity only); returns the dead-reckoned tip, or None once
    /// the time limit is exceeded.
    pub fn propagate_linear(
        &mut self,
        t_ns: u64,
        linear: Option<Vector3<f64>>,
    ) -> Option<Vector3<f64>> {
        let p = self.position?;
        let linear = linear.filter(|a| a.iter().all(|v| v.is_finite()));
        if t_ns <= self.t_ns {
            return self.current(t_ns);
        }
        if t_ns - self.last_seen_ns > self.config.max_duration_ns {
            return None;
        }
        let dt = (t_ns - self.t_ns) as f64 * 1e-9;
        let mut v = self.velocity * (-self.config.velocity_decay * dt).exp();
        if let (true, Some(linear)) = (self.config.use_accelerometer, linear) {
            v += linear * dt;
        }
        let v = clamp_norm(v, self.config.max_speed_mps);
        let next = p + (self.velocity + v) * (0.5 * dt);
        if (next - self.last_seen).norm() > self.config.max_drift_m {
            // Bounded drift: past this the extrapolation is a guess, not a measurement.
            self.position = None;
            return None;
        }
        self.velocity = v;
        self.position = Some(next);
        self.t_ns = t_ns;
        Some(next)
    }

    /// The latest tip (seen or extrapolated) if still within the time limit at `t_ns`.
    pub fn current(&self, t_ns: u64) -> Option<Vector3<f64>> {
        let fresh = t_ns.saturating_sub(self.last_seen_ns) <= self.config.max_duration_ns;
        self.position.filter(|_| fresh)
    }

    /// True when the last tip came from vision at `t_ns`.
    pub fn seen_at(&self, t_ns: u64) -> bool {
        self.last_seen_ns == t_ns && self.position.is_some()
    }
}

/// `v` scaled down to at most `max` in length.
fn clamp_norm(v: Vector3<f64>, max: f64) -> Vector3<f64> {
    let n = v.norm();
    if n > max && n > 0.0 {
        v * (max / n)
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tips_own_acceleration_is_integrated_and_none_leaves_the_velocity() {
        let cfg = DeadReckonConfig {
            velocity_decay: 0.0,
            ..Default::default()
        };
        let mut dr = TipDeadReckoner::new(cfg, WorldReference::default());
        dr.observe(0, &Vector3::zeros());
        // A pen setting off from rest at 2 m/s² along y: after 0.1 s, a t² / 2 = 10 mm.
        let a = Vector3::new(0.0, 2.0, 0.0);
        let mut last = None;
        for k in 1..=10u64 {
            last = dr.propagate_linear(k * 10_000_000, Some(a));
        }
        let p = last.expect("within the limit");
        assert!((p - Vector3::new(0.0, 0.01, 0.0)).norm() < 1e-9, "{p:?}");
        // Without an acceleration the velocity carries on: 0.2 m/s for 10 ms more.
        let q = dr
            .propagate_linear(110_000_000, None)
            .expect("within the limit");
        assert!(
            (q - p - Vector3::new(0.0, 0.002, 0.0)).norm() < 1e-9,
            "{q:?}"
        );
        // A non-finite acceleration is no acceleration.
        let r = dr
            .propagate_linear(120_000_000, Some(Vector3::new(f64::NAN, 0.0, 0.0)))
            .expect("within the limit");
        assert!(
            (r - q - Vector3::new(0.0, 0.002, 0.0)).norm() < 1e-9,
            "{r:?}"
        );
    }

    #[test]
    fn a_given_velocity_is_taken_clamped_and_a_jump_restarts_at_rest() {
        let cfg = DeadReckonConfig {
            velocity_decay: 0.0,
            ..Default::default()
        };
        let mut dr = TipDeadReckoner::new(cfg, WorldReference::default());
        let p0 = Vector3::new(0.1, 0.0, 0.5);
        let v = Vector3::new(0.0, 0.1, 0.0);
        dr.observe_with_velocity(0, &p0, &v);
        // The first tip has nothing to be a jump from, so it starts at rest.
        assert_eq!(dr.velocity, Vector3::zeros());
        dr.observe_with_velocity(10_000_000, &(p0 + v * 0.01), &v);
        assert_eq!(dr.velocity, v);
        let p = dr
            .propagate_linear(60_000_000, None)
            .expect("within the limit");
        assert!((p - (p0 + v * 0.06)).norm() < 1e-12, "{p:?}");
        // Faster than a hand: clamped to the fastest speed believed.
        let fast = Vector3::new(10.0, 0.0, 0.0);
        dr.observe_with_velocity(70_000_000, &(p0 + v * 0.07), &fast);
        assert!((dr.velocity.norm() - dr.config.max_speed_mps).abs() < 1e-12);
        // A tip 1 m from the prediction is a re-acquisition, not motion.
        dr.observe_with_velocity(80_000_000, &(p0 + Vector3::new(1.0, 0.0, 0.0)), &v);
        assert_eq!(dr.velocity, Vector3::zeros());
        // A non-finite velocity is no velocity; a non-finite tip is ignored.
        dr.observe_with_velocity(
            90_000_000,
            &(p0 + Vector3::new(1.0, 0.0, 0.0)),
            &Vector3::new(f64::NAN, 0.0, 0.0),
        );
        assert_eq!(dr.velocity, Vector3::zeros());
        dr.observe_with_velocity(100_000_000, &Vector3::new(f64::NAN, 0.0, 0.0), &v);
        assert_eq!(
            dr.current(100_000_000),
            Some(p0 + Vector3::new(1.0, 0.0, 0.0))
        );
    }

    #[test]
    fn extrapolates_a_constant_velocity_and_stops_after_the_limit() {
        let world = WorldReference::default();
        let cfg = DeadReckonConfig {
            velocity_decay: 0.0,
            ..Default::default()
        };
        let mut dr = TipDeadReckoner::new(cfg, world);
        let v = Vector3::new(0.2, 0.0, -0.1);
        for k in 0..60u64 {
            let t = k * 10_000_000;
            dr.observe(t, &(v * (t as f64 * 1e-9)));
        }
        let t_last = 59 * 10_000_000u64;
        let q = UnitQuaternion::identity();
        let rest = ImuSample {
            t_ns: 0,
            accel: (world.up() * world.gravity).into(),
            gyro: [0.0; 3],
            mag: [0.0, 1.0, 0.0],
        };
        let mut last = None;
        for k in 1..=40u64 {
            let s = ImuSample {
                t_ns: t_last + k * 5_000_000,
                ..rest
            };
            last = dr.propagate(&s, Some(&q));
            if k == 40 {
                assert!(last.is_some());
            }
        }
        let truth = v * ((t_last + 200_000_000) as f64 * 1e-9);
        let err = (last.unwrap() - truth).norm();
        assert!(err < 0.002, "{err}");
        let late = ImuSample {
            t_ns: t_last + 310_000_000,
            ..rest
        };
        assert!(dr.propagate(&late, Some(&q)).is_none());
    }

    #[test]
    fn tips_from_the_two_cameras_a_moment_apart_do_not_make_a_velocity() {
        // A pen at rest seen by both unsynchronised cameras 0.1 ms apart, each tip with 0.5 mm
        // of noise: the velocity stays near zero (it read 3 m/s, the speed clamp, when the
        // gain divided by 0.1 ms), so an occlusion does not throw the tip centimetres away.
        let world = WorldReference::default();
        let mut dr = TipDeadReckoner::new(DeadReckonConfig::default(), world);
        let p0 = Vector3::new(0.1, 0.0, 0.5);
        let mut rng = crate::rng::SplitMix64::new(5);
        let mut t = 0u64;
        for k in 0..200u64 {
            t = (k / 2) * 10_000_000 + (k % 2) * 100_000;
            let noise = Vector3::new(rng.gaussian(), rng.gaussian(), rng.gaussian()) * 5e-4;
            dr.observe(t, &(p0 + noise));
            assert!(
                dr.velocity.norm() < 0.2,
                "{} m/s at k = {k}",
                dr.velocity.norm()
            );
        }
        let q = UnitQuaternion::identity();
        let rest = ImuSample {
            t_ns: t + 50_000_000,
            accel: (world.up() * world.gravity).into(),
            gyro: [0.0; 3],
            mag: [0.0, 1.0, 0.0],
        };
        let p = dr
            .propagate(&rest, Some(&q))
            .expect("within the time limit");
        assert!((p - p0).norm() < 5e-3, "{:.1} mm", (p - p0).norm() * 1e3);
    }

    #[test]
    fn a_jump_in_vision_restarts_instead_of_becoming_velocity_and_drift_is_bounded() {
        let world = WorldReference::default();
        let mut dr = TipDeadReckoner::new(DeadReckonConfig::default(), world);
        let q = UnitQuaternion::identity();
        let at_rest = |t_ns| ImuSample {
            t_ns,
            accel: (world.up() * world.gravity).into(),
            gyro: [0.0; 3],
            mag: [0.0, 1.0, 0.0],
        };
        let p0 = Vector3::new(0.1, 0.0, 0.5);
        dr.observe(0, &p0);
        // A mislabelled frame 2 m away, 1 ms later: a re-acquisition, not 2000 m/s.
        let p1 = p0 + Vector3::new(2.0, 0.0, 0.0);
        dr.observe(1_000_000, &p1);
        let p = dr
            .propagate(&at_rest(100_000_000), Some(&q))
            .expect("within the time limit");
        assert!((p - p1).norm() < 1e-3, "{p:?}");
        // A wrong orientation makes gravity look like 1 g of acceleration: it is given up at 5 cm, not 0.3 s.
        let tilted = UnitQuaternion::from_euler_angles(std::f64::consts::FRAC_PI_2, 0.0, 0.0);
        let mut gave_up = false;
        for k in 1..=30u64 {
            match dr.propagate(&at_rest(100_000_000 + k * 10_000_000), Some(&tilted)) {
                Some(p) => assert!((p - p1).norm() <= 0.05 + 1e-9),
                None => gave_up = true,
            }
        }
        assert!(gave_up);
    }
}
