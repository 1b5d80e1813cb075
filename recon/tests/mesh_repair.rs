//! Reading imperfect meshes: polygon faces, shuffled orientation, non-manifold vertices
//! and edges, non-orientable strips, degenerate and duplicate faces; `mesh_info`; the
//! Laplacian benchmark on polygon meshes and its diagnosis of degenerate input.

use std::path::PathBuf;

use fires_recon::bench::{
    bench_laplacian, bench_solve_matrix, diagnose_laplacian_system, laplacian_fixed_vertices,
    laplacian_system, BenchError,
};
use fires_recon::generate::{cube, cylinder, icosphere, plane_grid, torus, uv_sphere};
use fires_recon::io::{
    read_mesh_file_repaired, write_mesh_file, write_off, write_ply, PlyEncoding, PolygonSoup,
};
use fires_recon::mesh::{mesh_info, RepairOptions, Repairs, SurfaceMesh, Vertex};
use fires_recon::operators::{
    cotan_matrix, face_triangles, gradient_matrix, triangulate, OperatorError,
};
use fires_recon::solve::sparse_triplets;
use fires_recon::Vec3;

fn repaired(points: &[Vec3], faces: &[Vec<usize>]) -> (SurfaceMesh, Repairs) {
    let (m, r) = SurfaceMesh::from_polygons_repaired(
        points,
        faces.iter().map(|f| f.as_slice()),
        &RepairOptions::default(),
    )
    .unwrap();
    m.validate().unwrap();
    (m, r)
}

