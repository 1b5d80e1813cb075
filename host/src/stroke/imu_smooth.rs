//! IMU-aided smoothing of a stroke's vision tips: one least-squares path over the whole stroke.
//!
//! A vision tip is one stereo pair's measurement, and on a narrow-baseline rig each carries its own
//! depth error: on the 6 cm Minoru rig one pixel of disparity is 8 mm of depth at half a metre, and
//! moving the other camera's blobs to the pair's time under a fast turn is off by about that much
//! from pair to pair (`fires-v2` seed 1, a crossing stroke: consecutive tips 1.6 mm behind, 3.3 mm
//! in front, 8.3 mm behind the pen). The tip's world acceleration from the IMU (the FIRES thesis,
//! §4.1.4, proposes it between camera frames) is what such tips lack: integrated over a fraction of a
//! second it is good to a fraction of a millimetre (docs/strokes.md, the IMU bridge), while it knows
//! nothing of where the path is. Together they fix it: the path `p(t)` on a time grid through every
//! tip (nodes at most [`ImuSmoothOptions::step_ns`] apart) minimises
//!
//! ```text
//! Σ_tips |p(t_i) − z_i|² / σ_i²  +  Σ_nodes |p''(t_k) − a(t_k) − b(t_k)|² / q_k²  +  Σ_knots |b_j|² / β²
//! ```
//!
//! per axis, where `p''` is the grid's second difference (exact for a quadratic path), `a` the IMU's
//! tip acceleration at the node, `b` a slowly varying acceleration error (piecewise linear over knots
//! [`ImuSmoothOptions::bias_knot_ns`] apart: the gravity an orientation error of a degree leaks in,
//! the accelerometer's bias) and `q_k = ρ / √h_k` the white part of the acceleration's error over the
//! node's span `h_k` (its density `ρ`, [`ImuSmoothOptions::accel_noise_density`]). The tips' σ start
//! at the tracker's own estimate (at least [`ImuSmoothOptions::min_sigma_m`]) and are rescaled from
//! the residuals, per axis, by their robust spread (1.4826 times the median absolute normalised
//! residual, never below 1), with Huber weights beyond [`HUBER_K`] of it: the tracker's σ holds the
//! centroid noise but not every alignment error, and the residuals measure what it misses. The
//! normal equations are banded in time order and solved by a banded Cholesky factorisation, linear
//! in the stroke's length.

use super::segment::{accel_at, samples_cover};
use super::{TimedAccel, TimedPoint};

/// How a stroke's tips are smoothed with the IMU ([`imu_smooth`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuSmoothOptions {
    /// Largest spacing of the path's time grid, nanoseconds (the IMU's 100 Hz period).
    pub step_ns: u64,
    /// Density of the white part of the tip acceleration's error, m/s²/√Hz.
    pub accel_noise_density: f64,
    /// Spacing of the acceleration-error knots, nanoseconds.
    pub bias_knot_ns: u64,
    /// Prior spread of the acceleration error at a knot, m/s².
    pub bias_prior_mps2: f64,
    /// Smallest σ a tip is given, metres.
    pub min_sigma_m: f64,
    /// Fewest tips a stroke is smoothed with (fewer are left as they are).
    pub min_tips: usize,
    /// The acceleration samples may be at most this far apart (and from the stroke's ends),
    /// nanoseconds; a stroke they do not cover is left as it is.
    pub max_sample_gap_ns: u64,
    /// Rounds of σ rescaling and Huber reweighting before the final solve.
    pub reweight_rounds: usize,
}

impl Default for ImuSmoothOptions {
    fn default() -> Self {
        Self {
            step_ns: 10_000_000,
            // 0.2 m/s² per 100 Hz sample: what the IMU bridge's fit leaves of the acceleration's
            // error (`StrokeRecordConfig::imu_accel_error_mps2`, docs/strokes.md).
            accel_noise_density: 0.02,
            bias_knot_ns: 300_000_000,
            // An orientation error of a few degrees leaks a few tenths of a m/s² of gravity.
            bias_prior_mps2: 0.5,
            min_sigma_m: 5e-5,
            min_tips: 6,
            // Three 100 Hz samples, as the IMU bridge allows.
            max_sample_gap_ns: 30_000_000,
            reweight_rounds: 3,
        }
    }
}

/// Most nodes a path may have (half an hour of a 100 Hz grid); a longer stroke is left as tracked.
const MAX_NODES: usize = 200_000;

