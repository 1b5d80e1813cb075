//! End-of-stroke post-processing (thesis §4.1.3):
//!
//! 1. [`sample_by_distance`]: keep a point when it is at least `threshold` from the last kept one
//!    (the first and last raw points are always kept);
//! 2. [`BSpline::fit`]: a weighted least-squares **cubic** B-spline (clamped, uniform interior
//!    knots, chord-length parameters) with its end points **constrained** to the stroke's first
//!    and last points, plus a small second-difference penalty so spans without data stay
//!    well-posed;
//! 3. [`BSpline::resample`]: points at equal arc-length spacing, ends included exactly.
//!
//! Degree, knots, weights and constraints are not in the thesis; these are the
//! natural choices for a clamped cubic B-spline. The constrained solve eliminates the two fixed control points (the clamped
//! spline passes through its first and last control points), which is exactly the KKT solution.

use nalgebra::{DMatrix, Vector3};
use thiserror::Error;

/// Post-processing failures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum StrokeError {
    /// Fewer than two points.
    #[error("a stroke needs at least two points")]
    TooFewPoints,
    /// All points coincide (zero length).
    #[error("degenerate stroke (zero length)")]
    Degenerate,
    /// A coordinate or weight is NaN or infinite, or a weight is negative.
    #[error("non-finite point or invalid weight")]
    InvalidInput,
    /// The least-squares system could not be solved.
    #[error("spline fit failed")]
    FitFailed,
}

/// Post-processing parameters (metres).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PostprocessConfig {
    /// Distance-threshold sampling step.
    pub sample_threshold: f64,
    /// Approximate arc length per control-point span.
    pub control_spacing: f64,
    /// Relative weight of the second-difference penalty.
    pub smoothing: f64,
    /// Output point spacing.
    pub resample_spacing: f64,
}

impl Default for PostprocessConfig {
    fn default() -> Self {
        Self {
            sample_threshold: 0.002,
            control_spacing: 0.01,
            smoothing: 1e-4,
            resample_spacing: 0.002,
        }
    }
}

/// Most points [`BSpline::resample`] returns.
pub const MAX_RESAMPLED: usize = 100_000;

/// Sampling, spline fit and resampling with uniform weights.
pub fn postprocess(
    points: &[[f64; 3]],
    config: &PostprocessConfig,
) -> Result<Vec<[f64; 3]>, StrokeError> {
    let kept = sample_by_distance(points, config.sample_threshold);
    let spline = BSpline::fit(&kept, None, config)?;
    Ok(spline.resample(config.resample_spacing))
}

