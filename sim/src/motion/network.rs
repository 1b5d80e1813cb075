//! Curve-network planning (the order the thesis's curve-insertion tool needs): a closed boundary loop first, then
//! curves that start and end on earlier curves and cross the earlier ones.
//!
//! Curves are planned in a 2D "front view" parameter plane `(u, v)` perpendicular to the viewing direction and
//! lifted onto the object by casting a ray along the viewing direction ([`Scene::lift`]), so every planned point
//! lies on the camera-facing side of the object. Because the same lift maps both curves, an endpoint planned on
//! the boundary in the plane lies exactly on the lifted boundary curve.

use crate::objects::{Shape, V3};
use crate::rng::SimRng;
use fires_record::StrokeKind;

/// The target object and the parameter plane used to place strokes on it.
#[derive(Debug)]
pub struct Scene {
    /// The object.
    pub shape: Box<dyn Shape>,
    /// Unit viewing direction (from the cameras into the scene).
    pub view: V3,
    /// First in-plane axis (unit, perpendicular to `view`).
    pub e1: V3,
    /// Second in-plane axis.
    pub e2: V3,
    /// A point on the object's axis of view (origin of the parameter plane).
    pub origin: V3,
    /// Radius of the planning disc in the parameter plane, metres.
    pub rho: f64,
    /// Direction from the object towards the user's eye (the pen leans that way).
    pub eye: V3,
    /// World up (unit).
    pub up: V3,
}

impl Scene {
    /// A scene looking at `shape` along `view`, with `up` defining the second plane axis.
    pub fn new(shape: Box<dyn Shape>, view: V3, up: V3, eye: V3, rho: f64) -> Self {
        let view = view.normalize();
        let e2 = (-up + view * up.dot(&view)).normalize();
        let e1 = e2.cross(&view);
        let origin = shape.bound_centre();
        Scene {
            shape,
            view,
            e1,
            e2,
            origin,
            rho,
            eye,
            up: up.normalize(),
        }
    }

    /// Surface point and outward normal under the plane point `uv` (ray along the viewing direction).
    pub fn lift(&self, uv: [f64; 2]) -> Option<(V3, V3)> {
        let far = 2.0 * self.shape.bound_radius() + 1.0;
        let start = self.origin + self.e1 * uv[0] + self.e2 * uv[1] - self.view * far;
        let t = self.shape.ray_hit(&start, &self.view, 2.0 * far)?;
        let p = start + self.view * t;
        Some((p, self.shape.normal(&p)))
    }

    /// The point in front of the whole object reached by moving `p` towards the cameras (for pen-up moves).
    pub fn clear_point(&self, p: &V3, clearance: f64) -> V3 {
        let c = self.shape.bound_centre();
        let depth = (p - c).dot(&self.view) + self.shape.bound_radius() + clearance;
        p - self.view * depth.max(clearance)
    }
}

/// A planned curve in the parameter plane, `s` in [0, 1].
#[derive(Clone, Debug, PartialEq)]
pub enum Curve {
    /// Closed loop `r(theta) = rho (1 + a sin(3 theta + phase) + b cos(2 theta))`, `theta = theta0 + 2 pi s`.
    Loop {
        /// Mean radius.
        rho: f64,
        /// Three-lobe amplitude.
        a: f64,
        /// Two-lobe amplitude.
        b: f64,
        /// Three-lobe phase.
        phase: f64,
        /// Start angle.
        theta0: f64,
    },
    /// Bowed chord from `a` towards `b`: `c(r) = a + (b - a) r + n bow sin(pi r)` with `n` the left normal of
    /// `b - a`, drawn for `r = span * s` (`span < 1` stops it where it meets an earlier curve).
    Chord {
        /// Start point.
        a: [f64; 2],
        /// End point of the full chord.
        b: [f64; 2],
        /// Bow, plane metres.
        bow: f64,
        /// Fraction of the full chord that is drawn.
        span: f64,
    },
}

impl Curve {
    /// The plane point at `s`.
    pub fn uv(&self, s: f64) -> [f64; 2] {
        match *self {
            Curve::Loop {
                rho,
                a,
                b,
                phase,
                theta0,
            } => {
                let th = theta0 + 2.0 * std::f64::consts::PI * s;
                let r = loop_radius(rho, a, b, phase, th);
                [r * th.cos(), r * th.sin()]
            }
            Curve::Chord { a, b, bow, span } => {
                let s = s * span;
                let d = [b[0] - a[0], b[1] - a[1]];
                let len = (d[0] * d[0] + d[1] * d[1]).sqrt().max(1e-12);
                let n = [-d[1] / len, d[0] / len];
                let w = bow * (std::f64::consts::PI * s).sin();
                [a[0] + d[0] * s + n[0] * w, a[1] + d[1] * s + n[1] * w]
            }
        }
    }

