//! From a finished stroke (tracked tip samples between pen-down and pen-up) to the strokes file's
//! [`fires_record::Stroke`]: the post-processed polyline (thesis §4.1.3), a time for every point, the pen-mode
//! buttons and whether the stroke closes on itself (docs/strokes.md).

use fires_record::{StrokePiece, StrokePoint};

use super::imu_bridge::{imu_bridge, ImuBridgeOptions};
use super::imu_smooth::{imu_smooth, ImuSmoothOptions};
use super::{postprocess, PostprocessConfig, Stroke, TimedAccel, TimedPoint};

/// How a finished stroke becomes a record of the strokes file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrokeRecordConfig {
    /// End-of-stroke post-processing.
    pub postprocess: PostprocessConfig,
    /// A stroke whose end is within this distance of its start is closed, metres.
    pub close_distance_m: f64,
    /// ... and only if it is at least this many closing distances long (a dab is not a loop).
    pub min_closed_length: f64,
    /// Largest error allowed where the polyline bridges a gap between two tracked tips, metres.
    pub max_bridge_error_m: f64,
    /// Acceleration of a drawing hand the bridge must allow for, m/s^2.
    pub drawing_accel_mps2: f64,
    /// Error of the IMU's tip acceleration over a gap, m/s^2: a gap too long for the chord is bridged
    /// with the acceleration integrated between its two tips ([`imu_bridge`]) up to the length at
    /// which this error leaves the bridge `max_bridge_error_m` off.
    pub imu_accel_error_mps2: f64,
    /// How the IMU bridges a gap.
    pub imu_bridge: ImuBridgeOptions,
    /// How the stroke's tips are smoothed with the IMU before they are bridged and post-processed
    /// ([`imu_smooth`]; None: the tips as tracked).
    pub imu_smooth: Option<ImuSmoothOptions>,
}

impl Default for StrokeRecordConfig {
    fn default() -> Self {
        // A hand closing a loop by eye ends within about a centimetre of its start; the curve network snaps
        // the ends together.
        StrokeRecordConfig {
            postprocess: PostprocessConfig::default(),
            close_distance_m: 0.010,
            min_closed_length: 4.0,
            // A gap is bridged only where the bridge stays within 1 mm of the pen (issue: strokes
            // that follow the pen) for a hand accelerating at 1 m/s^2 (drawing strokes of a few
            // centimetres in half a second).
            max_bridge_error_m: 0.001,
            drawing_accel_mps2: 1.0,
            // What the bridge's fit leaves of the tip acceleration's error (docs/strokes.md).
            imu_accel_error_mps2: 0.2,
            imu_bridge: ImuBridgeOptions::default(),
            imu_smooth: Some(ImuSmoothOptions::default()),
        }
    }
}

impl StrokeRecordConfig {
    /// The longest gap between two tracked tips that the polyline bridges, nanoseconds: a path
    /// with acceleration `a` leaves its chord by at most `a dt^2 / 8` over a gap `dt`, so the gap
    /// limit is `sqrt(8 e / a)` for the bridge error `e`.
    pub fn max_gap_ns(&self) -> u64 {
        self.gap_for_accel_error(self.drawing_accel_mps2)
    }

    /// The longest gap the IMU bridges, nanoseconds: `sqrt(8 e / b)` for the acceleration error `b`.
    pub fn max_imu_gap_ns(&self) -> u64 {
        self.gap_for_accel_error(self.imu_accel_error_mps2)
    }

    /// The gap over which a path off by acceleration `a` leaves its bridge `max_bridge_error_m` off
    /// (`a dt^2 / 8`), nanoseconds.
    fn gap_for_accel_error(&self, a: f64) -> u64 {
        let dt = (8.0 * self.max_bridge_error_m.max(0.0) / a.max(1e-9)).sqrt();
        (dt * 1e9).min(u64::MAX as f64) as u64
    }

