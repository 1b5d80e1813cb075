//! The initial boundary: the first closed curve, which bounds the object (FIRES thesis §5.1).
//!
//! Rule 1 forbids a curve that starts and ends on one polyline, so a boundary of one edge could take no
//! first curve. The thesis does not say how the loop is split; we split it into two edges at the two loop
//! points farthest apart in space (its diameter pair), which are well separated along the loop for any
//! reasonable drawing. The face traverses the loop in drawing order. ΔV = 2, ΔE = 2, ΔF = 1.

use super::{CurveInput, ToolError};
use crate::network::geom::dist;
use crate::network::mesh::{EdgeUse, Network, PolylineAttrs, Vertex};
use crate::network::ops::SAME_POINT_M;
use crate::network::{EdgeId, FaceId, Transaction, VertexId};

/// Options of [`insert_boundary`].
#[derive(Clone, Debug)]
pub struct BoundaryOptions {
    /// Largest distance between the first and last point of a closed curve, mm (the strokes file's
    /// closing distance), widened by the curve's [`CurveInput::untracked_mm`] (the pen drew that far
    /// unseen; a straight chord closes the loop across the gap).
    pub close_mm: f64,
}

impl Default for BoundaryOptions {
    fn default() -> Self {
        BoundaryOptions { close_mm: 10.0 }
    }
}

/// What [`insert_boundary`] made.
#[derive(Clone, Debug, PartialEq)]
pub struct BoundaryReport {
    /// The two split vertices.
    pub vertices: [VertexId; 2],
    /// The two edges.
    pub edges: [EdgeId; 2],
    /// The face.
    pub face: FaceId,
}

/// Adds a closed curve as a new boundary loop of two edges and one face.
pub fn insert_boundary(
    net: &mut Network,
    curve: CurveInput<'_>,
    options: &BoundaryOptions,
) -> Result<(BoundaryReport, Transaction), ToolError> {
    let mut pts = super::distinct_points(curve.points)?;
    if pts.len() < 3 {
        return Err(ToolError::BadCurve(
            "a boundary needs at least 3 distinct points".into(),
        ));
    }
    let gap = dist(pts[0], pts[pts.len() - 1]);
    // What the pen drew unseen at either end widens the limit: the loop closes across it with a chord.
    let limit_mm = options.close_mm + curve.untracked_mm.iter().map(|u| u.max(0.0)).sum::<f64>();
    if gap > limit_mm * 1e-3 {
        return Err(ToolError::NotClosed {
            gap_mm: gap * 1e3,
            limit_mm,
        });
    }
    if gap <= SAME_POINT_M {
        pts.pop();
    }
    if pts.len() < 3 {
        return Err(ToolError::BadCurve(
            "a boundary needs at least 3 distinct points".into(),
        ));
    }
    let (i, j) = diameter_pair(&pts);
    let first: Vec<[f64; 3]> = pts[i..=j].to_vec();
    let mut second: Vec<[f64; 3]> = pts[j..].to_vec();
    second.extend_from_slice(&pts[..=i]);
    let attrs = PolylineAttrs {
        stroke: curve.stroke,
        ..PolylineAttrs::default()
    };
    net.transact(|net| {
        let va = net.push_vertex(Vertex {
            position: pts[i],
            edges: Vec::new(),
        });
        let vb = net.push_vertex(Vertex {
            position: pts[j],
            edges: Vec::new(),
        });
        let e1 = net.add_edge(va, vb, first, attrs);
        let e2 = net.add_edge(vb, va, second, attrs);
        let face = net.add_face(vec![
            EdgeUse {
                edge: e1,
                reversed: false,
            },
            EdgeUse {
                edge: e2,
                reversed: false,
            },
        ]);
        Ok::<_, ToolError>(BoundaryReport {
            vertices: [va, vb],
            edges: [e1, e2],
            face,
        })
    })
}

/// The two points farthest apart, `i < j` (exact for up to 4096 points, else over every k-th point).
fn diameter_pair(pts: &[[f64; 3]]) -> (usize, usize) {
    let step = pts.len().div_ceil(4096).max(1);
    let mut best = (0, 1, -1.0);
    for i in (0..pts.len()).step_by(step) {
        for j in (i + 1..pts.len()).step_by(step) {
            let d = crate::network::geom::dist2(pts[i], pts[j]);
            if d > best.2 {
                best = (i, j, d);
            }
        }
    }
    (best.0, best.1)
}