/// Distance-threshold sampling; the first and last points are always kept.
pub fn sample_by_distance(points: &[[f64; 3]], threshold: f64) -> Vec<[f64; 3]> {
    let mut out: Vec<[f64; 3]> = Vec::with_capacity(points.len());
    for p in points {
        match out.last() {
            None => out.push(*p),
            Some(l) if dist(l, p) >= threshold => out.push(*p),
            _ => {}
        }
    }
    if let (Some(last), Some(kept)) = (points.last(), out.last()) {
        if kept != last {
            out.push(*last);
        }
    }
    out
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// A clamped cubic B-spline on `[0, 1]` (built by [`BSpline::fit`], so always >= 4 control points).
#[derive(Debug, Clone, PartialEq)]
pub struct BSpline {
    knots: Vec<f64>,
    control: Vec<Vector3<f64>>,
}

impl BSpline {
    /// Knot vector (length = control points + 4).
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    /// Control points.
    pub fn control_points(&self) -> &[Vector3<f64>] {
        &self.control
    }

    /// Clamped cubic knot vector for `n >= 4` control points with uniform interior knots.
    fn clamped_knots(n: usize) -> Vec<f64> {
        let spans = (n - 3) as f64;
        let mut k = vec![0.0; 4];
        k.extend((1..n - 3).map(|i| i as f64 / spans));
        k.extend([1.0; 4]);
        k
    }

    /// Index of the knot span containing `u` and the four non-zero basis values
    /// (The NURBS Book, A2.1/A2.2).
    fn basis(&self, u: f64) -> (usize, [f64; 4]) {
        let n = self.control.len();
        let u = u.clamp(0.0, 1.0);
        let span = if u >= 1.0 {
            n - 1
        } else {
            (3..n).rfind(|&i| self.knots[i] <= u).unwrap_or(3)
        };
        let k = &self.knots;
        let mut left = [0.0; 4];
        let mut right = [0.0; 4];
        let mut b = [1.0, 0.0, 0.0, 0.0];
        for j in 1..=3 {
            left[j] = u - k[span + 1 - j];
            right[j] = k[span + j] - u;
            let mut saved = 0.0;
            for r in 0..j {
                let den = right[r + 1] + left[j - r];
                let tmp = if den.abs() > 0.0 { b[r] / den } else { 0.0 };
                b[r] = saved + right[r + 1] * tmp;
                saved = left[j - r] * tmp;
            }
            b[j] = saved;
        }
        (span, b)
    }

    /// Point at parameter `u` in `[0, 1]`.
    pub fn evaluate(&self, u: f64) -> Vector3<f64> {
        if u >= 1.0 {
            return self.control[self.control.len() - 1];
        }
        if u <= 0.0 {
            return self.control[0];
        }
        let (span, b) = self.basis(u);
        (0..4).map(|r| self.control[span - 3 + r] * b[r]).sum()
    }

    /// Weighted least-squares fit with the end points fixed to the first and last input points.
    pub fn fit(
        points: &[[f64; 3]],
        weights: Option<&[f64]>,
        config: &PostprocessConfig,
    ) -> Result<Self, StrokeError> {
        validate(points, weights)?;
        let params = chord_params(points)?;
        let length: f64 = points.windows(2).map(|w| dist(&w[0], &w[1])).sum();
        let n = ((length / config.control_spacing.max(1e-6)).ceil() as usize + 3)
            .clamp(4, points.len().max(4) + 2);
        let mut spline = Self {
            knots: Self::clamped_knots(n),
            control: vec![Vector3::zeros(); n],
        };
        let (g, rhs) = spline.normal_equations(points, weights, &params, config.smoothing);
        let first = Vector3::from(points[0]);
        let last = Vector3::from(points[points.len() - 1]);
        let m = n - 2;
        let g_int = g.view((1, 1), (m, m)).into_owned();
        let mut b = DMatrix::zeros(m, 3);
        for i in 0..m {
            for c in 0..3 {
                b[(i, c)] =
                    rhs[(i + 1, c)] - g[(i + 1, 0)] * first[c] - g[(i + 1, n - 1)] * last[c];
            }
        }
        let chol = g_int.cholesky().ok_or(StrokeError::FitFailed)?;
        let x = chol.solve(&b);
        spline.control[0] = first;
        spline.control[n - 1] = last;
        for i in 0..m {
            spline.control[i + 1] = Vector3::new(x[(i, 0)], x[(i, 1)], x[(i, 2)]);
        }
        if spline
            .control
            .iter()
            .all(|p| p.iter().all(|v| v.is_finite()))
        {
            Ok(spline)
        } else {
            Err(StrokeError::FitFailed)
        }
    }

    /// `G = A^T W A + λ D^T D` and `A^T W Q` over all control points.
    fn normal_equations(
        &self,
        points: &[[f64; 3]],
        weights: Option<&[f64]>,
        params: &[f64],
        smoothing: f64,
    ) -> (DMatrix<f64>, DMatrix<f64>) {
        let n = self.control.len();
        let mut g: DMatrix<f64> = DMatrix::zeros(n, n);
        let mut rhs = DMatrix::zeros(n, 3);
        for (i, (p, &u)) in points.iter().zip(params).enumerate() {
            let w = weights.map_or(1.0, |w| w[i]);
            let (span, b) = self.basis(u);
            for r in 0..4 {
                let a = span - 3 + r;
                for s in 0..4 {
                    g[(a, span - 3 + s)] += w * b[r] * b[s];
                }
                for c in 0..3 {
                    rhs[(a, c)] += w * b[r] * p[c];
                }
            }
        }
        let lambda = smoothing * (g.trace() / n as f64).max(1e-12);
        for i in 0..n - 2 {
            let d = [1.0, -2.0, 1.0];
            for r in 0..3 {
                for s in 0..3 {
                    g[(i + r, i + s)] += lambda * d[r] * d[s];
                }
            }
        }
        (g, rhs)
    }

    /// Points at equal arc-length spacing (at most `spacing` apart), both ends included exactly.
    pub fn resample(&self, spacing: f64) -> Vec<[f64; 3]> {
        let dense = (self.control.len() * 32).max(256);
        let pts: Vec<Vector3<f64>> = (0..=dense)
            .map(|i| self.evaluate(i as f64 / dense as f64))
            .collect();
        let mut cum = vec![0.0; pts.len()];
        for i in 1..pts.len() {
            cum[i] = cum[i - 1] + (pts[i] - pts[i - 1]).norm();
        }
        let total = cum[cum.len() - 1];
        // Bounded output whatever the input: a stroke of 200 m at 2 mm spacing, far beyond any real one.
        let count = ((total / spacing.max(1e-9)).ceil().min(MAX_RESAMPLED as f64) as usize).max(1);
        let mut out = Vec::with_capacity(count + 1);
        let mut seg = 0;
        for j in 0..=count {
            let s = total * j as f64 / count as f64;
            while seg + 2 < cum.len() && cum[seg + 1] < s {
                seg += 1;
            }
            let len = cum[seg + 1] - cum[seg];
            let f = if len > 0.0 {
                ((s - cum[seg]) / len).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let u = (seg as f64 + f) / dense as f64;
            let u = if j == count {
                1.0
            } else if j == 0 {
                0.0
            } else {
                u
            };
            out.push(self.evaluate(u).into());
        }
        out
    }
}

fn validate(points: &[[f64; 3]], weights: Option<&[f64]>) -> Result<(), StrokeError> {
    if points.len() < 2 {
        return Err(StrokeError::TooFewPoints);
    }
    if !points.iter().flatten().all(|v| v.is_finite()) {
        return Err(StrokeError::InvalidInput);
    }
    if let Some(w) = weights {
        if w.len() != points.len() || !w.iter().all(|v| v.is_finite() && *v >= 0.0) {
            return Err(StrokeError::InvalidInput);
        }
    }
    Ok(())
}

/// Normalised cumulative chord-length parameters.
fn chord_params(points: &[[f64; 3]]) -> Result<Vec<f64>, StrokeError> {
    let mut t = Vec::with_capacity(points.len());
    let mut acc = 0.0;
    t.push(0.0);
    for w in points.windows(2) {
        acc += dist(&w[0], &w[1]);
        t.push(acc);
    }
    if acc <= 1e-12 {
        return Err(StrokeError::Degenerate);
    }
    Ok(t.into_iter().map(|v| v / acc).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn helix(t: f64) -> [f64; 3] {
        [0.05 * (3.0 * t).cos(), 0.05 * (3.0 * t).sin(), 0.03 * t]
    }

    #[test]
    fn distance_sampling_keeps_the_ends_and_the_spacing() {
        let pts: Vec<[f64; 3]> = (0..=500).map(|i| helix(i as f64 * 0.002)).collect();
        let s = sample_by_distance(&pts, 0.005);
        assert_eq!(s[0], pts[0]);
        assert_eq!(s[s.len() - 1], pts[500]);
        assert!(s
            .windows(2)
            .take(s.len() - 2)
            .all(|w| dist(&w[0], &w[1]) >= 0.005));
    }

    #[test]
    fn spline_interpolates_the_ends_and_approximates_curves() {
        let cfg = PostprocessConfig::default();
        let pts: Vec<[f64; 3]> = (0..=300).map(|i| helix(i as f64 / 300.0)).collect();
        let sp = BSpline::fit(&pts, None, &cfg).unwrap();
        assert!((sp.evaluate(0.0) - Vector3::from(pts[0])).norm() <= 1e-12);
        assert!((sp.evaluate(1.0) - Vector3::from(pts[300])).norm() <= 1e-12);
        let out = sp.resample(0.002);
        for p in &out {
            // distance to the true helix (dense search)
            let d = (0..=3000)
                .map(|i| dist(p, &helix(i as f64 / 3000.0)))
                .fold(f64::INFINITY, f64::min);
            assert!(d < 1e-4, "{d}");
        }
        assert_eq!(out[0], pts[0]);
        assert_eq!(out[out.len() - 1], pts[300]);
        let gaps: Vec<f64> = out.windows(2).map(|w| dist(&w[0], &w[1])).collect();
        let (lo, hi) = gaps
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), g| (a.min(*g), b.max(*g)));
        assert!(hi <= 0.002 + 1e-9 && lo > 0.9 * hi, "{lo} {hi}");
    }

    #[test]
    fn noisy_circle_residual_is_below_the_noise() {
        let mut rng = SplitMix64::new(4);
        let sigma = 0.0008;
        let truth: Vec<[f64; 3]> = (0..=400)
            .map(|i| (i as f64 / 400.0 * 5.5).sin_cos())
            .map(|(s, c)| [0.06 * c, 0.06 * s, 0.0])
            .collect();
        let mut noisy: Vec<[f64; 3]> = truth
            .iter()
            .map(|p| p.map(|v| v + sigma * rng.gaussian()))
            .collect();
        noisy[0] = truth[0];
        noisy[400] = truth[400];
        let cfg = PostprocessConfig {
            control_spacing: 0.03,
            ..Default::default()
        };
        let sp = BSpline::fit(&noisy, None, &cfg).unwrap();
        let out = sp.resample(0.002);
        let err = |p: &[f64; 3]| ((p[0].hypot(p[1]) - 0.06).powi(2) + p[2] * p[2]).sqrt();
        let rms_fit = (out.iter().map(|p| err(p).powi(2)).sum::<f64>() / out.len() as f64).sqrt();
        assert!(rms_fit < sigma, "fit {rms_fit} vs noise {sigma}");
        assert_eq!(out[0], noisy[0]);
        assert!(postprocess(&noisy, &cfg).is_ok());
    }

    #[test]
    fn degenerate_input_is_an_error() {
        let cfg = PostprocessConfig::default();
        assert_eq!(
            BSpline::fit(&[[0.0; 3]], None, &cfg),
            Err(StrokeError::TooFewPoints)
        );
        assert_eq!(
            BSpline::fit(&[[0.0; 3]; 5], None, &cfg),
            Err(StrokeError::Degenerate)
        );
        assert_eq!(
            BSpline::fit(&[[0.0; 3], [f64::NAN, 0.0, 0.0]], None, &cfg),
            Err(StrokeError::InvalidInput)
        );
        let two = BSpline::fit(&[[0.0; 3], [0.01, 0.0, 0.0]], None, &cfg).unwrap();
        assert!((two.evaluate(0.5) - Vector3::new(0.005, 0.0, 0.0)).norm() < 1e-9);
    }
}
