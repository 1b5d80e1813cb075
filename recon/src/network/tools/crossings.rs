//! Where a new curve meets the network (FIRES thesis §5.2.1, Fig. 5.7b): for each existing polyline the
//! curve comes within the intersection threshold of, the pair (point on the new curve, point on the old
//! polyline) at the shortest distance, one pair per separate approach, ordered along the new curve.
//!
//! Spatial index: the new curve's segments go into a uniform hash grid (cell = the larger of twice the
//! threshold and the mean segment length), grown by the threshold; each old polyline whose bounding box
//! meets the curve's is walked once and each of its segments looks up only the cells it covers, so the
//! cost is O(old segments near the curve + candidate pairs), not all pairs.

use std::collections::HashMap;

use crate::network::geom::{arc_lengths, bbox, boxes_overlap, dist, lerp, segment_segment, P3};
use crate::network::mesh::Network;
use crate::network::EdgeId;

/// A place where the new curve meets an existing edge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Hit {
    /// Arc length along the new curve, metres.
    pub(crate) sigma: f64,
    /// The edge met.
    pub(crate) edge: EdgeId,
    /// Segment of the edge's polyline.
    pub(crate) seg: usize,
    /// Parameter on that segment.
    pub(crate) t: f64,
    /// The point on the old polyline.
    pub(crate) point: P3,
    /// Distance between the curves there, metres.
    pub(crate) distance: f64,
}

type Cell = (i64, i64, i64);

/// A fast hasher for integer cell keys (FxHash's multiply-rotate; the keys are not adversarial).
#[derive(Default, Clone, Copy)]
struct CellHasher(u64);

