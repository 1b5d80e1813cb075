//! From a finished stroke (tracked tip samples between pen-down and pen-up) to the strokes file's
//! [`fires_record::Stroke`]: the post-processed polyline (thesis §4.1.3), a time for every point, the pen-mode
//! buttons and whether the stroke closes on itself (docs/strokes.md).

use fires_record::{StrokePiece, StrokePoint};

use super::{postprocess, PostprocessConfig, Stroke};

/// How a finished stroke becomes a record of the strokes file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrokeRecordConfig {
    /// End-of-stroke post-processing.
    pub postprocess: PostprocessConfig,
    /// A stroke whose end is within this distance of its start is closed, metres.
    pub close_distance_m: f64,
    /// ... and only if it is at least this many closing distances long (a dab is not a loop).
    pub min_closed_length: f64,
}

impl Default for StrokeRecordConfig {
    fn default() -> Self {
        // A hand closing a loop by eye ends within about a centimetre of its start; the curve network snaps
        // the ends together.
        StrokeRecordConfig {
            postprocess: PostprocessConfig::default(),
            close_distance_m: 0.010,
            min_closed_length: 4.0,
        }
    }
}

/// The strokes-file record of `stroke`, with its stable `id` and the `buttons` held at pen-down. Each output
/// point gets the time at which the tip passed the same fraction of the raw path's arc length.
pub fn stroke_record(
    id: u32,
    buttons: u8,
    stroke: &Stroke,
    config: &StrokeRecordConfig,
) -> fires_record::Stroke {
    let raw: Vec<[f64; 3]> = stroke.points.iter().map(|p| p.p).collect();
    let polyline = postprocess(&raw, &config.postprocess).unwrap_or_else(|_| raw.clone());
    let times = arc_length_times(stroke, &polyline);
    let points = polyline
        .iter()
        .zip(times)
        .map(|(&p_m, t_ns)| StrokePoint {
            t_ns,
            p_m,
            sigma_mm: None,
        })
        .collect();
    let length: f64 = polyline.windows(2).map(|w| dist(&w[0], &w[1])).sum();
    let closed = match (polyline.first(), polyline.last()) {
        (Some(a), Some(b)) => {
            dist(a, b) <= config.close_distance_m
                && length >= config.min_closed_length * config.close_distance_m
        }
        _ => false,
    };
    fires_record::Stroke {
        id,
        t_start_ns: stroke.t_start_ns,
        t_end_ns: stroke.t_end_ns,
        buttons,
        closed,
        raw_points: raw.len(),
        pieces: vec![StrokePiece { points }],
    }
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
fn arc_length_times(stroke: &Stroke, polyline: &[[f64; 3]]) -> Vec<u64> {
    let raw_s = normalised_arc_length(stroke.points.iter().map(|p| p.p));
    let out_s = normalised_arc_length(polyline.iter().copied());
    let raw_t: Vec<u64> = stroke.points.iter().map(|p| p.t_ns).collect();
    out_s
        .iter()
        .map(|&s| {
            let i = raw_s.partition_point(|&r| r < s);
            match (i.checked_sub(1), raw_t.get(i)) {
                (_, None) => raw_t.last().copied().unwrap_or(stroke.t_start_ns),
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
                }
            })
            .collect();
        Stroke {
            t_start_ns: 1_000_000_000,
            t_end_ns: 3_000_000_000,
            points,
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
}
