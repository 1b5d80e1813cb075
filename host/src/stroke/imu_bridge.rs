//! Bridging a gap between two vision tips of a stroke with the IMU's tip acceleration.
//!
//! Around a gap the tip follows `p(t) = c0 + c1 τ + c2 τ² / 2 + D(t)`, where `D` is the world-frame tip
//! acceleration integrated twice and `τ = t - t0` the time from the gap's first tip. The three vectors `c`
//! are fitted to the vision tips within [`ImuBridgeOptions::fit_window_ns`] of the gap on both sides: `c0`
//! and `c1` are the position and velocity that double integration leaves open, `c2` absorbs the
//! acceleration's own slowly varying error (the gravity that an orientation error of 1° leaks in, 0.17
//! m/s², and the accelerometer's bias), so what is left is only the error's variation over the gap.
//! With fewer than four tips the path is pinned to the gap's two ends (`c2 = 0`); a fit that misses one of
//! its tips by more than [`ImuBridgeOptions::max_fit_residual_m`] bridges nothing. This is the use of the
//! IMU between camera frames that the FIRES thesis, §4.1.4, proposes for occlusions, with both sides held
//! by vision; docs/strokes.md gives the measured errors.

use nalgebra::{Matrix3, Vector3};

use super::segment::{accel_at, samples_cover};
use super::{TimedAccel, TimedPoint};

/// How a gap is bridged with the IMU.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuBridgeOptions {
    /// Vision tips this close to either end of the gap take part in the fit, nanoseconds.
    pub fit_window_ns: u64,
    /// The acceleration samples may be at most this far apart (and from the gap's ends), nanoseconds.
    pub max_sample_gap_ns: u64,
    /// A fitted path that misses one of its own tips by more than this (or, for a noisier tip, more
    /// than its noise explains) is no bridge, metres: the tips
    /// around the gap disagree with the IMU (tips hooked as the pen turned into a view the cameras
    /// could not resolve, whose error the fit's acceleration term would carry across the gap).
    pub max_fit_residual_m: f64,
}

impl Default for ImuBridgeOptions {
    fn default() -> Self {
        ImuBridgeOptions {
            // Six 60 Hz frames on each side, one or two at 15 Hz.
            fit_window_ns: 100_000_000,
            // Three 100 Hz samples: a lost packet or two, not a link outage.
            max_sample_gap_ns: 30_000_000,
            // The strokes' bridge error (`StrokeRecordConfig::max_bridge_error_m`).
            max_fit_residual_m: 0.001,
        }
    }
}

