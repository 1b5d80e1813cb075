//! Spheres: a subdivided icosahedron and a latitude/longitude (UV) sphere.

use std::collections::HashMap;
use std::f64::consts::PI;

use super::build;
use crate::geometry::Vec3;
use crate::mesh::SurfaceMesh;

/// Icosphere of radius `r` centred at the origin: an icosahedron whose triangles are split
/// in four `subdivisions` times, new vertices projected onto the sphere.
/// It has `10·4^k + 2` vertices and `20·4^k` faces.
pub fn icosphere(subdivisions: u32, r: f64) -> SurfaceMesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut pts: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize_or_zero())
    .collect();
    let mut tris: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        tris = split_on_sphere(&mut pts, &tris);
    }
    let pts: Vec<Vec3> = pts.into_iter().map(|p| p * r).collect();
    let faces: Vec<Vec<usize>> = tris.iter().map(|t| t.to_vec()).collect();
    build(&pts, &faces)
}

fn split_on_sphere(pts: &mut Vec<Vec3>, tris: &[[usize; 3]]) -> Vec<[usize; 3]> {
    let mut mid: HashMap<(usize, usize), usize> = HashMap::new();
    let mut midpoint = |a: usize, b: usize, pts: &mut Vec<Vec3>| {
        *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
            pts.push(((pts[a] + pts[b]) * 0.5).normalize_or_zero());
            pts.len() - 1
        })
    };
    let mut out = Vec::with_capacity(tris.len() * 4);
    for &[a, b, c] in tris {
        let ab = midpoint(a, b, pts);
        let bc = midpoint(b, c, pts);
        let ca = midpoint(c, a, pts);
        out.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
    }
    out
}

/// UV sphere of radius `r`: `slices ≥ 3` meridians, `stacks ≥ 2` bands, triangles at the
/// poles and quads elsewhere (`quads = true`) or all triangles.
pub fn uv_sphere(slices: usize, stacks: usize, r: f64, quads: bool) -> SurfaceMesh {
    let (slices, stacks) = (slices.max(3), stacks.max(2));
    let mut pts = vec![Vec3::new(0.0, 0.0, r)];
    for i in 1..stacks {
        let theta = PI * i as f64 / stacks as f64;
        for j in 0..slices {
            let phi = 2.0 * PI * j as f64 / slices as f64;
            pts.push(
                Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                ) * r,
            );
        }
    }
    pts.push(Vec3::new(0.0, 0.0, -r));
    let south = pts.len() - 1;
    let ring = |i: usize, j: usize| 1 + (i - 1) * slices + j % slices;
    let mut faces = Vec::new();
    for j in 0..slices {
        faces.push(vec![0, ring(1, j), ring(1, j + 1)]);
        faces.push(vec![south, ring(stacks - 1, j + 1), ring(stacks - 1, j)]);
    }
    for i in 1..stacks - 1 {
        for j in 0..slices {
            let q = [
                ring(i, j),
                ring(i + 1, j),
                ring(i + 1, j + 1),
                ring(i, j + 1),
            ];
            push_quad(&mut faces, q, quads);
        }
    }
    build(&pts, &faces)
}

/// Pushes a quad, or two triangles split along its first diagonal.
pub(super) fn push_quad(faces: &mut Vec<Vec<usize>>, q: [usize; 4], quads: bool) {
    if quads {
        faces.push(q.to_vec());
    } else {
        faces.push(vec![q[0], q[1], q[2]]);
        faces.push(vec![q[0], q[2], q[3]]);
    }
}

/// Outward unit normal of the origin-centred sphere at `p`.
pub fn sphere_normal(p: Vec3) -> Vec3 {
    p.normalize_or_zero()
}
/// Area 4πr².
pub fn sphere_area(r: f64) -> f64 {
    4.0 * PI * r * r
}
/// Volume 4πr³/3.
pub fn sphere_volume(r: f64) -> f64 {
    4.0 * PI * r * r * r / 3.0
}
/// Mean curvature (κ1 + κ2)/2 = 1/r.
pub fn sphere_mean_curvature(r: f64) -> f64 {
    1.0 / r
}
