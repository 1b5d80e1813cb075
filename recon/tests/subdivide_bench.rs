//! Loop subdivision and the benchmark entry points on generated meshes.

use fires_recon::bench::{bench_laplacian, bench_solve_matrix_market, laplacian_system};
use fires_recon::generate::{icosphere, plane_grid};
use fires_recon::io::{write_matrix_market_lower, write_mesh_file, PolygonSoup};
use fires_recon::subdivide::{loop_subdivision, loop_subdivision_n};

#[test]
fn loop_subdivision_counts_validity_and_shape() {
    let m = icosphere(1, 1.0);
    let s = loop_subdivision(&m).unwrap();
    s.validate().unwrap();
    assert_eq!(s.n_vertices(), m.n_vertices() + m.n_edges());
    assert_eq!(s.n_faces(), 4 * m.n_faces());
    assert_eq!(s.euler_characteristic(), 2);
    // Loop shrinks a convex polyhedron towards its limit surface, staying inside r = 1.
    assert!(s
        .positions()
        .iter()
        .all(|p| p.norm() < 1.0 && p.norm() > 0.85));
    let g = loop_subdivision_n(&plane_grid(3, 3, 1.0, 1.0, false), 2).unwrap();
    g.validate().unwrap();
    assert_eq!(g.euler_characteristic(), 1);
    assert!(g.positions().iter().all(|p| p.z == 0.0));
    assert!(loop_subdivision(&fires_recon::generate::cube(1.0, true)).is_err());
}

#[test]
fn bench_entry_points_run_on_small_inputs() {
    let dir = std::env::temp_dir().join(format!("fires-recon-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mesh = icosphere(2, 1.0);
    let mtx = dir.join("a.mtx");
    write_matrix_market_lower(
        std::fs::File::create(&mtx).unwrap(),
        &laplacian_system(&mesh).unwrap(),
    )
    .unwrap();
    let t = bench_solve_matrix_market(&mtx, 3).unwrap();
    assert_eq!(t.n, 162 - 9);
    assert!(t.analyze_ms >= 0.0 && t.factor_ms >= 0.0 && t.solve_ms >= 0.0);
    let line = t.to_json_line();
    for key in [
        "\"n\":",
        "\"nnz\":",
        "\"analyze_ms\":",
        "\"factor_ms\":",
        "\"solve_ms\":",
    ] {
        assert!(line.contains(key), "{line}");
    }
    let off = dir.join("m.off");
    write_mesh_file(&off, &PolygonSoup::from_mesh(&icosphere(1, 1.0))).unwrap();
    let t = bench_laplacian(&off, 1, 1).unwrap();
    assert_eq!(t.n, 162 - 9);
    std::fs::remove_dir_all(&dir).unwrap();
}
