//! Target objects: ray intersection (for occlusion and for placing strokes on the surface) and surface normals.
//!
//! Every object is a closed solid described by a signed distance (negative inside). Spheres and cylinders are
//! intersected in closed form; the rounded box and the blob by sphere tracing followed by bisection to 1e-12 m.
//!
//! [`Shape::distance`] is the exact Euclidean distance to the surface (what a reconstructed surface is measured
//! against): the sphere's, the cylinder's and the rounded box's signed distances are exact (the rounded box is
//! a box grown by a ball, whose distance is the box's minus the ball's radius, inside and out), the blob's is
//! not and it searches its closest point ([`Blob::closest_point`]). [`from_truth`] rebuilds an object from the
//! ground truth's description of it.

mod blob;
mod boxes;
mod cylinder;
mod sphere;
mod truth;

pub use blob::Blob;
pub use boxes::RoundedBox;
pub use cylinder::Cylinder;
pub use sphere::Sphere;
pub use truth::{from_truth, TruthError};

use fires_record::ObjectTruth;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// Type alias for 3-vectors in metres.
pub type V3 = Vector3<f64>;

/// The object kinds a scenario can place in front of the cameras.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ObjectKind {
    /// A sphere.
    Sphere,
    /// A capped cylinder.
    Cylinder,
    /// A box with rounded edges.
    Box,
    /// A smooth star-shaped freeform blob.
    Blob,
}

impl ObjectKind {
    /// All kinds.
    pub const ALL: [ObjectKind; 4] = [
        ObjectKind::Sphere,
        ObjectKind::Cylinder,
        ObjectKind::Box,
        ObjectKind::Blob,
    ];

    /// Parses `sphere`, `cylinder`, `box` or `blob`.
    pub fn parse(name: &str) -> Option<Self> {
        match name {
            "sphere" => Some(ObjectKind::Sphere),
            "cylinder" => Some(ObjectKind::Cylinder),
            "box" => Some(ObjectKind::Box),
            "blob" => Some(ObjectKind::Blob),
            _ => None,
        }
    }

    /// Builds an object of about `size` metres radius centred at `centre`; `up` is the world up direction.
    pub fn build(self, centre: V3, size: f64, up: V3) -> Box<dyn Shape> {
        match self {
            ObjectKind::Sphere => Box::new(Sphere {
                centre,
                radius: size,
            }),
            ObjectKind::Cylinder => Box::new(Cylinder {
                centre,
                axis: up.normalize(),
                radius: 0.8 * size,
                half_length: 1.2 * size,
            }),
            ObjectKind::Box => Box::new(RoundedBox::new(
                centre,
                V3::new(0.9 * size, 0.75 * size, 0.8 * size),
                0.25 * size,
                up,
                30f64.to_radians(),
            )),
            ObjectKind::Blob => Box::new(Blob {
                centre,
                radius: size,
            }),
        }
    }
}

/// A solid target object.
pub trait Shape: Send + Sync + std::fmt::Debug {
    /// Human-readable description for the ground truth.
    fn describe(&self) -> String;
    /// The object as the ground truth records it (`target.object` of `truth/world.json`).
    fn to_truth(&self) -> ObjectTruth;
    /// The surface point closest to `p` (Euclidean). The default steps along the gradient by the signed
    /// distance, exact for shapes whose [`Shape::sdf`] is an exact distance (away from the medial axis, where
    /// the closest point is not unique and one of them is returned).
    fn closest_point(&self, p: &V3) -> V3 {
        p - self.gradient(p) * self.sdf(p)
    }
    /// Exact Euclidean distance from `p` to the surface (unsigned). The default is `|sdf|`, exact for shapes
    /// whose [`Shape::sdf`] is an exact distance; others override it.
    fn distance(&self, p: &V3) -> f64 {
        self.sdf(p).abs()
    }
    /// Unit gradient of the signed distance at `p` (central differences of 1e-7 m).
    fn gradient(&self, p: &V3) -> V3 {
        let h = 1e-7;
        let g = V3::new(
            self.sdf(&(p + V3::x() * h)) - self.sdf(&(p - V3::x() * h)),
            self.sdf(&(p + V3::y() * h)) - self.sdf(&(p - V3::y() * h)),
            self.sdf(&(p + V3::z() * h)) - self.sdf(&(p - V3::z() * h)),
        );
        g.try_normalize(1e-300).unwrap_or_else(V3::z)
    }
    /// Signed distance (or a lower bound of it, scaled by [`Shape::lipschitz`]); negative inside.
    fn sdf(&self, p: &V3) -> f64;
    /// Bound on `|grad sdf|` (1 for exact distances); sphere tracing divides steps by it.
    fn lipschitz(&self) -> f64 {
        1.0
    }
    /// Centre of a bounding sphere.
    fn bound_centre(&self) -> V3;
    /// Radius of a bounding sphere.
    fn bound_radius(&self) -> f64;
    /// First intersection `t` in `(0, t_max]` of the ray `origin + t * dir` (`dir` unit) with the surface;
    /// `Some(0.0)` if `origin` is inside.
    fn ray_hit(&self, origin: &V3, dir: &V3, t_max: f64) -> Option<f64> {
        sphere_trace(self, origin, dir, t_max)
    }
    /// Outward unit normal at (or near) a surface point.
    fn normal(&self, p: &V3) -> V3 {
        let h = 1e-6;
        let g = V3::new(
            self.sdf(&(p + V3::x() * h)) - self.sdf(&(p - V3::x() * h)),
            self.sdf(&(p + V3::y() * h)) - self.sdf(&(p - V3::y() * h)),
            self.sdf(&(p + V3::z() * h)) - self.sdf(&(p - V3::z() * h)),
        );
        g.try_normalize(1e-300).unwrap_or_else(V3::z)
    }
    /// Whether the segment from `a` to `b` passes through the object (endpoints excluded by `margin` metres).
    fn blocks_segment(&self, a: &V3, b: &V3, margin: f64) -> bool {
        let d = b - a;
        let len = d.norm();
        if len <= 2.0 * margin {
            return false;
        }
        let dir = d / len;
        let start = a + dir * margin;
        self.ray_hit(&start, &dir, len - 2.0 * margin).is_some()
    }
}