    /// How the gap between two consecutive tips is bridged, or None when it splits the stroke.
    fn bridge(&self, tracked: &[TimedPoint], i: usize, accel: &[TimedAccel]) -> Option<Bridge> {
        let gap = tracked[i + 1].t_ns.saturating_sub(tracked[i].t_ns);
        if gap <= self.max_gap_ns() {
            return Some(Bridge::Chord);
        }
        if gap > self.max_imu_gap_ns() {
            return None;
        }
        imu_bridge(tracked, i, accel, &self.imu_bridge).map(Bridge::Imu)
    }
}

/// The path across a gap between two consecutive tips of a piece.
enum Bridge {
    /// The chord (short gaps).
    Chord,
    /// The IMU's path, as timed points inside the gap.
    Imu(Vec<(u64, [f64; 3])>),
}

/// The strokes-file record of `stroke`, with its stable `id` and the `buttons` held at pen-down. The raw
/// samples are first moved onto the IMU-smoothed path (with [`StrokeRecordConfig::imu_smooth`], run by run
/// between gaps longer than [`StrokeRecordConfig::max_imu_gap_ns`]), then split into pieces where two consecutive ones are more than
/// [`StrokeRecordConfig::max_gap_ns`] apart and the IMU cannot bridge them
/// ([`StrokeRecordConfig::max_imu_gap_ns`]); each piece is post-processed on its own. Each output
/// point gets the time at which the tip passed the same fraction of its piece's raw arc length, and
/// the uncertainty of the raw sample nearest that time.
pub fn stroke_record(
    id: u32,
    buttons: u8,
    stroke: &Stroke,
    config: &StrokeRecordConfig,
) -> fires_record::Stroke {
    let smoothed = config
        .imu_smooth
        .as_ref()
        .map(|o| smoothed_tips(&stroke.points, &stroke.accel, config.max_imu_gap_ns(), o));
    let pts = smoothed.as_deref().unwrap_or(&stroke.points);
    let bridges: Vec<Option<Bridge>> = (0..pts.len().saturating_sub(1))
        .map(|i| config.bridge(pts, i, &stroke.accel))
        .collect();
    let mut pieces = Vec::new();
    let mut start = 0;
    for i in 1..=pts.len() {
        let split = i == pts.len() || bridges[i - 1].is_none();
        if split && i > start {
            let inner = &bridges[start..i - 1];
            pieces.push(piece(&pts[start..i], inner, stroke.t_start_ns, config));
            start = i;
        }
    }
    let polyline: Vec<[f64; 3]> = pieces
        .iter()
        .flat_map(|p: &StrokePiece| p.points.iter().map(|q| q.p_m))
        .collect();
    let length: f64 = pieces
        .iter()
        .map(|p| {
            p.points
                .windows(2)
                .map(|w| dist(&w[0].p_m, &w[1].p_m))
                .sum::<f64>()
        })
        .sum();
    let mut record = fires_record::Stroke {
        id,
        t_start_ns: stroke.t_start_ns,
        t_end_ns: stroke.t_end_ns,
        buttons,
        closed: false,
        raw_points: stroke.points.len(),
        pieces,
    };
    // The ends may be apart by what the pen drew unseen at either end (the button was down, the
    // tracker had no tip): a loop whose start was lost still closes.
    let [u0, u1] = record.untracked_mm();
    record.closed = match (polyline.first(), polyline.last()) {
        (Some(a), Some(b)) => {
            dist(a, b) <= config.close_distance_m + (u0 + u1) * 1e-3
                && length >= config.min_closed_length * config.close_distance_m
        }
        _ => false,
    };
    record
}

/// The tips moved onto the IMU-smoothed path ([`imu_smooth`]), times and σ kept, run by run: runs
/// part where two tips are further apart than `max_gap_ns`, the longest gap the IMU bridges (across
/// a longer one the acceleration is not trusted to tie the two sides together). A run the smoother
/// declines (too few tips, the IMU's samples not covering it) keeps its tips as tracked.
fn smoothed_tips(
    tips: &[TimedPoint],
    accel: &[TimedAccel],
    max_gap_ns: u64,
    options: &ImuSmoothOptions,
) -> Vec<TimedPoint> {
    let mut out = Vec::with_capacity(tips.len());
    let mut start = 0;
    for i in 1..=tips.len() {
        let split = i == tips.len() || tips[i].t_ns.saturating_sub(tips[i - 1].t_ns) > max_gap_ns;
        if split {
            let run = &tips[start..i];
            match imu_smooth(run, accel, options) {
                Some(path) => out.extend(run.iter().zip(path).map(|(t, p)| TimedPoint { p, ..*t })),
                None => out.extend_from_slice(run),
            }
            start = i;
        }
    }
    out
}

