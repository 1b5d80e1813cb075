//! Hole creation (FIRES thesis §5.1.2 and §5.2.2): the user draws a convex closed curve, the border of
//! a hole.
//!
//! * **No crossing** (the curve comes within the intersection threshold of no curve): the hole lies in one
//!   n-sided face and is joined to the face's n vertices by n generated **spokes** (`hole_spokes.rs`):
//!   the face's Coons patch, the foot points of the hole by the hybrid Newton solve, straight spokes in
//!   the parameter domain mapped back onto the patch. The face is replaced by n faces (old edge, spoke,
//!   hole arc, spoke) and the hole gets none: ΔV = n, ΔE = 2n, ΔF = n − 1, Δχ = −1, one more boundary.
//! * **Crossings**: the curve splits the faces it runs through as curve insertion does (its crossings
//!   become vertices; rule 1 does not apply, the two-sided faces it makes are inside), then the faces
//!   inside it, the edges left without a face and the vertices left without an edge are removed
//!   (`hole_cut.rs`). No curve is generated.
//!
//! The two cases are one tool: [`create_hole`] applies fully and returns one
//! [`Transaction`], or returns a [`ToolError`] (rule [`HoleRule`], or the curve insertion rule that
//! failed) and leaves the network bit for bit as it was.

use std::fmt;

use super::crossings::{arcs, find_hits, gap};
use super::{widened_m, CurveInput, InsertOptions, ToolError};
use crate::network::geom::P3;
use crate::network::mesh::Network;
use crate::network::ops::SAME_POINT_M;
use crate::network::{EdgeId, FaceId, Transaction};

/// Options of [`create_hole`] (millimetres).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct HoleOptions {
    /// Intersection threshold, snapping and closing distance (`close_mm`): a hole crossing the network is
    /// inserted with these, and a hole comes within `intersect_mm` of no curve to have no crossing.
    pub insert: InsertOptions,
    /// Farthest a hole point may be from the face's Coons patch (no-crossing case), mm.
    pub max_distance_mm: f64,
    /// Grid samples per direction for the Newton solve's initial guess.
    pub newton_grid: usize,
    /// Most Newton iterations per foot point.
    pub newton_iterations: usize,
    /// The tangent fraction of the Q' corner angles (as triquadrification's).
    pub tangent_fraction: f64,
    /// Fewest segments of a spoke.
    pub min_segments: usize,
}

impl Default for HoleOptions {
    fn default() -> Self {
        HoleOptions {
            insert: InsertOptions::default(),
            max_distance_mm: 50.0,
            newton_grid: 16,
            newton_iterations: 50,
            tangent_fraction: 0.05,
            min_segments: 2,
        }
    }
}

/// A rule of hole creation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HoleRule {
    /// A hole without crossings lies in one face: every hole point's foot point is inside the face's
    /// Coons patch domain and within `max_distance_mm` of it.
    InsideOneFace,
    /// The face has at least two sides (so the hole has at least two arcs).
    FaceSides,
    /// The hole is convex enough: its centroid is inside it in the patch domain and the spokes meet it in
    /// the face's order at distinct points.
    Convex,
    /// A hole with crossings cuts the surface into an inside and an outside.
    Separates,
    /// Removing the inside leaves no vertex with a single edge.
    NoDangling,
    /// The hole's border touches no other border (a vertex shared by two border loops is not a surface).
    ClearOfBorder,
}

impl HoleRule {
    /// The rule's short name (what [`ToolError::rule`] returns).
    pub fn name(&self) -> &'static str {
        match self {
            HoleRule::InsideOneFace => "hole inside one face",
            HoleRule::FaceSides => "hole face has two sides",
            HoleRule::Convex => "hole is convex",
            HoleRule::Separates => "hole separates the surface",
            HoleRule::NoDangling => "hole leaves no dangling edge",
            HoleRule::ClearOfBorder => "hole keeps clear of the border",
        }
    }
}

