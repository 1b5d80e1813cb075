//! How well the live display follows the pen, against ground truth: its *lag*, the time shift that best aligns
//! the display with the true tip (the shift `s` minimising the RMS of `display(t) − tip(t − s)` over a grid of
//! shifts), and its *jitter at rest*, the RMS distance of the display from its own mean over the windows in
//! which the true tip rests.

use fires_record::report::DisplayReport;

/// The true tip as a time-sorted series, linearly interpolated.
#[derive(Debug, Clone, Default)]
pub struct TipTruth {
    t_ns: Vec<u64>,
    tip: Vec<[f64; 3]>,
}

impl TipTruth {
    /// From `(time, tip)` pairs in any order.
    pub fn new(mut samples: Vec<(u64, [f64; 3])>) -> Self {
        samples.sort_by_key(|s| s.0);
        samples.dedup_by_key(|s| s.0);
        TipTruth {
            t_ns: samples.iter().map(|s| s.0).collect(),
            tip: samples.iter().map(|s| s.1).collect(),
        }
    }

    /// The true tip at `t_ns`; `None` outside the series or inside a gap longer than `max_gap_ns`.
    pub fn at(&self, t_ns: u64, max_gap_ns: u64) -> Option<[f64; 3]> {
        let i = self.t_ns.partition_point(|&t| t <= t_ns);
        let a = i.checked_sub(1)?;
        if self.t_ns[a] == t_ns {
            return Some(self.tip[a]);
        }
        let b = i;
        let (ta, tb) = (self.t_ns[a], *self.t_ns.get(b)?);
        if tb - ta > max_gap_ns {
            return None;
        }
        let w = (t_ns - ta) as f64 / (tb - ta) as f64;
        let (p, q) = (self.tip[a], self.tip[b]);
        Some(std::array::from_fn(|k| p[k] + w * (q[k] - p[k])))
    }

    /// Speed of the true tip at `t_ns` (over the surrounding truth interval), m/s.
    pub fn speed(&self, t_ns: u64, max_gap_ns: u64) -> Option<f64> {
        let i = self.t_ns.partition_point(|&t| t <= t_ns).max(1);
        let (a, b) = (i - 1, i.min(self.t_ns.len().checked_sub(1)?));
        if a == b || self.t_ns[b] - self.t_ns[a] > max_gap_ns {
            return None;
        }
        let dt = (self.t_ns[b] - self.t_ns[a]) as f64 * 1e-9;
        Some(dist(&self.tip[a], &self.tip[b]) / dt)
    }
}

/// Settings of the display figures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DisplayOptions {
    /// Largest time shift tried, nanoseconds.
    pub max_shift_ns: u64,
    /// Step between the shifts tried, nanoseconds.
    pub shift_step_ns: u64,
    /// The true tip rests while it moves slower than this, m/s.
    pub rest_speed_mps: f64,
    /// Shortest rest window counted, nanoseconds.
    pub min_rest_ns: u64,
    /// Truth samples farther apart than this are a gap (no truth in between), nanoseconds.
    pub max_truth_gap_ns: u64,
}

