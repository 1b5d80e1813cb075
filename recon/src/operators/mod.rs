//! Discrete differential operators on triangle meshes (FIRES thesis, Part I §1.1–1.6,
//! Differential Methods for Intuitive 3D Shape Modeling, ch. 1; conventions of FIRES thesis, Part I §0).
//!
//! Polygon meshes: the cotangent matrix and the vertex areas (so the cotangent
//! Laplacians and mass matrices) triangulate each polygon first ([`face_triangles`]); the
//! other triangle operators return [`OperatorError::NeedsTriangles`] naming themselves.
//!
//! Conventions:
//! * Matrices are indexed by vertex/face *index*; call
//!   [`crate::mesh::SurfaceMesh::garbage_collection`] first so indices are dense.
//! * [`cotan_matrix`] is the symmetric, negative semidefinite `C` with
//!   `C_ij = ½(cot α_ij + cot β_ij)` (libigl's `cotmatrix`, the FEM stiffness with a minus
//!   sign). The thesis table's `L̄` (FIRES thesis, Part I §1.4) is `2C`; with its `D = 1/(2A_i)`
//!   both give the same `L = M⁻¹ C`.
//! * Mean curvature `H` is the average (κ1 + κ2)/2; the mean curvature *normal*
//!   `H⃗ = −Δ X = 2 H N` (so ‖H⃗‖ = 2/r on a sphere), FIRES thesis, Part I §0, §1.5.
//!
//! Robustness (what is clamped): a cotangent uses `cos/max(sin, 1e-8·|u||v|)`, so a
//! degenerate corner gives a weight of at most ~1e8 instead of ∞/NaN
//! ([`crate::geometry::cot_of_angle_between`]); negative cotangent weights of obtuse
//! triangles are *kept* (they are needed for linear precision) — call
//! [`clamp_negative_offdiagonal`] for an M-matrix. Vertex areas are floored at
//! `1e-300` before being inverted; zero-area faces contribute nothing to gradients.

mod areas;
mod cotan;
mod curvature;
mod geodesic;
mod gradient;
mod laplacians;
mod mass;
mod normals;
mod triangulate;

pub use areas::{face_areas, mean_edge_length, total_area, volume};
pub use cotan::{clamp_negative_offdiagonal, cotan_matrix};
pub use curvature::{
    angle_defects, gaussian_curvature, mean_curvature, mean_curvature_normals, principal_curvatures,
};
pub(crate) use geodesic::dijkstra;
pub use geodesic::{geodesic_dijkstra, geodesic_heat, HeatGeodesic};
pub use gradient::{divergence_matrix, gradient_matrix, vertex_gradient_matrix};
pub use laplacians::{laplacian, LaplacianKind};
pub use mass::{mass_matrix, vertex_areas, MassKind};
pub use normals::{face_normals, vertex_normals, NormalWeighting};
pub use triangulate::{face_triangles, triangulate, triangulate_polygon, MAX_DP_DEGREE};

use crate::mesh::{Face, SurfaceMesh, Vertex};
use crate::solve::SolveError;

/// Errors of operator construction.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OperatorError {
    /// The operator needs triangles; this face has another degree.
    #[error("operator needs a triangle mesh; face {0} is not a triangle")]
    NotTriangle(Face),
    /// The named operator needs triangles; this face has another degree (triangulate the
    /// mesh with [`triangulate`] first).
    #[error("{operator} needs a triangle mesh; face {face} is not a triangle (triangulate first)")]
    NeedsTriangles {
        /// Which operator refused.
        operator: &'static str,
        /// The first non-triangle face.
        face: Face,
    },
    /// The mesh has deleted elements; call `garbage_collection()` first.
    #[error("mesh has deleted elements; call garbage_collection() first")]
    HasGarbage,
    /// A source vertex is out of range or deleted.
    #[error("invalid source vertex {0}")]
    InvalidVertex(Vertex),
    /// Building a mesh failed.
    #[error(transparent)]
    Mesh(#[from] crate::mesh::MeshError),
    /// The linear solve failed.
    #[error(transparent)]
    Solve(#[from] SolveError),
}

/// [`triangles`] for the named operator: a polygon gives [`OperatorError::NeedsTriangles`].
pub(crate) fn triangles_for(
    mesh: &SurfaceMesh,
    operator: &'static str,
) -> Result<Vec<[usize; 3]>, OperatorError> {
    triangles(mesh).map_err(|e| match e {
        OperatorError::NotTriangle(face) => OperatorError::NeedsTriangles { operator, face },
        e => e,
    })
}

/// The three vertex indices of every face, checking the mesh is a compact triangle mesh.
pub fn triangles(mesh: &SurfaceMesh) -> Result<Vec<[usize; 3]>, OperatorError> {
    if mesh.has_garbage() {
        return Err(OperatorError::HasGarbage);
    }
    mesh.faces()
        .map(|f| {
            if mesh.face_valence(f) != 3 {
                return Err(OperatorError::NotTriangle(f));
            }
            let [a, b, c] = mesh.triangle(f);
            Ok([a.idx(), b.idx(), c.idx()])
        })
        .collect()
}
