//! The foot point of a point on a Coons patch (FIRES thesis §5.2.2, hole creation): the parameters
//! (u, v) ∈ [0, 1]² of the patch point nearest to C, the solution of
//!
//! ```text
//! (x(u,v) − C) · x_u(u,v) = 0
//! (x(u,v) − C) · x_v(u,v) = 0
//! ```
//!
//! by a hybrid Newton method (Dennis & Schnabel, "Numerical Methods for Unconstrained Optimization and
//! Nonlinear Equations", §6.3: Newton's step on f = ½‖x − C‖² globalised by a backtracking line search,
//! falling back to the Gauss–Newton step where the Hessian is not positive definite and to steepest descent
//! where that is singular), projected onto the unit square so a point beyond the patch's border gets the
//! parameters of its projection onto the border. The initial guess is the nearest sample of a regular grid
//! over the domain (the thesis's rule; the grid size is ours, [`FootPointOptions::grid`]).
//!
//! The sides are piecewise linear, so x_u and x_v jump across knot lines; a solve that stalls there
//! (Newton zig-zagging over a kink) is finished on the nearest knot line with that parameter held.
//!
//! [`FootPointSolver`] precomputes the grid once per patch; each [`FootPointSolver::solve`] is then a grid
//! scan and a few Newton steps. On a bilinear patch (straight sides) the Hessian is exact and the solve
//! converges quadratically to the exact foot point.

use super::coons::{CoonsPatch, Side};
use crate::geometry::Vec3;

/// Options of the foot-point solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FootPointOptions {
    /// Grid samples per parameter direction for the initial guess (default 16, at least 2).
    pub grid: usize,
    /// Most Newton iterations (default 50).
    pub max_iterations: usize,
    /// Converged when a step moves (u, v) by less than this (default 1e-15).
    pub step_tolerance: f64,
}

impl Default for FootPointOptions {
    fn default() -> Self {
        FootPointOptions {
            grid: 16,
            max_iterations: 50,
            step_tolerance: 1e-15,
        }
    }
}

/// A solved foot point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FootPoint {
    /// Parameter u in [0, 1].
    pub u: f64,
    /// Parameter v in [0, 1].
    pub v: f64,
    /// The patch point x(u, v).
    pub point: Vec3,
    /// Its distance from the query point.
    pub distance: f64,
    /// Newton iterations taken.
    pub iterations: usize,
    /// The last step was below the tolerance (or the gradient vanished) before the iteration cap.
    pub converged: bool,
}

/// A patch with its initial-guess grid, for many foot-point solves.
#[derive(Clone, Debug)]
pub struct FootPointSolver<'a> {
    patch: &'a CoonsPatch,
    samples: Vec<(f64, f64, Vec3)>,
    options: FootPointOptions,
}

impl<'a> FootPointSolver<'a> {
    /// Samples `patch` on a `grid × grid` lattice of the unit square (corners included).
    pub fn new(patch: &'a CoonsPatch, options: &FootPointOptions) -> Self {
        let g = options.grid.max(2);
        let mut samples = Vec::with_capacity(g * g);
        for i in 0..g {
            for j in 0..g {
                let (u, v) = (i as f64 / (g - 1) as f64, j as f64 / (g - 1) as f64);
                samples.push((u, v, patch.eval(u, v)));
            }
        }
        FootPointSolver {
            patch,
            samples,
            options: *options,
        }
    }

    /// The foot point of `c` starting from the nearest grid sample.
    pub fn solve(&self, c: Vec3) -> FootPoint {
        let (mut u, mut v) = (0.0, 0.0);
        let mut best = f64::INFINITY;
        for &(su, sv, p) in &self.samples {
            let d = (p - c).norm_squared();
            if d < best {
                best = d;
                (u, v) = (su, sv);
            }
        }
        self.solve_from(c, u, v)
    }

    /// The foot point of `c` starting from (u0, v0) (clamped to the unit square).
    pub fn solve_from(&self, c: Vec3, u0: f64, v0: f64) -> FootPoint {
        let clamp = |x: f64| {
            if x.is_finite() {
                x.clamp(0.0, 1.0)
            } else {
                0.0
            }
        };
        let (u, v) = (clamp(u0), clamp(v0));
        let mut best = self.iterate(c, u, v, [false; 2], self.options.max_iterations);
        if !best.3 {
            // Stalled by a kink: the sides are piecewise linear, so x_u, x_v jump across the knot lines
            // and a minimum on one makes Newton zig-zag over it. Retry on the nearest knot line of each
            // parameter with that parameter fixed (a smooth 1-D problem) and keep the better point.
            let near_knot = |x: f64, a: &Side, b: &Side| {
                a.knots()
                    .iter()
                    .chain(b.knots())
                    .copied()
                    .min_by(|p, q| (p - x).abs().total_cmp(&(q - x).abs()))
                    .filter(|k| (k - x).abs() < 1e-6)
            };
            let p = self.patch;
            let tries = [
                near_knot(best.1, p.left(), p.right()).map(|k| (best.0, k, [false, true])),
                near_knot(best.0, p.bottom(), p.top()).map(|k| (k, best.1, [true, false])),
            ];
            let mut used = best.4;
            for (tu, tv, fixed) in tries.into_iter().flatten() {
                let r = self.iterate(c, tu, tv, fixed, self.options.max_iterations);
                used += r.4;
                if r.3 && r.2 <= best.2 * (1.0 + 1e-10) + f64::MIN_POSITIVE {
                    best = r;
                }
            }
            best.4 = used;
        }
        let (u, v, _, converged, iterations) = best;
        let point = self.patch.eval(u, v);
        FootPoint {
            u,
            v,
            point,
            distance: (point - c).norm(),
            iterations,
            converged,
        }
    }