    /// `n + 1` plane points at uniform `s`.
    pub fn sample(&self, n: usize) -> Vec<[f64; 2]> {
        (0..=n).map(|i| self.uv(i as f64 / n as f64)).collect()
    }
}

fn loop_radius(rho: f64, a: f64, b: f64, phase: f64, th: f64) -> f64 {
    rho * (1.0 + a * (3.0 * th + phase).sin() + b * (2.0 * th).cos())
}

/// A planned stroke with its place in the network.
#[derive(Clone, Debug, PartialEq)]
pub struct PlannedStroke {
    /// Id in drawing order.
    pub id: u32,
    /// Boundary or crossing curve.
    pub kind: StrokeKind,
    /// The curve.
    pub curve: Curve,
    /// Earlier stroke the start lies on.
    pub starts_on: Option<u32>,
    /// Earlier stroke the end lies on.
    pub ends_on: Option<u32>,
    /// Earlier strokes crossed in the interior.
    pub crosses: Vec<u32>,
    /// Pen mode held while drawing it (the mode buttons, `buttons >> 1`; 0: curve insertion).
    pub mode: u8,
}

/// Chord offsets of one family, as fractions of `rho`, in drawing order: the middle first, then outwards,
/// so the network grows like a grid. Neighbours are 0.225 `rho` apart (10 mm on the default scene; with
/// the random tilts, offsets and bows, junctions stay at least 0.15 `rho` apart), and the outermost chords
/// stay at 0.45 `rho`, so the corner where two of them cross lies at least 0.3 `rho` (13 mm) from their
/// ends on the boundary even where the boundary dips to 0.88 `rho` (`tests/motion.rs` checks both over
/// 400 seeds). The network's insertion rules take a crossing within the snapping distance plus the
/// intersection threshold (13 mm) of a stroke's end on the network for an overshoot, so a tighter corner
/// would make truth the network cannot represent (the offsets were 0.3 and 0.6 `rho`, whose corners
/// came within 0.05 `rho`, 2 mm, of the boundary).
const CHORD_OFFSETS: [f64; 5] = [0.0, -0.225, 0.225, -0.45, 0.45];

/// The most strokes [`plan_network`] plans: the boundary and two families of [`CHORD_OFFSETS`] chords.
pub const MAX_PLANNED_STROKES: usize = 1 + 2 * CHORD_OFFSETS.len();

/// Plans `count` strokes (at most [`MAX_PLANNED_STROKES`]) in a disc of radius `rho`: stroke 0 is the
/// closed boundary; the later strokes are chords of two roughly perpendicular families, alternating, at the
/// offsets of [`CHORD_OFFSETS`], so every chord crosses the chords of the other family drawn before it
/// (small random tilts, offsets and bows keep them a person's curves, never closer than about 0.2 `rho`).
/// A chord starts on the boundary and ends on it, or, for about a third of the chords from the fourth
/// stroke on, exactly on the last earlier chord it meets (a T junction).
pub fn plan_network(rho: f64, count: usize, rng: &mut SimRng) -> Vec<PlannedStroke> {
    let count = count.min(MAX_PLANNED_STROKES);
    let (a, b, phase, theta0) = (
        rng.range(0.02, 0.07),
        rng.range(0.0, 0.05),
        rng.range(0.0, std::f64::consts::TAU),
        rng.range(0.0, std::f64::consts::TAU),
    );
    let boundary = Curve::Loop {
        rho,
        a,
        b,
        phase,
        theta0,
    };
    let mut out = vec![PlannedStroke {
        id: 0,
        kind: StrokeKind::Boundary,
        curve: boundary,
        starts_on: None,
        ends_on: None,
        crosses: Vec::new(),
        mode: 0,
    }];
    let alpha0 = rng.range(0.0, std::f64::consts::PI);
    for k in 1..count {
        let family = (k - 1) % 2;
        let m = (k - 1) / 2;
        let alpha = alpha0 + std::f64::consts::FRAC_PI_2 * family as f64 + rng.range(-0.03, 0.03);
        let offset = rho * (CHORD_OFFSETS[m] + rng.range(-0.01, 0.01));
        let dir = [alpha.cos(), alpha.sin()];
        let foot = [-dir[1] * offset, dir[0] * offset];
        let end_plus = boundary_hit(foot, dir, rho, a, b, phase);
        let end_minus = boundary_hit(foot, [-dir[0], -dir[1]], rho, a, b, phase);
        let (pa, pb) = if k % 2 == 0 {
            (end_plus, end_minus)
        } else {
            (end_minus, end_plus)
        };
        let mut curve = Curve::Chord {
            a: pa,
            b: pb,
            bow: rho * rng.range(-0.03, 0.03),
            span: 1.0,
        };
        let mut ends_on = 0;
        if k >= 3 && rng.chance(0.35) {
            // Stop at the last crossing with an earlier chord, if it leaves at least 40% of the chord.
            let best = out
                .iter()
                .filter(|s| s.kind == StrokeKind::Crossing)
                .filter_map(|s| curve_intersection(&curve, &s.curve).map(|(r, _)| (r, s.id)))
                .filter(|&(r, _)| r > 0.4 && r < 0.95)
                .max_by(|a, b| a.0.total_cmp(&b.0));
            if let (Some((r, id)), Curve::Chord { span, .. }) = (best, &mut curve) {
                *span = r;
                ends_on = id;
            }
        }
        let mine = curve.sample(96);
        let crosses: Vec<u32> = out
            .iter()
            .filter(|s| s.kind == StrokeKind::Crossing)
            .filter(|s| polylines_cross(&mine, &s.curve.sample(96)))
            .map(|s| s.id)
            .collect();
        out.push(PlannedStroke {
            id: k as u32,
            kind: StrokeKind::Crossing,
            curve,
            starts_on: Some(0),
            ends_on: Some(ends_on),
            crosses: crosses.into_iter().filter(|&id| id != ends_on).collect(),
            mode: 0,
        });
    }
    out
}

