//! FIRESV1 (FIRES thesis §6.1–6.3): the base mesh of a curve network, Coons patches, triquadrification,
//! basic refinement, NULISSmod and the whole method, on generated networks.

mod common;

use common::disc::circle;
use common::netgen::{network_from_polygons, straight};
use fires_recon::network::tools::{insert_boundary, BoundaryOptions, CurveInput};
use fires_recon::network::Network;
use fires_recon::surface::{base_mesh, ControlMesh, SurfaceError, VertexTag};
use fires_recon::Vec3;

/// Every curve edge's ends lie on its curve at its span's parameters (to `tol`).
fn assert_spans_on_curves(cm: &ControlMesh, tol: f64) {
    for e in cm.mesh.edges() {
        if let Some(s) = cm.span(e) {
            let (a, b) = cm.mesh.edge_vertices(e);
            let c = &cm.curves[s.curve];
            assert!((cm.mesh.position(a) - c.point_at(s.t0)).norm() <= tol);
            assert!((cm.mesh.position(b) - c.point_at(s.t1)).norm() <= tol);
        }
    }
}

fn cube_network(sharp: f64) -> Network {
    let p: Vec<[f64; 3]> = (0..8)
        .map(|i| {
            [
                (i & 1) as f64 * 0.1,
                ((i >> 1) & 1) as f64 * 0.1,
                ((i >> 2) & 1) as f64 * 0.1,
            ]
        })
        .collect();
    let faces = vec![
        vec![0, 2, 3, 1],
        vec![4, 5, 7, 6],
        vec![0, 1, 5, 4],
        vec![2, 6, 7, 3],
        vec![0, 4, 6, 2],
        vec![1, 3, 7, 5],
    ];
    let q = p.clone();
    network_from_polygons(
        &p,
        &faces,
        move |a, b| straight(q[a], q[b], 7),
        |_, _| sharp,
    )
}

#[test]
fn base_mesh_of_a_cube_network_is_the_cube() {
    let net = cube_network(1.0);
    let cm = base_mesh(&net).unwrap();
    assert_eq!(
        (cm.mesh.n_vertices(), cm.mesh.n_edges(), cm.mesh.n_faces()),
        (8, 12, 6)
    );
    assert!(cm.mesh.is_closed());
    assert_eq!(cm.curves.len(), 12);
    assert!(cm
        .curves
        .iter()
        .all(|c| c.sharp && !c.generated && c.source.is_some()));
    assert!(cm.vertex_tag.iter().all(|t| *t == VertexTag::Corner));
    for e in cm.mesh.edges() {
        let s = cm.span(e).expect("every edge follows a curve");
        let len = cm.curves[s.curve].length();
        assert!(
            (s.t0 - s.t1).abs() == len,
            "each edge spans its whole curve"
        );
    }
    assert_spans_on_curves(&cm, 1e-15);
    assert_eq!(cm.sharp_valence(fires_recon::mesh::Vertex::new(0)), 3);
    // Outward orientation as the loops: the signed volume is positive.
    let vol: f64 = cm
        .mesh
        .faces()
        .map(|f| {
            let v: Vec<Vec3> = cm
                .mesh
                .face_vertices(f)
                .map(|v| cm.mesh.position(v))
                .collect();
            (1..v.len() - 1)
                .map(|k| v[0].dot(v[k].cross(v[k + 1])) / 6.0)
                .sum::<f64>()
        })
        .sum();
    assert!((vol - 1e-3).abs() < 1e-12, "volume {vol}");
    let soft = base_mesh(&cube_network(0.4)).unwrap();
    assert!(soft.curves.iter().all(|c| !c.sharp));
}

#[test]
fn a_two_sided_disc_face_becomes_a_triangle_with_a_midpoint() {
    let mut net = Network::new();
    insert_boundary(
        &mut net,
        CurveInput::new(&circle(400)),
        &BoundaryOptions::default(),
    )
    .unwrap();
    let cm = base_mesh(&net).unwrap();
    assert_eq!((cm.mesh.n_vertices(), cm.mesh.n_faces()), (3, 1));
    let on_curve: Vec<_> = cm
        .vertex_tag
        .iter()
        .filter_map(|t| match t {
            VertexTag::OnCurve(p) => Some(*p),
            _ => None,
        })
        .collect();
    assert_eq!(on_curve.len(), 1);
    let c = &cm.curves[on_curve[0].curve];
    assert!((on_curve[0].t - c.length() / 2.0).abs() < 1e-15);
    assert_eq!(cm.edge_curve.iter().filter(|s| s.is_some()).count(), 3);
    assert_spans_on_curves(&cm, 1e-15);
    // The split spans together cover the curve once.
    let covered: f64 = cm
        .mesh
        .edges()
        .filter_map(|e| cm.span(e))
        .filter(|s| s.curve == on_curve[0].curve)
        .map(|s| (s.t1 - s.t0).abs())
        .sum();
    assert!((covered - c.length()).abs() < 1e-15);
}

#[test]
fn base_mesh_refuses_an_empty_network() {
    assert_eq!(
        base_mesh(&Network::new()).unwrap_err(),
        SurfaceError::EmptyNetwork
    );
}
