//! Small point and segment helpers on `[f64; 3]` (metres).

pub(crate) type P3 = [f64; 3];

pub(crate) fn sub(a: P3, b: P3) -> P3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(crate) fn dot(a: P3, b: P3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(crate) fn dist(a: P3, b: P3) -> f64 {
    let d = sub(a, b);
    dot(d, d).sqrt()
}

pub(crate) fn dist2(a: P3, b: P3) -> f64 {
    let d = sub(a, b);
    dot(d, d)
}

pub(crate) fn lerp(a: P3, b: P3, t: f64) -> P3 {
    [
        a[0] + t * (b[0] - a[0]),
        a[1] + t * (b[1] - a[1]),
        a[2] + t * (b[2] - a[2]),
    ]
}

/// Closest points of segments `p0p1` and `q0q1`: parameters `(s, t)` in [0, 1] and the distance
/// (Ericson, "Real-Time Collision Detection", §5.1.9).
pub(crate) fn segment_segment(p0: P3, p1: P3, q0: P3, q1: P3) -> (f64, f64, f64) {
    let d1 = sub(p1, p0);
    let d2 = sub(q1, q0);
    let r = sub(p0, q0);
    let a = dot(d1, d1);
    let e = dot(d2, d2);
    let f = dot(d2, r);
    let eps = 1e-30;
    let (s, t);
    if a <= eps && e <= eps {
        return (0.0, 0.0, dist(p0, q0));
    }
    if a <= eps {
        s = 0.0;
        t = (f / e).clamp(0.0, 1.0);
    } else {
        let c = dot(d1, r);
        if e <= eps {
            t = 0.0;
            s = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = dot(d1, d2);
            let denom = a * e - b * b;
            let mut s0 = if denom > eps * a * e {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t0 = (b * s0 + f) / e;
            if t0 < 0.0 {
                t0 = 0.0;
                s0 = (-c / a).clamp(0.0, 1.0);
            } else if t0 > 1.0 {
                t0 = 1.0;
                s0 = ((b - c) / a).clamp(0.0, 1.0);
            }
            s = s0;
            t = t0;
        }
    }
    (s, t, dist(lerp(p0, p1, s), lerp(q0, q1, t)))
}

/// Cumulative arc length at each point of a polyline.
pub(crate) fn arc_lengths(points: &[P3]) -> Vec<f64> {
    let mut out = Vec::with_capacity(points.len());
    let mut s = 0.0;
    for (i, p) in points.iter().enumerate() {
        if i > 0 {
            s += dist(points[i - 1], *p);
        }
        out.push(s);
    }
    out
}

/// Axis-aligned bounding box `(min, max)` of points.
pub(crate) fn bbox(points: &[P3]) -> (P3, P3) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// Boxes overlap after growing the first by `margin`.
pub(crate) fn boxes_overlap(a: (P3, P3), b: (P3, P3), margin: f64) -> bool {
    (0..3).all(|k| a.0[k] - margin <= b.1[k] && b.0[k] <= a.1[k] + margin)
}

/// Segments per chunk box of [`PolyBoxes`].
pub(crate) const CHUNK: usize = 16;

/// A polyline's bounding box and the boxes of its runs of [`CHUNK`] segments (a two-level hierarchy
/// that lets a query skip most of a long polyline).
#[derive(Clone, Debug, Default)]
pub(crate) struct PolyBoxes {
    pub(crate) whole: (P3, P3),
    pub(crate) chunks: Vec<(P3, P3)>,
}

impl PolyBoxes {
    pub(crate) fn new(points: &[P3]) -> Self {
        let chunks: Vec<(P3, P3)> = if points.len() < 2 {
            Vec::new()
        } else {
            (0..points.len() - 1)
                .step_by(CHUNK)
                .map(|s| bbox(&points[s..(s + CHUNK + 1).min(points.len())]))
                .collect()
        };
        let whole = chunks.iter().fold(bbox(&[]), |a, b| {
            (
                [a.0[0].min(b.0[0]), a.0[1].min(b.0[1]), a.0[2].min(b.0[2])],
                [a.1[0].max(b.1[0]), a.1[1].max(b.1[1]), a.1[2].max(b.1[2])],
            )
        });
        PolyBoxes { whole, chunks }
    }

    /// Segment indices (of a polyline with `n` points) in the chunks whose box meets `b` grown by `margin`.
    pub(crate) fn segments_near(
        &self,
        b: (P3, P3),
        margin: f64,
        n: usize,
    ) -> impl Iterator<Item = usize> + '_ {
        let whole = boxes_overlap(b, self.whole, margin);
        self.chunks
            .iter()
            .enumerate()
            .filter(move |(_, c)| whole && boxes_overlap(b, **c, margin))
            .flat_map(move |(k, _)| k * CHUNK..((k + 1) * CHUNK).min(n.saturating_sub(1)))
    }
}