/// Most entries of the banded normal matrix a stroke may need (160 MB of f64); a longer or denser
/// stroke is left as tracked.
const MAX_BAND_ENTRIES: usize = 20_000_000;

/// Most multiply-adds of its factorisation (about a second).
const MAX_BAND_WORK: f64 = 2e9;

/// Residuals beyond this many robust spreads are down-weighted (Huber's constant).
pub const HUBER_K: f64 = 2.5;

/// The tips' positions on the smoothed path, tip for tip; None when there are fewer than
/// [`ImuSmoothOptions::min_tips`] tips, the acceleration samples leave part of the stroke
/// uncovered, the times are not increasing, or the system is not solvable.
pub fn imu_smooth(
    tips: &[TimedPoint],
    accel: &[TimedAccel],
    options: &ImuSmoothOptions,
) -> Option<Vec<[f64; 3]>> {
    if tips.len() < options.min_tips.max(3) || tips.windows(2).any(|w| w[1].t_ns <= w[0].t_ns) {
        return None;
    }
    let (t0, t1) = (tips.first()?.t_ns, tips.last()?.t_ns);
    let inside =
        &accel[accel.partition_point(|s| s.t_ns < t0)..accel.partition_point(|s| s.t_ns <= t1)];
    if !samples_cover(inside, t0, t1, options.max_sample_gap_ns) {
        return None;
    }
    // The grid's size, bounded before it is built.
    let nodes = tips
        .len()
        .saturating_add(((t1 - t0) / options.step_ns.max(1)) as usize);
    if nodes > MAX_NODES {
        return None;
    }
    let grid = Grid::new(tips, options)?;
    let sigma: Vec<f64> = tips
        .iter()
        .map(|p| p.sigma_m.unwrap_or(0.0).max(options.min_sigma_m))
        .collect();
    let mut out = vec![[0.0; 3]; tips.len()];
    for axis in 0..3 {
        let z: Vec<f64> = tips.iter().map(|p| p.p[axis]).collect();
        let a: Vec<f64> = grid
            .times
            .iter()
            .map(|&t| accel_at(accel, t).map(|v| v[axis]))
            .collect::<Option<_>>()?;
        let mut tip_scale = vec![1.0; tips.len()];
        let mut node_scale = vec![1.0; grid.times.len()];
        let mut path = grid.solve(&z, &sigma, &tip_scale, &a, &node_scale, options)?;
        for _ in 0..options.reweight_rounds {
            let u: Vec<f64> = (0..tips.len())
                .map(|i| (z[i] - path.nodes[grid.tip_node[i]]) / sigma[i])
                .collect();
            let spread = (1.4826 * median(u.iter().map(|v| v.abs()).collect())).max(1.0);
            for (w, &ui) in tip_scale.iter_mut().zip(&u) {
                *w = spread * huber_scale(ui.abs() / spread);
            }
            for (k, w) in node_scale.iter_mut().enumerate() {
                *w = grid
                    .accel_residual(&path, &a, k, options)
                    .map_or(1.0, |r| huber_scale(r.abs()));
            }
            path = grid.solve(&z, &sigma, &tip_scale, &a, &node_scale, options)?;
        }
        for (i, o) in out.iter_mut().enumerate() {
            o[axis] = path.nodes[grid.tip_node[i]];
        }
    }
    out.iter()
        .all(|p| p.iter().all(|v| v.is_finite()))
        .then_some(out)
}

/// One axis of a solved path: its value at every node and the acceleration error at every knot.
struct Path {
    nodes: Vec<f64>,
    bias: Vec<f64>,
}

/// The σ factor of a residual `r` robust spreads out: 1 within [`HUBER_K`], `r / HUBER_K` beyond
/// (Huber's weight, applied to the residual's standard deviation).
fn huber_scale(r: f64) -> f64 {
    if r > HUBER_K {
        r / HUBER_K
    } else {
        1.0
    }
}

/// The path's time grid: every tip's time, and nodes between them at most a step apart.
struct Grid {
    /// Node times, nanoseconds, increasing.
    times: Vec<u64>,
    /// The node of each tip.
    tip_node: Vec<usize>,
    /// Times of the acceleration-error knots, nanoseconds (at least two, at the ends).
    knots: Vec<u64>,
    /// Each unknown's place in the banded system (node `k` is unknown `k`, knot `j` unknown
    /// `nodes + j`).
    pos: Vec<usize>,
}

