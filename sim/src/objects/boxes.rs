//! Box with rounded edges (exact signed distance, so the surface normal is continuous and a tip sliding over an
//! edge moves smoothly).

use super::{Shape, V3};
use fires_record::ObjectTruth;
use nalgebra::{Rotation3, Vector3};

/// A rotated box with rounded edges.
#[derive(Clone, Debug, PartialEq)]
pub struct RoundedBox {
    /// Centre, metres.
    pub centre: V3,
    /// Half extents including the rounding, metres.
    pub half: V3,
    /// Edge rounding radius, metres.
    pub rounding: f64,
    /// Box -> world rotation.
    pub rotation: Rotation3<f64>,
}

impl RoundedBox {
    /// A box turned by `yaw` about the world `up` axis (so two faces face the cameras).
    pub fn new(centre: V3, half: V3, rounding: f64, up: V3, yaw: f64) -> Self {
        // Local y along -up (OpenCV-style y down), local z along the view direction before the yaw.
        let y = -up.normalize();
        let z0 = Vector3::z();
        let z = (z0 - y * y.dot(&z0)).normalize();
        let x = y.cross(&z);
        let base = Rotation3::from_basis_unchecked(&[x, y, z]);
        let yaw_rot = Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(y), yaw);
        RoundedBox {
            centre,
            half,
            rounding,
            rotation: yaw_rot * base,
        }
    }

    /// The `up` and `yaw` [`RoundedBox::new`] was given, recovered from the rotation (the local y axis is
    /// `-up`, and the yaw turns the un-yawed local z about it).
    pub fn up_and_yaw(&self) -> (V3, f64) {
        let y = self.rotation * Vector3::y();
        let z0 = Vector3::z();
        let z = (z0 - y * y.dot(&z0)).normalize();
        let zr = self.rotation * Vector3::z();
        let yaw = y.dot(&z.cross(&zr)).atan2(z.dot(&zr));
        (-y, yaw)
    }
}

impl Shape for RoundedBox {
    fn describe(&self) -> String {
        format!(
            "rounded box half=[{:.4}, {:.4}, {:.4}] m rounding={:.4} m at [{:.4}, {:.4}, {:.4}]",
            self.half.x,
            self.half.y,
            self.half.z,
            self.rounding,
            self.centre.x,
            self.centre.y,
            self.centre.z
        )
    }
    fn to_truth(&self) -> ObjectTruth {
        let (up, yaw) = self.up_and_yaw();
        ObjectTruth::RoundedBox {
            centre_m: self.centre.into(),
            half_extents_m: self.half.into(),
            rounding_m: self.rounding,
            up: up.into(),
            yaw_rad: yaw,
        }
    }
    fn sdf(&self, p: &V3) -> f64 {
        let l = self.rotation.inverse() * (p - self.centre);
        let q = l.abs() - self.half + V3::repeat(self.rounding);
        let outside = q.map(|v| v.max(0.0)).norm();
        outside + q.x.max(q.y.max(q.z)).min(0.0) - self.rounding
    }
    fn bound_centre(&self) -> V3 {
        self.centre
    }
    fn bound_radius(&self) -> f64 {
        self.half.norm() + 1e-9
    }
}
