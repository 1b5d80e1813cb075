//! The bilinearly blended Coons patch over four polyline sides (FIRES thesis §6.1.2, used again by the
//! basic refinement §6.2 and NULISSmod's face rule §6.3).
//!
//! ```text
//! x(u,v) = (1-v) B(u) + v T(u) + (1-u) L(v) + u R(v)
//!        - [(1-u)(1-v) P00 + u(1-v) P10 + (1-u) v P01 + u v P11]
//! ```
//! with B = x(·,0), T = x(·,1) running in u and L = x(0,·), R = x(1,·) running in v (opposite sides in the
//! same direction). Each side is a piecewise-linear curve on [0, 1] with chord-length knots (the thesis's
//! printed formula lacks the division by the knot interval; see the research digest's corrections). A
//! triangle is the patch with one side collapsed to a point ([`CoonsPatch::triangle`]).

use super::control::{ControlMesh, Curve, CurveSpan};
use crate::geometry::Vec3;
use crate::mesh::Halfedge;

/// A polyline on [0, 1] with chord-length knots; a zero-length polyline is the constant at its first point.
#[derive(Clone, Debug)]
pub struct Side {
    points: Vec<Vec3>,
    knots: Vec<f64>,
}

impl Side {
    /// The side through `points` (at least one).
    pub fn new(points: Vec<Vec3>) -> Self {
        let knots = chord_params(&points);
        Side { points, knots }
    }

    /// The point at parameter `t` in [0, 1] (clamped).
    pub fn at(&self, t: f64) -> Vec3 {
        let n = self.points.len();
        if n == 0 {
            return Vec3::ZERO;
        }
        if n == 1 || t <= 0.0 {
            return self.points[0];
        }
        if t >= 1.0 {
            return self.points[n - 1];
        }
        let j = self.knots.partition_point(|&k| k <= t).clamp(1, n - 1);
        let (k0, k1) = (self.knots[j - 1], self.knots[j]);
        let w = if k1 > k0 { (t - k0) / (k1 - k0) } else { 0.0 };
        self.points[j - 1] * (1.0 - w) + self.points[j] * w
    }

    /// The derivative d/dt at parameter `t` (piecewise constant: the slope of the knot span holding `t`,
    /// the span to the right at a knot, the last non-empty span at `t` ≥ 1; zero for a zero-length side).
    pub fn derivative(&self, t: f64) -> Vec3 {
        let n = self.points.len();
        if n < 2 {
            return Vec3::ZERO;
        }
        let mut j = self.knots.partition_point(|&k| k <= t).clamp(1, n - 1);
        while j > 1 && self.knots[j] <= self.knots[j - 1] {
            j -= 1;
        }
        let (k0, k1) = (self.knots[j - 1], self.knots[j]);
        if k1 > k0 {
            (self.points[j] - self.points[j - 1]) / (k1 - k0)
        } else {
            Vec3::ZERO
        }
    }

    /// The knots (chord-length parameters of the points, 0 to 1).
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    /// The points.
    pub fn points(&self) -> &[Vec3] {
        &self.points
    }

    /// The first point.
    pub fn first(&self) -> Vec3 {
        self.points.first().copied().unwrap_or(Vec3::ZERO)
    }

    /// The last point.
    pub fn last(&self) -> Vec3 {
        self.points.last().copied().unwrap_or(Vec3::ZERO)
    }

    /// The same side run backwards.
    pub fn reversed(&self) -> Side {
        Side::new(self.points.iter().rev().copied().collect())
    }
}

/// Chord-length parameters of `points` normalised to [0, 1] (all 0 for a zero-length polyline).
pub fn chord_params(points: &[Vec3]) -> Vec<f64> {
    let mut k = Vec::with_capacity(points.len());
    let mut s = 0.0;
    for (i, p) in points.iter().enumerate() {
        if i > 0 {
            s += (*p - points[i - 1]).norm();
        }
        k.push(s);
    }
    if s > 0.0 {
        for x in &mut k {
            *x /= s;
        }
        if let Some(l) = k.last_mut() {
            *l = 1.0;
        }
    }
    k
}

/// The points of `curve` from arc parameter `t0` to `t1` (either order): the two end points and every
/// sample strictly between them.
pub fn span_points(curve: &Curve, t0: f64, t1: f64) -> Vec<Vec3> {
    let (lo, hi) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
    let mut out = vec![curve.point_at(lo)];
    let a = curve.arc.partition_point(|&s| s <= lo);
    for j in a..curve.points.len() {
        if curve.arc[j] >= hi {
            break;
        }
        out.push(curve.points[j]);
    }
    out.push(curve.point_at(hi));
    if t0 > t1 {
        out.reverse();
    }
    out
}

/// A bilinearly blended Coons patch.
#[derive(Clone, Debug)]
pub struct CoonsPatch {
    bottom: Side,
    right: Side,
    top: Side,
    left: Side,
    corners: [Vec3; 4],
}