impl Grid {
    fn new(tips: &[TimedPoint], options: &ImuSmoothOptions) -> Option<Self> {
        let step = options.step_ns.max(1);
        let mut times = Vec::new();
        let mut tip_node = Vec::with_capacity(tips.len());
        for (i, p) in tips.iter().enumerate() {
            if let Some(prev) = i.checked_sub(1).map(|j| tips[j].t_ns) {
                let gap = p.t_ns - prev;
                let n = gap.div_ceil(step);
                times.extend((1..n).map(|k| prev + gap * k / n));
            }
            tip_node.push(times.len());
            times.push(p.t_ns);
        }
        let (t0, t1) = (tips.first()?.t_ns, tips.last()?.t_ns);
        let spans = ((t1 - t0).div_ceil(options.bias_knot_ns.max(1))).max(1);
        let knots: Vec<u64> = (0..=spans).map(|j| t0 + (t1 - t0) * j / spans).collect();
        // Unknowns in time order (node k, then knot j just before the first node after its time), so
        // the normal matrix is banded.
        let n_nodes = times.len();
        let mut key: Vec<(f64, usize)> = (0..n_nodes).map(|k| (k as f64, k)).collect();
        for (j, &t) in knots.iter().enumerate() {
            let k = times.partition_point(|&x| x <= t);
            key.push((k as f64 - 0.5 + j as f64 * 1e-6, n_nodes + j));
        }
        key.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut pos = vec![0; key.len()];
        for (p, &(_, u)) in key.iter().enumerate() {
            pos[u] = p;
        }
        Some(Self {
            times,
            tip_node,
            knots,
            pos,
        })
    }

    /// The knots whose hat functions are non-zero at `t`, with their values.
    fn hats(&self, t: u64) -> [(usize, f64); 2] {
        let j = (self.knots.partition_point(|&k| k <= t).max(1) - 1).min(self.knots.len() - 2);
        let (a, b) = (self.knots[j], self.knots[j + 1]);
        let w = (t.saturating_sub(a)) as f64 / (b - a).max(1) as f64;
        [(j, 1.0 - w.min(1.0)), (j + 1, w.min(1.0))]
    }

    /// The path for one axis: tips `z` with σ `sigma · tip_scale`, node accelerations `a` with
    /// their error widened by `node_scale`.
    fn solve(
        &self,
        z: &[f64],
        sigma: &[f64],
        tip_scale: &[f64],
        a: &[f64],
        node_scale: &[f64],
        options: &ImuSmoothOptions,
    ) -> Option<Path> {
        let n_nodes = self.times.len();
        let n = n_nodes + self.knots.len();
        // Unknowns in time order: node k at position k, knot j just after the node at its time.
        let pos = &self.pos;
        let mut rows: Vec<Row> = Vec::with_capacity(n + z.len());
        for (i, &k) in self.tip_node.iter().enumerate() {
            rows.push((vec![(pos[k], 1.0)], z[i], 1.0 / (sigma[i] * tip_scale[i])));
        }
        for k in 1..n_nodes.saturating_sub(1) {
            let (coefs, q) = self.accel_row(k, options);
            let coefs = coefs.into_iter().map(|(u, v)| (pos[u], v)).collect();
            rows.push((coefs, a[k], 1.0 / (q * node_scale[k])));
        }
        for j in 0..self.knots.len() {
            rows.push((
                vec![(pos[n_nodes + j], 1.0)],
                0.0,
                1.0 / options.bias_prior_mps2,
            ));
        }
        let x = banded_least_squares(n, &rows)?;
        Some(Path {
            nodes: (0..n_nodes).map(|k| x[pos[k]]).collect(),
            bias: (0..self.knots.len()).map(|j| x[pos[n_nodes + j]]).collect(),
        })
    }

    /// Node `k`'s acceleration row (interior nodes): the coefficients of `p''(t_k) − b(t_k)` by
    /// unknown (node `i` is unknown `i`, knot `j` unknown `nodes + j`), and the acceleration's
    /// error there.
    fn accel_row(&self, k: usize, options: &ImuSmoothOptions) -> (Vec<(usize, f64)>, f64) {
        let n_nodes = self.times.len();
        let h1 = (self.times[k] - self.times[k - 1]) as f64 * 1e-9;
        let h2 = (self.times[k + 1] - self.times[k]) as f64 * 1e-9;
        let c = 2.0 / (h1 + h2);
        let mut coefs = vec![(k - 1, c / h1), (k, -c / h1 - c / h2), (k + 1, c / h2)];
        for (j, v) in self.hats(self.times[k]) {
            if v > 0.0 {
                coefs.push((n_nodes + j, -v));
            }
        }
        let q = options.accel_noise_density / (0.5 * (h1 + h2)).sqrt();
        (coefs, q)
    }

