//! Operators against closed forms (issue 6, "Done means").

use std::f64::consts::PI;

use faer::Mat;
use fires_recon::generate::*;
use fires_recon::operators::*;
use fires_recon::solve::{sparse_mul_dense, sparse_triplets};
use fires_recon::{SurfaceMesh, Vec3};

fn apply(m: &fires_recon::solve::SparseMatrix, f: &[f64]) -> Vec<f64> {
    let x = Mat::from_fn(f.len(), 1, |i, _| f[i]);
    let y = sparse_mul_dense(m.as_ref(), x.as_ref()).unwrap();
    (0..m.nrows()).map(|i| y[(i, 0)]).collect()
}

fn perturbed_grid() -> SurfaceMesh {
    let mut m = plane_grid(12, 9, 2.0, 1.5, false);
    for (i, p) in m.positions_mut().iter_mut().enumerate() {
        let s = ((i * 7919) % 13) as f64 / 13.0 - 0.5;
        if p.x > 0.0 && p.x < 2.0 && p.y > 0.0 && p.y < 1.5 {
            p.x += 0.03 * s;
            p.y -= 0.02 * s;
        }
    }
    m
}

#[test]
fn cotan_laplacian_annihilates_linear_functions_on_a_plane_grid() {
    let m = perturbed_grid();
    let f: Vec<f64> = m
        .positions()
        .iter()
        .map(|p| 3.0 * p.x - 2.0 * p.y + 0.5)
        .collect();
    for kind in [
        LaplacianKind::Cotan(MassKind::MixedVoronoi),
        LaplacianKind::Cotan(MassKind::Barycentric),
        LaplacianKind::CotanNormalized,
    ] {
        let l = laplacian(&m, kind).unwrap();
        let lf = apply(&l, &f);
        for v in m.vertices().filter(|&v| !m.is_boundary_vertex(v)) {
            assert!(lf[v.idx()].abs() < 1e-9, "{kind:?} {}", lf[v.idx()]);
        }
    }
}

#[test]
fn every_laplacian_has_zero_row_sums_and_cotan_is_symmetric() {
    let m = icosphere(2, 1.3);
    for kind in [
        LaplacianKind::Cotan(MassKind::MixedVoronoi),
        LaplacianKind::CotanNormalized,
        LaplacianKind::Umbrella,
        LaplacianKind::ScaledUmbrella,
        LaplacianKind::MeanValue,
    ] {
        let l = laplacian(&m, kind).unwrap();
        let ones = vec![1.0; m.n_vertices()];
        assert!(apply(&l, &ones).iter().all(|x| x.abs() < 1e-9), "{kind:?}");
    }
    let c = cotan_matrix(&m).unwrap();
    let d = c.to_dense();
    for (i, j, v) in sparse_triplets(c.as_ref()) {
        assert!((v - d[(j, i)]).abs() < 1e-14);
    }
}

#[test]
fn icosphere_mean_curvature_is_one_over_r_within_one_percent() {
    let r = 2.0;
    let m = icosphere(4, r);
    let h = mean_curvature(&m).unwrap();
    for x in &h {
        assert!((x * r - 1.0).abs() < 0.01, "H = {x}");
    }
    let hn = mean_curvature_normals(&m).unwrap();
    for v in m.vertices() {
        let n = sphere_normal(m.position(v));
        assert!((hn[v.idx()].normalize_or_zero().dot(n) - 1.0).abs() < 1e-4);
    }
}

#[test]
fn gauss_bonnet_holds_to_rounding_on_closed_meshes() {
    for m in [
        icosphere(3, 1.0),
        torus(3.0, 1.0, 20, 12, false),
        uv_sphere(16, 9, 1.0, false),
        cube(2.0, false),
    ] {
        let total: f64 = angle_defects(&m).unwrap().iter().sum();
        let expected = 2.0 * PI * m.euler_characteristic() as f64;
        assert!((total - expected).abs() < 1e-9, "{total} vs {expected}");
    }
    // Open meshes: boundary vertices use π − Σθ, so the sum is still 2πχ (disk: 2π, annulus: 0).
    let g = perturbed_grid();
    let total: f64 = angle_defects(&g).unwrap().iter().sum();
    assert!((total - 2.0 * PI).abs() < 1e-9, "{total}");
    let cyl = cylinder(1.0, 2.0, 17, 5, false);
    let total: f64 = angle_defects(&cyl).unwrap().iter().sum();
    assert!(total.abs() < 1e-9, "{total}");
}

