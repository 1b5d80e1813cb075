//! Tracked strokes against the true strokes of a simulated recording (`truth/strokes.json`).
//!
//! Each tracked stroke is matched to the true stroke whose `[start, end]` interval overlaps its own
//! `[t_start_ns, t_end_ns]` the longest (the button stream is the same, so matching by time is unambiguous).
//! Per true stroke: the distance of every tracked point to the true tip polyline (point to segment), the
//! fraction of the true path's length within [`StrokeCompareOptions::cover_m`] of the tracked pieces (each piece
//! a polyline; a one-point piece a point), and the tracked length over the true length.

use fires_record::report::{MedianWorst, StrokeVsTruth, StrokesSummary};
use fires_record::{Stroke, StrokeTruth};

/// Settings of the comparison.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrokeCompareOptions {
    /// A true point within this distance of the tracked pieces is covered, metres.
    pub cover_m: f64,
    /// The true path is sampled at most this far apart to measure its coverage, metres.
    pub cover_step_m: f64,
}

impl Default for StrokeCompareOptions {
    fn default() -> Self {
        StrokeCompareOptions {
            cover_m: 0.003,
            cover_step_m: 0.000_1,
        }
    }
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Distance from `p` to the segment `a`–`b`.
pub fn point_segment_distance(p: &[f64; 3], a: &[f64; 3], b: &[f64; 3]) -> f64 {
    let ab: [f64; 3] = std::array::from_fn(|k| b[k] - a[k]);
    let ap: [f64; 3] = std::array::from_fn(|k| p[k] - a[k]);
    let len2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
    let s = if len2 > 0.0 {
        ((ap[0] * ab[0] + ap[1] * ab[1] + ap[2] * ab[2]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let q: [f64; 3] = std::array::from_fn(|k| a[k] + s * ab[k]);
    dist(p, &q)
}

/// Distance from `p` to a polyline (a single point when it has one; infinite when empty).
pub fn point_polyline_distance(p: &[f64; 3], line: &[[f64; 3]]) -> f64 {
    match line {
        [] => f64::INFINITY,
        [a] => dist(p, a),
        _ => line
            .windows(2)
            .map(|w| point_segment_distance(p, &w[0], &w[1]))
            .fold(f64::INFINITY, f64::min),
    }
}

/// Length of a polyline.
pub fn polyline_length(line: &[[f64; 3]]) -> f64 {
    line.windows(2).map(|w| dist(&w[0], &w[1])).sum()
}

/// The figures of one true path against tracked pieces (each a polyline), with the true stroke's id and the
/// tracked strokes' ids.
pub fn compare_polylines(
    truth_id: u32,
    tracked_ids: Vec<u32>,
    truth: &[[f64; 3]],
    pieces: &[Vec<[f64; 3]>],
    opt: &StrokeCompareOptions,
) -> StrokeVsTruth {
    let d: Vec<f64> = pieces
        .iter()
        .flatten()
        .map(|p| point_polyline_distance(p, truth))
        .collect();
    let lost = d.is_empty();
    let true_len = polyline_length(truth);
    let tracked_len: f64 = pieces.iter().map(|p| polyline_length(p)).sum();
    let near = |p: &[f64; 3]| {
        pieces
            .iter()
            .any(|line| point_polyline_distance(p, line) <= opt.cover_m)
    };
    // Coverage by the midpoint rule on sub-segments at most `cover_step_m` long.
    let coverage = (true_len > 0.0).then(|| {
        let mut covered = 0.0;
        for w in truth.windows(2) {
            let len = dist(&w[0], &w[1]);
            let n = (len / opt.cover_step_m.max(1e-9)).ceil().max(1.0) as usize;
            for j in 0..n {
                let s = (j as f64 + 0.5) / n as f64;
                let p: [f64; 3] = std::array::from_fn(|k| w[0][k] + s * (w[1][k] - w[0][k]));
                if near(&p) {
                    covered += len / n as f64;
                }
            }
        }
        (covered / true_len).min(1.0)
    });
    StrokeVsTruth {
        truth_id,
        tracked_ids,
        rms_mm: (!lost)
            .then(|| (d.iter().map(|e| e * e).sum::<f64>() / d.len() as f64).sqrt() * 1e3),
        max_mm: (!lost).then(|| d.iter().copied().fold(0.0, f64::max) * 1e3),
        coverage_3mm: coverage,
        length_ratio: (!lost && true_len > 0.0).then(|| tracked_len / true_len),
    }
}

/// One entry per true stroke, in the order of `truth`: the tracked strokes matched to it by time overlap.
pub fn strokes_vs_truth(
    tracked: &[Stroke],
    truth: &[StrokeTruth],
    opt: &StrokeCompareOptions,
) -> Vec<StrokeVsTruth> {
    let overlap = |s: &Stroke, t: &StrokeTruth| {
        s.t_end_ns
            .min(t.end_time_ns)
            .saturating_sub(s.t_start_ns.max(t.start_time_ns))
    };
    let mut assigned: Vec<Vec<&Stroke>> = vec![Vec::new(); truth.len()];
    for s in tracked {
        let best = truth
            .iter()
            .enumerate()
            .map(|(i, t)| (i, overlap(s, t)))
            .filter(|&(_, o)| o > 0)
            .max_by_key(|&(_, o)| o);
        if let Some((i, _)) = best {
            assigned[i].push(s);
        }
    }
    truth
        .iter()
        .zip(assigned)
        .map(|(t, strokes)| {
            let pieces: Vec<Vec<[f64; 3]>> = strokes
                .iter()
                .flat_map(|s| &s.pieces)
                .map(|p| p.points.iter().map(|q| q.p_m).collect::<Vec<_>>())
                .filter(|p: &Vec<[f64; 3]>| !p.is_empty())
                .collect();
            let ids = strokes.iter().map(|s| s.id).collect();
            compare_polylines(t.id, ids, &t.tip_polyline_m, &pieces, opt)
        })
        .collect()
}

/// Median and worst of values where `worse(a, b)` says `a` is worse than `b`.
fn median_worst(mut v: Vec<f64>, worse: impl Fn(f64, f64) -> bool) -> MedianWorst {
    if v.is_empty() {
        return MedianWorst::default();
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    let median = if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    };
    let worst = v
        .iter()
        .copied()
        .fold(v[0], |w, x| if worse(x, w) { x } else { w });
    MedianWorst {
        median: Some(median),
        worst: Some(worst),
    }
}

/// The median and worst of each figure (over the strokes that have it).
pub fn strokes_summary(entries: &[StrokeVsTruth]) -> StrokesSummary {
    let col = |f: &dyn Fn(&StrokeVsTruth) -> Option<f64>| entries.iter().filter_map(f).collect();
    StrokesSummary {
        true_strokes: entries.len(),
        kept: entries.iter().filter(|e| !e.tracked_ids.is_empty()).count(),
        rms_mm: median_worst(col(&|e| e.rms_mm), |a, b| a > b),
        max_mm: median_worst(col(&|e| e.max_mm), |a, b| a > b),
        coverage_3mm: median_worst(col(&|e| e.coverage_3mm), |a, b| a < b),
        length_ratio: median_worst(col(&|e| e.length_ratio), |a, b| {
            (a.ln()).abs() > (b.ln()).abs()
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 0.1 m arc of a 0.05 m circle sampled at 201 points.
    fn arc(offset_z: f64) -> Vec<[f64; 3]> {
        (0..=200)
            .map(|i| {
                let a = i as f64 / 200.0 * 2.0;
                [0.05 * a.cos(), 0.05 * a.sin(), 0.6 + offset_z]
            })
            .collect()
    }

    #[test]
    fn identical_offset_and_half_missing_give_exact_figures() {
        let opt = StrokeCompareOptions::default();
        let truth = arc(0.0);
        let same = compare_polylines(0, vec![0], &truth, std::slice::from_ref(&truth), &opt);
        assert_eq!(same.rms_mm, Some(0.0));
        assert_eq!(same.max_mm, Some(0.0));
        assert_eq!(same.coverage_3mm, Some(1.0));
        assert!((same.length_ratio.unwrap() - 1.0).abs() < 1e-12);

        // Offset by 2 mm along the circle's axis: every point 2 mm away, all of it covered, same length.
        let off = compare_polylines(0, vec![0], &truth, &[arc(0.002)], &opt);
        assert!((off.rms_mm.unwrap() - 2.0).abs() < 1e-9, "{off:?}");
        assert!((off.max_mm.unwrap() - 2.0).abs() < 1e-9);
        assert_eq!(off.coverage_3mm, Some(1.0));
        // Offset by 4 mm: nothing within 3 mm.
        let far = compare_polylines(0, vec![0], &truth, &[arc(0.004)], &opt);
        assert_eq!(far.coverage_3mm, Some(0.0));

        // The first half tracked in two pieces: half the path, plus the 3 mm the end of the tracked half
        // reaches along the arc (its chord, 3 mm, at this curvature covers 3.000003 mm of arc).
        let len = polyline_length(&truth);
        let half = compare_polylines(
            0,
            vec![0],
            &truth,
            &[truth[..=50].to_vec(), truth[50..=100].to_vec()],
            &opt,
        );
        let expect = 0.5 + 0.003 / len;
        assert!(
            (half.coverage_3mm.unwrap() - expect).abs() < 2e-3,
            "{half:?} vs {expect}"
        );
        assert!((half.length_ratio.unwrap() - 0.5).abs() < 1e-12);
        assert_eq!(half.rms_mm, Some(0.0));

        // Lost: no distances, nothing covered.
        let lost = compare_polylines(3, vec![], &truth, &[], &opt);
        assert_eq!(
            (lost.rms_mm, lost.max_mm, lost.length_ratio),
            (None, None, None)
        );
        assert_eq!(lost.coverage_3mm, Some(0.0));
    }

    #[test]
    fn summary_takes_median_and_worst_over_strokes_with_the_figure() {
        let e = |rms: Option<f64>, cov: f64, ratio: Option<f64>| StrokeVsTruth {
            truth_id: 0,
            tracked_ids: if rms.is_some() { vec![0] } else { vec![] },
            rms_mm: rms,
            max_mm: rms,
            coverage_3mm: Some(cov),
            length_ratio: ratio,
        };
        let s = strokes_summary(&[
            e(Some(1.0), 1.0, Some(1.1)),
            e(Some(3.0), 0.9, Some(0.8)),
            e(None, 0.0, None),
            e(Some(2.0), 0.95, Some(1.0)),
        ]);
        assert_eq!((s.true_strokes, s.kept), (4, 3));
        assert_eq!(s.rms_mm.median, Some(2.0));
        assert_eq!(s.rms_mm.worst, Some(3.0));
        assert_eq!(s.coverage_3mm.worst, Some(0.0));
        assert_eq!(s.coverage_3mm.median, Some(0.925));
        assert_eq!(s.length_ratio.worst, Some(0.8));
        assert_eq!(strokes_summary(&[]).rms_mm, MedianWorst::default());
    }
}