/// Entry and exit `t` of a ray with a sphere, if it meets it.
pub fn ray_sphere(origin: &V3, dir: &V3, centre: &V3, radius: f64) -> Option<(f64, f64)> {
    let oc = origin - centre;
    let b = oc.dot(dir);
    let c = oc.norm_squared() - radius * radius;
    let disc = b * b - c;
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    Some((-b - s, -b + s))
}

/// Sphere tracing within the bounding sphere, then bisection on the sign of the distance.
fn sphere_trace<S: Shape + ?Sized>(shape: &S, origin: &V3, dir: &V3, t_max: f64) -> Option<f64> {
    if shape.sdf(origin) < 0.0 {
        return Some(0.0);
    }
    let (t_in, t_out) = ray_sphere(origin, dir, &shape.bound_centre(), shape.bound_radius())?;
    let t_end = t_out.min(t_max);
    let mut t = t_in.max(0.0);
    if t >= t_end {
        return None;
    }
    let k = shape.lipschitz();
    let mut prev = t;
    // Sphere tracing with a minimum step of 10 um: far from the surface the steps are d/k (never overshooting),
    // near it the minimum step crosses it and the crossing is then bracketed in [prev, t] and bisected to
    // machine precision, so the hit point is a smooth function of the ray (no dependence on the iteration path).
    for _ in 0..20_000 {
        let d = shape.sdf(&(origin + dir * t));
        if d < 0.0 {
            let (mut lo, mut hi) = (prev, t);
            for _ in 0..80 {
                let mid = 0.5 * (lo + hi);
                if shape.sdf(&(origin + dir * mid)) < 0.0 {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            return (lo <= t_max).then_some(lo);
        }
        if t >= t_end {
            return None;
        }
        prev = t;
        t = (t + (d / k).max(1e-5)).min(t_end);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn up() -> V3 {
        V3::new(0.0, -1.0, 0.0)
    }

    #[test]
    fn sphere_and_traced_shapes_agree_with_closed_forms() {
        let c = V3::new(0.1, 0.0, 1.0);
        let s = Sphere {
            centre: c,
            radius: 0.2,
        };
        let o = V3::new(0.1, 0.0, 0.0);
        assert!((s.ray_hit(&o, &V3::z(), 10.0).unwrap() - 0.8).abs() < 1e-12);
        assert!(s.ray_hit(&o, &V3::z(), 0.5).is_none());
        assert!(s.ray_hit(&o, &(-V3::z()), 10.0).is_none());
        // Off-axis ray: closed form t = z0 - sqrt(r^2 - d^2).
        let o2 = V3::new(0.2, 0.0, 0.0);
        let want = 1.0 - (0.04f64 - 0.01).sqrt();
        assert!((s.ray_hit(&o2, &V3::z(), 10.0).unwrap() - want).abs() < 1e-12);
        // The generic tracer finds the same hit on a blob-free sphere description (cylinder side, box face).
        let cyl = Cylinder {
            centre: c,
            axis: V3::y(),
            radius: 0.2,
            half_length: 0.3,
        };
        assert!((cyl.ray_hit(&o2, &V3::z(), 10.0).unwrap() - want).abs() < 1e-10);
        assert!((cyl.normal(&V3::new(0.1, 0.0, 0.8)) - V3::new(0.0, 0.0, -1.0)).norm() < 1e-9);
        let bx = RoundedBox::new(c, V3::new(0.2, 0.2, 0.2), 0.05, up(), 0.0);
        assert!((bx.ray_hit(&o, &V3::z(), 10.0).unwrap() - 0.8).abs() < 1e-10);
        assert!((bx.normal(&V3::new(0.1, 0.0, 0.8)) - V3::new(0.0, 0.0, -1.0)).norm() < 1e-6);
        let blob = Blob {
            centre: c,
            radius: 0.2,
        };
        let t = blob.ray_hit(&o, &V3::z(), 10.0).unwrap();
        assert!(blob.sdf(&(o + V3::z() * t)).abs() < 1e-12);
        assert!(blob.sdf(&(o + V3::z() * (t - 1e-4))) > 0.0);
    }

    #[test]
    fn segments_through_objects_are_blocked() {
        for kind in ObjectKind::ALL {
            let shape = kind.build(V3::new(0.0, 0.0, 1.0), 0.1, up());
            assert!(
                shape.blocks_segment(&V3::new(0.0, 0.0, 1.5), &V3::zeros(), 1e-4),
                "{kind:?}"
            );
            assert!(!shape.blocks_segment(&V3::new(0.5, 0.0, 1.5), &V3::new(0.5, 0.0, 0.0), 1e-4));
            assert_eq!(
                shape.ray_hit(&V3::new(0.0, 0.0, 1.0), &V3::z(), 1.0),
                Some(0.0)
            );
        }
    }
}