    /// Newton iterations from (u, v) with the `fixed` parameters held: (u, v, f, converged, iterations).
    fn iterate(
        &self,
        c: Vec3,
        mut u: f64,
        mut v: f64,
        fixed: [bool; 2],
        max_iterations: usize,
    ) -> (f64, f64, f64, bool, usize) {
        let clamp = |x: f64| x.clamp(0.0, 1.0);
        let f = |u: f64, v: f64| 0.5 * (self.patch.eval(u, v) - c).norm_squared();
        let mut fu = f(u, v);
        let mut converged = false;
        let mut iterations = 0;
        while iterations < max_iterations {
            iterations += 1;
            let [x, xu, xv, xuv] = self.patch.eval_derivatives(u, v);
            let r = x - c;
            let g = [r.dot(xu), r.dot(xv)];
            // The gradient projected onto the feasible directions at a clamped or fixed parameter.
            let free = |x: f64, gx: f64| !((x <= 0.0 && gx > 0.0) || (x >= 1.0 && gx < 0.0));
            let hold = [fixed[0] || !free(u, g[0]), fixed[1] || !free(v, g[1])];
            let gp = [
                if hold[0] { 0.0 } else { g[0] },
                if hold[1] { 0.0 } else { g[1] },
            ];
            let scale = xu.norm_squared() + xv.norm_squared();
            if gp[0].hypot(gp[1]) <= 1e-300 || scale <= 0.0 {
                converged = true;
                break;
            }
            let gn = [[xu.dot(xu), xu.dot(xv)], [xu.dot(xv), xv.dot(xv)]];
            let newton = [
                [gn[0][0], gn[0][1] + r.dot(xuv)],
                [gn[1][0] + r.dot(xuv), gn[1][1]],
            ];
            let step = match hold {
                [false, false] => solve_spd(newton, g)
                    .or_else(|| solve_spd(gn, g))
                    .unwrap_or([-g[0] / scale, -g[1] / scale]),
                [true, false] => [0.0, -g[1] / gn[1][1].max(f64::MIN_POSITIVE)],
                [false, true] => [-g[0] / gn[0][0].max(f64::MIN_POSITIVE), 0.0],
                [true, true] => [0.0, 0.0],
            };
            let mut lambda = 1.0;
            let mut accepted = false;
            for _ in 0..60 {
                let (nu, nv) = (clamp(u + lambda * step[0]), clamp(v + lambda * step[1]));
                let fnew = f(nu, nv);
                // Near the minimum f changes below the rounding of x − C (relative ~1e-14 when the
                // point is off the patch): there a step that shrinks the gradient without raising f by
                // more than 1e-10 of itself is accepted too.
                let flat = fnew <= fu * (1.0 + 1e-10) + f64::MIN_POSITIVE
                    && self.gradient_norm(c, nu, nv) < gp[0].hypot(gp[1]);
                if fnew <= fu || flat {
                    let moved = (nu - u).hypot(nv - v);
                    (u, v, fu) = (nu, nv, fnew);
                    accepted = true;
                    if moved < self.options.step_tolerance {
                        converged = true;
                    }
                    break;
                }
                lambda *= 0.5;
            }
            if !accepted || converged {
                // No descent left along the step: a minimum to rounding.
                converged = true;
                break;
            }
        }
        (u, v, fu, converged, iterations)
    }

    /// The norm of the gradient of ½‖x − C‖² at (u, v).
    fn gradient_norm(&self, c: Vec3, u: f64, v: f64) -> f64 {
        let [x, xu, xv, _] = self.patch.eval_derivatives(u, v);
        let r = x - c;
        r.dot(xu).hypot(r.dot(xv))
    }
}

/// The Newton step −H⁻¹g of a symmetric 2×2 `h` when `h` is positive definite.
fn solve_spd(h: [[f64; 2]; 2], g: [f64; 2]) -> Option<[f64; 2]> {
    let det = h[0][0] * h[1][1] - h[0][1] * h[1][0];
    let tr = h[0][0] + h[1][1];
    if !(h[0][0] > 0.0 && det > 1e-14 * tr * tr && det.is_finite()) {
        return None;
    }
    Some([
        -(h[1][1] * g[0] - h[0][1] * g[1]) / det,
        -(h[0][0] * g[1] - h[1][0] * g[0]) / det,
    ])
}

/// The foot point of `c` on `patch` (a one-off [`FootPointSolver`]).
pub fn foot_point(patch: &CoonsPatch, c: Vec3, options: &FootPointOptions) -> FootPoint {
    FootPointSolver::new(patch, options).solve(c)
}
