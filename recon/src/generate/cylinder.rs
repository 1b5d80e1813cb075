//! Open cylinder (two boundary loops) around the z axis.

use std::f64::consts::PI;

use super::build;
use super::sphere::push_quad;
use crate::geometry::Vec3;
use crate::mesh::SurfaceMesh;

/// Open cylinder of radius `r`, from z = 0 to z = `height`, `n_around ≥ 3` vertices per
/// ring and `n_rings ≥ 2` rings; quads or triangles.
pub fn cylinder(r: f64, height: f64, n_around: usize, n_rings: usize, quads: bool) -> SurfaceMesh {
    let (na, nr) = (n_around.max(3), n_rings.max(2));
    let mut pts = Vec::with_capacity(na * nr);
    for i in 0..nr {
        let z = height * i as f64 / (nr - 1) as f64;
        for j in 0..na {
            let phi = 2.0 * PI * j as f64 / na as f64;
            pts.push(Vec3::new(r * phi.cos(), r * phi.sin(), z));
        }
    }
    let id = |i: usize, j: usize| i * na + j % na;
    let mut faces = Vec::new();
    for i in 0..nr - 1 {
        for j in 0..na {
            push_quad(
                &mut faces,
                [id(i, j), id(i, j + 1), id(i + 1, j + 1), id(i + 1, j)],
                quads,
            );
        }
    }
    build(&pts, &faces)
}

/// Outward unit normal at `p`.
pub fn cylinder_normal(p: Vec3) -> Vec3 {
    Vec3::new(p.x, p.y, 0.0).normalize_or_zero()
}
/// Lateral area 2πrh.
pub fn cylinder_area(r: f64, height: f64) -> f64 {
    2.0 * PI * r * height
}
/// Mean curvature (κ1 + κ2)/2 = 1/(2r).
pub fn cylinder_mean_curvature(r: f64) -> f64 {
    0.5 / r
}
