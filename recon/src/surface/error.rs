//! Errors of the surface reconstruction stages.

use crate::mesh::MeshError;

/// Why a curve network cannot be turned into a surface.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SurfaceError {
    /// The network has no face to build a surface on.
    #[error("the curve network has no faces: draw a closed boundary first")]
    EmptyNetwork,
    /// A network face the polygon mesh cannot hold (it visits a vertex twice, or its loop is broken).
    #[error("network face {face} cannot become a mesh polygon: {reason}")]
    UnsupportedFace {
        /// The network face handle, as text (`f3`).
        face: String,
        /// What is wrong with it.
        reason: String,
    },
    /// The faces do not form a manifold, consistently oriented surface (an edge used by more than two
    /// faces, two faces traversing an edge the same way, or a vertex whose faces are not one fan).
    #[error("the network's faces do not form a manifold surface: {0}")]
    NonManifold(#[from] MeshError),
    /// Geometry a stage cannot work with (a zero-length or non-finite polyline, a collapsed patch).
    #[error("degenerate geometry: {0}")]
    Degenerate(String),
    /// A stage was given a mesh it does not accept (e.g. a polygon with more than four sides after
    /// triquadrification).
    #[error("unexpected control mesh: {0}")]
    BadControlMesh(String),
}
