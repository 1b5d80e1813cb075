//! Why a tool refused a curve.

use std::fmt;

use crate::network::{EdgeId, VertexId};

/// Which end of a curve.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum End {
    /// The first point drawn.
    Start,
    /// The last point drawn.
    End,
}

impl fmt::Display for End {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            End::Start => "start",
            End::End => "end",
        })
    }
}

/// A tool's refusal; the network is unchanged. Distances in millimetres.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ToolError {
    /// The curve has fewer than two usable points or a point that is not finite.
    #[error("rule \"valid curve\": {0}")]
    BadCurve(String),
    /// A boundary stroke does not end where it began.
    #[error(
        "rule \"closed boundary\": the ends are {gap_mm:.2} mm apart (limit {limit_mm:.2} mm)"
    )]
    NotClosed {
        /// Distance between first and last point.
        gap_mm: f64,
        /// The closing distance.
        limit_mm: f64,
    },
    /// An end of an inserted curve is neither on the network, nor within the snapping distance of it, nor
    /// an overshoot past a crossing that can be trimmed.
    #[error("rule \"ends on the network\": the {end} is {distance_mm:.2} mm from the network (snapping distance {limit_mm:.2} mm)")]
    EndNotOnNetwork {
        /// Which end.
        end: End,
        /// Distance from that end point to the nearest network point (infinite when none is near).
        distance_mm: f64,
        /// The snapping distance used.
        limit_mm: f64,
    },
    /// Rule 1 (FIRES thesis §5.1): a piece of the curve starts and ends on the same polyline.
    #[error(
        "rule 1 \"not on the same polyline\": a piece of the curve starts and ends on edge {edge}"
    )]
    SamePolyline {
        /// The edge both ends lie on.
        edge: EdgeId,
    },
    /// Rule 2 (FIRES thesis §5.1): between two consecutive points where the curve meets the network there
    /// is no face holding both, so the curve crossed a curve without coming within the intersection
    /// threshold, or left the surface.
    #[error("rule 2 \"crossings intersect\": piece {piece} of the curve lies in no face (intersection threshold {threshold_mm:.2} mm)")]
    NoCommonFace {
        /// The piece (0 = from the start to the first crossing).
        piece: usize,
        /// The intersection threshold used.
        threshold_mm: f64,
    },
    /// No edge comes from the stroke.
    #[error("rule \"stroke exists\": no edge comes from stroke {stroke}")]
    NoSuchStroke {
        /// The stroke id.
        stroke: u32,
    },
    /// Deleting would open the surface or leave a dangling edge.
    #[error("rule \"delete merges two faces\": removing the stroke would open the surface or leave edge {edge} dangling")]
    CannotDelete {
        /// The edge at fault.
        edge: EdgeId,
    },
    /// The stroke's pen mode selects a tool that does not exist (yet).
    #[error("rule \"pen mode has a tool\": mode {mode} selects no implemented tool")]
    NoToolForMode {
        /// The mode value (`buttons >> 1`).
        mode: u8,
    },
    /// Hole creation (FIRES thesis §5.2.2) refused the closed curve.
    #[error("rule \"{}\": {detail}", rule.name())]
    Hole {
        /// The hole rule that failed.
        rule: super::hole::HoleRule,
        /// What failed, with the numbers.
        detail: String,
        /// The distance that failed, mm, where there is one.
        distance_mm: Option<f64>,
    },
    /// An end of a closure, gluing or skinning curve is not on a boundary edge.
    #[error("rule \"ends on a boundary\": the {end} is {distance_mm:.2} mm from the nearest boundary edge (limit {limit_mm:.2} mm)")]
    NotOnBoundary {
        /// Which end.
        end: End,
        /// Distance to the nearest boundary point (infinite when there is no boundary).
        distance_mm: f64,
        /// The snapping distance used.
        limit_mm: f64,
    },
    /// An edge that should be on a boundary loop is not (it has two faces, or none).
    #[error("rule \"boundary edge\": edge {edge} is not on a boundary loop")]
    NotABoundaryEdge {
        /// The edge.
        edge: EdgeId,
    },
    /// Two boundary loops touch at a vertex, so the loop through it is ambiguous.
    #[error("rule \"simple boundary loop\": two boundary loops touch at vertex {vertex}")]
    PinchedBoundary {
        /// The vertex.
        vertex: VertexId,
    },
    /// Closure needs both ends on one loop.
    #[error("rule \"one boundary loop\": the ends lie on two different boundary loops (edges {first} and {second})")]
    DifferentBoundaries {
        /// An edge of the first end's loop.
        first: EdgeId,
        /// An edge of the second end's loop.
        second: EdgeId,
    },
    /// Gluing one loop to itself, or half-loops, needs the second curve.
    #[error("rule \"gluing needs two curves\": paths on one loop, or halves of two loops, need the second curve")]
    NeedsSecondCurve,
    /// A glued path would have no length (both ends of a path on one vertex).
    #[error("rule \"glued paths have length\": a path to glue starts and ends on one vertex")]
    DegenerateGluing,
    /// The gluing curves cross, so the glued surface would not be orientable.
    #[error("rule \"orientable gluing\": the curves cross (a Möbius band), the faces would traverse the glued curve the same way")]
    CrossedGluing,
    /// A skinning spine does not come within the intersection threshold of a profile.
    #[error("rule \"spines cross every profile\": spine {spine} passes {distance_mm:.2} mm from profile {profile} (threshold {limit_mm:.2} mm)")]
    SpineMissesProfile {
        /// The spine (0 or 1).
        spine: usize,
        /// The profile (in the given order).
        profile: usize,
        /// Closest distance between the two.
        distance_mm: f64,
        /// The threshold used.
        limit_mm: f64,
    },
    /// A skinning spine meets the profiles out of order (either way along it).
    #[error("rule \"spines cross the profiles in order\": spine {spine} meets the profiles out of order")]
    SpineOrder {
        /// The spine (0 or 1).
        spine: usize,
    },
    /// The two spines cross a profile at (nearly) one point, so it has no two halves.
    #[error("rule \"spines cross a profile apart\": the spines cross profile {profile} {distance_mm:.2} mm apart")]
    SpinesMeet {
        /// The profile.
        profile: usize,
        /// Distance between the two crossings.
        distance_mm: f64,
    },
}