/// Where the ray `foot + t dir` (foot inside) leaves the star-shaped boundary loop (bisection to 1e-14).
fn boundary_hit(foot: [f64; 2], dir: [f64; 2], rho: f64, a: f64, b: f64, phase: f64) -> [f64; 2] {
    let f = |t: f64| {
        let p = [foot[0] + dir[0] * t, foot[1] + dir[1] * t];
        let th = p[1].atan2(p[0]);
        (p[0] * p[0] + p[1] * p[1]).sqrt() - loop_radius(rho, a, b, phase, th)
    };
    let (mut lo, mut hi) = (0.0, 3.0 * rho);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    [foot[0] + dir[0] * lo, foot[1] + dir[1] * lo]
}

/// Parameters `(s, u)` of an interior crossing of curves `p` and `q` (the one with the largest `s`), refined by
/// Newton's method to machine precision.
pub fn curve_intersection(p: &Curve, q: &Curve) -> Option<(f64, f64)> {
    let n = 96;
    let (ps, qs) = (p.sample(n), q.sample(n));
    let mut found = None;
    for i in 0..n {
        for j in 0..n {
            if let Some((a, b)) = segment_params(ps[i], ps[i + 1], qs[j], qs[j + 1]) {
                let s = (i as f64 + a) / n as f64;
                if found.is_none_or(|(fs, _)| s > fs) {
                    found = Some((s, (j as f64 + b) / n as f64));
                }
            }
        }
    }
    let (mut s, mut u) = found?;
    for _ in 0..30 {
        let (a, b) = (p.uv(s), q.uv(u));
        let f = [a[0] - b[0], a[1] - b[1]];
        if f[0].abs().max(f[1].abs()) < 1e-15 {
            break;
        }
        let h = 1e-7;
        let (ps1, qu1) = (p.uv(s + h), q.uv(u + h));
        let j = [
            [(ps1[0] - a[0]) / h, -(qu1[0] - b[0]) / h],
            [(ps1[1] - a[1]) / h, -(qu1[1] - b[1]) / h],
        ];
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if det.abs() < 1e-300 {
            return None;
        }
        s -= (j[1][1] * f[0] - j[0][1] * f[1]) / det;
        u -= (-j[1][0] * f[0] + j[0][0] * f[1]) / det;
    }
    ((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&u)).then_some((s, u))
}

/// Parameters along two segments of their proper intersection.
fn segment_params(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> Option<(f64, f64)> {
    let r = [b[0] - a[0], b[1] - a[1]];
    let q = [d[0] - c[0], d[1] - c[1]];
    let den = r[0] * q[1] - r[1] * q[0];
    if den.abs() < 1e-300 {
        return None;
    }
    let w = [c[0] - a[0], c[1] - a[1]];
    let t = (w[0] * q[1] - w[1] * q[0]) / den;
    let u = (w[0] * r[1] - w[1] * r[0]) / den;
    ((0.0..1.0).contains(&t) && (0.0..1.0).contains(&u)).then_some((t, u))
}

/// Whether two polylines cross at interior points (segment-segment proper intersection).
pub fn polylines_cross(p: &[[f64; 2]], q: &[[f64; 2]]) -> bool {
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    for i in 1..p.len().saturating_sub(2) {
        for j in 1..q.len().saturating_sub(2) {
            let (a, b, c, d) = (p[i], p[i + 1], q[j], q[j + 1]);
            let d1 = cross(c, d, a);
            let d2 = cross(c, d, b);
            let d3 = cross(a, b, c);
            let d4 = cross(a, b, d);
            if d1 * d2 < 0.0 && d3 * d4 < 0.0 {
                return true;
            }
        }
    }
    false
}
