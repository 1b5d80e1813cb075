//! Mesh closure (FIRES thesis ch. 5 introduction and §5.1.1: "closing meshes" is one of the operations
//! beyond curve insertion, and to the user it looks like a curve insertion). The thesis gives no
//! internals; ours: the user draws a curve whose two ends lie on one boundary loop (typically the curve
//! across the open side, e.g. a southern meridian of a sphere whose equator is the boundary); the tool
//! adds one face spanning that loop (the "remaining side"), traversing each loop edge opposite to the face
//! already there. The drawn curve is only a locator: inserting it into the new face is the next,
//! ordinary curve insertion (journal: a `close` step then an `insert` step of the same stroke).
//!
//! Bookkeeping: ΔV = 0, ΔE = 0, ΔF = +1, one boundary loop fewer, so Δχ = +1 and the genus is unchanged
//! (closing the last loop of a genus-g surface gives the closed genus-g surface: χ = 2 − 2g).
//! Refused: an end farther than `snap_mm` from every boundary edge, ends on two different loops, and a
//! pinched loop (a vertex where two boundary loops touch, so the loop is ambiguous).

use super::border::{border_end, border_loop};
use super::{widened_m, CurveInput, End, ToolError};
use crate::network::mesh::Network;
use crate::network::{FaceId, Transaction};

/// Options of [`close_boundary`] (millimetres).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct CloseOptions {
    /// Each end of the locating curve must be this close to the boundary loop.
    pub snap_mm: f64,
    /// The distance is widened to this many times the stroke's σ when that is larger.
    pub sigma_factor: f64,
}

impl Default for CloseOptions {
    fn default() -> Self {
        CloseOptions {
            snap_mm: 8.0,
            sigma_factor: 3.0,
        }
    }
}

/// What [`close_boundary`] made.
#[derive(Clone, Debug, PartialEq)]
pub struct CloseReport {
    /// The new face on the open side.
    pub face: FaceId,
    /// Number of edges of the closed loop.
    pub loop_edges: usize,
}

/// Closes the boundary loop that both ends of `curve` lie on with one new face.
pub fn close_boundary(
    net: &mut Network,
    curve: CurveInput<'_>,
    options: &CloseOptions,
) -> Result<(CloseReport, Transaction), ToolError> {
    let (Some(&a), Some(&b)) = (curve.points.first(), curve.points.last()) else {
        return Err(ToolError::BadCurve("the curve has no points".into()));
    };
    if !curve.points.iter().flatten().all(|c| c.is_finite()) {
        return Err(ToolError::BadCurve("a point is not finite".into()));
    }
    let r = widened_m(options.snap_mm, curve.sigma_mm, options.sigma_factor);
    let start = border_end(net, a, End::Start, r)?;
    let end = border_end(net, b, End::End, r)?;
    let uses = border_loop(net, start.edge)?;
    if !uses.iter().any(|u| u.edge == end.edge) {
        return Err(ToolError::DifferentBoundaries {
            first: start.edge,
            second: end.edge,
        });
    }
    let loop_edges = uses.len();
    net.transact(|net| {
        let face = net.add_face(uses);
        Ok(CloseReport { face, loop_edges })
    })
}