    /// Node `k`'s acceleration residual on `path`, in units of its error (None at the ends).
    fn accel_residual(
        &self,
        path: &Path,
        a: &[f64],
        k: usize,
        options: &ImuSmoothOptions,
    ) -> Option<f64> {
        if k == 0 || k + 1 >= self.times.len() {
            return None;
        }
        let n_nodes = self.times.len();
        let (coefs, q) = self.accel_row(k, options);
        let value: f64 = coefs
            .iter()
            .map(|&(u, v)| {
                v * if u < n_nodes {
                    path.nodes[u]
                } else {
                    path.bias[u - n_nodes]
                }
            })
            .sum();
        Some((value - a[k]) / q)
    }
}

/// One least-squares row: sparse coefficients by unknown, the target and the weight.
type Row = (Vec<(usize, f64)>, f64, f64);

/// Minimises `Σ w² (c · x − r)²` over the rows `(c, r, w)` (sparse coefficients by unknown), through
/// the banded normal equations.
fn banded_least_squares(n: usize, rows: &[Row]) -> Option<Vec<f64>> {
    let bw = rows
        .iter()
        .map(|(c, _, _)| {
            let lo = c.iter().map(|e| e.0).min().unwrap_or(0);
            let hi = c.iter().map(|e| e.0).max().unwrap_or(0);
            hi - lo
        })
        .max()?;
    // A stroke of pathological density (external data) is declined rather than factored slowly.
    if n.saturating_mul(bw + 1) > MAX_BAND_ENTRIES || n as f64 * (bw as f64).powi(2) > MAX_BAND_WORK
    {
        return None;
    }
    let mut band = Band::new(n, bw);
    let mut rhs = vec![0.0; n];
    for (c, r, w) in rows {
        let w2 = w * w;
        for &(i, vi) in c {
            rhs[i] += w2 * vi * r;
            for &(j, vj) in c {
                if j <= i {
                    *band.at(i, j) += w2 * vi * vj;
                }
            }
        }
    }
    band.cholesky()?;
    Some(band.solve(rhs))
}

/// A symmetric band matrix stored by its lower band, row by row (`bw + 1` entries per row).
struct Band {
    n: usize,
    bw: usize,
    data: Vec<f64>,
}

impl Band {
    fn new(n: usize, bw: usize) -> Self {
        Self {
            n,
            bw,
            data: vec![0.0; n * (bw + 1)],
        }
    }

    /// Entry `(i, j)`, `j <= i <= j + bw`.
    fn at(&mut self, i: usize, j: usize) -> &mut f64 {
        &mut self.data[i * (self.bw + 1) + (i - j)]
    }

    fn get(&self, i: usize, j: usize) -> f64 {
        self.data[i * (self.bw + 1) + (i - j)]
    }

    /// In-place LLᵀ; None when the matrix is not positive definite.
    fn cholesky(&mut self) -> Option<()> {
        for j in 0..self.n {
            let lo = j.saturating_sub(self.bw);
            let d = self.get(j, j) - (lo..j).map(|k| self.get(j, k).powi(2)).sum::<f64>();
            if !(d > 0.0 && d.is_finite()) {
                return None;
            }
            let d = d.sqrt();
            *self.at(j, j) = d;
            for i in j + 1..(j + self.bw + 1).min(self.n) {
                let lo = i.saturating_sub(self.bw);
                let s = self.get(i, j)
                    - (lo..j)
                        .map(|k| self.get(i, k) * self.get(j, k))
                        .sum::<f64>();
                *self.at(i, j) = s / d;
            }
        }
        Some(())
    }

    /// Solves `L Lᵀ x = b` with the factor.
    fn solve(&self, mut b: Vec<f64>) -> Vec<f64> {
        for i in 0..self.n {
            let lo = i.saturating_sub(self.bw);
            let s: f64 = (lo..i).map(|k| self.get(i, k) * b[k]).sum();
            b[i] = (b[i] - s) / self.get(i, i);
        }
        for i in (0..self.n).rev() {
            let hi = (i + self.bw + 1).min(self.n);
            let s: f64 = (i + 1..hi).map(|k| self.get(k, i) * b[k]).sum();
            b[i] = (b[i] - s) / self.get(i, i);
        }
        b
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => 0.0,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}
