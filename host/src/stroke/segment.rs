//! Stroke segmentation by the pen button (left open by the FIRES thesis; decided here): a stroke starts when the
//! drawing button is pressed and ends when it is released, both with the status packet's
//! timestamp; tip samples inside `[press, release]` belong to the stroke. Samples without a tip
//! (lost tracking) are skipped. A stroke with fewer than `min_points` points is discarded.

/// A tip sample with its time.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TimedPoint {
    /// Time, nanoseconds.
    pub t_ns: u64,
    /// Tip position, metres.
    pub p: [f64; 3],
    /// One-sigma per-axis uncertainty of `p`, metres (None when the tracker gave none).
    #[serde(default)]
    pub sigma_m: Option<f64>,
}

/// The tip's world-frame acceleration (gravity removed) from one IMU sample, for bridging gaps
/// between vision tips ([`super::imu_bridge`]).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TimedAccel {
    /// Time, nanoseconds.
    pub t_ns: u64,
    /// Acceleration, m/s^2.
    pub a: [f64; 3],
}

/// The acceleration at `t`, linear between samples (in time order) and held beyond the first and
/// last; None without samples.
pub(crate) fn accel_at(accel: &[TimedAccel], t: u64) -> Option<[f64; 3]> {
    let i = accel.partition_point(|s| s.t_ns <= t);
    Some(match (i.checked_sub(1).map(|k| &accel[k]), accel.get(i)) {
        (Some(p), Some(q)) => {
            let w = (t - p.t_ns) as f64 / (q.t_ns - p.t_ns) as f64;
            [0, 1, 2].map(|k| p.a[k] * (1.0 - w) + q.a[k] * w)
        }
        (Some(p), None) => p.a,
        (None, Some(q)) => q.a,
        (None, None) => return None,
    })
}

/// True when the samples `inside` `[t0, t1]` cover it: none further than `max_gap` from the next, nor
/// the first from `t0` and the last from `t1` (false without samples).
pub(crate) fn samples_cover(inside: &[TimedAccel], t0: u64, t1: u64, max_gap: u64) -> bool {
    match (inside.first(), inside.last()) {
        (Some(f), Some(l)) => {
            f.t_ns.saturating_sub(t0) <= max_gap
                && t1.saturating_sub(l.t_ns) <= max_gap
                && inside.windows(2).all(|w| w[1].t_ns - w[0].t_ns <= max_gap)
        }
        _ => false,
    }
}

/// A finished stroke.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Stroke {
    /// Button press time.
    pub t_start_ns: u64,
    /// Button release time.
    pub t_end_ns: u64,
    /// Raw tip samples in time order.
    pub points: Vec<TimedPoint>,
    /// The tip's acceleration from the IMU while the stroke was drawn, in time order (empty when the
    /// tracker had no orientation and world reference to compute it).
    #[serde(default)]
    pub accel: Vec<TimedAccel>,
}

/// What a button change did.
#[derive(Debug, Clone, PartialEq)]
pub enum StrokeEvent {
    /// A stroke began.
    Started {
        /// Press time.
        t_ns: u64,
    },
    /// A stroke finished.
    Ended(Stroke),
    /// A stroke finished with too few points and was dropped.
    Discarded {
        /// Release time.
        t_ns: u64,
    },
}

/// Button-driven stroke builder.
#[derive(Debug, Clone)]
pub struct StrokeSegmenter {
    /// Strokes with fewer points are discarded.
    pub min_points: usize,
    current: Option<Stroke>,
}

impl Default for StrokeSegmenter {
    fn default() -> Self {
        Self {
            min_points: 2,
            current: None,
        }
    }
}

impl StrokeSegmenter {
    /// True while a stroke is open.
    pub fn is_drawing(&self) -> bool {
        self.current.is_some()
    }

    /// A button state (from a status packet) at `t_ns`; repeated states are ignored.
    pub fn button(&mut self, t_ns: u64, pressed: bool) -> Option<StrokeEvent> {
        match (pressed, self.current.take()) {
            (true, None) => {
                self.current = Some(Stroke {
                    t_start_ns: t_ns,
                    t_end_ns: t_ns,
                    points: Vec::new(),
                    accel: Vec::new(),
                });
                Some(StrokeEvent::Started { t_ns })
            }
            (true, Some(open)) => {
                self.current = Some(open);
                None
            }
            (false, Some(mut stroke)) => {
                stroke.t_end_ns = t_ns;
                stroke.points.retain(|p| p.t_ns <= t_ns);
                stroke.accel.retain(|a| a.t_ns <= t_ns);
                if stroke.points.len() >= self.min_points {
                    Some(StrokeEvent::Ended(stroke))
                } else {
                    Some(StrokeEvent::Discarded { t_ns })
                }
            }
            (false, None) => None,
        }
    }

    /// A tracker sample; kept if a stroke is open and the sample is not before its start.
    pub fn tip(&mut self, t_ns: u64, tip: Option<[f64; 3]>) {
        self.tip_with_sigma(t_ns, tip, None);
    }

    /// [`Self::tip`] with the tip's one-sigma per-axis uncertainty, metres.
    pub fn tip_with_sigma(&mut self, t_ns: u64, tip: Option<[f64; 3]>, sigma_m: Option<f64>) {
        if let (Some(stroke), Some(p)) = (self.current.as_mut(), tip) {
            let in_order = stroke.points.last().is_none_or(|l| l.t_ns < t_ns);
            if t_ns >= stroke.t_start_ns && in_order && p.iter().all(|v| v.is_finite()) {
                let sigma_m = sigma_m.filter(|s| s.is_finite() && *s >= 0.0);
                stroke.points.push(TimedPoint { t_ns, p, sigma_m });
            }
        }
    }

    /// The tip's acceleration at `t_ns` (world frame, m/s^2); kept while a stroke is open, in time order.
    pub fn accel(&mut self, t_ns: u64, a: [f64; 3]) {
        if let Some(stroke) = self.current.as_mut() {
            let in_order = stroke.accel.last().is_none_or(|l| l.t_ns < t_ns);
            if t_ns >= stroke.t_start_ns && in_order && a.iter().all(|v| v.is_finite()) {
                stroke.accel.push(TimedAccel { t_ns, a });
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn press_and_release_delimit_strokes() {
        let mut s = StrokeSegmenter::default();
        s.tip(5, Some([0.0; 3]));
        assert_eq!(s.button(10, true), Some(StrokeEvent::Started { t_ns: 10 }));
        assert_eq!(s.button(12, true), None);
        for t in [8, 11, 13, 15, 25] {
            s.tip(t, Some([t as f64, 0.0, 0.0]));
        }
        s.tip(16, None);
        let Some(StrokeEvent::Ended(stroke)) = s.button(20, false) else {
            panic!("no stroke")
        };
        let times: Vec<u64> = stroke.points.iter().map(|p| p.t_ns).collect();
        assert_eq!(times, vec![11, 13, 15]);
        assert!(!s.is_drawing());
        s.button(30, true);
        assert_eq!(
            s.button(31, false),
            Some(StrokeEvent::Discarded { t_ns: 31 })
        );
    }
}