#[test]
fn areas_and_volumes_match_closed_forms() {
    let c = cube(1.5, true);
    assert!((total_area(&c) - cube_area(1.5)).abs() < 1e-12);
    assert!((volume(&c) - cube_volume(1.5)).abs() < 1e-12);
    let s = icosphere(5, 1.0);
    assert!((total_area(&s) / sphere_area(1.0) - 1.0).abs() < 2e-3);
    assert!((volume(&s) / sphere_volume(1.0) - 1.0).abs() < 3e-3);
    let t = torus(2.0, 0.5, 200, 100, false);
    assert!((total_area(&t) / torus_area(2.0, 0.5) - 1.0).abs() < 1e-3);
    assert!((volume(&t) / torus_volume(2.0, 0.5) - 1.0).abs() < 1e-3);
    let cy = cylinder(1.0, 3.0, 256, 4, true);
    assert!((total_area(&cy) / cylinder_area(1.0, 3.0) - 1.0).abs() < 1e-3);
    for kind in [MassKind::Barycentric, MassKind::MixedVoronoi] {
        let a: f64 = vertex_areas(&s, kind).unwrap().iter().sum();
        assert!((a - total_area(&s)).abs() < 1e-10);
    }
    assert!((mean_edge_length(&c) - 1.5).abs() < 1e-12);
    assert_eq!(face_areas(&c).len(), 6);
}

#[test]
fn normals_match_the_analytic_ones() {
    let m = icosphere(3, 1.0);
    for w in [NormalWeighting::Area, NormalWeighting::Angle] {
        for (v, n) in m.vertices().zip(vertex_normals(&m, w)) {
            assert!((n.dot(sphere_normal(m.position(v))) - 1.0).abs() < 1e-4);
        }
    }
    let t = torus(2.0, 0.5, 60, 30, false);
    for (v, n) in t.vertices().zip(vertex_normals(&t, NormalWeighting::Angle)) {
        assert!(n.dot(torus_normal(t.position(v), 2.0)) > 0.999);
    }
}

#[test]
fn torus_curvatures_match_closed_forms() {
    let (rr, r) = (3.0, 1.0);
    let t = torus(rr, r, 120, 60, false);
    let k = gaussian_curvature(&t).unwrap();
    let h = mean_curvature(&t).unwrap();
    let pc = principal_curvatures(&t).unwrap();
    for v in t.vertices() {
        let p = t.position(v);
        assert!((k[v.idx()] - torus_gaussian_curvature(p, rr, r)).abs() < 0.02);
        assert!((h[v.idx()] - torus_mean_curvature(p, rr, r)).abs() < 0.02);
        assert!((pc[v.idx()].0 - 1.0 / r).abs() < 0.03);
    }
}

#[test]
fn divergence_of_gradient_is_the_cotan_matrix() {
    let m = icosphere(2, 1.0);
    let g = gradient_matrix(&m).unwrap();
    let d = divergence_matrix(&m).unwrap();
    let c = cotan_matrix(&m).unwrap().to_dense();
    let f: Vec<f64> = m.positions().iter().map(|p| p.x * p.y + p.z).collect();
    let gf = apply(&g, &f);
    let dgf = apply(&d, &gf);
    for i in 0..f.len() {
        let cf: f64 = (0..f.len()).map(|j| c[(i, j)] * f[j]).sum();
        assert!((dgf[i] - cf).abs() < 1e-10);
    }
    // Gradient of a linear function on a planar grid is exact.
    let grid = perturbed_grid();
    let lin: Vec<f64> = grid
        .positions()
        .iter()
        .map(|p| 2.0 * p.x + 5.0 * p.y)
        .collect();
    let gl = apply(&gradient_matrix(&grid).unwrap(), &lin);
    for f in 0..grid.n_faces() {
        assert!(
            (gl[3 * f] - 2.0).abs() < 1e-9
                && (gl[3 * f + 1] - 5.0).abs() < 1e-9
                && gl[3 * f + 2].abs() < 1e-9
        );
    }
}

#[test]
fn heat_geodesic_on_sphere_is_close_to_great_circle_distance() {
    let m = icosphere(4, 1.0);
    let src = m.vertices().next().unwrap();
    let d = geodesic_heat(&m, &[src]).unwrap();
    let dj = geodesic_dijkstra(&m, &[src]).unwrap();
    let s = m.position(src);
    let mut max_err: f64 = 0.0;
    for v in m.vertices() {
        let exact = s.dot(m.position(v)).clamp(-1.0, 1.0).acos();
        max_err = max_err.max((d[v.idx()] - exact).abs());
        assert!(
            dj[v.idx()] >= exact * 0.995 - 1e-12,
            "edge paths are not much shorter than arcs"
        );
    }
    assert!(max_err < 0.05, "max error {max_err}");
    let plane = plane_grid(20, 20, 1.0, 1.0, false);
    let d = geodesic_dijkstra(&plane, &[fires_recon::mesh::Vertex::new(0)]).unwrap();
    assert!((d[20] - 1.0).abs() < 1e-12);
    let _ = Vec3::ZERO;
}