impl CoonsPatch {
    /// The patch with sides `bottom` = x(u, 0), `right` = x(1, v), `top` = x(u, 1), `left` = x(0, v), each
    /// running in increasing parameter. The corners are taken from `bottom` and `top`
    /// (P00, P10, P01, P11); the sides should meet there.
    pub fn new(bottom: Side, right: Side, top: Side, left: Side) -> Self {
        let corners = [bottom.first(), bottom.last(), top.first(), top.last()];
        CoonsPatch {
            bottom,
            right,
            top,
            left,
            corners,
        }
    }

    /// The patch bounded by the closed loop `s0, s1, s2, s3` (each side starting where the previous one
    /// ends): `s0` is x(u, 0), `s1` is x(1, v), `s2` is x(u, 1) run backwards, `s3` is x(0, v) run
    /// backwards.
    pub fn from_loop(s: [Vec<Vec3>; 4]) -> Self {
        let [s0, s1, s2, s3] = s;
        let top = Side::new(s2.into_iter().rev().collect());
        let left = Side::new(s3.into_iter().rev().collect());
        CoonsPatch::new(Side::new(s0), Side::new(s1), top, left)
    }

    /// The triangle bounded by the loop `s0` (A → B), `s1` (B → C), `s2` (C → A): the patch whose left
    /// side x(0, v) is collapsed to A, so x(u, 0) = s0, x(1, v) = s1 and x(u, 1) runs from A to C.
    pub fn triangle(s0: Vec<Vec3>, s1: Vec<Vec3>, s2: Vec<Vec3>) -> Self {
        let a = s0.first().copied().unwrap_or(Vec3::ZERO);
        Self::from_loop([s0, s1, s2, vec![a]])
    }

    /// The point x(u, v), (u, v) in [0, 1]².
    pub fn eval(&self, u: f64, v: f64) -> Vec3 {
        let [p00, p10, p01, p11] = self.corners;
        let ruled_v = self.bottom.at(u) * (1.0 - v) + self.top.at(u) * v;
        let ruled_u = self.left.at(v) * (1.0 - u) + self.right.at(v) * u;
        let bilinear = p00 * ((1.0 - u) * (1.0 - v))
            + p10 * (u * (1.0 - v))
            + p01 * ((1.0 - u) * v)
            + p11 * (u * v);
        ruled_v + ruled_u - bilinear
    }

    /// The point and its derivatives at (u, v): `[x, x_u, x_v, x_uv]`. The sides are piecewise linear, so
    /// within a knot cell x_uu = x_vv = 0 and these are all the second derivatives there.
    pub fn eval_derivatives(&self, u: f64, v: f64) -> [Vec3; 4] {
        let [p00, p10, p01, p11] = self.corners;
        let (b, t, l, r) = (
            self.bottom.at(u),
            self.top.at(u),
            self.left.at(v),
            self.right.at(v),
        );
        let (db, dt, dl, dr) = (
            self.bottom.derivative(u),
            self.top.derivative(u),
            self.left.derivative(v),
            self.right.derivative(v),
        );
        let x = self.eval(u, v);
        let xu = db * (1.0 - v) + dt * v - l + r - ((p10 - p00) * (1.0 - v) + (p11 - p01) * v);
        let xv = t - b + dl * (1.0 - u) + dr * u - ((p01 - p00) * (1.0 - u) + (p11 - p10) * u);
        let xuv = dt - db + dr - dl - (p11 - p10 - p01 + p00);
        [x, xu, xv, xuv]
    }

    /// The side x(u, 0).
    pub fn bottom(&self) -> &Side {
        &self.bottom
    }
    /// The side x(1, v).
    pub fn right(&self) -> &Side {
        &self.right
    }
    /// The side x(u, 1).
    pub fn top(&self) -> &Side {
        &self.top
    }
    /// The side x(0, v).
    pub fn left(&self) -> &Side {
        &self.left
    }
}

/// The span of halfedge `h`'s edge oriented along `h` (`t0` at its source), if the edge follows a curve.
pub(crate) fn halfedge_span(cm: &ControlMesh, h: Halfedge) -> Option<CurveSpan> {
    let s = cm.span(h.edge())?;
    Some(if h == h.edge().halfedge(0) {
        s
    } else {
        CurveSpan {
            curve: s.curve,
            t0: s.t1,
            t1: s.t0,
        }
    })
}

/// The polyline halfedge `h` follows, from its source to its target: its curve span's points, or the
/// straight segment when it follows no curve.
pub(crate) fn halfedge_polyline(cm: &ControlMesh, h: Halfedge) -> Vec<Vec3> {
    let m = &cm.mesh;
    let (a, b) = (m.position(m.from_vertex(h)), m.position(m.to_vertex(h)));
    match halfedge_span(cm, h).and_then(|s| cm.curves.get(s.curve).map(|c| (s, c))) {
        Some((s, c)) => {
            let mut pts = span_points(c, s.t0, s.t1);
            // The mesh vertices are the span's ends; use them exactly.
            let n = pts.len();
            pts[0] = a;
            pts[n - 1] = b;
            pts
        }
        None => vec![a, b],
    }
}
