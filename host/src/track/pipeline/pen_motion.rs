//! How the pen moved between a blob's frames and the pair's time, from the IMU: the gyro's rates
//! integrated into the pen's turn, and the tip's world acceleration into the part of its
//! translation that the image velocity of the frame before does not carry.
//!
//! Between two frames of a 15 Hz camera (66 ms) the pen turns and accelerates, and moving the
//! other camera's blobs a third of a frame to the pair's time at the image velocity of the frame
//! before misses by pixels, which on the 6 cm Minoru baseline is a centimetre of depth (fires-v2
//! seed 4: a stroke's tips 7-14 mm off where the pen set off from rest, the last frames having
//! shown it still). The IMU measures both at 200 Hz; the camera measures the velocity.

use nalgebra::{UnitQuaternion, Vector3};
use std::collections::VecDeque;

/// How long the IMU's samples are kept, nanoseconds: the three frames of a 15 Hz camera and the
/// pair's time after them.
const HISTORY_NS: u64 = 300_000_000;

/// The last [`HISTORY_NS`] of one IMU quantity, each sample's value held until the next.
#[derive(Debug, Clone, Default)]
struct Samples(VecDeque<(u64, Vector3<f64>)>);

impl Samples {
    /// Keeps a finite sample newer than the last and drops those older than [`HISTORY_NS`].
    fn push(&mut self, t_ns: u64, value: Vector3<f64>) {
        if !value.iter().all(|v| v.is_finite()) || self.0.back().is_some_and(|&(t, _)| t >= t_ns) {
            return;
        }
        self.0.push_back((t_ns, value));
        while self.0.front().is_some_and(|&(t, _)| t_ns - t > HISTORY_NS) {
            self.0.pop_front();
        }
    }

    /// True when the samples reach back to `lo` and, held [`MAX_HOLD_NS`] past the last, on to
    /// `hi` (ns).
    fn covers(&self, lo: f64, hi: f64) -> bool {
        match (self.0.front(), self.0.back()) {
            (Some(&(first, _)), Some(&(last, _))) => {
                first as f64 <= lo && last as f64 >= hi - MAX_HOLD_NS
            }
            _ => false,
        }
    }

    /// Each sample's value with the part of `[lo, hi]` (ns) over which it is held (the first's
    /// from before it, the last's onwards), in time order; pieces of zero length are skipped.
    fn held(&self, lo: f64, hi: f64) -> impl Iterator<Item = (f64, f64, Vector3<f64>)> + '_ {
        // The sample whose held value covers `lo`: the last one at or before it, or the first.
        let from = self
            .0
            .partition_point(|&(t, _)| t as f64 <= lo)
            .saturating_sub(1);
        self.0
            .iter()
            .enumerate()
            .skip(from)
            .take_while(move |&(i, &(t, _))| i == from || (t as f64) < hi)
            .filter_map(move |(i, &(t, v))| {
                let start = if i == 0 { f64::NEG_INFINITY } else { t as f64 };
                let end = self
                    .0
                    .get(i + 1)
                    .map_or(f64::INFINITY, |&(tn, _)| tn as f64);
                let (a, b) = (start.max(lo), end.min(hi));
                (b > a).then_some((a, b, v))
            })
    }
}

/// The gyro's last samples, for how the pen turned between two recent instants: integrated
/// from the rates alone, with none of the orientation filter's corrections (a vision update
/// between two frames turns the filter's direction by a fraction of a degree, which on the
/// pen's 0.16 m lever is as large as the motion being predicted at 60 Hz).
#[derive(Debug, Clone, Default)]
pub(super) struct GyroHistory {
    samples: Samples,
}

impl GyroHistory {
    /// Keeps a sample (pen frame, rad/s) and drops those older than [`HISTORY_NS`].
    pub(super) fn push(&mut self, t_ns: u64, rate: Vector3<f64>) {
        self.samples.push(t_ns, rate);
    }

    /// The pen-frame rotation from `t0` to `t1` (ns): `q(t1) = q(t0) · R`, each sample's rate
    /// held until the next (the last's onwards, the first's before it); None without samples.
    pub(super) fn rotation(&self, t0: f64, t1: f64) -> Option<UnitQuaternion<f64>> {
        if t1 < t0 {
            return self.rotation(t1, t0).map(|r| r.inverse());
        }
        if self.samples.0.is_empty() {
            return None;
        }
        Some(
            self.samples
                .held(t0, t1)
                .fold(UnitQuaternion::identity(), |r, (a, b, w)| {
                    r * UnitQuaternion::from_scaled_axis(w * ((b - a) * 1e-9))
                }),
        )
    }
}

/// The tip's world acceleration over the last samples (gravity removed, the lever included:
/// `Tracker::tip_acceleration`), each held until the next.
#[derive(Debug, Clone, Default)]
pub(super) struct AccelHistory {
    samples: Samples,
}

impl AccelHistory {
    /// Keeps a sample (world frame, m/s²) and drops those older than [`HISTORY_NS`].
    pub(super) fn push(&mut self, t_ns: u64, accel: Vector3<f64>) {
        self.samples.push(t_ns, accel);
    }