#[test]
fn obtuse_and_degenerate_triangles_give_finite_operators() {
    let pts = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.5, 1e-12, 0.0),
        Vec3::new(0.5, 0.0, 0.0),
        Vec3::new(0.5, -0.2, 0.0),
    ];
    let m = SurfaceMesh::from_faces(&pts, &[[0, 1, 2], [1, 0, 4], [0, 4, 3]])
        .unwrap_or_else(|_| SurfaceMesh::from_faces(&pts, &[[0, 1, 2], [1, 0, 4]]).unwrap());
    for kind in [
        LaplacianKind::Cotan(MassKind::MixedVoronoi),
        LaplacianKind::MeanValue,
        LaplacianKind::CotanNormalized,
    ] {
        let l = laplacian(&m, kind).unwrap();
        assert!(sparse_triplets(l.as_ref()).iter().all(|t| t.2.is_finite()));
    }
    let c = clamp_negative_offdiagonal(&cotan_matrix(&m).unwrap()).unwrap();
    assert!(sparse_triplets(c.as_ref())
        .iter()
        .all(|t| t.0 == t.1 || t.2 >= 0.0));
    assert!(mean_curvature(&m).unwrap().iter().all(|x| x.is_finite()));
    assert!(gradient_matrix(&m).is_ok());
}

#[test]
fn hat_gradients_match_the_metric_tensor_form() {
    // ω^{j1} = g¹¹e1 + g¹²e2, ω^{j2} = g²¹e1 + g²²e2 (FIRES thesis, Part I §1.2, eq. 1.7).
    let pts = [
        Vec3::new(0.1, -0.2, 0.3),
        Vec3::new(1.3, 0.1, -0.2),
        Vec3::new(0.4, 0.9, 0.5),
    ];
    let m = SurfaceMesh::from_faces(&pts, &[[0, 1, 2]]).unwrap();
    let g = gradient_matrix(&m).unwrap().to_dense();
    let (e1, e2) = (pts[1] - pts[0], pts[2] - pts[0]);
    let (a, b, d) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let det = a * d - b * b;
    let (g11, g12, g22) = (d / det, -b / det, a / det);
    let w1 = e1 * g11 + e2 * g12;
    let w2 = e1 * g12 + e2 * g22;
    let w0 = -(w1 + w2);
    for (k, w) in [w0, w1, w2].iter().enumerate() {
        for c in 0..3 {
            assert!((g[(c, k)] - w[c]).abs() < 1e-12);
        }
    }
}

#[test]
fn vertex_gradient_is_exact_for_linear_functions_and_kills_constants() {
    let m = perturbed_grid();
    let w = vertex_gradient_matrix(&m).unwrap();
    let lin: Vec<f64> = m
        .positions()
        .iter()
        .map(|p| -1.5 * p.x + 0.25 * p.y + 4.0)
        .collect();
    let gl = apply(&w, &lin);
    let gc = apply(&w, &vec![1.0; m.n_vertices()]);
    for v in 0..m.n_vertices() {
        assert!((gl[3 * v] + 1.5).abs() < 1e-9 && (gl[3 * v + 1] - 0.25).abs() < 1e-9);
        assert!(gc[3 * v..3 * v + 3].iter().all(|x| x.abs() < 1e-9));
    }
}

#[test]
fn heat_geodesic_on_a_plane_with_boundary_is_close_to_euclidean() {
    let m = plane_grid(40, 40, 1.0, 1.0, false);
    let centre = fires_recon::mesh::Vertex::new(20 * 41 + 20);
    let geo = HeatGeodesic::new(&m).unwrap();
    let d = geo.distance(&[centre]).unwrap();
    let c = m.position(centre);
    for v in m.vertices() {
        let exact = m.position(v).distance(c);
        assert!(
            (d[v.idx()] - exact).abs() < 0.03,
            "{} vs {exact}",
            d[v.idx()]
        );
    }
    // The precomputed factorisations serve other sources too.
    let corner = geo.distance(&[fires_recon::mesh::Vertex::new(0)]).unwrap();
    assert!((corner[40] - 1.0).abs() < 0.05);
    assert!(geo
        .distance(&[fires_recon::mesh::Vertex::new(99_999)])
        .is_err());
}
