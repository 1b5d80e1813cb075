//! Polygon triangulation: planar polygons are covered exactly (no folds), T-junction
//! corners are not joined into zero-area triangles, existing edges are not reused, and
//! very large faces fall back to a fan.

use fires_recon::geometry::{is_degenerate_triangle, triangle_normal};
use fires_recon::mesh::SurfaceMesh;
use fires_recon::operators::{face_triangles, triangulate, triangulate_polygon, MAX_DP_DEGREE};
use fires_recon::Vec3;

fn planar(points: &[(f64, f64)]) -> Vec<Vec3> {
    points.iter().map(|&(x, y)| Vec3::new(x, y, 0.0)).collect()
}

/// Signed area of a planar polygon (shoelace).
fn shoelace(p: &[Vec3]) -> f64 {
    let n = p.len();
    (0..n)
        .map(|k| p[k].x * p[(k + 1) % n].y - p[(k + 1) % n].x * p[k].y)
        .sum::<f64>()
        / 2.0
}

fn check_exact_cover(p: &[Vec3]) {
    let poly: Vec<usize> = (0..p.len()).collect();
    let tris = triangulate_polygon(p, &poly, |_, _| false);
    assert_eq!(tris.len(), p.len() - 2);
    // Every triangle counter-clockwise (z > 0) and the areas add up to the polygon's:
    // no triangle outside the polygon, no overlap.
    let mut sum = 0.0;
    for t in &tris {
        let n = triangle_normal(p[t[0]], p[t[1]], p[t[2]]);
        assert!(n.z > 0.0, "{t:?} is folded");
        sum += n.z / 2.0;
    }
    assert!((sum - shoelace(p)).abs() < 1e-12 * shoelace(p));
}

#[test]
fn non_convex_planar_polygons_are_covered_exactly() {
    // L-shape, a comb and a star (all counter-clockwise).
    check_exact_cover(&planar(&[
        (0.0, 0.0),
        (2.0, 0.0),
        (2.0, 1.0),
        (1.0, 1.0),
        (1.0, 2.0),
        (0.0, 2.0),
    ]));
    check_exact_cover(&planar(&[
        (0.0, 0.0),
        (5.0, 0.0),
        (5.0, 3.0),
        (4.0, 3.0),
        (4.0, 1.0),
        (3.0, 1.0),
        (3.0, 3.0),
        (2.0, 3.0),
        (2.0, 1.0),
        (1.0, 1.0),
        (1.0, 3.0),
        (0.0, 3.0),
    ]));
    let star: Vec<(f64, f64)> = (0..14)
        .map(|k| {
            let t = k as f64 * std::f64::consts::PI / 7.0;
            let r = if k % 2 == 0 { 1.0 } else { 0.45 };
            (r * t.cos(), r * t.sin())
        })
        .collect();
    check_exact_cover(&planar(&star));
}

#[test]
fn t_junction_corners_are_not_joined() {
    // Square with two extra corners on its bottom edge: some triangulations of the
    // hexagon join collinear corners into a zero-area triangle; the chosen one does not.
    let p = planar(&[
        (0.0, 0.0),
        (1.0, 0.0),
        (2.0, 0.0),
        (3.0, 0.0),
        (3.0, 3.0),
        (0.0, 3.0),
    ]);
    let tris = triangulate_polygon(&p, &[0, 1, 2, 3, 4, 5], |_, _| false);
    assert!(
        tris.iter()
            .all(|t| !is_degenerate_triangle(p[t[0]], p[t[1]], p[t[2]])),
        "{tris:?}"
    );
    check_exact_cover(&p);
}

#[test]
fn existing_edges_are_not_used_as_diagonals() {
    // A quad 0 1 2 3 whose diagonal 0–2 already exists: it must be split along 1–3.
    let p = planar(&[(0.0, 0.0), (1.0, 0.0), (1.1, 1.0), (0.0, 1.0)]);
    let free = triangulate_polygon(&p, &[0, 1, 2, 3], |_, _| false);
    let blocked = triangulate_polygon(&p, &[0, 1, 2, 3], |a, b| (a.min(b), a.max(b)) == (0, 2));
    let uses = |tris: &[[usize; 3]], a: usize, b: usize| {
        tris.iter().any(|t| t.contains(&a) && t.contains(&b))
    };
    assert!(uses(&free, 0, 2) != uses(&free, 1, 3));
    assert!(!uses(&blocked, 0, 2) && uses(&blocked, 1, 3));
}

#[test]
fn triangulated_mesh_is_manifold_and_keeps_area() {
    // A pyramid on an octagon: the base polygon's triangulation must avoid nothing but
    // keep the mesh closed and its vertex indices.
    let mut pts: Vec<Vec3> = (0..8)
        .map(|k| {
            let t = k as f64 * std::f64::consts::PI / 4.0;
            Vec3::new(t.cos(), t.sin(), 0.0)
        })
        .collect();
    pts.push(Vec3::new(0.0, 0.0, 1.0));
    let mut faces: Vec<Vec<usize>> = vec![(0..8).rev().collect()];
    for k in 0..8 {
        faces.push(vec![k, (k + 1) % 8, 8]);
    }
    let m = SurfaceMesh::from_faces(&pts, &faces).unwrap();
    let t = triangulate(&m).unwrap();
    t.validate().unwrap();
    assert!(t.is_closed() && t.is_triangle_mesh());
    assert_eq!(
        (t.n_vertices(), t.n_faces(), t.euler_characteristic()),
        (9, 14, 2)
    );
    assert_eq!(t.positions(), m.positions());
}

#[test]
fn faces_beyond_the_dynamic_program_are_fans() {
    let n = MAX_DP_DEGREE + 6;
    let pts: Vec<Vec3> = (0..n)
        .map(|k| {
            let t = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
            Vec3::new(t.cos(), t.sin(), 0.0)
        })
        .collect();
    let m = SurfaceMesh::from_faces(&pts, &[(0..n).collect::<Vec<_>>()]).unwrap();
    let tris = face_triangles(&m).unwrap();
    assert_eq!(tris.len(), n - 2);
    let first = m
        .face_vertices(m.faces().next().unwrap())
        .next()
        .unwrap()
        .idx();
    assert!(tris.iter().all(|t| t[0] == first));
}
