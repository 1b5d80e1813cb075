//! The One Euro filter for the live display of the tip: Casiez, Roussel, Vogel, "1€ Filter: A Simple
//! Speed-based Low-pass Filter for Noisy Input in Interactive Systems", CHI 2012, §3 (the algorithm) and §4
//! (tuning). A first-order low-pass whose cutoff rises with the speed of the signal,
//! `f_c = min_cutoff + beta · |ẋ|`, where `ẋ` is itself low-passed at `d_cutoff`; at rest the cutoff is low
//! (little jitter), when the pen moves it is high (little lag). Each step with `dt` between samples applies
//! `x̂ = x̂' + α (x − x̂')`, `α = 1 / (1 + τ/dt)`, `τ = 1 / (2π f_c)`, with irregular `dt` taken from the timestamps.
//!
//! In three dimensions one cutoff is used for all axes, driven by the norm of the filtered velocity vector, so
//! the filter does not depend on the orientation of the world frame. As in the paper's pseudo-code, the
//! velocity is taken against the previous *filtered* position.
//!
//! Default tuning for a pen tip in metres (the paper's procedure, §4: `beta = 0`, lower `min_cutoff` until the
//! resting tip is steady, then raise `beta` until the moving tip does not lag), from the physics of the rigs
//! and measured on them:
//! - `min_cutoff = 0.5 Hz`: a resting tip with σ = 0.5 mm of white vision noise per axis at 100 Hz is steadied to
//!   well under 0.1 mm (a first-order low-pass keeps `sqrt(α / (2 − α))` of white noise; α = 0.030 at 0.5 Hz,
//!   100 Hz). At rest the cutoff is set mostly by the velocity noise (below), and what is left of the resting
//!   tip's wander on `fires-v1` (0.6–0.75 mm raw) is slow: it changes from pose to pose, not sample to sample.
//! - `beta = 20 /m` (Hz per m/s): drawing speeds are 0.05–0.3 m/s (peaks of minimum-jerk strokes), so the cutoff
//!   rises to 1.5–6.5 Hz while drawing, and the lag of a ramp stays below `τ = 1 / (2π f_c)` (less in
//!   practice: while the filter trails, the velocity against the filtered position reads high). Larger values cut
//!   the lag further but let the velocity noise of a resting tip (σ/dt ≈ 0.05 m/s raw) open the cutoff.
//! - `d_cutoff = 1.5 Hz`: the velocity estimate must fall within about 100–150 ms when the pen stops (a hold
//!   before a stroke is 0.1–0.25 s), or its tail keeps the cutoff open at rest; its noise at rest is then about
//!   0.01 m/s, +0.2 Hz of cutoff.
//!
//! Measured on the simulated rigs (60 s, seeds 1–5), display lag and jitter at rest, against the first tuning
//! (1 Hz, 30 /m, 2 Hz): `fires-v1` 15 ms (was 10) and 0.20–0.35 mm (was 0.25–0.41; 0.17–0.23 mm since the
//! direction filter averages a still pen's axes over longer, `OrientationConfig::walk_rate`); `webcam` 20 ms (was 15)
//! and 0.016–0.046 mm (was 0.013–0.065); `fires-v2` 30–60 ms (was 20–50). The lag targets are 20, 30 and 70 ms
//! (docs/report.md, `display`).

/// Parameters of the One Euro filter.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct OneEuroConfig {
    /// Cutoff at rest, hertz.
    pub min_cutoff_hz: f64,
    /// Cutoff increase per unit speed, hertz per (metre per second).
    pub beta: f64,
    /// Cutoff of the velocity estimate, hertz.
    pub d_cutoff_hz: f64,
}

impl Default for OneEuroConfig {
    fn default() -> Self {
        OneEuroConfig {
            min_cutoff_hz: 0.5,
            beta: 20.0,
            d_cutoff_hz: 1.5,
        }
    }
}

/// Smoothing factor of a first-order low-pass with cutoff `cutoff_hz` for a step of `dt_s` seconds.
pub fn alpha(cutoff_hz: f64, dt_s: f64) -> f64 {
    let tau = 1.0 / (2.0 * std::f64::consts::PI * cutoff_hz.max(1e-12));
    1.0 / (1.0 + tau / dt_s.max(1e-12))
}

/// State of a streaming One Euro filter over 3-D points with nanosecond timestamps.
#[derive(Debug, Clone)]
pub struct OneEuroFilter {
    config: OneEuroConfig,
    /// Last time, filtered position and filtered velocity (m/s).
    state: Option<(u64, [f64; 3], [f64; 3])>,
}

impl OneEuroFilter {
    /// A filter with no history.
    pub fn new(config: OneEuroConfig) -> Self {
        OneEuroFilter {
            config,
            state: None,
        }
    }

    /// Forgets the history: the next sample passes unfiltered.
    pub fn reset(&mut self) {
        self.state = None;
    }

