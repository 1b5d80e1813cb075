//! Rebuilding a target object from the ground truth's description of it (`target.object` of
//! `truth/world.json`, docs/recording.md), so any replay can measure a surface against the true object.

use super::{Blob, Cylinder, RoundedBox, Shape, Sphere, V3};
use fires_record::ObjectTruth;

/// Why a recorded object description cannot be rebuilt.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TruthError {
    /// A coordinate or parameter is NaN or infinite.
    #[error("object parameter {0} is not finite")]
    NotFinite(&'static str),
    /// A length that must be positive is not (or a rounding larger than the half extents).
    #[error("object parameter {0} is out of range")]
    OutOfRange(&'static str),
    /// A direction has (nearly) zero length.
    #[error("object direction {0} is not a direction")]
    NotADirection(&'static str),
}

fn point(a: [f64; 3], name: &'static str) -> Result<V3, TruthError> {
    if a.iter().all(|x| x.is_finite()) {
        Ok(V3::from(a))
    } else {
        Err(TruthError::NotFinite(name))
    }
}

fn direction(a: [f64; 3], name: &'static str) -> Result<V3, TruthError> {
    point(a, name)?
        .try_normalize(1e-9)
        .ok_or(TruthError::NotADirection(name))
}

fn positive(x: f64, name: &'static str) -> Result<f64, TruthError> {
    if !x.is_finite() {
        Err(TruthError::NotFinite(name))
    } else if x > 0.0 {
        Ok(x)
    } else {
        Err(TruthError::OutOfRange(name))
    }
}

/// The object a ground truth describes; `from_truth(&shape.to_truth())` is `shape` (to rounding).
pub fn from_truth(t: &ObjectTruth) -> Result<Box<dyn Shape>, TruthError> {
    Ok(match *t {
        ObjectTruth::Sphere { centre_m, radius_m } => Box::new(Sphere {
            centre: point(centre_m, "centre_m")?,
            radius: positive(radius_m, "radius_m")?,
        }),
        ObjectTruth::Cylinder {
            centre_m,
            axis,
            radius_m,
            half_length_m,
        } => Box::new(Cylinder {
            centre: point(centre_m, "centre_m")?,
            axis: direction(axis, "axis")?,
            radius: positive(radius_m, "radius_m")?,
            half_length: positive(half_length_m, "half_length_m")?,
        }),
        ObjectTruth::RoundedBox {
            centre_m,
            half_extents_m,
            rounding_m,
            up,
            yaw_rad,
        } => {
            let half = point(half_extents_m, "half_extents_m")?;
            if !rounding_m.is_finite() || !yaw_rad.is_finite() {
                return Err(TruthError::NotFinite("rounding_m or yaw_rad"));
            }
            if !(rounding_m >= 0.0 && half.min() >= rounding_m && half.min() > 0.0) {
                return Err(TruthError::OutOfRange("half_extents_m or rounding_m"));
            }
            let up = direction(up, "up")?;
            // The box's axes are built from world z made perpendicular to `up`.
            if up.cross(&V3::z()).norm() < 1e-9 {
                return Err(TruthError::NotADirection("up (parallel to world z)"));
            }
            Box::new(RoundedBox::new(
                point(centre_m, "centre_m")?,
                half,
                rounding_m,
                up,
                yaw_rad,
            ))
        }
        ObjectTruth::Blob {
            centre_m,
            mean_radius_m,
        } => Box::new(Blob {
            centre: point(centre_m, "centre_m")?,
            radius: positive(mean_radius_m, "mean_radius_m")?,
        }),
    })
}
