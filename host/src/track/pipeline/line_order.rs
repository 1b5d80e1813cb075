//! Blob correspondence between two consecutive frames of one camera without LED identities: the
//! pen's LEDs image on a line, in pen order, so when both frames show the same number of blobs,
//! all on one line, and with the same relative spacing, the k-th blob along the line is the same
//! LED in both. Unlike nearest-neighbour matching this cannot alias to the neighbouring LED when
//! the pen moves about one LED spacing between frames (the order along the line is kept), and it
//! lets the time alignment move the other camera's blobs while no vision pose is known (FIRES
//! thesis, §4.1.3: the cameras are never exposed at the same instant).

/// Limits of [`match_along_line`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct LineOrderOptions {
    /// Largest distance of a blob from the frame's line, pixels.
    pub(super) max_line_residual_px: f64,
    /// Shortest line (first to last blob), pixels: shorter lines have no reliable direction.
    pub(super) min_length_px: f64,
    /// Largest turn of the line between the frames, radians.
    pub(super) max_turn_rad: f64,
    /// Largest change of a gap's share of the line length between the frames.
    pub(super) max_spacing_change: f64,
    /// Largest relative change of the line length between the frames (the pen's triples come in
    /// near-twins with the same spacing shares, {2,3,4} and {1,2,4}, 1.78 times longer).
    pub(super) max_length_change: f64,
    /// Largest motion of a blob between the frames, pixels.
    pub(super) max_motion_px: f64,
}

impl Default for LineOrderOptions {
    fn default() -> Self {
        Self {
            max_line_residual_px: 2.0,
            min_length_px: 15.0,
            max_turn_rad: 20f64.to_radians(),
            max_spacing_change: 0.08,
            max_length_change: 0.25,
            max_motion_px: 40.0,
        }
    }
}

/// The line of a frame's blobs: unit direction and the blob indices in order along it, or None
/// when there are fewer than two blobs, they do not lie on one line, or the line is too short.
fn line_order(blobs: &[[f64; 2]], o: &LineOrderOptions) -> Option<([f64; 2], Vec<usize>)> {
    let n = blobs.len();
    if n < 2 {
        return None;
    }
    let c = blobs.iter().fold([0.0, 0.0], |a, b| {
        [a[0] + b[0] / n as f64, a[1] + b[1] / n as f64]
    });
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for b in blobs {
        let (x, y) = (b[0] - c[0], b[1] - c[1]);
        sxx += x * x;
        sxy += x * y;
        syy += y * y;
    }
    let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let d = [angle.cos(), angle.sin()];
    let along = |b: &[f64; 2]| (b[0] - c[0]) * d[0] + (b[1] - c[1]) * d[1];
    let across = |b: &[f64; 2]| ((b[1] - c[1]) * d[0] - (b[0] - c[0]) * d[1]).abs();
    if blobs
        .iter()
        .any(|b| across(b).is_nan() || across(b) > o.max_line_residual_px)
    {
        return None;
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| along(&blobs[a]).total_cmp(&along(&blobs[b])));
    let length = along(&blobs[order[n - 1]]) - along(&blobs[order[0]]);
    (length >= o.min_length_px).then_some((d, order))
}

/// Pairs of (previous blob, current blob) indices that image the same LED, or None when the
/// frames cannot be matched safely: different blob counts, blobs off a line, a line that turned
/// too much, changed relative spacing (other LEDs seen) or a blob that moved too far.
pub(super) fn match_along_line(
    previous: &[[f64; 2]],
    current: &[[f64; 2]],
    o: &LineOrderOptions,
) -> Option<Vec<(usize, usize)>> {
    if previous.len() != current.len() {
        return None;
    }
    let (dp, mut op) = line_order(previous, o)?;
    let (dc, oc) = line_order(current, o)?;
    let dot = dp[0] * dc[0] + dp[1] * dc[1];
    if dot.abs() < o.max_turn_rad.cos() {
        return None;
    }
    if dot < 0.0 {
        op.reverse();
    }
    let dist = |a: &[f64; 2], b: &[f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let shares = |blobs: &[[f64; 2]], order: &[usize]| -> Vec<f64> {
        let total = dist(&blobs[order[0]], &blobs[order[order.len() - 1]]);
        order
            .windows(2)
            .map(|w| dist(&blobs[w[0]], &blobs[w[1]]) / total)
            .collect()
    };
    let length = |blobs: &[[f64; 2]], order: &[usize]| {
        dist(&blobs[order[0]], &blobs[order[order.len() - 1]])
    };
    let ratio = length(current, &oc) / length(previous, &op);
    if !(ratio <= 1.0 + o.max_length_change && ratio * (1.0 + o.max_length_change) >= 1.0) {
        return None;
    }
    let (sp, sc) = (shares(previous, &op), shares(current, &oc));
    if sp
        .iter()
        .zip(&sc)
        .any(|(a, b)| (a - b).abs() > o.max_spacing_change)
    {
        return None;
    }
    let pairs: Vec<(usize, usize)> = op.into_iter().zip(oc).collect();
    pairs
        .iter()
        .all(|&(p, c)| dist(&previous[p], &current[c]) <= o.max_motion_px)
        .then_some(pairs)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// LEDs 2, 3, 4 of the 70/40/50 pen at 1 px/mm, along a slanted line.
    fn pen(offset: [f64; 2], positions: &[f64]) -> Vec<[f64; 2]> {
        let d = [0.8, 0.6];
        positions
            .iter()
            .map(|s| [offset[0] + s * d[0], offset[1] + s * d[1]])
            .collect()
    }

    /// A pen that moves by one LED spacing along itself between frames is matched LED to LED
    /// (nearest neighbour would pair each blob with the neighbouring LED), in any blob order.
    #[test]
    fn a_pen_moving_one_led_spacing_is_matched_by_order_not_by_proximity() {
        let o = LineOrderOptions::default();
        let prev = pen([100.0, 100.0], &[70.0, 110.0, 160.0]);
        let mut cur = pen([132.0, 124.0], &[70.0, 110.0, 160.0]);
        cur.reverse();
        let pairs = match_along_line(&prev, &cur, &o).unwrap();
        assert_eq!(pairs, vec![(0, 2), (1, 1), (2, 0)]);
        // The current blob nearest the previous LED 3 is LED 2's image.
        let nearest = (0..3)
            .min_by(|&a, &b| {
                let d = |i: usize| (cur[i][0] - prev[1][0]).hypot(cur[i][1] - prev[1][1]);
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        assert_eq!(nearest, 2);
    }

    /// Other LEDs in view (same count: the twin triple {1,2,4} has {2,3,4}'s spacing shares,
    /// or another spacing), blobs off the line, or another count: no match.
    #[test]
    fn frames_that_may_show_other_leds_are_not_matched() {
        let o = LineOrderOptions::default();
        let prev = pen([100.0, 100.0], &[70.0, 110.0, 160.0]);
        let twin = pen([101.0, 100.0], &[0.0, 70.0, 160.0]);
        assert!(match_along_line(&prev, &twin, &o).is_none());
        let other_spacing = pen([101.0, 100.0], &[70.0, 90.0, 160.0]);
        assert!(match_along_line(&prev, &other_spacing, &o).is_none());
        let mut off_line = prev.clone();
        off_line[1][1] += 6.0;
        assert!(match_along_line(&prev, &off_line, &o).is_none());
        assert!(match_along_line(&prev, &prev[..2], &o).is_none());
        assert!(match_along_line(&prev, &prev, &o).is_some());
    }
}