impl ToolError {
    /// A short name of the rule that failed.
    pub fn rule(&self) -> &'static str {
        match self {
            ToolError::BadCurve(_) => "valid curve",
            ToolError::NotClosed { .. } => "closed boundary",
            ToolError::EndNotOnNetwork { .. } => "ends on the network",
            ToolError::SamePolyline { .. } => "rule 1: not on the same polyline",
            ToolError::NoCommonFace { .. } => "rule 2: crossings intersect",
            ToolError::NoSuchStroke { .. } => "stroke exists",
            ToolError::CannotDelete { .. } => "delete merges two faces",
            ToolError::NoToolForMode { .. } => "pen mode has a tool",
            ToolError::Hole { rule, .. } => rule.name(),
            ToolError::NotOnBoundary { .. } => "ends on a boundary",
            ToolError::NotABoundaryEdge { .. } => "boundary edge",
            ToolError::PinchedBoundary { .. } => "simple boundary loop",
            ToolError::DifferentBoundaries { .. } => "one boundary loop",
            ToolError::NeedsSecondCurve => "gluing needs two curves",
            ToolError::DegenerateGluing => "glued paths have length",
            ToolError::CrossedGluing => "orientable gluing",
            ToolError::SpineMissesProfile { .. } => "spines cross every profile",
            ToolError::SpineOrder { .. } => "spines cross the profiles in order",
            ToolError::SpinesMeet { .. } => "spines cross a profile apart",
        }
    }

    /// The distance that failed, millimetres, where there is one.
    pub fn distance_mm(&self) -> Option<f64> {
        match self {
            ToolError::NotClosed { gap_mm, .. } => Some(*gap_mm),
            ToolError::EndNotOnNetwork { distance_mm, .. } => Some(*distance_mm),
            ToolError::NoCommonFace { threshold_mm, .. } => Some(*threshold_mm),
            ToolError::Hole { distance_mm, .. } => *distance_mm,
            ToolError::NotOnBoundary { distance_mm, .. } => Some(*distance_mm),
            ToolError::SpineMissesProfile { distance_mm, .. } => Some(*distance_mm),
            ToolError::SpinesMeet { distance_mm, .. } => Some(*distance_mm),
            _ => None,
        }
    }
}
