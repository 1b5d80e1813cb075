//! The sketching tools (FIRES thesis ch. 5). Each is a transaction: it applies fully and returns its
//! report and [`Transaction`](super::Transaction), or returns a [`ToolError`] naming the rule that
//! failed and leaves the network bit for bit as it was.

mod align;
mod border;
mod boundary;
mod closure;
mod crossings;
mod delete;
mod error;
mod glue_paths;
mod gluing;
mod hole;
mod hole_cut;
mod hole_spokes;
mod insert;
mod mirror;
mod sharp;
mod skin;
mod skinning;
mod tube;

pub use align::{align_curves, quaternion_matrix, transform_network, AlignOptions, Alignment};
pub use boundary::{insert_boundary, BoundaryOptions, BoundaryReport};
pub use closure::{close_boundary, CloseOptions, CloseReport};
pub use delete::{delete_stroke, DeleteReport};
pub use error::{End, ToolError};
pub use gluing::{glue_borders, GlueOptions, GluePart, GlueReport, Survivor};
pub use hole::{create_hole, HoleKind, HoleOptions, HoleReport, HoleRule};
pub use insert::{insert_curve, Adjustment, InsertOptions, InsertReport};
pub use mirror::{mirror_curve, Mirrored};
pub use sharp::tag_sharp;
pub use skin::{skin_profiles, SkinOptions, SkinReport};
pub use skinning::{half_direction, pair_halves};
pub use tube::{glue_tube, TubeHalves, TubeOptions, TubeReport};

use crate::network::geom::{dist, P3};
use crate::network::ops::SAME_POINT_M;

/// A curve as a tool reads it: a drawn stroke or a generated curve.
#[derive(Clone, Copy, Debug)]
pub struct CurveInput<'a> {
    /// Points in drawing order, metres.
    pub points: &'a [[f64; 3]],
    /// The stroke it comes from, kept on every polyline made of it.
    pub stroke: Option<u32>,
    /// The curve's largest one-sigma position uncertainty, millimetres (widens the thresholds).
    pub sigma_mm: Option<f64>,
    /// Length the pen may have drawn past the first and the last point without being tracked,
    /// millimetres (0: the curve is complete). Curve insertion extends such an end along its
    /// tangent, by at most this and `overshoot_mm`, to the first curve it meets, instead of taking
    /// the end for an overshoot.
    pub untracked_mm: [f64; 2],
}

impl<'a> CurveInput<'a> {
    /// A curve with no stroke id and no uncertainty.
    pub fn new(points: &'a [[f64; 3]]) -> Self {
        CurveInput {
            points,
            stroke: None,
            sigma_mm: None,
            untracked_mm: [0.0; 2],
        }
    }
}

/// The points of a drawn curve with exact repeats (within [`SAME_POINT_M`]) dropped, or a
/// refusal when one is not finite; every tool that reads a curve's points starts here.
pub(crate) fn distinct_points(points: &[P3]) -> Result<Vec<P3>, ToolError> {
    let mut pts: Vec<P3> = Vec::with_capacity(points.len());
    for p in points {
        if !p.iter().all(|c| c.is_finite()) {
            return Err(ToolError::BadCurve("a point is not finite".into()));
        }
        if pts.last().is_none_or(|q| dist(*q, *p) > SAME_POINT_M) {
            pts.push(*p);
        }
    }
    Ok(pts)
}

/// A threshold in millimetres widened to `factor · σ` when the curve's uncertainty is larger, in metres.
pub(crate) fn widened_m(base_mm: f64, sigma_mm: Option<f64>, factor: f64) -> f64 {
    let s = sigma_mm.filter(|s| s.is_finite()).unwrap_or(0.0) * factor;
    base_mm.max(s) * 1e-3
}