/// One piece: the post-processed polyline of raw samples tracked without a gap they could not bridge
/// (`bridges[i]` between `tracked[i]` and `tracked[i + 1]`). The IMU's bridge points join the raw samples,
/// carrying the uncertainty of the nearest tracked one.
fn piece(
    tracked: &[TimedPoint],
    bridges: &[Option<Bridge>],
    t_start_ns: u64,
    config: &StrokeRecordConfig,
) -> StrokePiece {
    let mut raw = Vec::with_capacity(tracked.len());
    for (i, p) in tracked.iter().enumerate() {
        raw.push(*p);
        if let Some(Some(Bridge::Imu(path))) = bridges.get(i) {
            raw.extend(path.iter().map(|&(t_ns, q)| TimedPoint {
                t_ns,
                p: q,
                sigma_m: match (p.sigma_m, tracked[i + 1].sigma_m) {
                    (Some(a), Some(b)) => Some(a.max(b)),
                    (a, b) => a.or(b),
                },
            }));
        }
    }
    let raw = &raw[..];
    let pts: Vec<[f64; 3]> = raw.iter().map(|p| p.p).collect();
    let polyline = if pts.len() >= 2 {
        let step = config.postprocess.sample_threshold;
        postprocess(&chord_bridged(&pts, step), &config.postprocess).unwrap_or_else(|_| pts.clone())
    } else {
        pts.clone()
    };
    let times = arc_length_times(raw, t_start_ns, &polyline);
    let points = polyline
        .iter()
        .zip(times)
        .map(|(&p_m, t_ns)| StrokePoint {
            t_ns,
            p_m,
            sigma_mm: sigma_at(raw, t_ns).map(|s| s * 1e3),
        })
        .collect();
    StrokePiece { points }
}

/// `points` with points at most `step` apart inserted along every chord longer than two steps.
///
/// A gap the piece bridges (up to [`StrokeRecordConfig::max_gap_ns`]) is bridged by its chord: that is
/// the path whose error the gap limit bounds. Left without data, the spline's knot spans across the gap
/// are held only by its small smoothing penalty and bulge with the slopes at the gap's ends (fires-v1
/// seed 3, the boundary stroke: an 85 ms gap of 21 mm while the pen pointed at a camera bulged 8.6 mm
/// from the pen's path).
fn chord_bridged(points: &[[f64; 3]], step: f64) -> Vec<[f64; 3]> {
    let mut out = Vec::with_capacity(points.len());
    for (i, p) in points.iter().enumerate() {
        if let Some(q) = i.checked_sub(1).map(|j| points[j]) {
            let c = dist(&q, p);
            if step > 0.0 && c > 2.0 * step {
                let n = (c / step).ceil() as usize;
                out.extend((1..n).map(|k| {
                    let a = k as f64 / n as f64;
                    [0, 1, 2].map(|j| q[j] + a * (p[j] - q[j]))
                }));
            }
        }
        out.push(*p);
    }
    out
}

