//! Capped cylinder (exact signed distance; intersection by sphere tracing).

use super::{Shape, V3};
use fires_record::ObjectTruth;

/// A solid cylinder with flat caps.
#[derive(Clone, Debug, PartialEq)]
pub struct Cylinder {
    /// Centre of the axis segment, metres.
    pub centre: V3,
    /// Unit axis direction.
    pub axis: V3,
    /// Radius, metres.
    pub radius: f64,
    /// Half the length along the axis, metres.
    pub half_length: f64,
}

impl Shape for Cylinder {
    fn describe(&self) -> String {
        format!(
            "cylinder r={:.4} m half_length={:.4} m at [{:.4}, {:.4}, {:.4}] axis [{:.4}, {:.4}, {:.4}]",
            self.radius,
            self.half_length,
            self.centre.x,
            self.centre.y,
            self.centre.z,
            self.axis.x,
            self.axis.y,
            self.axis.z
        )
    }
    fn to_truth(&self) -> ObjectTruth {
        ObjectTruth::Cylinder {
            centre_m: self.centre.into(),
            axis: self.axis.into(),
            radius_m: self.radius,
            half_length_m: self.half_length,
        }
    }
    fn sdf(&self, p: &V3) -> f64 {
        let d = p - self.centre;
        let h = d.dot(&self.axis);
        let r = (d - self.axis * h).norm();
        let qx = r - self.radius;
        let qy = h.abs() - self.half_length;
        let outside = (qx.max(0.0).powi(2) + qy.max(0.0).powi(2)).sqrt();
        outside + qx.max(qy).min(0.0)
    }
    fn bound_centre(&self) -> V3 {
        self.centre
    }
    fn bound_radius(&self) -> f64 {
        (self.radius * self.radius + self.half_length * self.half_length).sqrt() + 1e-9
    }
    fn normal(&self, p: &V3) -> V3 {
        let d = p - self.centre;
        let h = d.dot(&self.axis);
        let radial = d - self.axis * h;
        let r = radial.norm();
        if (h.abs() - self.half_length) > (r - self.radius) {
            self.axis * h.signum()
        } else {
            radial.try_normalize(1e-300).unwrap_or_else(V3::z)
        }
    }
}
