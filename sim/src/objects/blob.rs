//! A smooth freeform blob: a star-shaped solid whose radius varies with direction,
//! `R(u) = radius * (1 + 0.12 sin(3 u_x + 1) sin(2 u_y) + 0.08 cos(4 u_z - 0.5) + 0.06 sin(5 u_x u_y))`.
//!
//! Its signed distance `|p - c| - R(u)` is not a Euclidean distance, so [`Blob::closest_point`] searches the
//! surface point `S(u) = c + R(u) u` nearest to `p` over the directions `u`: every point nearer than the radial
//! one `S(u_p)` lies in the cone of directions that sees the ball `B(p, |p - S(u_p)|)` from the centre; that
//! cone is sampled on rings, and the best samples are refined by a damped Newton iteration on
//! `f(u) = |S(u) - p|^2` in a tangent chart of the sphere of directions (Nocedal and Wright, *Numerical
//! Optimization*, §3.1 backtracking line search and §3.4 Newton with a positive-definite fallback, here the
//! Gauss-Newton matrix).

use super::{Shape, V3};
use fires_record::ObjectTruth;

/// Most rings of the cone sampling (the cone's axis plus up to this many rings).
const RINGS: usize = 8;
/// Largest angle between rings, radians: far below the blob's shortest angular wavelength (2 pi / 5), so
/// every basin of the distance is sampled.
const RING_STEP: f64 = 0.04;
/// Samples refined by Newton's method (the best ones of the cone sampling).
const STARTS: usize = 3;
/// Newton iterations per start.
const NEWTON_ITERATIONS: usize = 30;

/// A star-shaped freeform solid.
#[derive(Clone, Debug, PartialEq)]
pub struct Blob {
    /// Centre, metres.
    pub centre: V3,
    /// Mean radius, metres.
    pub radius: f64,
}

impl Blob {
    /// The surface point in the unit direction `u` from the centre.
    pub fn surface_point(&self, u: &V3) -> V3 {
        self.centre + u * self.radius_towards(u)
    }

    /// The surface point nearest to `p` (module docs); to about 1e-12 of the radius.
    pub fn closest_point(&self, p: &V3) -> V3 {
        let d = p - self.centre;
        let r = d.norm();
        let axis = if r > 1e-12 * self.radius {
            d / r
        } else {
            V3::z()
        };
        let radial = self.surface_point(&axis);
        let d0 = (radial - p).norm();
        // Half-angle of the cone of directions of the points nearer than `radial`.
        let half_angle = if d0 < r {
            (d0 / r).asin().min(std::f64::consts::PI)
        } else {
            std::f64::consts::PI
        };
        let (t1, t2) = tangent_basis(&axis);
        let mut samples: Vec<(f64, V3)> = vec![(d0, axis)];
        let rings = ((half_angle / RING_STEP).ceil() as usize).clamp(1, RINGS);
        let step = half_angle / rings as f64;
        let near = (1.5 * step).cos();
        for k in 1..=rings {
            let theta = step * k as f64;
            let count = ((std::f64::consts::TAU * theta.sin() / step).ceil() as usize).max(6);
            for j in 0..count {
                let phi = std::f64::consts::TAU * (j as f64 + 0.5 * (k % 2) as f64) / count as f64;
                let u = axis * theta.cos() + (t1 * phi.cos() + t2 * phi.sin()) * theta.sin();
                samples.push(((self.surface_point(&u) - p).norm(), u));
            }
        }
        samples.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut best = (d0, radial);
        let mut starts: Vec<V3> = Vec::new();
        for (_, u) in &samples {
            // Distinct basins: skip a start next to one already taken.
            if starts.iter().all(|s| s.dot(u) < near) {
                starts.push(*u);
            }
            if starts.len() == STARTS {
                break;
            }
        }
        starts.push(axis);
        for u0 in starts {
            let q = self.newton(p, u0);
            let dq = (q - p).norm();
            if dq < best.0 {
                best = (dq, q);
            }
        }
        best.1
    }