/// The uncertainty of the raw sample nearest `t_ns`.
fn sigma_at(raw: &[TimedPoint], t_ns: u64) -> Option<f64> {
    let i = raw.partition_point(|p| p.t_ns < t_ns);
    let near = [i.checked_sub(1), Some(i)]
        .into_iter()
        .flatten()
        .filter_map(|k| raw.get(k))
        .min_by_key(|p| p.t_ns.abs_diff(t_ns))?;
    near.sigma_m
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

/// Cumulative arc length of a polyline, normalised to 0..=1 (all zeros for a path of no length).
fn normalised_arc_length(points: impl Iterator<Item = [f64; 3]>) -> Vec<f64> {
    let mut s = Vec::new();
    let mut prev: Option<[f64; 3]> = None;
    let mut total = 0.0;
    for p in points {
        if let Some(q) = prev {
            total += dist(&p, &q);
        }
        s.push(total);
        prev = Some(p);
    }
    if total > 0.0 {
        s.iter_mut().for_each(|v| *v /= total);
    }
    s
}

/// The time of each output point: the raw samples' time, interpolated at the same normalised arc length.
fn arc_length_times(raw: &[TimedPoint], t_start_ns: u64, polyline: &[[f64; 3]]) -> Vec<u64> {
    let raw_s = normalised_arc_length(raw.iter().map(|p| p.p));
    let out_s = normalised_arc_length(polyline.iter().copied());
    let raw_t: Vec<u64> = raw.iter().map(|p| p.t_ns).collect();
    out_s
        .iter()
        .map(|&s| {
            let i = raw_s.partition_point(|&r| r < s);
            match (i.checked_sub(1), raw_t.get(i)) {
                (_, None) => raw_t.last().copied().unwrap_or(t_start_ns),
                (None, Some(&t)) => t,
                (Some(j), Some(&t1)) => {
                    let (s0, s1, t0) = (raw_s[j], raw_s[i], raw_t[j]);
                    let w = if s1 > s0 { (s - s0) / (s1 - s0) } else { 0.0 };
                    t0 + ((t1 - t0) as f64 * w).round() as u64
                }
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stroke::TimedPoint;

    fn line_stroke(n: usize, closed: bool) -> Stroke {
        let points = (0..n)
            .map(|i| {
                let a = i as f64 / (n - 1) as f64;
                let p = if closed {
                    let th = a * std::f64::consts::TAU;
                    [0.05 * th.cos(), 0.05 * th.sin(), 0.5]
                } else {
                    [0.1 * a, 0.0, 0.5]
                };
                TimedPoint {
                    t_ns: 1_000_000_000 + (a * 2e9) as u64,
                    p,
                    sigma_m: Some(0.5e-3),
                }
            })
            .collect();
        Stroke {
            t_start_ns: 1_000_000_000,
            t_end_ns: 3_000_000_000,
            points,
            accel: Vec::new(),
        }
    }

    #[test]
    fn times_follow_the_arc_length_of_a_uniformly_drawn_line() {
        let r = stroke_record(7, 0b0011, &line_stroke(201, false), &Default::default());
        assert_eq!(
            (r.id, r.buttons, r.closed, r.raw_points),
            (7, 0b0011, false, 201)
        );
        let pts: Vec<_> = r.points().collect();
        assert!(pts.len() > 10);
        for p in &pts {
            // Drawn at constant speed: time is linear in x (0.1 m in 2 s), to within the spline's smoothing.
            let expect = 1e9 + p.p_m[0] / 0.1 * 2e9;
            assert!(
                (p.t_ns as f64 - expect).abs() < 2e7,
                "{} vs {expect}",
                p.t_ns
            );
        }
        assert!(pts.windows(2).all(|w| w[0].t_ns <= w[1].t_ns));
    }

    #[test]
    fn a_loop_is_closed_and_a_line_or_a_dab_is_not() {
        let cfg = StrokeRecordConfig::default();
        assert!(stroke_record(0, 1, &line_stroke(400, true), &cfg).closed);
        assert!(!stroke_record(0, 1, &line_stroke(400, false), &cfg).closed);
        let mut dab = line_stroke(50, false);
        dab.points.iter_mut().for_each(|p| p.p[0] *= 0.02);
        assert!(!stroke_record(0, 1, &dab, &cfg).closed);
    }

    #[test]
    fn a_loop_whose_start_was_not_tracked_is_still_closed() {
        // The 50 mm loop is drawn in 2 s (157 mm/s); the tracker missed its first 0.1 s, so its ends
        // are a 15.7 mm chord apart, over the 10 mm closing distance.
        let cfg = StrokeRecordConfig::default();
        let mut late = line_stroke(400, true);
        late.points.retain(|p| p.t_ns >= 1_100_000_000);
        let r = stroke_record(0, 1, &late, &cfg);
        let [u0, u1] = r.untracked_mm();
        assert!((u0 - 15.7).abs() < 0.5 && u1 == 0.0, "{u0} {u1}");
        assert!(r.closed);
        // The same points with the button pressed at the first of them: nothing was drawn unseen, and
        // a 15.7 mm gap is an open curve.
        late.t_start_ns = late.points[0].t_ns;
        assert!(!stroke_record(0, 1, &late, &cfg).closed);
    }

    #[test]
    fn a_gap_too_long_to_bridge_splits_the_stroke_into_pieces_of_one_id() {
        let cfg = StrokeRecordConfig::default();
        // sqrt(8 * 1 mm / 1 m/s^2) = 89.4 ms.
        assert_eq!(cfg.max_gap_ns() / 1_000_000, 89);
        let mut stroke = line_stroke(201, false);
        // Drop the samples of 0.4 s in the middle (a 0.41 s gap): two pieces.
        stroke
            .points
            .retain(|p| !(1_800_000_000..2_200_000_000).contains(&p.t_ns));
        let r = stroke_record(3, 1, &stroke, &cfg);
        assert_eq!((r.id, r.pieces.len()), (3, 2));
        let (a, b) = (&r.pieces[0].points, &r.pieces[1].points);
        let end_a = a.last().unwrap().p_m[0];
        let start_b = b.first().unwrap().p_m[0];
        // Nothing is drawn across the gap (x from 0.04 to 0.06 m).
        assert!(end_a < 0.0401 && start_b > 0.0599, "{end_a} {start_b}");
        assert!(r
            .points()
            .all(|p| p.sigma_mm.is_some_and(|s| (s - 0.5).abs() < 1e-12)));
        // A gap within the limit (50 ms) is bridged.
        let mut short = line_stroke(201, false);
        short
            .points
            .retain(|p| !(1_980_000_000..2_020_000_000).contains(&p.t_ns));
        assert_eq!(stroke_record(3, 1, &short, &cfg).pieces.len(), 1);
    }

    #[test]
    fn a_bridged_gap_follows_its_chord_and_does_not_bulge() {
        // A hand at the bridge's design acceleration (1 m/s^2: a 62.5 mm-radius arc at 0.25 m/s),
        // one sample per 10 ms, with 7 samples missing (an 80 ms, 20 mm gap, within the 89 ms
        // limit). The three samples before the gap hook 0.5, 1 and 1.5 mm off the path, as tips
        // from two LEDs do while the pen turns towards a camera (fires-v1 seed 3). The chord leaves
        // the arc by a dt^2 / 8 = 0.8 mm, less than the hook: bridged by it, the stroke stays
        // within its worst sample's error (0.95 mm); left to the spline's smoothing penalty
        // alone, the data-free spans carried the hook on into the gap (2.1 mm).
        let (r, v) = (0.0625, 0.25);
        let points: Vec<TimedPoint> = (0..=120)
            .filter(|i| !(61..68).contains(i))
            .map(|i| {
                let t = i as f64 * 0.01;
                let th = v * t / r;
                let hook = match i {
                    58..=60 => (i - 57) as f64 * 0.5e-3,
                    _ => 0.0,
                };
                TimedPoint {
                    t_ns: 1_000_000_000 + i as u64 * 10_000_000,
                    p: [(r + hook) * th.cos(), (r + hook) * th.sin(), 0.5],
                    sigma_m: None,
                }
            })
            .collect();
        let stroke = Stroke {
            t_start_ns: 1_000_000_000,
            t_end_ns: 2_200_000_000,
            points,
            accel: Vec::new(),
        };
        let rec = stroke_record(0, 0, &stroke, &Default::default());
        assert_eq!(rec.pieces.len(), 1);
        let worst = rec
            .points()
            .map(|p| (p.p_m[0].hypot(p.p_m[1]) - r).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1.5e-3, "{worst}");
    }
}
