//! Sphere.

use super::{ray_sphere, Shape, V3};
use fires_record::ObjectTruth;

/// A sphere.
#[derive(Clone, Debug, PartialEq)]
pub struct Sphere {
    /// Centre, metres.
    pub centre: V3,
    /// Radius, metres.
    pub radius: f64,
}

impl Shape for Sphere {
    fn describe(&self) -> String {
        format!(
            "sphere r={:.4} m at [{:.4}, {:.4}, {:.4}]",
            self.radius, self.centre.x, self.centre.y, self.centre.z
        )
    }
    fn to_truth(&self) -> ObjectTruth {
        ObjectTruth::Sphere {
            centre_m: self.centre.into(),
            radius_m: self.radius,
        }
    }
    fn closest_point(&self, p: &V3) -> V3 {
        self.centre + self.normal(p) * self.radius
    }
    fn sdf(&self, p: &V3) -> f64 {
        (p - self.centre).norm() - self.radius
    }
    fn bound_centre(&self) -> V3 {
        self.centre
    }
    fn bound_radius(&self) -> f64 {
        self.radius
    }
    fn ray_hit(&self, origin: &V3, dir: &V3, t_max: f64) -> Option<f64> {
        if self.sdf(origin) < 0.0 {
            return Some(0.0);
        }
        let (t0, _) = ray_sphere(origin, dir, &self.centre, self.radius)?;
        (t0 >= 0.0 && t0 <= t_max).then_some(t0)
    }
    fn normal(&self, p: &V3) -> V3 {
        (p - self.centre)
            .try_normalize(1e-300)
            .unwrap_or_else(V3::z)
    }
}
