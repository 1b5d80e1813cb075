//! A smooth freeform blob: a star-shaped solid whose radius varies with direction,
//! `R(u) = radius * (1 + 0.12 sin(3 u_x + 1) sin(2 u_y) + 0.08 cos(4 u_z - 0.5) + 0.06 sin(5 u_x u_y))`.

use super::{Shape, V3};

/// A star-shaped freeform solid.
#[derive(Clone, Debug, PartialEq)]
pub struct Blob {
    /// Centre, metres.
    pub centre: V3,
    /// Mean radius, metres.
    pub radius: f64,
}

impl Blob {
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
