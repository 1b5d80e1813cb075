//! Errors of mesh construction and editing.

use super::handles::{Edge, Face, Halfedge, Vertex};

/// What went wrong building or editing a [`super::SurfaceMesh`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// A face refers to a vertex index that does not exist.
    #[error("face {face} refers to vertex {index}, but the mesh has {n_vertices} vertices")]
    VertexIndexOutOfRange {
        /// Face number in the input.
        face: usize,
        /// The offending index.
        index: usize,
        /// Number of vertices.
        n_vertices: usize,
    },
    /// A face has fewer than three vertices or repeats a vertex.
    #[error("face {face} is degenerate (fewer than 3 distinct vertices)")]
    DegenerateFace {
        /// Face number in the input.
        face: usize,
    },
    /// The directed edge `from → to` is used by two faces (non-manifold edge, or two faces
    /// with inconsistent orientation).
    #[error("non-manifold or inconsistently oriented edge {from} -> {to} (face {face})")]
    NonManifoldEdge {
        /// Edge start vertex.
        from: Vertex,
        /// Edge end vertex.
        to: Vertex,
        /// Input face that used the directed edge a second time.
        face: usize,
    },
    /// The faces around a vertex do not form a single fan (disk or half-disk).
    #[error("non-manifold vertex {0}")]
    NonManifoldVertex(Vertex),
    /// The mesh has more elements than 32-bit handles can address.
    #[error("too many elements for 32-bit handles")]
    TooLarge,
    /// The operation is not allowed on this edge (see the `is_*_ok` predicates).
    #[error("operation not allowed on edge {0}")]
    EdgeOperationRejected(Edge),
    /// The operation is not allowed on this face (e.g. it was deleted).
    #[error("operation not allowed on face {0}")]
    FaceOperationRejected(Face),
    /// The operation is not allowed on this halfedge.
    #[error("operation not allowed on halfedge {0}")]
    HalfedgeOperationRejected(Halfedge),
    /// A property with this name already exists.
    #[error("property `{0}` already exists")]
    PropertyExists(String),
    /// An invariant check failed; the message says which.
    #[error("invalid mesh: {0}")]
    Invalid(String),
}
