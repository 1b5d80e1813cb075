//! Flat rectangular grid in the z = 0 plane.

use super::build;
use super::sphere::push_quad;
use crate::geometry::Vec3;
use crate::mesh::SurfaceMesh;

/// Grid of `nx × ny` cells covering `[0, width] × [0, depth]` at z = 0, normal +z;
/// quads or triangles (each cell split along its diagonal).
pub fn plane_grid(nx: usize, ny: usize, width: f64, depth: f64, quads: bool) -> SurfaceMesh {
    let (nx, ny) = (nx.max(1), ny.max(1));
    let mut pts = Vec::with_capacity((nx + 1) * (ny + 1));
    for j in 0..=ny {
        for i in 0..=nx {
            pts.push(Vec3::new(
                width * i as f64 / nx as f64,
                depth * j as f64 / ny as f64,
                0.0,
            ));
        }
    }
    let id = |i: usize, j: usize| j * (nx + 1) + i;
    let mut faces = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            push_quad(
                &mut faces,
                [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)],
                quads,
            );
        }
    }
    build(&pts, &faces)
}
