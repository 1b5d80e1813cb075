//! Generated meshes with closed-form geometry, for tests (pmp-library's `shapes.h` idea).
//!
//! Every generator returns a valid [`SurfaceMesh`] together with nothing else; the
//! analytic quantities to test against (area, volume, normals, curvatures) are the free
//! functions in each shape's module. Curvature convention: `mean` is the *average*
//! (κ1 + κ2)/2, see FIRES thesis, Part I §0.

mod cube;
mod cylinder;
mod grid;
mod sphere;
mod torus;

pub use cube::{cube, cube_area, cube_volume};
pub use cylinder::{cylinder, cylinder_area, cylinder_mean_curvature, cylinder_normal};
pub use grid::plane_grid;
pub use sphere::{
    icosphere, sphere_area, sphere_mean_curvature, sphere_normal, sphere_volume, uv_sphere,
};
pub use torus::{
    torus, torus_area, torus_gaussian_curvature, torus_mean_curvature, torus_normal, torus_volume,
};

use crate::geometry::Vec3;
use crate::mesh::SurfaceMesh;

/// Builds a mesh from generator output that is valid by construction.
fn build(points: &[Vec3], faces: &[Vec<usize>]) -> SurfaceMesh {
    match SurfaceMesh::from_faces(points, faces) {
        Ok(m) => m,
        Err(e) => unreachable!("generator produced an invalid mesh: {e}"),
    }
}
