//! Real-time Gaussian smoothing of the tip trajectory (thesis §4.1.3): a Gaussian
//! kernel discretised on `taps` points (300 by default) applied `passes` times (3 by default).
//! The thesis does not give σ, causality or end handling; our defaults:
//! σ = 50 samples, truncated kernels renormalised at the ends.
//!
//! - [`smooth_centred`]: the symmetric (non-causal) filter for a finished stroke or replay.
//! - [`CausalSmoother`]: for live display, each pass uses the one-sided half of the kernel over
//!   the most recent samples (no look-ahead, lag ≈ 0.8 σ per pass).

use std::collections::VecDeque;

/// Kernel length, width and number of passes.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GaussianConfig {
    /// Kernel length in samples (odd lengths are centred exactly).
    pub taps: usize,
    /// Standard deviation in samples.
    pub sigma: f64,
    /// Number of passes.
    pub passes: usize,
}

impl Default for GaussianConfig {
    fn default() -> Self {
        Self {
            taps: 300,
            sigma: 50.0,
            passes: 3,
        }
    }
}

impl GaussianConfig {
    /// Kernel weights at offsets `-(taps-1)/2 ..= (taps-1)/2` (not normalised).
    fn centred_weights(&self) -> (Vec<f64>, isize) {
        let half = (self.taps.max(1) as isize - 1) / 2;
        let s = self.sigma.max(1e-9);
        let w = (-half..=half)
            .map(|k| (-(k * k) as f64 / (2.0 * s * s)).exp())
            .collect();
        (w, half)
    }

    /// One-sided weights for ages `0 .. taps/2 + 1` (newest first).
    fn causal_weights(&self) -> Vec<f64> {
        let s = self.sigma.max(1e-9);
        (0..self.taps / 2 + 1)
            .map(|k| (-((k * k) as f64) / (2.0 * s * s)).exp())
            .collect()
    }
}

/// Centred Gaussian smoothing with `passes` passes; truncated kernels are renormalised at the ends,
/// so the first and last points move only as much as their one-sided neighbourhoods dictate.
pub fn smooth_centred(points: &[[f64; 3]], config: &GaussianConfig) -> Vec<[f64; 3]> {
    let (w, half) = config.centred_weights();
    let mut cur = points.to_vec();
    let n = cur.len() as isize;
    for _ in 0..config.passes {
        let prev = cur.clone();
        for (i, out) in cur.iter_mut().enumerate() {
            let (mut acc, mut wsum) = ([0.0; 3], 0.0);
            let i = i as isize;
            for j in (i - half).max(0)..=(i + half).min(n - 1) {
                let wk = w[(j - i + half) as usize];
                let p = prev[j as usize];
                acc = [acc[0] + wk * p[0], acc[1] + wk * p[1], acc[2] + wk * p[2]];
                wsum += wk;
            }
            *out = acc.map(|a| a / wsum);
        }
    }
    cur
}

/// Streaming causal smoother (one ring buffer per pass).
#[derive(Debug, Clone)]
pub struct CausalSmoother {
    weights: Vec<f64>,
    stages: Vec<VecDeque<[f64; 3]>>,
}

impl CausalSmoother {
    /// A smoother with the given kernel.
    pub fn new(config: &GaussianConfig) -> Self {
        let weights = config.causal_weights();
        let stages = (0..config.passes)
            .map(|_| VecDeque::with_capacity(weights.len()))
            .collect();
        Self { weights, stages }
    }

    /// Forgets the history (call at stroke start).
    pub fn reset(&mut self) {
        self.stages.iter_mut().for_each(VecDeque::clear);
    }

    /// Adds a raw tip sample and returns the smoothed one.
    pub fn push(&mut self, p: [f64; 3]) -> [f64; 3] {
        let mut x = p;
        for ring in &mut self.stages {
            if ring.len() == self.weights.len() {
                ring.pop_back();
            }
            ring.push_front(x);
            let (mut acc, mut wsum) = ([0.0; 3], 0.0);
            for (q, w) in ring.iter().zip(&self.weights) {
                acc = [acc[0] + w * q[0], acc[1] + w * q[1], acc[2] + w * q[2]];
                wsum += w;
            }
            x = acc.map(|a| a / wsum);
        }
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    #[test]
    fn reproduces_lines_away_from_the_ends_and_reduces_noise_20x() {
        let cfg = GaussianConfig::default();
        let line: Vec<[f64; 3]> = (0..1000)
            .map(|i| [0.001 * i as f64, 0.5, -0.0002 * i as f64])
            .collect();
        let s = smooth_centred(&line, &cfg);
        for i in 450..550 {
            for k in 0..3 {
                assert!((s[i][k] - line[i][k]).abs() < 1e-12);
            }
        }
        let mut rng = SplitMix64::new(1);
        let noise: Vec<[f64; 3]> = (0..3000)
            .map(|_| [rng.gaussian(), rng.gaussian(), rng.gaussian()])
            .collect();
        let s = smooth_centred(&noise, &cfg);
        let var = |v: &[[f64; 3]]| v.iter().map(|p| p[0] * p[0]).sum::<f64>() / v.len() as f64;
        assert!(var(&noise[500..2500]) / var(&s[500..2500]) >= 20.0);
    }

    #[test]
    fn noisy_circle_error_is_below_the_noise() {
        let mut rng = SplitMix64::new(2);
        let (r, sigma) = (0.05, 0.001);
        let truth: Vec<[f64; 3]> = (0..1000)
            .map(|i| {
                let a = i as f64 * 0.01 * 0.63;
                [r * a.cos(), r * a.sin(), 0.0]
            })
            .collect();
        let noisy: Vec<[f64; 3]> = truth
            .iter()
            .map(|p| p.map(|v| v + sigma * rng.gaussian()))
            .collect();
        let cfg = GaussianConfig {
            taps: 61,
            sigma: 8.0,
            passes: 3,
        };
        let s = smooth_centred(&noisy, &cfg);
        let rms = |a: &[[f64; 3]]| {
            (a.iter()
                .zip(&truth)
                .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>())
                .sum::<f64>()
                / a.len() as f64)
                .sqrt()
        };
        assert!(
            rms(&s) < 0.3 * rms(&noisy),
            "{} vs {}",
            rms(&s),
            rms(&noisy)
        );
        // Causal: a constant is reproduced exactly, and a noisy resting tip is steadied 5x.
        let mut c = CausalSmoother::new(&cfg);
        assert_eq!(c.push([1.0, 2.0, 3.0]), [1.0, 2.0, 3.0]);
        c.reset();
        let out: Vec<f64> = (0..2000)
            .map(|_| c.push([sigma * rng.gaussian(), 0.0, 0.0])[0])
            .collect();
        let var = out[500..].iter().map(|v| v * v).sum::<f64>() / 1500.0;
        assert!(var * 5.0 < sigma * sigma, "{var}");
    }
}