    /// Damped Newton descent of `|S(u) - p|^2` from the direction `u0`; returns the surface point reached.
    /// Works relative to the centre, so rounding stays at the scale of the radius.
    fn newton(&self, p: &V3, u0: V3) -> V3 {
        let pc = p - self.centre;
        let local = |u: &V3| u * self.radius_towards(u);
        let f = |u: &V3| (local(u) - pc).norm_squared();
        let mut u = u0;
        let mut fu = f(&u);
        let h = 1e-5;
        // Stop once a step moves the point by less than 0.1 nm.
        let tiny = 1e-10 / self.radius;
        for _ in 0..NEWTON_ITERATIONS {
            let (t1, t2) = tangent_basis(&u);
            let chart = |a: f64, b: f64| (u + t1 * a + t2 * b).normalize();
            let s = |a: f64, b: f64| local(&chart(a, b));
            let s0 = local(&u);
            let (sp0, sm0, s0p, s0m) = (s(h, 0.0), s(-h, 0.0), s(0.0, h), s(0.0, -h));
            let (spp, smm, spm, smp) = (s(h, h), s(-h, -h), s(h, -h), s(-h, h));
            let ja = (sp0 - sm0) / (2.0 * h);
            let jb = (s0p - s0m) / (2.0 * h);
            let saa = (sp0 - s0 * 2.0 + sm0) / (h * h);
            let sbb = (s0p - s0 * 2.0 + s0m) / (h * h);
            let sab = (spp - spm - smp + smm) / (4.0 * h * h);
            let res = s0 - pc;
            // Gradient and Hessian of f / 2.
            let g = [ja.dot(&res), jb.dot(&res)];
            let gn = [ja.dot(&ja), ja.dot(&jb), jb.dot(&jb)];
            let newton = [
                gn[0] + saa.dot(&res),
                gn[1] + sab.dot(&res),
                gn[2] + sbb.dot(&res),
            ];
            let step = solve_2x2(newton, g).or_else(|| solve_2x2(gn, g));
            let Some(mut delta) = step else { break };
            // Descent direction required; otherwise use Gauss-Newton's, which always is one.
            if delta[0] * g[0] + delta[1] * g[1] <= 0.0 {
                match solve_2x2(gn, g) {
                    Some(d) => delta = d,
                    None => break,
                }
            }
            let size = delta[0].abs() + delta[1].abs();
            if size < tiny {
                break;
            }
            let mut alpha = 1.0;
            let mut moved = false;
            for _ in 0..30 {
                let cand = chart(-alpha * delta[0], -alpha * delta[1]);
                let fc = f(&cand);
                if fc < fu {
                    u = cand;
                    fu = fc;
                    moved = true;
                    break;
                }
                alpha *= 0.5;
            }
            if !moved || alpha * size < tiny {
                break;
            }
        }
        self.surface_point(&u)
    }

    fn radius_towards(&self, u: &V3) -> f64 {
        self.radius
            * (1.0
                + 0.12 * (3.0 * u.x + 1.0).sin() * (2.0 * u.y).sin()
                + 0.08 * (4.0 * u.z - 0.5).cos()
                + 0.06 * (5.0 * u.x * u.y).sin())
    }
}

impl Shape for Blob {
    fn describe(&self) -> String {
        format!(
            "blob mean_r={:.4} m at [{:.4}, {:.4}, {:.4}]",
            self.radius, self.centre.x, self.centre.y, self.centre.z
        )
    }
    fn to_truth(&self) -> ObjectTruth {
        ObjectTruth::Blob {
            centre_m: self.centre.into(),
            mean_radius_m: self.radius,
        }
    }
    fn closest_point(&self, p: &V3) -> V3 {
        Blob::closest_point(self, p)
    }
    fn distance(&self, p: &V3) -> f64 {
        (Blob::closest_point(self, p) - p).norm()
    }
    fn sdf(&self, p: &V3) -> f64 {
        let d = p - self.centre;
        let r = d.norm();
        if r < 1e-12 {
            return -self.radius;
        }
        r - self.radius_towards(&(d / r))
    }
    fn lipschitz(&self) -> f64 {
        // |grad R| <= radius * (0.36 + 0.24 + 0.32 + 0.30) along the unit sphere; 2.5 is a safe bound here.
        2.5
    }
    fn bound_centre(&self) -> V3 {
        self.centre
    }
    fn bound_radius(&self) -> f64 {
        self.radius * 1.27
    }
}

/// Two unit vectors completing the unit `n` to an orthonormal basis.
fn tangent_basis(n: &V3) -> (V3, V3) {
    let helper = if n.x.abs() < 0.9 { V3::x() } else { V3::y() };
    let t1 = n.cross(&helper).normalize();
    (t1, n.cross(&t1))
}

/// Solves the symmetric 2x2 system `[[m0, m1], [m1, m2]] x = b` if it is positive definite.
fn solve_2x2(m: [f64; 3], b: [f64; 2]) -> Option<[f64; 2]> {
    let det = m[0] * m[2] - m[1] * m[1];
    let definite = m[0] > 0.0 && det > 1e-300 * (m[0] * m[2]).abs().max(1e-300);
    if !definite || !det.is_finite() {
        return None;
    }
    Some([
        (m[2] * b[0] - m[1] * b[1]) / det,
        (m[0] * b[1] - m[1] * b[0]) / det,
    ])
}
