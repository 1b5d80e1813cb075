//! Halfedge mesh: construction, rejection of non-manifold input, Euler operations,
//! garbage collection, properties.

use fires_recon::generate::{cube, cylinder, icosphere, plane_grid, torus, uv_sphere};
use fires_recon::mesh::{MeshError, SurfaceMesh, Vertex};
use fires_recon::Vec3;

fn pts(n: usize) -> Vec<Vec3> {
    (0..n)
        .map(|i| Vec3::new(i as f64, (i * i) as f64 * 0.1, (i % 3) as f64))
        .collect()
}

#[test]
fn generated_meshes_are_valid_with_expected_euler_characteristic() {
    let cases: Vec<(SurfaceMesh, i64)> = vec![
        (icosphere(2, 1.0), 2),
        (uv_sphere(12, 8, 1.0, true), 2),
        (uv_sphere(12, 8, 1.0, false), 2),
        (torus(2.0, 0.5, 12, 8, true), 0),
        (torus(2.0, 0.5, 12, 8, false), 0),
        (cylinder(1.0, 2.0, 10, 4, false), 0),
        (plane_grid(4, 3, 1.0, 1.0, true), 1),
        (cube(1.0, true), 2),
        (cube(1.0, false), 2),
    ];
    for (m, chi) in cases {
        m.validate().unwrap();
        assert_eq!(m.euler_characteristic(), chi);
    }
    let ico = icosphere(2, 1.0);
    assert_eq!(ico.n_vertices(), 162);
    assert_eq!(ico.n_faces(), 320);
    assert!(ico.is_closed() && ico.is_triangle_mesh());
    assert_eq!(cylinder(1.0, 2.0, 10, 4, false).boundary_loops().len(), 2);
    assert_eq!(
        plane_grid(4, 3, 1.0, 1.0, true).boundary_loops()[0].len(),
        14
    );
}