/// The bridge across the gap between `tracked[gap]` and `tracked[gap + 1]`, as timed points at the
/// acceleration samples inside it; None when the samples leave part of the gap uncovered (so that the
/// integral would be a guess), the tips around it disagree with the IMU, or the gap is not one.
///
/// `tracked` and `accel` are in time order. The acceleration is linear between samples and held at the
/// nearest sample beyond them.
pub fn imu_bridge(
    tracked: &[TimedPoint],
    gap: usize,
    accel: &[TimedAccel],
    options: &ImuBridgeOptions,
) -> Option<Vec<(u64, [f64; 3])>> {
    let (a, b) = (tracked.get(gap)?, tracked.get(gap + 1)?);
    let (t0, t1) = (a.t_ns, b.t_ns);
    if t1 <= t0 {
        return None;
    }
    let max_step = options.max_sample_gap_ns;
    let from = accel.partition_point(|s| s.t_ns <= t0);
    let to = accel.partition_point(|s| s.t_ns < t1);
    let inside = &accel[from..to];
    if !samples_cover(inside, t0, t1, max_step) {
        return None;
    }
    // The fit's tips: the gap's ends and the tips within the window that the samples reach.
    let (lo, hi) = (
        t0.saturating_sub(options.fit_window_ns),
        t1.saturating_add(options.fit_window_ns),
    );
    let reach = |t: u64| {
        accel.first().is_some_and(|s| t + max_step >= s.t_ns)
            && accel.last().is_some_and(|s| t <= s.t_ns + max_step)
    };
    let fit: Vec<&TimedPoint> = tracked
        .iter()
        .enumerate()
        .filter(|(i, p)| {
            *i == gap || *i == gap + 1 || ((lo..=hi).contains(&p.t_ns) && reach(p.t_ns))
        })
        .map(|(_, p)| p)
        .collect();
    let start = fit.first()?.t_ns.min(t0);
    let path = DoubleIntegral::new(accel, start, fit.last()?.t_ns.max(t1))?;
    let tau = |t: u64| (t as f64 - t0 as f64) * 1e-9;
    let residual = |p: &TimedPoint| Vector3::from(p.p) - path.at(p.t_ns);
    // Four tips or more: the quadratic has three per axis, and the fourth checks it.
    let c = if fit.len() >= 4 {
        // Least squares of c0 + c1 τ + c2 τ²/2 against p - D, the same 3x3 normal matrix for every axis.
        let mut n = Matrix3::zeros();
        let mut rhs = Matrix3::zeros();
        for p in &fit {
            let x = tau(p.t_ns);
            let row = Vector3::new(1.0, x, 0.5 * x * x);
            n += row * row.transpose();
            rhs += row * residual(p).transpose();
        }
        let c = n.lu().solve(&rhs)?;
        // A miss is beyond both the allowed error and what the tip's own noise explains (3.4 σ per
        // axis: 1% of three-dimensional normal errors lie further out).
        let misses = |p: &&TimedPoint| {
            let x = tau(p.t_ns);
            let allowed = options
                .max_fit_residual_m
                .max(3.4 * p.sigma_m.unwrap_or(0.0));
            (residual(p) - c.transpose() * Vector3::new(1.0, x, 0.5 * x * x)).norm() > allowed
        };
        if fit.iter().any(misses) {
            return None;
        }
        c
    } else {
        let (r0, r1) = (residual(a), residual(b));
        let mut c = Matrix3::zeros();
        c.set_row(0, &r0.transpose());
        c.set_row(1, &((r1 - r0) / tau(t1)).transpose());
        c
    };
    if !c.iter().all(|v| v.is_finite()) {
        return None;
    }
    let points = inside
        .iter()
        .map(|s| {
            let x = tau(s.t_ns);
            let p = c.transpose() * Vector3::new(1.0, x, 0.5 * x * x) + path.at(s.t_ns);
            (s.t_ns, p.into())
        })
        .collect();
    Some(points)
}

/// The acceleration integrated twice from `start` (position and velocity zero there), exactly for an
/// acceleration linear between samples and held beyond the first and last.
struct DoubleIntegral {
    knots: Vec<Knot>,
}

/// The double integral's state at one knot: time, acceleration, velocity and position.
type Knot = (u64, Vector3<f64>, Vector3<f64>, Vector3<f64>);

impl DoubleIntegral {
    fn new(accel: &[TimedAccel], start: u64, end: u64) -> Option<Self> {
        let mut times = vec![start];
        times.extend(
            accel
                .iter()
                .map(|s| s.t_ns)
                .filter(|&t| t > start && t < end),
        );
        times.push(end);
        let mut knots = Vec::with_capacity(times.len());
        let (mut v, mut x) = (Vector3::zeros(), Vector3::zeros());
        let mut prev: Option<(u64, Vector3<f64>)> = None;
        for t in times {
            let a = Vector3::from(accel_at(accel, t)?);
            if let Some((tp, ap)) = prev {
                let h = (t - tp) as f64 * 1e-9;
                x += v * h + (ap / 3.0 + a / 6.0) * h * h;
                v += (ap + a) * (0.5 * h);
            }
            knots.push((t, a, v, x));
            prev = Some((t, a));
        }
        Some(DoubleIntegral { knots })
    }

    /// The double integral at `t` (clamped to the covered span).
    fn at(&self, t: u64) -> Vector3<f64> {
        let i = self.knots.partition_point(|k| k.0 <= t).max(1) - 1;
        let (tk, ak, vk, xk) = self.knots[i];
        let Some(&(tn, an, _, _)) = self.knots.get(i + 1) else {
            return xk;
        };
        let span = (tn - tk) as f64 * 1e-9;
        let h = (t.saturating_sub(tk) as f64 * 1e-9).min(span);
        let slope = if span > 0.0 {
            (an - ak) / span
        } else {
            Vector3::zeros()
        };
        xk + vk * h + ak * (0.5 * h * h) + slope * (h * h * h / 6.0)
    }
}
