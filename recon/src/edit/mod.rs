//! Differential mesh editing (issue 16): one shared core and one file per method.
//!
//! * [`spec`]: the JSON edit specification (ROI, anchors, handles with transforms or
//!   explicit positions);
//! * [`frames`]: local frames of handles given as positions (Yu et al. 2004, §3.3);
//! * [`problem`]: the specification resolved on a mesh, in a local numbering;
//! * [`system`]: a quadratic energy with fixed entries, factored once, solved per move;
//! * [`session`]: [`EditSession`], which keeps a method's factorisation and refactors only
//!   when the ROI or anchors change;
//! * methods: [`naive`] (uniform Laplacian coordinates, the baseline), [`poisson`]
//!   (Yu et al. 2004), [`lse`] (Sorkine et al. 2004), [`implicit`] (Fu, ch. 2);
//! * tools: [`coating`] (coating transfer), [`transplant`], [`denoise`];
//! * [`detail_error()`]: the normalised as-rigid-as-possible energy used to compare them.

pub mod basis;
pub mod coating;
pub mod denoise;
pub mod detail_error;
pub mod frames;
pub mod implicit;
mod implicit_fit;
mod implicit_systems;
pub mod local;
pub mod lse;
pub mod naive;
pub mod poisson;
mod poisson_rhs;
pub mod problem;
mod row_builder;
pub mod run;
pub mod session;
pub mod similarity;
pub mod spec;
pub mod system;
pub mod transplant;

pub use basis::AffineBasis;
pub use detail_error::detail_error;
pub use frames::{fit_similarity, HandleShape};
pub use implicit::{ImplicitEditor, ImplicitOptions};
pub use lse::{LseEditor, LseOptions};
pub use naive::{NaiveLaplacian, NaiveOptions};
pub use poisson::{PoissonEditor, PoissonOptions};
pub use problem::{EditProblem, Role};
pub use row_builder::RowBuilder;
pub use run::{bench_edit, edit_mesh, BenchEditReport, EditReport, Method};
pub use session::{EditMethod, EditSession, SessionStats};
pub use similarity::Similarity;
pub use spec::{EditSpec, HandleSpec, RotateSpec, Select, TransformSpec};

use crate::operators::OperatorError;
use crate::solve::SolveError;

/// Errors of the editing methods and their specification.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EditError {
    /// The specification is malformed (JSON error, unknown key, bad value).
    #[error("edit specification: {0}")]
    Spec(String),
    /// A selection matched no vertex.
    #[error("the {0} selection is empty")]
    EmptySelection(String),
    /// A vertex index is out of range.
    #[error("vertex index {index} out of range (mesh has {n} vertices)")]
    InvalidVertex {
        /// The index.
        index: usize,
        /// Number of vertices.
        n: usize,
    },
    /// A handle vertex is outside the ROI.
    #[error("handle {handle}: vertex {vertex} is outside the ROI")]
    HandleOutsideRoi {
        /// Handle number.
        handle: usize,
        /// Global vertex index.
        vertex: usize,
    },
    /// A handle vertex is also an anchor.
    #[error("handle {handle}: vertex {vertex} is also an anchor")]
    HandleIsAnchor {
        /// Handle number.
        handle: usize,
        /// Global vertex index.
        vertex: usize,
    },
    /// Two handles share a vertex.
    #[error("handles {first} and {second} share vertex {vertex}")]
    HandlesOverlap {
        /// First handle.
        first: usize,
        /// Second handle.
        second: usize,
        /// Global vertex index.
        vertex: usize,
    },
    /// A transform or weight is invalid.
    #[error("handle {handle}: {reason}")]
    BadTransform {
        /// Handle number.
        handle: usize,
        /// What is wrong.
        reason: String,
    },
    /// A handle's explicit positions are invalid (count, order, finiteness, or given together
    /// with a transform).
    #[error("handle {handle} positions: {reason}")]
    BadPositions {
        /// Handle number.
        handle: usize,
        /// What is wrong.
        reason: String,
    },
    /// Nothing is fixed: the ROI has no outside ring (it covers the mesh) and no anchors.
    #[error("nothing is fixed: the ROI covers the whole mesh and no anchors are given")]
    NothingFixed,
    /// The implicit method's constraints leave the system singular.
    #[error("singular constraints: {0}")]
    Singular(String),
    /// The wrong number of handle transforms was given.
    #[error("{got} handle transforms given for {expected} handles")]
    TransformCount {
        /// Number of handles.
        expected: usize,
        /// Number given.
        got: usize,
    },
    /// Two meshes do not match (coating transfer needs the same connectivity).
    #[error("meshes do not match: {0}")]
    Mismatch(String),
    /// An operator could not be built (e.g. not a triangle mesh).
    #[error(transparent)]
    Operator(#[from] OperatorError),
    /// A factorisation or solve failed.
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// Building a mesh failed.
    #[error(transparent)]
    Mesh(#[from] crate::mesh::MeshError),
}
