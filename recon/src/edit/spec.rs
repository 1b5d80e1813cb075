//! The JSON edit specification shared by the library, the CLI and the tests:
//!
//! ```json
//! {"roi": SELECT, "anchors": SELECT, "anchor_weight": 1.0,
//!  "handles": [{"select": SELECT, "weight": 1.0, "fix_gradient": false,
//!               "transform": {"scale": 1.0, "rotate": {"axis": [0, 0, 1], "deg": 90},
//!                             "about": [0, 0, 0], "translate": [0, 0, 0]}}]}
//! ```
//!
//! `SELECT` is `"all"`, `{"vertices": [i, ...]}`, `{"sphere": {"center": [x, y, z],
//! "radius": r}}` or `{"box": {"min": [..], "max": [..]}}`. A transform is scale, then
//! rotation, both about `about` (default: the handle's centroid), then translation; every
//! part is optional. `anchors` defaults to the ring of vertices just outside the ROI.
//! Unknown keys are errors (`deny_unknown_fields`).
//!
//! Instead of a `transform`, a handle may give its target as explicit positions, one per
//! selected vertex: `{"select": {"vertices": [7, 3, 9]}, "positions": [[x, y, z], ...]}`.
//! With `{"vertices": [...]}` the positions follow the listed order; with any other
//! selection they follow ascending vertex index. Such a handle may be deformed
//! non-rigidly; its rotation and scale come from local frames (see [`super::frames`]).
//! The full format is documented in the repository's `docs/edit-spec.md`.

use serde::{Deserialize, Serialize};

use super::similarity::{axis_angle, Similarity};
use super::EditError;
use crate::geometry::Vec3;
use crate::mesh::SurfaceMesh;

/// A vertex selection.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", deny_unknown_fields)]
pub enum Select {
    /// Every vertex.
    All,
    /// Explicit vertex indices.
    Vertices(Vec<usize>),
    /// Vertices within `radius` of `center` (inclusive).
    Sphere {
        /// Centre of the ball.
        center: [f64; 3],
        /// Radius of the ball.
        radius: f64,
    },
    /// Vertices inside the axis-aligned box (inclusive).
    Box {
        /// Lower corner.
        min: [f64; 3],
        /// Upper corner.
        max: [f64; 3],
    },
}

impl Select {
    /// The selected vertex indices (sorted, unique). Fails on an index out of range.
    pub fn resolve(&self, mesh: &SurfaceMesh) -> Result<Vec<usize>, EditError> {
        let n = mesh.vertices_size();
        let mut out: Vec<usize> = match self {
            Select::All => mesh.vertices().map(|v| v.idx()).collect(),
            Select::Vertices(list) => {
                if let Some(&bad) = list.iter().find(|&&i| i >= n) {
                    return Err(EditError::InvalidVertex { index: bad, n });
                }
                list.clone()
            }
            Select::Sphere { center, radius } => {
                let c = Vec3::from_array(*center);
                mesh.vertices()
                    .filter(|&v| mesh.position(v).distance(c) <= *radius)
                    .map(|v| v.idx())
                    .collect()
            }
            Select::Box { min, max } => mesh
                .vertices()
                .filter(|&v| {
                    let p = mesh.position(v).to_array();
                    (0..3).all(|k| p[k] >= min[k] && p[k] <= max[k])
                })
                .map(|v| v.idx())
                .collect(),
        };
        out.sort_unstable();
        out.dedup();
        Ok(out)
    }
}

/// A rotation by `deg` degrees about `axis`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotateSpec {
    /// Rotation axis (any length but zero).
    pub axis: [f64; 3],
    /// Angle in degrees (right-handed about `axis`).
    pub deg: f64,
}

/// A handle transform; every part optional.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransformSpec {
    /// Uniform scale (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<f64>,
    /// Rotation (default none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotate: Option<RotateSpec>,
    /// Fixed point of scale and rotation (default: the handle's centroid).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub about: Option<[f64; 3]>,
    /// Translation (default none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub translate: Option<[f64; 3]>,
}

