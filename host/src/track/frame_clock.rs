//! A camera's frame times from noisy host timestamps. A free-running camera exposes its frames on
//! its own crystal, one period apart, but the host stamps each frame when it arrives (USB transfer
//! and scheduling add about a millisecond of jitter on a webcam). Two cameras' stamps are what
//! time alignment moves blobs by (docs/architecture.md §3), so that jitter, times the image speed,
//! is a disparity error: 1 ms at 250 px/s is 0.25 px, about 1 mm of depth at 0.6 m on a 0.2 m
//! baseline.
//!
//! [`FrameClock`] fits the line `t = a + b·k` (frame index `k`, counted from the stamps' spacing so
//! that dropped frames keep their place) to a sliding window of stamps by least squares, and
//! returns for each frame the line's value moved towards its own stamp by the gain
//! `σₑ² / (σₑ² + σₛ²)` (`σₑ` the exposures' own jitter about their period, `σₛ` the stamps' noise
//! about the exposures): the minimum-variance combination of the two when each is white. A
//! crystal-clocked webcam (`σₑ ≈ 0`) gets the line, a camera whose stamps are exact (`σₛ = 0`)
//! its stamps. The fit is causal (the newest frame is the window's end), so it serves a live
//! tracker as it does a replay. A stamp far off the line (a stall, a restarted stream) is not
//! fitted; several in a row restart the fit.

use std::collections::VecDeque;

/// How a camera's frames are timed ([`FrameClock`]'s model).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct FrameTiming {
    /// Nominal frame period, nanoseconds (0: unknown, stamps are used as they are).
    pub period_ns: f64,
    /// Standard deviation of the exposures about their period, nanoseconds.
    pub exposure_jitter_ns: f64,
    /// Standard deviation of the stamps about the exposures, nanoseconds (0: stamps are exact and
    /// used as they are).
    pub stamp_noise_ns: f64,
}

impl FrameTiming {
    /// Whether stamps are to be filtered at all: a known period and stamp noise, and finite,
    /// non-negative figures (a configuration that is not gets the stamps as they are).
    pub fn filters(&self) -> bool {
        let finite = [self.period_ns, self.exposure_jitter_ns, self.stamp_noise_ns]
            .iter()
            .all(|x| x.is_finite() && *x >= 0.0);
        finite && self.period_ns > 0.0 && self.stamp_noise_ns > 0.0
    }
}

/// Frames in the fitted window (about 4 s at 60 Hz: the line's error at the window's end is about
/// `2σ/√N`, a tenth of the stamps' noise, while a crystal's drift over the window stays far below
/// it).
const WINDOW: usize = 240;

/// Frames needed before the line is used (with fewer the stamps are returned as they are).
const MIN_FIT: usize = 8;

/// A stamp further than this many standard deviations (of exposure jitter and stamp noise
/// combined) from the line is not fitted.
const OUTLIER_SIGMAS: f64 = 6.0;

/// This many rejected stamps among the last [`RECENT`] restart the fit from the first of them
/// (the stream's phase changed; a jump of a few standard deviations rejects most frames after
/// it, not all).
const RESTART_AFTER: usize = 4;

/// Frames remembered for the restart test.
const RECENT: usize = 8;

/// Online frame times of one camera ([module docs](self)).
#[derive(Debug, Clone)]
pub struct FrameClock {
    timing: FrameTiming,
    /// `(k, stamp)` of the fitted window, oldest first; `k` counts periods from the first frame.
    window: VecDeque<(i64, f64)>,
    /// Index and stamp of the last frame seen (fitted or not).
    last: Option<(i64, f64)>,
    /// The last [`RECENT`] frames: index, stamp and whether the line rejected it.
    recent: VecDeque<(i64, f64, bool)>,
}

impl FrameClock {
    /// A clock with no frames yet.
    pub fn new(timing: FrameTiming) -> Self {
        Self {
            timing,
            window: VecDeque::with_capacity(WINDOW),
            last: None,
            recent: VecDeque::with_capacity(RECENT),
        }
    }

    /// The model this clock uses.
    pub fn timing(&self) -> FrameTiming {
        self.timing
    }

    /// The time of the frame stamped `stamp_ns` (frames in arrival order), nanoseconds.
    pub fn time(&mut self, stamp_ns: u64) -> u64 {
        if !self.timing.filters() {
            return stamp_ns;
        }
        let s = stamp_ns as f64;
        let line = self.line();
        let period = line.map_or(self.timing.period_ns, |(_, b)| b);
        // The frame's index: periods since the last frame, at least one.
        let k = match self.last {
            None => 0,
            Some((k0, s0)) => {
                let from = line.map_or(s0, |(a, b)| a + b * k0 as f64);
                k0 + ((s - from) / period).round().max(1.0) as i64
            }
        };
        self.last = Some((k, s));
        let Some((a, b)) = line else {
            self.admit(k, s);
            return stamp_ns;
        };
        let on_line = a + b * k as f64;
        let sigma = self
            .timing
            .exposure_jitter_ns
            .hypot(self.timing.stamp_noise_ns);
        let rejected = (s - on_line).abs() > OUTLIER_SIGMAS * sigma;
        if self.recent.len() == RECENT {
            self.recent.pop_front();
        }
        self.recent.push_back((k, s, rejected));
        if rejected {
            if self.recent.iter().filter(|r| r.2).count() >= RESTART_AFTER {
                // Refit from the first rejected frame on.
                let first = self.recent.iter().position(|r| r.2).unwrap_or(0);
                self.window.clear();
                for (k, s, _) in self.recent.drain(..).skip(first) {
                    self.window.push_back((k, s));
                }
            }
            return stamp_ns;
        }
        self.admit(k, s);
        let (a, b) = self.line().unwrap_or((a, b));
        let on_line = a + b * k as f64;
        let (e2, s2) = (
            self.timing.exposure_jitter_ns.powi(2),
            self.timing.stamp_noise_ns.powi(2),
        );
        let gain = e2 / (e2 + s2);
        (on_line + gain * (s - on_line)).round().max(0.0) as u64
    }

    fn admit(&mut self, k: i64, s: f64) {
        if self.window.len() == WINDOW {
            self.window.pop_front();
        }
        self.window.push_back((k, s));
    }

    /// The least-squares line `(a, b)` of the window (`None` before [`MIN_FIT`] frames), with the
    /// sums taken about the window's first frame so that they stay small.
    fn line(&self) -> Option<(f64, f64)> {
        if self.window.len() < MIN_FIT {
            return None;
        }
        let &(k0, s0) = self.window.front()?;
        let n = self.window.len() as f64;
        let (mut sk, mut ss, mut skk, mut sks) = (0.0, 0.0, 0.0, 0.0);
        for &(k, s) in &self.window {
            let (x, y) = ((k - k0) as f64, s - s0);
            sk += x;
            ss += y;
            skk += x * x;
            sks += x * y;
        }
        let det = n * skk - sk * sk;
        if det <= 0.0 {
            return None;
        }
        let b = (n * sks - sk * ss) / det;
        let a = (ss - b * sk) / n;
        // Back to absolute index and time: t = s0 + a + b (k − k0).
        Some((s0 + a - b * k0 as f64, b))
    }
}