#[test]
fn rejects_non_manifold_edge_and_vertex() {
    // Three triangles on edge 0-1.
    let e = SurfaceMesh::from_faces(&pts(5), &[[0, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap_err();
    assert!(matches!(e, MeshError::NonManifoldEdge { .. }), "{e:?}");
    // Two triangles touching at vertex 0 only (bow tie).
    let e = SurfaceMesh::from_faces(&pts(5), &[[0, 1, 2], [0, 3, 4]]).unwrap_err();
    assert_eq!(e, MeshError::NonManifoldVertex(Vertex::new(0)));
    // Inconsistent orientation.
    let e = SurfaceMesh::from_faces(&pts(4), &[[0, 1, 2], [0, 1, 3]]).unwrap_err();
    assert!(matches!(e, MeshError::NonManifoldEdge { .. }));
    let e = SurfaceMesh::from_faces(&pts(3), &[[0, 1, 7]]).unwrap_err();
    assert!(matches!(
        e,
        MeshError::VertexIndexOutOfRange { index: 7, .. }
    ));
    let e = SurfaceMesh::from_faces(&pts(3), &[[0, 1, 1]]).unwrap_err();
    assert!(matches!(e, MeshError::DegenerateFace { face: 0 }));
}

#[test]
fn closed_fans_sharing_a_vertex_are_rejected() {
    // Two closed cones (octahedron halves would be closed) glued at a vertex: two tetrahedra sharing vertex 0.
    let faces = [
        [0, 2, 1],
        [0, 1, 3],
        [0, 3, 2],
        [1, 2, 3],
        [0, 5, 4],
        [0, 4, 6],
        [0, 6, 5],
        [4, 5, 6],
    ];
    let e = SurfaceMesh::from_faces(&pts(7), &faces).unwrap_err();
    assert_eq!(e, MeshError::NonManifoldVertex(Vertex::new(0)));
}

#[test]
fn edge_splits_flips_face_splits_keep_invariants_and_chi() {
    for mut m in [
        icosphere(1, 1.0),
        plane_grid(3, 3, 1.0, 1.0, false),
        cylinder(1.0, 1.0, 6, 3, false),
    ] {
        let chi = m.euler_characteristic();
        let edges: Vec<_> = m.edges().take(15).collect();
        for e in edges {
            let (a, b) = m.edge_vertices(e);
            let mid = (m.position(a) + m.position(b)) * 0.5;
            m.split_edge(e, mid).unwrap();
            m.validate().unwrap();
            assert_eq!(m.euler_characteristic(), chi);
        }
        let faces: Vec<_> = m.faces().take(10).collect();
        for f in faces {
            let c = m
                .face_vertices(f)
                .map(|v| m.position(v))
                .fold(Vec3::ZERO, |s, p| s + p)
                / 3.0;
            m.split_face(f, c).unwrap();
            m.validate().unwrap();
            assert_eq!(m.euler_characteristic(), chi);
        }
        let edges: Vec<_> = m.edges().collect();
        let mut flipped = 0;
        for e in edges {
            if m.is_flip_ok(e) {
                m.flip(e).unwrap();
                flipped += 1;
                m.validate().unwrap();
            }
        }
        assert!(flipped > 0);
        assert_eq!(m.euler_characteristic(), chi);
    }
}

#[test]
fn collapses_respect_link_condition_and_garbage_collection_compacts() {
    for mut m in [
        icosphere(2, 1.0),
        plane_grid(5, 5, 1.0, 1.0, false),
        torus(2.0, 0.7, 10, 8, false),
    ] {
        let chi = m.euler_characteristic();
        let mut collapsed = 0;
        for _ in 0..40 {
            let h = m.halfedges().find(|&h| m.is_collapse_ok(h));
            let Some(h) = h else { break };
            m.collapse(h).unwrap();
            collapsed += 1;
            m.validate().unwrap();
            assert_eq!(m.euler_characteristic(), chi);
        }
        assert!(collapsed > 10);
        let (nv, nf) = (m.n_vertices(), m.n_faces());
        m.garbage_collection();
        m.validate().unwrap();
        assert!(!m.has_garbage());
        assert_eq!((m.vertices_size(), m.faces_size()), (nv, nf));
        assert_eq!(m.euler_characteristic(), chi);
    }
}

#[test]
fn pillow_collapse_is_rejected_by_the_link_condition() {
    // A tetrahedron collapses once into a two-triangle "pillow" (still a sphere);
    // every further collapse would break the surface and must be rejected.
    let mut m =
        SurfaceMesh::from_faces(&pts(4), &[[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]).unwrap();
    let h = m.halfedges().next().unwrap();
    m.collapse(h).unwrap();
    m.validate().unwrap();
    assert_eq!(m.euler_characteristic(), 2);
    for h in m.halfedges().collect::<Vec<_>>() {
        assert!(!m.is_collapse_ok(h));
        assert!(m.collapse(h).is_err());
    }
    m.validate().unwrap();
}

#[test]
fn properties_follow_garbage_collection() {
    let mut m = icosphere(1, 1.0);
    let p = m.vertex_props.add::<Vertex, usize>("id", 0).unwrap();
    for (i, v) in m
        .vertex_props
        .values_mut(&p)
        .unwrap()
        .iter_mut()
        .enumerate()
    {
        *v = i;
    }
    assert!(m.vertex_props.add::<Vertex, usize>("id", 0).is_err());
    let h = m.halfedges().find(|&h| m.is_collapse_ok(h)).unwrap();
    let removed = m.from_vertex(h).idx();
    m.collapse(h).unwrap();
    m.garbage_collection();
    let ids = m.vertex_props.values(&p).unwrap();
    assert_eq!(ids.len(), m.n_vertices());
    assert!(!ids.contains(&removed));
    assert!(ids.windows(2).all(|w| w[0] < w[1]));
}

#[test]
fn random_sequences_of_euler_operations_stay_valid() {
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut next = move |n: usize| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state % n.max(1) as u64) as usize
    };
    for mut m in [
        torus(2.0, 0.7, 9, 7, false),
        cylinder(1.0, 1.0, 8, 4, false),
        icosphere(1, 1.0),
    ] {
        let chi = m.euler_characteristic();
        for step in 0..400 {
            match next(4) {
                0 => {
                    let e = fires_recon::mesh::Edge::new(next(m.edges_size()));
                    if !m.is_deleted_edge(e) {
                        let (a, b) = m.edge_vertices(e);
                        m.split_edge(e, (m.position(a) + m.position(b)) * 0.5)
                            .unwrap();
                    }
                }
                1 => {
                    let e = fires_recon::mesh::Edge::new(next(m.edges_size()));
                    if !m.is_deleted_edge(e) && m.is_flip_ok(e) {
                        m.flip(e).unwrap();
                    }
                }
                2 => {
                    let h = fires_recon::mesh::Halfedge::new(next(m.halfedges_size()));
                    if !m.is_deleted_edge(h.edge()) {
                        let ok = m.is_collapse_ok(h);
                        assert_eq!(m.collapse(h).is_ok(), ok);
                    }
                }
                _ => {
                    let f = fires_recon::mesh::Face::new(next(m.faces_size()));
                    if !m.is_deleted_face(f) {
                        let c = m
                            .face_vertices(f)
                            .map(|v| m.position(v))
                            .fold(Vec3::ZERO, |s, p| s + p)
                            / 3.0;
                        m.split_face(f, c).unwrap();
                    }
                }
            }
            if let Err(e) = m.validate() {
                panic!("step {step}: {e}");
            }
            assert_eq!(m.euler_characteristic(), chi, "step {step}");
            if step % 100 == 99 {
                m.garbage_collection();
                m.validate().unwrap();
            }
        }
    }
}

#[test]
fn large_polygons_are_checked_in_n_log_n() {
    // A 60000-gon (a hostile OFF face) builds quickly; one repeated corner is rejected.
    let n = 60_000;
    let points: Vec<Vec3> = (0..n)
        .map(|i| Vec3::new((i as f64).cos(), (i as f64).sin(), 0.0))
        .collect();
    let mut face: Vec<usize> = (0..n).collect();
    let m = SurfaceMesh::from_faces(&points, &[face.clone()]).unwrap();
    m.validate().unwrap();
    face[n - 1] = 17;
    assert!(matches!(
        SurfaceMesh::from_faces(&points, &[face]),
        Err(MeshError::DegenerateFace { face: 0 })
    ));
}