impl fmt::Display for HoleRule {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Which case [`create_hole`] applied.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HoleKind {
    /// No crossing: the hole is joined to the face's vertices by spokes.
    Spokes {
        /// The face the hole was in (now removed).
        face: FaceId,
        /// Its number of sides n (= spokes).
        sides: usize,
        /// (u, v) of the hole centroid's foot point on the face's Coons patch.
        centroid_uv: (f64, f64),
        /// The largest distance of a hole point from the patch, mm.
        max_distance_mm: f64,
        /// The most Newton iterations a foot point took.
        newton_iterations: usize,
    },
    /// Crossings: the face region inside the curve was removed.
    Cut {
        /// Vertices on the hole curve (its crossings with the network).
        crossings: usize,
    },
}

/// What [`create_hole`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct HoleReport {
    /// The case.
    pub kind: HoleKind,
    /// The edges of the hole's border, in order round it.
    pub hole_edges: Vec<EdgeId>,
    /// The generated spokes (no-crossing case), one per face vertex in loop order.
    pub spokes: Vec<EdgeId>,
    /// The faces that border the hole.
    pub faces: Vec<FaceId>,
    /// Faces removed (the old face, or the faces inside the curve).
    pub removed_faces: usize,
    /// Edges removed (inside the curve).
    pub removed_edges: usize,
    /// Vertices removed (inside the curve).
    pub removed_vertices: usize,
}

/// The error of a hole rule.
pub(crate) fn refuse(rule: HoleRule, detail: String, distance_mm: Option<f64>) -> ToolError {
    ToolError::Hole {
        rule,
        detail,
        distance_mm,
    }
}

/// Makes a hole bounded by the closed `curve` (module docs).
pub fn create_hole(
    net: &mut Network,
    curve: CurveInput<'_>,
    options: &HoleOptions,
) -> Result<(HoleReport, Transaction), ToolError> {
    let mut pts = super::distinct_points(curve.points)?;
    if pts.len() < 3 {
        return Err(ToolError::BadCurve(
            "a hole needs at least 3 distinct points".into(),
        ));
    }
    let close = gap(pts[0], pts[pts.len() - 1]);
    if close > options.insert.close_mm * 1e-3 {
        return Err(ToolError::NotClosed {
            gap_mm: close * 1e3,
            limit_mm: options.insert.close_mm,
        });
    }
    // The loop without its closing point.
    if close <= SAME_POINT_M {
        pts.pop();
    }
    if pts.len() < 3 {
        return Err(ToolError::BadCurve(
            "a hole needs at least 3 distinct points".into(),
        ));
    }
    let thr = widened_m(
        options.insert.intersect_mm,
        curve.sigma_mm,
        options.insert.sigma_factor,
    );
    let mut closed = pts.clone();
    closed.push(pts[0]);
    let (hits, _) = find_hits(net, &closed, &arcs(&closed), thr, 0.0);
    if hits.is_empty() {
        let plan = super::hole_spokes::plan(net, &pts, options)?;
        return net.transact(|net| super::hole_spokes::apply(net, &plan, curve.stroke));
    }
    // Crossings: start the loop in the middle of the longest stretch between two meeting points, so no
    // approach to the network straddles the loop's seam.
    let arc = arcs(&closed);
    let total = arc[arc.len() - 1];
    let mut sig: Vec<f64> = hits.iter().map(|h| h.sigma).collect();
    sig.push(sig[0] + total);
    let (mut best, mut mid) = (-1.0, 0.0);
    for w in sig.windows(2) {
        if w[1] - w[0] > best {
            (best, mid) = (w[1] - w[0], ((w[0] + w[1]) / 2.0).rem_euclid(total));
        }
    }
    let start = arc.partition_point(|&s| s < mid).min(pts.len() - 1);
    let mut rotated: Vec<P3> = pts[start..].iter().chain(&pts[..start]).copied().collect();
    rotated.push(rotated[0]);
    let (hits, _) = find_hits(net, &rotated, &arcs(&rotated), thr, 0.0);
    let vertex_snap = widened_m(
        options.insert.vertex_snap_mm,
        curve.sigma_mm,
        options.insert.sigma_factor,
    );
    net.transact(|net| {
        let (edges, vertices) =
            super::hole_cut::insert_loop(net, &rotated, &hits, vertex_snap, thr, curve.stroke)?;
        super::hole_cut::remove_inside(net, &edges, &vertices)
    })
}