/// A face's index cycle rotated to start at its smallest index.
fn rotated_to_min(mut f: Vec<usize>) -> Vec<usize> {
    let s = (0..f.len()).min_by_key(|&k| f[k]).unwrap_or(0);
    f.rotate_left(s);
    f
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fires-mesh-repair-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Hexagonal prism with a pyramid cap: 6 triangles, 6 quads, 1 hexagon (χ = 2).
fn mixed_polygon_soup() -> PolygonSoup {
    let mut soup = PolygonSoup::new();
    for z in [0.0, 1.0] {
        for k in 0..6 {
            let t = k as f64 * std::f64::consts::PI / 3.0;
            soup.points.push(Vec3::new(t.cos(), t.sin(), z));
        }
    }
    soup.points.push(Vec3::new(0.0, 0.0, 1.7));
    soup.push_face(&[5, 4, 3, 2, 1, 0]);
    for k in 0..6 {
        let k1 = (k + 1) % 6;
        soup.push_face(&[k, k1, 6 + k1, 6 + k]);
        soup.push_face(&[6 + k, 6 + k1, 12]);
    }
    soup
}

fn rows_sum_to_zero(c: &fires_recon::solve::SparseMatrix) -> bool {
    let mut sum = vec![0.0; c.nrows()];
    let mut scale = vec![0.0f64; c.nrows()];
    for (i, _, v) in sparse_triplets(c.as_ref()) {
        sum[i] += v;
        scale[i] = scale[i].max(v.abs());
    }
    sum.iter()
        .zip(&scale)
        .all(|(s, m)| s.abs() <= 1e-12 * m.max(1.0))
}

#[test]
fn quad_mesh_reads_with_counts_and_its_cotan_is_that_of_its_triangulation() {
    let m = torus(2.0, 0.5, 16, 8, true);
    let path = tmp("torus_quads.off");
    write_mesh_file(&path, &PolygonSoup::from_mesh(&m)).unwrap();
    let (q, repairs) = read_mesh_file_repaired(&path).unwrap();
    assert!(repairs.is_clean(), "{repairs:?}");
    let info = mesh_info(&q, &repairs);
    assert_eq!((info.vertices, info.edges, info.faces), (128, 256, 128));
    assert_eq!((info.quads, info.triangles, info.polygons), (128, 0, 0));
    assert_eq!((info.genus, info.components, info.closed), (1, 1, true));
    let c = cotan_matrix(&q).unwrap();
    let t = triangulate(&q).unwrap();
    t.validate().unwrap();
    assert_eq!(t.n_faces(), 2 * q.n_faces());
    // Same triangles, summed in another order: equal to rounding.
    let ct = sparse_triplets(cotan_matrix(&t).unwrap().as_ref());
    let cq = sparse_triplets(c.as_ref());
    assert_eq!(cq.len(), ct.len());
    for ((i, j, a), (k, l, b)) in cq.iter().zip(&ct) {
        assert!(
            (i, j) == (k, l) && (a - b).abs() < 1e-13,
            "({i},{j}): {a} vs {b}"
        );
    }
    assert!(rows_sum_to_zero(&c));
    let timings = bench_solve_matrix(&laplacian_system(&q).unwrap(), 1, faer::Par::Seq).unwrap();
    assert_eq!(timings.n, 128 - 7);
    // The benchmark runs on the quad file, with and without subdivision.
    assert_eq!(bench_laplacian(&path, 0, 1).unwrap().n, 121);
    let sub = bench_laplacian(&path, 1, 1).unwrap();
    // Triangulated torus: V + E = 128 + 384 vertices after one Loop step.
    assert_eq!(sub.n, 512 - 512_usize.div_ceil(20));
}

#[test]
fn planar_quad_grid_laplacian_has_linear_precision() {
    // Jittered planar quads: any triangulation of a planar mesh keeps C·x = 0 inside.
    let mut m = plane_grid(6, 5, 3.0, 2.0, true);
    for v in m.vertices().collect::<Vec<_>>() {
        let p = m.position(v);
        let j = ((v.idx() * 7919) % 13) as f64 / 13.0 - 0.5;
        if !m.is_boundary_vertex(v) {
            m.set_position(v, Vec3::new(p.x + 0.08 * j, p.y - 0.06 * j, 0.0));
        }
    }
    let c = cotan_matrix(&m).unwrap();
    let mut cx = vec![0.0; m.vertices_size()];
    for (i, j, w) in sparse_triplets(c.as_ref()) {
        cx[i] += w * m.positions()[j].x;
    }
    for v in m.vertices() {
        if !m.is_boundary_vertex(v) {
            assert!(
                cx[v.idx()].abs() < 1e-12,
                "row {} gives {}",
                v.idx(),
                cx[v.idx()]
            );
        }
    }
}

#[test]
fn mixed_polygon_mesh_reads_counts_and_runs_the_laplacian() {
    let soup = mixed_polygon_soup();
    let path = tmp("mixed.ply");
    write_ply(
        std::fs::File::create(&path).unwrap(),
        &soup,
        PlyEncoding::Ascii,
    )
    .unwrap();
    let (m, repairs) = read_mesh_file_repaired(&path).unwrap();
    assert!(repairs.is_clean(), "{repairs:?}");
    let info = mesh_info(&m, &repairs);
    assert_eq!((info.vertices, info.edges, info.faces), (13, 24, 13));
    assert_eq!((info.triangles, info.quads, info.polygons), (6, 6, 1));
    assert_eq!(info.max_face_degree, 6);
    assert_eq!((info.euler_characteristic, info.genus), (2, 0));
    // Hexagon → 4 triangles, quads → 2 each, triangles as they are.
    assert_eq!(face_triangles(&m).unwrap().len(), 4 + 12 + 6);
    assert!(rows_sum_to_zero(&cotan_matrix(&m).unwrap()));
    assert_eq!(bench_laplacian(&path, 0, 1).unwrap().n, 12);
    assert_eq!(bench_laplacian(&path, 1, 1).unwrap().n, 13 + 33 - 3);
    // Operators that need triangles say which one refused.
    match gradient_matrix(&m) {
        Err(OperatorError::NeedsTriangles { operator, .. }) => {
            assert_eq!(operator, "gradient matrix")
        }
        other => panic!("{other:?}"),
    }
}

fn signed_volume(m: &SurfaceMesh) -> f64 {
    face_triangles(m)
        .unwrap()
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions()[i]);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

#[test]
fn shuffled_orientation_comes_back_consistent() {
    for original in [
        icosphere(2, 1.0),
        uv_sphere(10, 6, 1.0, true),
        torus(2.0, 0.6, 12, 8, false),
    ] {
        let soup = PolygonSoup::from_mesh(&original);
        let mut faces: Vec<Vec<usize>> = soup.faces().map(<[usize]>::to_vec).collect();
        let mut flipped = 0;
        for (k, f) in faces.iter_mut().enumerate() {
            if (k * 2654435761) % 7 < 3 {
                f.reverse();
                flipped += 1;
            }
        }
        let (m, r) = repaired(&soup.points, &faces);
        assert_eq!(r.flipped_faces, flipped);
        assert_eq!(r.non_orientable_components, 0);
        assert!(
            m.is_closed(),
            "an edge kept two faces traversing it the same way"
        );
        assert_eq!(
            (m.n_vertices(), m.n_edges()),
            (original.n_vertices(), original.n_edges())
        );
        // Every face has its original cyclic order back.
        for (f, g) in m.faces().zip(original.faces()) {
            let a: Vec<Vertex> = m.face_vertices(f).collect();
            let b: Vec<Vertex> = original.face_vertices(g).collect();
            let s = b.iter().position(|&v| v == a[0]).unwrap();
            assert!((0..a.len()).all(|k| a[k] == b[(s + k) % b.len()]));
        }
        assert!((signed_volume(&m) - signed_volume(&original)).abs() < 1e-12);
        // Every edge's two halfedges belong to faces traversing it oppositely.
        for e in m.edges() {
            let (h0, h1) = (e.halfedge(0), e.halfedge(1));
            assert!(m.face(h0).is_some() && m.face(h1).is_some());
            assert_eq!(m.from_vertex(h0), m.to_vertex(h1));
        }
    }
}

#[test]
fn shuffled_binary_stl_reads_back_closed_and_outward() {
    // STL has no shared vertices: corners are welded, then orientation is repaired.
    let sphere = icosphere(2, 1.0);
    let mut soup = PolygonSoup::from_mesh(&sphere);
    let faces: Vec<Vec<usize>> = soup
        .faces()
        .enumerate()
        .map(|(k, f)| {
            if k % 3 == 0 {
                f.iter().rev().copied().collect()
            } else {
                f.to_vec()
            }
        })
        .collect();
    let points = soup.points.clone();
    soup = PolygonSoup::new();
    soup.points = points;
    for f in &faces {
        soup.push_face(f);
    }
    let path = tmp("shuffled.stl");
    write_mesh_file(&path, &soup).unwrap();
    let (m, r) = read_mesh_file_repaired(&path).unwrap();
    assert_eq!(r.flipped_faces, faces.len().div_ceil(3));
    assert!(m.is_closed());
    assert_eq!(
        (m.n_vertices(), m.n_faces()),
        (sphere.n_vertices(), sphere.n_faces())
    );
    // f32 coordinates: the volume matches the f64 original to single precision.
    assert!((signed_volume(&m) - signed_volume(&sphere)).abs() < 1e-5);
}

#[test]
fn bow_tie_vertex_is_split_with_file_indices_kept() {
    let pts: Vec<Vec3> = [
        (0.0, 0.0, 0.0),
        (1.0, 0.0, 0.0),
        (1.0, 1.0, 0.0),
        (0.0, 1.0, 0.0),
        (-1.0, 1.0, 0.0),
        (-1.0, -1.0, 0.2),
        (0.0, -1.0, 0.2),
        (1.0, -1.0, 0.4),
    ]
    .map(|(x, y, z)| Vec3::new(x, y, z))
    .to_vec();
    let faces = vec![
        vec![0, 1, 2],
        vec![0, 2, 3],
        vec![0, 3, 4],
        vec![0, 5, 6],
        vec![0, 6, 7],
    ];
    let soup = {
        let mut s = PolygonSoup::new();
        s.points = pts.clone();
        for f in &faces {
            s.push_face(f);
        }
        s
    };
    let path = tmp("bowtie.off");
    write_off(std::fs::File::create(&path).unwrap(), &soup).unwrap();
    assert!(
        soup.to_mesh().is_err(),
        "the strict builder must refuse the bow-tie"
    );
    let (m, r) = read_mesh_file_repaired(&path).unwrap();
    m.validate().unwrap();
    assert_eq!(
        (r.non_manifold_vertices_split, r.vertex_copies_added),
        (1, 1)
    );
    assert_eq!(r.vertex_source, vec![0]);
    assert_eq!(m.n_vertices(), 9);
    for (i, p) in pts.iter().enumerate() {
        assert_eq!(m.position(Vertex::new(i)), *p);
    }
    assert_eq!(m.position(Vertex::new(8)), pts[0]);
    // The first fan keeps vertex 0, the second uses the copy; other indices unchanged.
    let lists: Vec<Vec<usize>> = m
        .face_index_lists()
        .into_iter()
        .map(rotated_to_min)
        .collect();
    let expect: Vec<Vec<usize>> = [[0, 1, 2], [0, 2, 3], [0, 3, 4], [8, 5, 6], [8, 6, 7]]
        .map(|f| rotated_to_min(f.to_vec()))
        .to_vec();
    assert_eq!(lists, expect);
    let info = mesh_info(&m, &r);
    assert!(!info.manifold);
    assert_eq!(
        (info.components, info.boundary_loops, info.genus),
        (2, 2, 0)
    );
}

#[test]
fn third_face_on_an_edge_is_detached_on_its_own_vertices() {
    let pts: Vec<Vec3> = [
        (0.0, 0.0, 0.0),
        (1.0, 0.0, 0.0),
        (0.5, 1.0, 0.0),
        (0.5, -1.0, 0.0),
        (0.5, 0.0, 1.0),
    ]
    .map(|(x, y, z)| Vec3::new(x, y, z))
    .to_vec();
    let faces = vec![vec![0, 1, 2], vec![1, 0, 3], vec![0, 1, 4]];
    let (m, r) = repaired(&pts, &faces);
    assert_eq!((r.detached_faces, r.vertex_copies_added), (1, 3));
    assert_eq!(r.vertex_source, vec![0, 1, 4]);
    assert_eq!(
        rotated_to_min(m.face_index_lists()[2].clone()),
        vec![5, 6, 7]
    );
    assert_eq!((m.n_faces(), m.n_vertices()), (3, 8));
    // Vertex 4 is now only used through its copy.
    assert!(m.is_isolated(Vertex::new(4)));
    assert_eq!(r.unreferenced_vertices, 0);
}

/// Möbius strip of `n` quads: rails a_i, b_i; the last quad closes with a half twist.
fn moebius(n: usize) -> (Vec<Vec3>, Vec<Vec<usize>>) {
    let mut pts = Vec::new();
    for i in 0..n {
        let t = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
        for w in [-0.3, 0.3] {
            let r = 1.0 + w * (t / 2.0).cos();
            pts.push(Vec3::new(r * t.cos(), r * t.sin(), w * (t / 2.0).sin()));
        }
    }
    let (a, b) = (|i: usize| 2 * i, |i: usize| 2 * i + 1);
    let mut faces: Vec<Vec<usize>> = (0..n - 1)
        .map(|i| vec![a(i), a(i + 1), b(i + 1), b(i)])
        .collect();
    faces.push(vec![a(n - 1), b(0), a(0), b(n - 1)]);
    (pts, faces)
}

#[test]
fn moebius_strip_is_reported_non_orientable_and_cut_open() {
    let (pts, faces) = moebius(12);
    let (m, r) = repaired(&pts, &faces);
    assert_eq!((r.non_orientable_components, r.cut_edges), (1, 1));
    assert_eq!(r.non_manifold_vertices_split, 2);
    let info = mesh_info(&m, &r);
    assert!(!info.orientable);
    assert_eq!(m.n_faces(), 12);
    // Cut along one rung: a disk (χ = 1, one boundary loop).
    assert_eq!(
        (info.euler_characteristic, info.boundary_loops, info.genus),
        (1, 1, 0)
    );
    // An orientable annulus with the same layout is not reported.
    let mut annulus = faces.clone();
    annulus.pop();
    let (_, r) = repaired(&pts, &annulus);
    assert_eq!(r.non_orientable_components, 0);
}

#[test]
fn degenerate_duplicate_and_zero_area_faces_are_counted() {
    let g = plane_grid(3, 3, 1.0, 1.0, false);
    let soup = PolygonSoup::from_mesh(&g);
    let mut faces: Vec<Vec<usize>> = soup.faces().map(<[usize]>::to_vec).collect();
    let n_good = faces.len();
    let f0 = faces[0].clone();
    let f1 = faces[1].clone();
    faces.push(vec![f0[0], f0[0], f0[1]]); // two distinct vertices: removed
    faces.push(vec![f0[0], f0[1], f0[0], f0[2]]); // repeated vertex: removed
    faces.push(f1.iter().rev().copied().collect()); // duplicate, reversed: removed
    faces.push(f0.clone()); // duplicate: removed
    faces.push(vec![f1[0], f1[1], f1[1], f1[2], f1[0]]); // collapses to f1: duplicate
    let (m, r) = repaired(&soup.points, &faces);
    assert_eq!(r.degenerate_faces_removed, 2);
    assert_eq!(r.duplicate_faces_removed, 3);
    assert_eq!(r.repeated_corners_collapsed, 2);
    assert_eq!(m.n_faces(), n_good);
    assert_eq!(r.face_source, (0..n_good).collect::<Vec<_>>());
    // Unreferenced vertex kept as isolated, counted.
    let mut pts = soup.points.clone();
    pts.push(Vec3::new(9.0, 9.0, 9.0));
    let (m, r) = repaired(&pts, &faces[..n_good]);
    assert_eq!(r.unreferenced_vertices, 1);
    assert_eq!(mesh_info(&m, &r).isolated_vertices, 1);
}

#[test]
fn zero_area_triangle_is_named_by_the_laplacian_benchmark() {
    // Square with a T-junction at 4 = midpoint of 0–1, filled by the flat triangle 0 1 4.
    let pts: Vec<Vec3> = [(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0), (1.0, 0.0)]
        .map(|(x, y)| Vec3::new(x, y, 0.0))
        .to_vec();
    let faces = [vec![0, 4, 3], vec![4, 1, 2], vec![4, 2, 3], vec![0, 1, 4]];
    let (m, r) = repaired(&pts, &faces);
    assert_eq!(r.zero_area_faces, 1);
    let mut soup = PolygonSoup::from_mesh(&m);
    soup.points = pts.clone();
    let path = tmp("tjunction.off");
    write_mesh_file(&path, &soup).unwrap();
    match bench_laplacian(&path, 0, 1) {
        Err(BenchError::DegenerateTriangles { count, first_face }) => {
            assert_eq!((count, first_face), (1, 3));
        }
        other => panic!("{other:?}"),
    }
    // Without the flat triangle the same square runs.
    let (m, _) = repaired(&pts, &faces[..3]);
    assert!(bench_solve_matrix(&laplacian_system(&m).unwrap(), 1, faer::Par::Seq).is_ok());
}

#[test]
fn every_component_gets_a_fixed_vertex_and_an_unfixed_one_is_named() {
    // Three icosahedra (0..12, 12..24, 24..36) and an isolated vertex 36: every 20th
    // vertex fixes 0 and 20, the third icosahedron gets its first vertex 24, the isolated
    // vertex is fixed too.
    let a = PolygonSoup::from_mesh(&icosphere(0, 1.0));
    let mut pts = a.points.clone();
    let mut faces: Vec<Vec<usize>> = a.faces().map(<[usize]>::to_vec).collect();
    for shift in [12, 24] {
        for f in a.faces() {
            faces.push(f.iter().map(|i| i + shift).collect());
        }
        pts.extend(
            a.points
                .iter()
                .map(|&p| p + Vec3::new(shift as f64, 0.0, 0.0)),
        );
    }
    pts.push(Vec3::new(0.0, 5.0, 0.0));
    let (m, _) = repaired(&pts, &faces);
    let fixed = laplacian_fixed_vertices(&m);
    let fixed_list: Vec<usize> = (0..fixed.len()).filter(|&i| fixed[i]).collect();
    assert_eq!(fixed_list, vec![0, 20, 24, 36]);
    assert!(bench_solve_matrix(&laplacian_system(&m).unwrap(), 1, faer::Par::Seq).is_ok());
    let mut only_first = vec![false; m.vertices_size()];
    only_first[0] = true;
    only_first[24] = true;
    only_first[36] = true;
    match diagnose_laplacian_system(&m, &only_first) {
        Some(BenchError::UnfixedComponent {
            vertices,
            first_vertex,
        }) => {
            assert_eq!((vertices, first_vertex), (12, 12))
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn genus_and_components_of_generated_meshes() {
    let cases = [
        (torus(2.0, 0.5, 12, 8, false), 1, 0),
        (torus(2.0, 0.5, 12, 8, true), 1, 0),
        (icosphere(1, 1.0), 0, 0),
        (cube(1.0, true), 0, 0),
        (plane_grid(4, 3, 1.0, 1.0, true), 0, 1),
        (cylinder(1.0, 2.0, 10, 4, false), 0, 2),
    ];
    for (m, genus, loops) in cases {
        let info = mesh_info(&m, &Repairs::default());
        assert_eq!(
            (info.genus, info.boundary_loops, info.components),
            (genus, loops, 1)
        );
        assert_eq!(info.euler_characteristic, m.euler_characteristic());
    }
    // Sphere + torus in one file: two components, total genus 1.
    let s = PolygonSoup::from_mesh(&icosphere(1, 1.0));
    let t = PolygonSoup::from_mesh(&torus(2.0, 0.5, 12, 8, false));
    let mut pts = s.points.clone();
    pts.extend(&t.points);
    let mut faces: Vec<Vec<usize>> = s.faces().map(<[usize]>::to_vec).collect();
    faces.extend(
        t.faces()
            .map(|f| f.iter().map(|i| i + s.points.len()).collect::<Vec<_>>()),
    );
    let (m, r) = repaired(&pts, &faces);
    let info = mesh_info(&m, &r);
    assert_eq!(
        (info.components, info.genus, info.euler_characteristic),
        (2, 1, 2)
    );
    let json = serde_json::to_string(&info).unwrap();
    assert!(json.contains("\"genus\":1") && json.contains("\"repairs\":{"));
}

#[test]
fn out_of_range_index_is_the_one_hard_error() {
    let pts = vec![Vec3::ZERO; 3];
    let faces = [vec![0usize, 1, 3]];
    assert!(SurfaceMesh::from_polygons_repaired(
        &pts,
        faces.iter().map(|f| f.as_slice()),
        &RepairOptions::default()
    )
    .is_err());
}
