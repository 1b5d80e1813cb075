//! Torus around the z axis.

use std::f64::consts::PI;

use super::build;
use super::sphere::push_quad;
use crate::geometry::Vec3;
use crate::mesh::SurfaceMesh;

/// Torus with tube centre radius `major` and tube radius `minor` (`major > minor`),
/// `n_major × n_minor` vertices, quads or triangles.
pub fn torus(major: f64, minor: f64, n_major: usize, n_minor: usize, quads: bool) -> SurfaceMesh {
    let (nu, nv) = (n_major.max(3), n_minor.max(3));
    let mut pts = Vec::with_capacity(nu * nv);
    for i in 0..nu {
        let u = 2.0 * PI * i as f64 / nu as f64;
        for j in 0..nv {
            let v = 2.0 * PI * j as f64 / nv as f64;
            let rho = major + minor * v.cos();
            pts.push(Vec3::new(rho * u.cos(), rho * u.sin(), minor * v.sin()));
        }
    }
    let id = |i: usize, j: usize| (i % nu) * nv + j % nv;
    let mut faces = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            push_quad(
                &mut faces,
                [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)],
                quads,
            );
        }
    }
    build(&pts, &faces)
}

/// (u, v) angles of a point on the torus.
fn torus_angles(p: Vec3, major: f64) -> (f64, f64) {
    let u = p.y.atan2(p.x);
    let rho = (p.x * p.x + p.y * p.y).sqrt();
    (u, p.z.atan2(rho - major))
}

/// Outward unit normal at a point `p` of the torus.
pub fn torus_normal(p: Vec3, major: f64) -> Vec3 {
    let (u, v) = torus_angles(p, major);
    Vec3::new(v.cos() * u.cos(), v.cos() * u.sin(), v.sin())
}
/// Gaussian curvature cos v / (minor (major + minor cos v)).
pub fn torus_gaussian_curvature(p: Vec3, major: f64, minor: f64) -> f64 {
    let (_, v) = torus_angles(p, major);
    v.cos() / (minor * (major + minor * v.cos()))
}
/// Mean curvature (κ1 + κ2)/2 = (major + 2 minor cos v) / (2 minor (major + minor cos v)),
/// positive with the outward normal convention used here (sphere: +1/r).
pub fn torus_mean_curvature(p: Vec3, major: f64, minor: f64) -> f64 {
    let (_, v) = torus_angles(p, major);
    (major + 2.0 * minor * v.cos()) / (2.0 * minor * (major + minor * v.cos()))
}
/// Area 4π² R r.
pub fn torus_area(major: f64, minor: f64) -> f64 {
    4.0 * PI * PI * major * minor
}
/// Volume 2π² R r².
pub fn torus_volume(major: f64, minor: f64) -> f64 {
    2.0 * PI * PI * major * minor * minor
}
