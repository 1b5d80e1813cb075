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
//! [`ControlMesh`] is the one type every stage passes on (control.rs); [`base_mesh`] makes the first one
//! from a network (from_network.rs); [`compare_surface`] measures a surface against the true object
//! (compare.rs).

mod catmull_clark;
mod compare;
mod control;
mod coons;
mod diffusion;
mod error;
mod face_patch;
mod foot_point;
mod from_network;
mod nuliss;
mod quad_cotan;
mod refine;
mod tessellate;
mod triquad;
mod v1;
mod v2;

pub use catmull_clark::{
    catmull_clark, catmull_clark_n, curve_target, interpolating_control, limit_positions,
    smooth_curve_target, smooth_point_at, CatmullClarkOptions, CurveKeeping,
};
pub use compare::{
    compare_surface, point_distances, sample_triangles, CompareError, CompareOptions,
    SurfaceComparison, COMPLETENESS_THRESHOLD_M,
};
pub use control::{ControlMesh, Curve, CurvePoint, CurveSpan, VertexTag};
pub use coons::{chord_params, span_points, CoonsPatch, Side};
pub use diffusion::{surface_diffusion, CurvatureField, DiffusionOptions, SurfaceDiffusion};
pub use error::SurfaceError;
pub use face_patch::{face_patch, FacePatch};
pub use foot_point::{foot_point, FootPoint, FootPointOptions, FootPointSolver};
pub use from_network::base_mesh;
pub use nuliss::{nuliss_mod, nuliss_mod_n, NulissOptions};
pub use quad_cotan::{vertex_normals_at, QuadCotan};
pub use refine::{refine, refine_step, RefineOptions};
pub use tessellate::{tessellate, tessellate_step, TessellateOptions};
pub use triquad::{triquadrify, TriquadOptions};
pub use v1::{
    reconstruct_v1, refined_v1, subdivide_v1, subdivide_v1_control, without_generated, V1Options,
};
pub use v2::{
    diffusion_options, reconstruct_v2, reconstruct_v2_from_base, subdivide, v2_refined, V2Options,
};
