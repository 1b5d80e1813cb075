//! Triangulating polygon faces, for the operators that are defined on triangles.
//!
//! Each polygon is split by the dynamic program of minimum-weight polygon triangulation
//! (Klincsek, *Minimal triangulations of polygonal domains*, 1980; used for hole filling
//! by Liepa, *Filling holes in meshes*, SGP 2003, §3, and by pmp-library's
//! `triangulate`): the weight of a triangle is its area plus `1e-3·Σℓ²` of its edges, so
//! a planar convex polygon (where every triangulation has the same area) is split along
//! its shorter diagonals; a zero-area triangle weighs `1e6·Σℓ²`, so collinear corners
//! (T-junctions) are not joined when another triangulation exists. A diagonal that is already an edge of the mesh (or of an
//! earlier face's triangulation) is not used when avoidable, so [`triangulate`] returns a
//! manifold mesh. Faces of more than [`MAX_DP_DEGREE`] vertices are fan-triangulated from
//! their first vertex (the O(n³) program would be too slow).
//!
//! Operators that triangulate internally: [`super::cotan_matrix`], [`super::vertex_areas`]
//! / [`super::mass_matrix`] and hence [`super::laplacian`] with `Cotan`/`CotanNormalized`
//! (the result is the operator of the triangulated mesh, on the same vertices). The
//! others refuse polygons with [`super::OperatorError::NeedsTriangles`] naming themselves.

use std::collections::HashSet;

use super::OperatorError;
use crate::geometry::{is_degenerate_triangle, triangle_area, Vec3};
use crate::mesh::{SurfaceMesh, Vertex};

/// Largest face degree triangulated by dynamic programming.
pub const MAX_DP_DEGREE: usize = 64;

/// Weight of the squared edge lengths in the triangle weight (tie-breaker).
const EDGE_WEIGHT: f64 = 1e-3;

/// Weight of the squared edge lengths of a zero-area triangle: avoided whenever the
/// polygon has another triangulation (e.g. three collinear corners of a T-junction).
const DEGENERATE_WEIGHT: f64 = 1e6;

/// Every face as triangles of vertex indices (triangles as they are, polygons
/// triangulated as the module docs describe), in face order.
pub fn face_triangles(mesh: &SurfaceMesh) -> Result<Vec<[usize; 3]>, OperatorError> {
    if mesh.has_garbage() {
        return Err(OperatorError::HasGarbage);
    }
    let p = mesh.positions();
    let mut diagonals: HashSet<(usize, usize)> = HashSet::new();
    let mut out = Vec::with_capacity(mesh.n_faces());
    let mut poly = Vec::new();
    for f in mesh.faces() {
        poly.clear();
        poly.extend(mesh.face_vertices(f).map(Vertex::idx));
        if poly.len() == 3 {
            out.push([poly[0], poly[1], poly[2]]);
            continue;
        }
        let taken = |a: usize, b: usize| {
            diagonals.contains(&(a.min(b), a.max(b)))
                || mesh.find_edge(Vertex::new(a), Vertex::new(b)).is_some()
        };
        let tris = triangulate_polygon(p, &poly, taken);
        for t in &tris {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                diagonals.insert((a.min(b), a.max(b)));
            }
        }
        out.extend(tris);
    }
    Ok(out)
}

/// A triangle mesh on the same vertices (same indices) with every polygon triangulated.
pub fn triangulate(mesh: &SurfaceMesh) -> Result<SurfaceMesh, OperatorError> {
    let tris = face_triangles(mesh)?;
    Ok(SurfaceMesh::from_triangles(mesh.positions(), &tris)?)
}

/// Triangulates one polygon (vertex indices into `points`); `taken(a, b)` marks vertex
/// pairs that must not become a diagonal if another triangulation exists.
pub fn triangulate_polygon(
    points: &[Vec3],
    poly: &[usize],
    taken: impl Fn(usize, usize) -> bool,
) -> Vec<[usize; 3]> {
    let n = poly.len();
    if n < 3 {
        return Vec::new();
    }
    let fan = || {
        (1..n - 1)
            .map(|k| [poly[0], poly[k], poly[k + 1]])
            .collect()
    };
    if n > MAX_DP_DEGREE {
        return fan();
    }
    let p = |k: usize| points[poly[k]];
    let allowed =
        |i: usize, j: usize| j == i + 1 || (i == 0 && j == n - 1) || !taken(poly[i], poly[j]);
    let weight = |i: usize, k: usize, j: usize| {
        let (a, b, c) = (p(i), p(k), p(j));
        let l2 = (b - a).norm_squared() + (c - b).norm_squared() + (a - c).norm_squared();
        let penalty = if is_degenerate_triangle(a, b, c) {
            DEGENERATE_WEIGHT
        } else {
            EDGE_WEIGHT
        };
        triangle_area(a, b, c) + penalty * l2
    };
    let idx = |i: usize, j: usize| i * n + j;
    let mut cost = vec![f64::INFINITY; n * n];
    let mut split = vec![usize::MAX; n * n];
    for i in 0..n - 1 {
        cost[idx(i, i + 1)] = 0.0;
    }
    for len in 2..n {
        for i in 0..n - len {
            let j = i + len;
            if !allowed(i, j) {
                continue;
            }
            for k in i + 1..j {
                let c = cost[idx(i, k)] + cost[idx(k, j)];
                if !c.is_finite() {
                    continue;
                }
                let c = c + weight(i, k, j);
                if c < cost[idx(i, j)] {
                    cost[idx(i, j)] = c;
                    split[idx(i, j)] = k;
                }
            }
        }
    }
    if !cost[idx(0, n - 1)].is_finite() {
        return fan();
    }
    let mut out = Vec::with_capacity(n - 2);
    let mut stack = vec![(0, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j <= i + 1 {
            continue;
        }
        let k = split[idx(i, j)];
        if k == usize::MAX {
            return fan();
        }
        out.push([poly[i], poly[k], poly[j]]);
        stack.push((i, k));
        stack.push((k, j));
    }
    out
}