    /// Adds the sample `p` taken at `t_ns` and returns the filtered position. A sample not later than the
    /// previous one does not change the state (the previous estimate is returned); non-finite input is ignored
    /// the same way.
    pub fn push(&mut self, t_ns: u64, p: [f64; 3]) -> [f64; 3] {
        let c = self.config;
        let Some((t0, x0, dx0)) = self.state else {
            if p.iter().all(|v| v.is_finite()) {
                self.state = Some((t_ns, p, [0.0; 3]));
            }
            return p;
        };
        if t_ns <= t0 || !p.iter().all(|v| v.is_finite()) {
            return x0;
        }
        let dt = (t_ns - t0) as f64 * 1e-9;
        let ad = alpha(c.d_cutoff_hz, dt);
        let dx: [f64; 3] = std::array::from_fn(|k| {
            let raw = (p[k] - x0[k]) / dt;
            dx0[k] + ad * (raw - dx0[k])
        });
        let speed = (dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2]).sqrt();
        let a = alpha(c.min_cutoff_hz + c.beta * speed, dt);
        let x: [f64; 3] = std::array::from_fn(|k| x0[k] + a * (p[k] - x0[k]));
        self.state = Some((t_ns, x, dx));
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    const DT_NS: u64 = 10_000_000;

    #[test]
    fn a_constant_passes_exactly() {
        let mut f = OneEuroFilter::new(OneEuroConfig::default());
        let p = [0.123, -0.456, 0.789];
        for i in 0..500 {
            assert_eq!(f.push(i * DT_NS, p), p);
        }
        // A repeated or earlier timestamp leaves the estimate alone.
        assert_eq!(f.push(0, [1.0; 3]), p);
    }

    #[test]
    fn white_noise_at_rest_is_reduced_by_the_low_pass_factor() {
        // With beta = 0 the filter is a first-order low-pass: white noise keeps sqrt(α / (2 − α)) of its σ.
        let cfg = OneEuroConfig {
            beta: 0.0,
            ..OneEuroConfig::default()
        };
        let a = alpha(cfg.min_cutoff_hz, 0.01);
        let expect = (a / (2.0 - a)).sqrt();
        let mut f = OneEuroFilter::new(cfg);
        let mut rng = SplitMix64::new(3);
        let sigma = 5e-4;
        let n = 200_000;
        let mut var = 0.0;
        for i in 0..n {
            let y = f.push(i * DT_NS, [sigma * rng.gaussian(), 0.0, 0.0])[0];
            if i >= 1000 {
                var += y * y;
            }
        }
        let ratio = (var / (n - 1000) as f64).sqrt() / sigma;
        assert!((ratio / expect - 1.0).abs() < 0.03, "{ratio} vs {expect}");
        // With the default beta the velocity noise lifts the cutoff: the filtered velocity of this noise is
        // about σ/dt · sqrt(α_d/(2 − α_d)) ≈ 0.012 m/s, +0.4 Hz of cutoff, so the filter keeps about 0.2 of
        // the noise; 0.3 leaves room for the cutoff's fluctuations.
        let mut f = OneEuroFilter::new(OneEuroConfig::default());
        let mut var = 0.0;
        for i in 0..n {
            let y = f.push(i * DT_NS, [sigma * rng.gaussian(), 0.0, 0.0])[0];
            if i >= 1000 {
                var += y * y;
            }
        }
        let ratio = (var / (n - 1000) as f64).sqrt() / sigma;
        assert!(ratio > expect && ratio < 0.3, "{ratio}");
    }

    #[test]
    fn a_ramp_lags_less_than_the_time_constant_of_its_speed() {
        // Steady state of a ramp of speed v: the filter trails by less than τ = 1/(2π (min_cutoff + beta v)),
        // since the speed estimate is at least v; with the defaults: below 40 ms above 0.1 m/s, 16 ms at 0.3.
        let c = OneEuroConfig::default();
        for v in [0.1, 0.2, 0.3] {
            let tau_ms = 1e3 / (2.0 * std::f64::consts::PI * (c.min_cutoff_hz + c.beta * v));
            let mut f = OneEuroFilter::new(c);
            let mut lag_ms = 0.0;
            for i in 0..300u64 {
                let t = i as f64 * 0.01;
                let y = f.push(i * DT_NS, [v * t, 0.0, 0.0]);
                lag_ms = (v * t - y[0]) / v * 1e3;
            }
            assert!(
                lag_ms > 0.0 && lag_ms < tau_ms,
                "{v} m/s: {lag_ms} ms vs {tau_ms}"
            );
            assert!(lag_ms < 40.0);
        }
        // Beta is what follows the pen: with beta = 0 the same ramp trails by the full 1/(2π min_cutoff).
        let mut f = OneEuroFilter::new(OneEuroConfig { beta: 0.0, ..c });
        let mut y = [0.0; 3];
        for i in 0..3000u64 {
            y = f.push(i * DT_NS, [0.1 * i as f64 * 0.01, 0.0, 0.0]);
        }
        let lag_ms = (0.1 * 29.99 - y[0]) / 0.1 * 1e3;
        assert!(lag_ms > 140.0, "{lag_ms}");
    }
}
