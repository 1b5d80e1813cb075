//! Index-based halfedge surface mesh (docs/architecture.md §8; model: pmp-library's
//! `SurfaceMesh`, geometry-central's attribute arrays).
//!
//! * [`SurfaceMesh`] stores connectivity in flat arrays addressed by typed handles
//!   ([`Vertex`], [`Halfedge`], [`Edge`], [`Face`]); twins are implicit (`h ^ 1`).
//! * Polygon faces of any degree are supported; the Euler operations that only make sense
//!   on triangles say so.
//! * Deleted elements stay in the arrays, flagged, until [`SurfaceMesh::garbage_collection`].

mod build;
mod circulators;
mod error;
mod euler;
mod garbage;
mod handles;
mod info;
mod properties;
mod repair;
mod surface_mesh;
mod validate;

pub use circulators::{FaceHalfedges, VertexHalfedges};
pub use error::MeshError;
pub use handles::{Edge, Face, Halfedge, Vertex};
pub use info::{mesh_info, ComponentInfo, MeshInfo, MAX_LISTED_COMPONENTS};
pub use properties::{Property, PropertyContainer};
pub use repair::{is_zero_area_polygon, RepairOptions, Repairs, ZERO_AREA_RELATIVE};
pub use surface_mesh::SurfaceMesh;
