//! # fires-recon: the FIRES geometry core
//!
//! Everything reconstruction and editing stand on (docs/architecture.md §8):
//! * [`mesh`]: an index-based halfedge [`mesh::SurfaceMesh`] with properties, circulators,
//!   Euler operations, garbage collection and `validate()`;
//! * [`io`]: OBJ, OFF, PLY and STL readers/writers and Matrix Market;
//! * [`generate`]: analytic test meshes (icosphere, UV sphere, torus, cylinder, grid, cube);
//! * [`operators`]: Laplacians, mass matrices, gradient/divergence, normals, curvatures,
//!   geodesic distance, all returning faer sparse matrices or plain vectors;
//! * [`network`]: the curve network (polyline mesh) and the sketching tools that build it;
//! * [`solve`]: sparse Cholesky with symbolic reuse, fixed-value (Dirichlet) elimination and
//!   stacked least squares (libigl's precompute/solve split);
//! * [`subdivide`]: Loop subdivision;
//! * [`surface`]: surfaces from curve networks (FIRESV1 and FIRESV2);
//! * [`edit`]: differential mesh editing (Laplacian surface editing, Poisson gradient
//!   editing, implicit Laplacian editing, naive Laplacian baseline, coating, transplanting,
//!   denoising) and the normalised ARAP `detail_error`;
//! * [`render`]: a small software rasteriser writing PNG images;
//! * [`mod@bench`]: solver timing used by `fires bench solve|laplacian`.

pub mod bench;
pub mod edit;
pub mod generate;
pub mod geometry;
mod handle;
pub mod io;
pub mod mesh;
pub mod network;
pub mod operators;
pub mod render;
pub mod solve;
pub mod subdivide;
pub mod surface;

pub use geometry::Vec3;
pub use mesh::SurfaceMesh;