impl std::hash::Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.write_u64(u64::from(*b));
        }
    }
    fn write_i64(&mut self, v: i64) {
        self.write_u64(v as u64);
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

type CellMap = HashMap<Cell, Vec<u32>, std::hash::BuildHasherDefault<CellHasher>>;

struct Grid {
    cell: f64,
    map: CellMap,
}

impl Grid {
    fn key(&self, p: P3) -> Cell {
        (
            (p[0] / self.cell).floor() as i64,
            (p[1] / self.cell).floor() as i64,
            (p[2] / self.cell).floor() as i64,
        )
    }

    fn cells(&self, lo: P3, hi: P3) -> impl Iterator<Item = Cell> {
        let (a, b) = (self.key(lo), self.key(hi));
        (a.0..=b.0)
            .flat_map(move |x| (a.1..=b.1).flat_map(move |y| (a.2..=b.2).map(move |z| (x, y, z))))
    }
}

/// All places where `curve` (with cumulative arc lengths `arc`) meets the network within `threshold`
/// metres, sorted by arc length, and the network points nearest to the curve's first and last point
/// within `radius` (one pass over the network).
pub(crate) fn find_hits(
    net: &Network,
    curve: &[P3],
    arc: &[f64],
    threshold: f64,
    radius: f64,
) -> (Vec<Hit>, [Option<Hit>; 2]) {
    let mut ends: [Option<Hit>; 2] = [None, None];
    if curve.len() < 2 {
        return (Vec::new(), ends);
    }
    let end_points = [curve[0], curve[curve.len() - 1]];
    let total = arc[arc.len() - 1];
    let mean = total / (curve.len() - 1) as f64;
    // The cell is at least an eighth of the longest segment, so no segment covers more than ~10³ cells.
    let longest = arc.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
    let mut grid = Grid {
        cell: (2.0 * threshold).max(mean).max(longest / 8.0).max(1e-6),
        map: CellMap::default(),
    };
    for i in 0..curve.len() - 1 {
        let (lo, hi) = bbox(&curve[i..=i + 1]);
        let lo = [lo[0] - threshold, lo[1] - threshold, lo[2] - threshold];
        let hi = [hi[0] + threshold, hi[1] + threshold, hi[2] + threshold];
        let (a, b) = (grid.key(lo), grid.key(hi));
        for x in a.0..=b.0 {
            for y in a.1..=b.1 {
                for z in a.2..=b.2 {
                    grid.map.entry((x, y, z)).or_default().push(i as u32);
                }
            }
        }
    }
    let curve_box = bbox(curve);
    let mut hits = Vec::new();
    let mut cand: Vec<u32> = Vec::new();
    for (e, poly, boxes) in net.edges_near(curve_box, threshold.max(radius)) {
        for (k, &p) in end_points.iter().enumerate() {
            for j in boxes.segments_near((p, p), radius, poly.points.len()) {
                let (q0, q1) = (poly.points[j], poly.points[j + 1]);
                let (_, t, d) = segment_segment(p, p, q0, q1);
                if d <= radius && ends[k].is_none_or(|b| d < b.distance) {
                    ends[k] = Some(Hit {
                        sigma: 0.0,
                        edge: e,
                        seg: j,
                        t,
                        point: lerp(q0, q1, t),
                        distance: d,
                    });
                }
            }
        }
        // (sigma, seg, t, point, distance) of every close segment pair.
        let mut close: Vec<(f64, usize, f64, P3, f64)> = Vec::new();
        for j in boxes.segments_near(curve_box, threshold, poly.points.len()) {
            let (q0, q1) = (poly.points[j], poly.points[j + 1]);
            let sb = bbox(&[q0, q1]);
            if !boxes_overlap(curve_box, sb, threshold) {
                continue;
            }
            cand.clear();
            let (ka, kb) = (grid.key(sb.0), grid.key(sb.1));
            let span = |a: i64, b: i64| (b.saturating_sub(a)).saturating_add(1) as f64;
            let n_cells = span(ka.0, kb.0) * span(ka.1, kb.1) * span(ka.2, kb.2);
            if n_cells > (curve.len() as f64) {
                // An old segment far longer than the cells: test it against every new segment.
                cand.extend(0..(curve.len() - 1) as u32);
            } else {
                for c in grid.cells(sb.0, sb.1) {
                    if let Some(v) = grid.map.get(&c) {
                        cand.extend_from_slice(v);
                    }
                }
            }
            cand.sort_unstable();
            cand.dedup();
            for &i in &cand {
                let i = i as usize;
                let (s, t, d) = segment_segment(curve[i], curve[i + 1], q0, q1);
                if d <= threshold {
                    let sigma = arc[i] + s * (arc[i + 1] - arc[i]);
                    close.push((sigma, j, t, lerp(q0, q1, t), d));
                }
            }
        }
        close.sort_by(|a, b| a.0.total_cmp(&b.0));
        // One hit per separate approach: break where the new curve leaves the edge for more than
        // twice the threshold.
        let mut start = 0;
        for k in 1..=close.len() {
            if k == close.len() || close[k].0 - close[k - 1].0 > 2.0 * threshold + 1e-12 {
                let best = close[start..k]
                    .iter()
                    .min_by(|a, b| a.4.total_cmp(&b.4).then(a.0.total_cmp(&b.0)));
                if let Some(&(sigma, seg, t, point, distance)) = best {
                    hits.push(Hit {
                        sigma,
                        edge: e,
                        seg,
                        t,
                        point,
                        distance,
                    });
                }
                start = k;
            }
        }
    }
    hits.sort_by(|a, b| a.sigma.total_cmp(&b.sigma).then(a.edge.cmp(&b.edge)));
    (hits, ends)
}

/// The network point nearest to `p` within `radius` metres: `(edge, seg, t, point, distance)`.
pub(crate) fn nearest_point(net: &Network, p: P3, radius: f64) -> Option<Hit> {
    nearest_point_on(net, p, radius, |_| true)
}

/// [`nearest_point`] among the edges `accept` takes.
pub(crate) fn nearest_point_on(
    net: &Network,
    p: P3,
    radius: f64,
    accept: impl Fn(EdgeId) -> bool,
) -> Option<Hit> {
    let pbox = (p, p);
    let mut best: Option<Hit> = None;
    for (e, poly, boxes) in net.edges_near(pbox, radius) {
        if !accept(e) {
            continue;
        }
        for j in boxes.segments_near(pbox, radius, poly.points.len()) {
            let (q0, q1) = (poly.points[j], poly.points[j + 1]);
            if !boxes_overlap(pbox, bbox(&[q0, q1]), radius) {
                continue;
            }
            let (_, t, d) = segment_segment(p, p, q0, q1);
            if d <= radius && best.is_none_or(|b| d < b.distance) {
                best = Some(Hit {
                    sigma: 0.0,
                    edge: e,
                    seg: j,
                    t,
                    point: lerp(q0, q1, t),
                    distance: d,
                });
            }
        }
    }
    best
}

/// Cumulative arc lengths (re-exported for the tools).
pub(crate) fn arcs(curve: &[P3]) -> Vec<f64> {
    arc_lengths(curve)
}

/// Distance helper for the tools.
pub(crate) fn gap(a: P3, b: P3) -> f64 {
    dist(a, b)
}