    /// The displacement, metres, that the acceleration adds to moving a point from `t1` to
    /// `t1 + s` at the mean velocity it had from `t0` to `t1` (ns): with `dt = t1 - t0`,
    /// `∫ a(u) w(u) du` where `w(u) = s (u - t0) / dt` before `t1` and `t1 + s - u` after (the
    /// mean velocity is the start's plus what the acceleration added, averaged over `dt`). None
    /// when the samples do not cover `[t0, t1 + s]` (or `dt` or `s` is negative).
    pub(super) fn move_part(&self, t0: f64, t1: f64, s: f64) -> Option<Vector3<f64>> {
        let dt = t1 - t0;
        if dt <= 0.0 || s < 0.0 {
            return None;
        }
        self.integrate(t0, t1 + s, t1, |u| {
            if u < t1 {
                s * (u - t0) / dt
            } else {
                t1 + s - u
            }
        })
        .map(|m| m * 1e-18)
    }

    /// How much the mean velocity over `[t1, t2]` exceeds that over `[t0, t1]` (ns), m/s: what
    /// the acceleration makes of the difference of two consecutive frame-to-frame velocities,
    /// `∫ a(u) k(u) du` with the triangle `k` rising from `t0` to 1 at `t1` and falling to `t2`.
    pub(super) fn mean_velocity_change(&self, t0: f64, t1: f64, t2: f64) -> Option<Vector3<f64>> {
        let (d0, d1) = (t1 - t0, t2 - t1);
        if d0 <= 0.0 || d1 <= 0.0 {
            return None;
        }
        self.integrate(t0, t2, t1, |u| {
            if u < t1 {
                (u - t0) / d0
            } else {
                (t2 - u) / d1
            }
        })
        .map(|m| m * 1e-9)
    }

    /// `∫ a(u) w(u) du` over `[lo, hi]` (ns) for a weight linear on each side of `split`, each
    /// sample's acceleration held until the next; None when the samples do not cover the span.
    fn integrate(
        &self,
        lo: f64,
        hi: f64,
        split: f64,
        w: impl Fn(f64) -> f64,
    ) -> Option<Vector3<f64>> {
        if !self.samples.covers(lo, hi) {
            return None;
        }
        let mut sum = Vector3::zeros();
        for (a, b, acc) in self.samples.held(lo, hi) {
            // Split at `split`, where the weight changes form; each piece is linear.
            for (u0, u1) in [(a, b.min(split)), (a.max(split), b)] {
                if u1 > u0 {
                    sum += acc * ((u1 - u0) * w(0.5 * (u0 + u1)));
                }
            }
        }
        Some(sum)
    }
}

/// How long the last acceleration sample is held past its time to cover a move, nanoseconds
/// (the link's latency: the pair's time is usually after the last sample that has arrived).
const MAX_HOLD_NS: f64 = 30_000_000.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gyro_history_integrates_the_rates_both_ways() {
        let mut g = GyroHistory::default();
        assert!(g.rotation(0.0, 1e7).is_none());
        // 1 rad/s about z for 50 ms, then 2 rad/s about x.
        for k in 0..10u64 {
            g.push(k * 5_000_000, Vector3::new(0.0, 0.0, 1.0));
        }
        for k in 10..20u64 {
            g.push(k * 5_000_000, Vector3::new(2.0, 0.0, 0.0));
        }
        let r = g.rotation(20e6, 70e6).unwrap();
        let want = UnitQuaternion::from_scaled_axis(Vector3::new(0.0, 0.0, 0.03))
            * UnitQuaternion::from_scaled_axis(Vector3::new(0.04, 0.0, 0.0));
        assert!(r.angle_to(&want) < 1e-12);
        assert!(g.rotation(70e6, 20e6).unwrap().angle_to(&want.inverse()) < 1e-12);
        // Past the last sample its rate carries on.
        let after = g.rotation(95e6, 105e6).unwrap();
        assert!((after.scaled_axis() - Vector3::new(0.02, 0.0, 0.0)).norm() < 1e-12);
    }

    /// A constant acceleration adds `a s (dt + s) / 2` (the velocity's lag over half the frame
    /// interval and the acceleration over the move); an acceleration only before `t0` adds
    /// nothing (the mean velocity carries it); samples that do not reach back to `t0` give None.
    #[test]
    fn the_acceleration_adds_what_the_mean_velocity_misses() {
        let mut h = AccelHistory::default();
        for k in 0..60u64 {
            h.push(k * 5_000_000, Vector3::new(2.0, 0.0, -1.0));
        }
        let (t0, t1, s) = (50e6, 116e6, 33e6);
        let got = h.move_part(t0, t1, s).unwrap();
        let want = Vector3::new(2.0, 0.0, -1.0) * (0.5 * s * (t1 - t0 + s) * 1e-18);
        assert!((got - want).norm() < 1e-15, "{got} vs {want}");
        let mut step = AccelHistory::default();
        for k in 0..60u64 {
            let a = if k * 5_000_000 < 40_000_000 { 3.0 } else { 0.0 };
            step.push(k * 5_000_000, Vector3::new(a, 0.0, 0.0));
        }
        assert!(step.move_part(t0, t1, s).unwrap().norm() < 1e-18);
        assert!(h.move_part(-1.0, t1, s).is_none());
        // Consecutive frame-to-frame velocities differ by a (dt0 + dt1) / 2 at a constant a.
        let dv = h.mean_velocity_change(20e6, 86e6, 152e6).unwrap();
        assert!(
            (dv - Vector3::new(2.0, 0.0, -1.0) * 0.066).norm() < 1e-12,
            "{dv}"
        );
    }
}
