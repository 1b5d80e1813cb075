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

// ----- Coons patches ------------------------------------------------------------------------------

use common::netgen::parametric_network;
use fires_recon::surface::{
    nuliss_mod, reconstruct_v1, refined_v1, triquadrify, CoonsPatch, NulissOptions, Side,
    TriquadOptions, V1Options,
};

fn v(p: [f64; 3]) -> Vec3 {
    Vec3::from_array(p)
}

/// A wavy curve from `a` to `b` with `n` unevenly spaced samples.
fn wavy(a: Vec3, b: Vec3, n: usize, amp: f64, seed: f64) -> Vec<Vec3> {
    (0..=n)
        .map(|i| {
            let t = (i as f64 / n as f64).powf(1.3);
            let w = (std::f64::consts::PI * t).sin() * amp;
            a * (1.0 - t)
                + b * t
                + Vec3::new(w * (seed).cos(), w * (2.0 * seed).sin(), w * (t * 7.0 + seed).cos())
        })
        .collect()
}

/// Distance from `p` to the polyline `pts`.
fn dist_polyline(p: Vec3, pts: &[Vec3]) -> f64 {
    pts.windows(2)
        .map(|w| {
            let d = w[1] - w[0];
            let t = ((p - w[0]).dot(d) / d.norm_squared().max(1e-300)).clamp(0.0, 1.0);
            (w[0] + d * t - p).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn coons_patch_interpolates_its_four_sides() {
    let c = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.1, 0.2),
        Vec3::new(1.2, 1.0, -0.1),
        Vec3::new(-0.1, 0.9, 0.3),
    ];
    let s: Vec<Vec<Vec3>> = (0..4)
        .map(|k| wavy(c[k], c[(k + 1) % 4], 9 + 3 * k, 0.2, k as f64 + 0.5))
        .collect();
    let p = CoonsPatch::from_loop([s[0].clone(), s[1].clone(), s[2].clone(), s[3].clone()]);
    let sides = [
        Side::new(s[0].clone()),
        Side::new(s[1].clone()),
        Side::new(s[2].clone()).reversed(),
        Side::new(s[3].clone()).reversed(),
    ];
    let mut worst: f64 = 0.0;
    for i in 0..=200 {
        let t = i as f64 / 200.0;
        worst = worst.max((p.eval(t, 0.0) - sides[0].at(t)).norm());
        worst = worst.max((p.eval(1.0, t) - sides[1].at(t)).norm());
        worst = worst.max((p.eval(t, 1.0) - sides[2].at(t)).norm());
        worst = worst.max((p.eval(0.0, t) - sides[3].at(t)).norm());
    }
    assert!(worst <= 1e-12, "side error {worst}");
    // The sample points themselves lie on the patch border.
    for q in &s[0] {
        assert!(dist_polyline(*q, &s[0]) == 0.0);
    }
    // A triangle: the collapsed side is the corner.
    let t = CoonsPatch::triangle(s[0].clone(), s[1].clone(), wavy(c[2], c[0], 5, 0.1, 3.0));
    for i in 0..=10 {
        assert!((t.eval(0.0, i as f64 / 10.0) - c[0]).norm() <= 1e-12);
    }
}

#[test]
fn coons_patch_reproduces_a_bilinear_patch() {
    let (p00, p10, p01, p11) = (
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(2.0, 0.3, 0.5),
        Vec3::new(0.2, 1.5, -0.4),
        Vec3::new(1.8, 1.9, 1.1),
    );
    let bil = |u: f64, w: f64| {
        p00 * ((1.0 - u) * (1.0 - w)) + p10 * (u * (1.0 - w)) + p01 * ((1.0 - u) * w) + p11 * (u * w)
    };
    // Straight sides, unevenly sampled (chord length is the bilinear parameter on a straight side).
    let ts = [0.0, 0.1, 0.35, 0.4, 0.8, 1.0];
    let side = |f: &dyn Fn(f64) -> Vec3| ts.iter().map(|&t| f(t)).collect::<Vec<_>>();
    let p = CoonsPatch::new(
        Side::new(side(&|t| bil(t, 0.0))),
        Side::new(side(&|t| bil(1.0, t))),
        Side::new(side(&|t| bil(t, 1.0))),
        Side::new(side(&|t| bil(0.0, t))),
    );
    for i in 0..=20 {
        for j in 0..=20 {
            let (u, w) = (i as f64 / 20.0, j as f64 / 20.0);
            assert!((p.eval(u, w) - bil(u, w)).norm() <= 1e-12);
        }
    }
}

// ----- triquadrification ----------------------------------------------------------------------------

/// One n-gon network: corners on a slightly wavy ellipse, wavy polylines.
fn ngon_network(n: usize) -> Network {
    let pts: Vec<[f64; 3]> = (0..n)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / n as f64 + 0.1 * (k as f64).sin();
            [0.1 * a.cos(), 0.08 * a.sin(), 0.01 * (3.0 * a).sin()]
        })
        .collect();
    let q = pts.clone();
    network_from_polygons(
        &pts,
        &[(0..n).collect()],
        move |a, b| {
            wavy(v(q[a]), v(q[b]), 12, 0.003, (a * 7 + b) as f64)
                .into_iter()
                .map(|p| p.to_array())
                .collect()
        },
        |_, _| 0.0,
    )
}

#[test]
fn triquadrification_face_counts_on_n_gons() {
    for n in 3..=12 {
        let net = ngon_network(n);
        let base = base_mesh(&net).unwrap();
        let tq = triquadrify(&base, &TriquadOptions::default()).unwrap();
        let want = match n {
            3 | 4 => 1,
            _ if n % 2 == 1 => (n - 1) / 2,
            _ => (n - 2) / 2,
        };
        assert_eq!(tq.mesh.n_faces(), want, "{n}-gon");
        let tris = tq.mesh.faces().filter(|&f| tq.mesh.face_valence(f) == 3).count();
        assert_eq!(tris, n % 2, "{n}-gon: one triangle for odd n");
        assert!(tq.mesh.faces().all(|f| tq.mesh.face_valence(f) <= 4));
        let generated = tq.curves.iter().filter(|c| c.generated).count();
        assert_eq!(generated, want - 1, "{n}-gon: faces − 1 new polylines");
        assert!(tq.curves.iter().filter(|c| c.generated).all(|c| !c.sharp));
        assert_spans_on_curves(&tq, 1e-12);
    }
}