impl Default for DisplayOptions {
    fn default() -> Self {
        // 1 mm/s: a resting hand drifts less than 0.1 mm over a 100 ms window, far below the jitter of interest.
        DisplayOptions {
            max_shift_ns: 600_000_000,
            shift_step_ns: 5_000_000,
            rest_speed_mps: 1e-3,
            min_rest_ns: 100_000_000,
            max_truth_gap_ns: 100_000_000,
        }
    }
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The shift (ns) that minimises the RMS distance (m) of `display(t)` from `truth(t − shift)`, over the samples
/// that have truth at every shift tried; `None` without such samples.
pub fn display_lag(
    display: &[(u64, [f64; 3])],
    truth: &TipTruth,
    opt: &DisplayOptions,
) -> Option<(u64, f64)> {
    let usable: Vec<&(u64, [f64; 3])> = display
        .iter()
        .filter(|(t, _)| {
            *t >= opt.max_shift_ns
                && truth.at(*t, opt.max_truth_gap_ns).is_some()
                && truth
                    .at(t - opt.max_shift_ns, opt.max_truth_gap_ns)
                    .is_some()
        })
        .collect();
    if usable.is_empty() {
        return None;
    }
    let mut best: Option<(u64, f64)> = None;
    let mut shift = 0;
    while shift <= opt.max_shift_ns {
        let (mut sum, mut n) = (0.0, 0usize);
        for (t, p) in &usable {
            if let Some(q) = truth.at(t - shift, opt.max_truth_gap_ns) {
                sum += dist(p, &q).powi(2);
                n += 1;
            }
        }
        if n > 0 {
            let rms = (sum / n as f64).sqrt();
            if best.is_none_or(|b| rms < b.1) {
                best = Some((shift, rms));
            }
        }
        shift += opt.shift_step_ns.max(1);
    }
    best
}

/// RMS distance (m) of the display from its mean over each window of consecutive samples in which the true
/// tip rests (slower than [`DisplayOptions::rest_speed_mps`] for at least [`DisplayOptions::min_rest_ns`]),
/// pooled over the windows, with the number of samples; `None` without a rest window. The windows are those of
/// the truth delayed by the display's `lag_ns`, so that a display still catching up with a pen that has
/// stopped counts as lag, not as jitter.
pub fn jitter_at_rest(
    display: &[(u64, [f64; 3])],
    truth: &TipTruth,
    lag_ns: u64,
    opt: &DisplayOptions,
) -> Option<(f64, usize)> {
    let mut windows: Vec<Vec<[f64; 3]>> = Vec::new();
    let mut cur: Vec<(u64, [f64; 3])> = Vec::new();
    let mut close = |cur: &mut Vec<(u64, [f64; 3])>| {
        if let (Some(a), Some(b)) = (cur.first(), cur.last()) {
            if b.0 - a.0 >= opt.min_rest_ns {
                windows.push(cur.iter().map(|s| s.1).collect());
            }
        }
        cur.clear();
    };
    for &(t, p) in display {
        let resting = t
            .checked_sub(lag_ns)
            .and_then(|t| truth.speed(t, opt.max_truth_gap_ns))
            .is_some_and(|v| v < opt.rest_speed_mps);
        let contiguous = cur
            .last()
            .is_none_or(|l| t >= l.0 && t - l.0 <= opt.max_truth_gap_ns);
        if !resting || !contiguous {
            close(&mut cur);
        }
        if resting {
            cur.push((t, p));
        }
    }
    close(&mut cur);
    let (mut sum, mut n) = (0.0, 0usize);
    for w in &windows {
        let mean: [f64; 3] =
            std::array::from_fn(|k| w.iter().map(|p| p[k]).sum::<f64>() / w.len() as f64);
        sum += w.iter().map(|p| dist(p, &mean).powi(2)).sum::<f64>();
        n += w.len();
    }
    (n > 0).then(|| ((sum / n as f64).sqrt(), n))
}

/// The `display` block: the filter's name and, with truth, its lag and jitter at rest, and the jitter of the
/// unfiltered tip `raw` in the same (truth) rest windows.
pub fn display_report(
    filter: &str,
    display: &[(u64, [f64; 3])],
    raw: &[(u64, [f64; 3])],
    truth: Option<&TipTruth>,
    opt: &DisplayOptions,
) -> DisplayReport {
    let mut r = DisplayReport {
        filter: filter.into(),
        ..DisplayReport::default()
    };
    let Some(truth) = truth else {
        return r;
    };
    let lag = display_lag(display, truth, opt);
    if let Some((shift, rms)) = lag {
        r.lag_ms = Some(shift as f64 / 1e6);
        r.rms_at_lag_mm = Some(rms * 1e3);
    }
    let lag_ns = lag.map_or(0, |l| l.0);
    if let Some((j, n)) = jitter_at_rest(display, truth, lag_ns, opt) {
        r.jitter_at_rest_mm = Some(j * 1e3);
        r.rest_samples = n;
    }
    r.raw_jitter_at_rest_mm = jitter_at_rest(raw, truth, 0, opt).map(|j| j.0 * 1e3);
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tip resting 1 s, moving along x at 0.1 m/s for 2 s, resting 1 s; sampled every 10 ms.
    fn path(t_ns: u64) -> [f64; 3] {
        let t = t_ns as f64 * 1e-9;
        let x = 0.1 * (t - 1.0).clamp(0.0, 2.0);
        [x, 0.2, 0.7]
    }

    #[test]
    fn a_delayed_display_shows_its_delay_and_no_jitter() {
        let ts: Vec<u64> = (0..=400).map(|i| i * 10_000_000).collect();
        let truth = TipTruth::new(ts.iter().map(|&t| (t, path(t))).collect());
        let delay = 35_000_000;
        let display: Vec<(u64, [f64; 3])> = ts
            .iter()
            .filter(|&&t| t >= delay)
            .map(|&t| (t, path(t - delay)))
            .collect();
        let (shift, rms) = display_lag(&display, &truth, &DisplayOptions::default()).unwrap();
        assert_eq!(shift, delay);
        assert!(rms < 1e-12, "{rms}");
        let (jitter, n) =
            jitter_at_rest(&display, &truth, shift, &DisplayOptions::default()).unwrap();
        // The rest windows are the first second and the last, delayed by the lag.
        assert!(n > 150, "{n}");
        assert!(jitter < 1e-12, "{jitter}");
        // Without the delay, the display's catch-up after the pen stops would count as jitter.
        let (undelayed, _) =
            jitter_at_rest(&display, &truth, 0, &DisplayOptions::default()).unwrap();
        assert!(undelayed > 1e-4, "{undelayed}");
        // A display that wobbles ±0.5 mm while the pen rests has 0.5 mm of jitter.
        let wobble: Vec<(u64, [f64; 3])> = ts
            .iter()
            .map(|&t| {
                let mut p = path(t);
                p[1] += if (t / 10_000_000) % 2 == 0 {
                    5e-4
                } else {
                    -5e-4
                };
                (t, p)
            })
            .collect();
        let (jitter, _) = jitter_at_rest(&wobble, &truth, 0, &DisplayOptions::default()).unwrap();
        assert!((jitter - 5e-4).abs() < 2e-5, "{jitter}");
    }
}
