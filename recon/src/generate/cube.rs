//! Axis-aligned cube.

use super::build;
use super::sphere::push_quad;
use crate::geometry::Vec3;
use crate::mesh::SurfaceMesh;

/// Cube `[-s/2, s/2]³` with outward orientation: 6 quads or 12 triangles.
pub fn cube(s: f64, quads: bool) -> SurfaceMesh {
    let h = s / 2.0;
    let pts: Vec<Vec3> = (0..8)
        .map(|i| {
            let c = |b: usize| if i & b != 0 { h } else { -h };
            Vec3::new(c(1), c(2), c(4))
        })
        .collect();
    let sides = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut faces = Vec::new();
    for q in sides {
        push_quad(&mut faces, q, quads);
    }
    build(&pts, &faces)
}

/// Surface area 6s².
pub fn cube_area(s: f64) -> f64 {
    6.0 * s * s
}
/// Volume s³.
pub fn cube_volume(s: f64) -> f64 {
    s * s * s
}