impl TransformSpec {
    /// True when no part is given (the identity; also what an absent `transform` means).
    pub fn is_identity(&self) -> bool {
        *self == TransformSpec::default()
    }

    /// The transform as a [`Similarity`], with `centroid` as the default fixed point.
    pub fn to_similarity(&self, centroid: Vec3, handle: usize) -> Result<Similarity, EditError> {
        let bad = |why: &str| EditError::BadTransform {
            handle,
            reason: why.to_string(),
        };
        let scale = self.scale.unwrap_or(1.0);
        if !(scale.is_finite() && scale > 0.0) {
            return Err(bad("scale must be a finite number > 0"));
        }
        let rotation = match self.rotate {
            None => nalgebra::UnitQuaternion::identity(),
            Some(r) => {
                if !r.deg.is_finite() || r.axis.iter().any(|a| !a.is_finite()) {
                    return Err(bad("rotation must be finite"));
                }
                axis_angle(Vec3::from_array(r.axis), r.deg)
                    .ok_or_else(|| bad("rotation axis is zero"))?
            }
        };
        let finite = |a: [f64; 3]| a.iter().all(|x| x.is_finite());
        let about = match self.about {
            Some(a) if !finite(a) => return Err(bad("about must be finite")),
            Some(a) => Vec3::from_array(a),
            None => centroid,
        };
        let translate = match self.translate {
            Some(t) if !finite(t) => return Err(bad("translate must be finite")),
            Some(t) => Vec3::from_array(t),
            None => Vec3::ZERO,
        };
        Ok(Similarity {
            scale,
            rotation,
            about,
            translate,
        })
    }
}

fn one() -> f64 {
    1.0
}

/// One handle: a vertex set inside the ROI moved by a transform or to explicit positions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HandleSpec {
    /// The handle's vertices.
    pub select: Select,
    /// Weight of the handle's soft constraints (methods with soft constraints only).
    #[serde(default = "one")]
    pub weight: f64,
    /// Also constrain the handle's deformation gradient to the transform's linear part
    /// (implicit editing).
    #[serde(default)]
    pub fix_gradient: bool,
    /// The handle's transform (default: identity). Absent or empty when `positions` is
    /// given.
    #[serde(default, skip_serializing_if = "TransformSpec::is_identity")]
    pub transform: TransformSpec,
    /// Explicit target positions, one per selected vertex (the listed order for
    /// `{"vertices": [...]}`, ascending vertex index otherwise), as an alternative to
    /// `transform`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub positions: Option<Vec<[f64; 3]>>,
}

impl HandleSpec {
    /// A handle moved by `transform`.
    pub fn with_transform(select: Select, transform: TransformSpec) -> Self {
        Self {
            select,
            weight: 1.0,
            fix_gradient: false,
            transform,
            positions: None,
        }
    }

    /// A handle whose vertices go to explicit `positions` (in the order described at
    /// [`HandleSpec::positions`]).
    pub fn with_positions(select: Select, positions: Vec<[f64; 3]>) -> Self {
        Self {
            positions: Some(positions),
            ..Self::with_transform(select, TransformSpec::default())
        }
    }
}

/// A complete edit: region of interest, anchors and handles.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EditSpec {
    /// Region of interest: the vertices allowed to move.
    pub roi: Select,
    /// Fixed vertices; default: the ring of vertices just outside the ROI.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub anchors: Option<Select>,
    /// Weight of anchor soft constraints (methods with soft constraints only).
    #[serde(default = "one")]
    pub anchor_weight: f64,
    /// The handles.
    pub handles: Vec<HandleSpec>,
}

impl EditSpec {
    /// Parses a JSON specification; unknown keys and malformed values are errors naming them.
    pub fn from_json(text: &str) -> Result<Self, EditError> {
        serde_json::from_str(text).map_err(|e| EditError::Spec(e.to_string()))
    }

    /// The specification as JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }
}
