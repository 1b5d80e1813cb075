//! Surfaces from curve networks: the FIRES thesis's chapter 6.
//!
//! Both methods turn a [`crate::network::Network`] into a [`ControlMesh`] (a quad-dominant
//! [`SurfaceMesh`](crate::mesh::SurfaceMesh) that knows which of its edges follow which drawn curve),
//! refine it, and subdivide it to the final resolution while keeping the curves:
//! * **FIRESV1** (§6.1–6.3): triquadrification, basic refinement by Coons patches, then Catmull-Clark or the
//!   interpolatory scheme with the curve-snapping edge rule (NULISSmod);
//! * **FIRESV2** (§6.4): a Catmull-Clark-topology tessellation of every face, the two-step surface-diffusion
//!   flow under the curve constraints, then Catmull-Clark with sharp rules.
//!
//! [`ControlMesh`] is the one type every stage passes on (control.rs); [`compare_surface`] measures a surface
//! against the true object (compare.rs).

mod compare;
mod control;

pub use compare::{
    compare_surface, sample_triangles, CompareError, CompareOptions, SurfaceComparison,
    COMPLETENESS_THRESHOLD_M,
};
pub use control::{ControlMesh, Curve, CurvePoint, CurveSpan, VertexTag};
