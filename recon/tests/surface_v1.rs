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
                + Vec3::new(
                    w * (seed).cos(),
                    w * (2.0 * seed).sin(),
                    w * (t * 7.0 + seed).cos(),
                )
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
        p00 * ((1.0 - u) * (1.0 - w))
            + p10 * (u * (1.0 - w))
            + p01 * ((1.0 - u) * w)
            + p11 * (u * w)
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
        let tris = tq
            .mesh
            .faces()
            .filter(|&f| tq.mesh.face_valence(f) == 3)
            .count();
        assert_eq!(tris, n % 2, "{n}-gon: one triangle for odd n");
        assert!(tq.mesh.faces().all(|f| tq.mesh.face_valence(f) <= 4));
        let generated = tq.curves.iter().filter(|c| c.generated).count();
        assert_eq!(generated, want - 1, "{n}-gon: faces − 1 new polylines");
        assert!(tq.curves.iter().filter(|c| c.generated).all(|c| !c.sharp));
        assert_spans_on_curves(&tq, 1e-12);
    }
}

// ----- planarity, NULISSmod ----------------------------------------------------------------------

/// A planar network in a tilted plane: three quads, a pentagon and a hexagon, with in-plane bent
/// polylines.
fn planar_network() -> (Network, Vec3, Vec3, f64) {
    let origin = Vec3::new(0.2, -0.1, 0.4);
    let (ex, ey) = (
        Vec3::new(1.0, 0.2, 0.3).normalize_or_zero(),
        Vec3::new(-0.1, 1.0, 0.5),
    );
    let n = ex.cross(ey).normalize_or_zero();
    let ey = n.cross(ex);
    let at = move |x: f64, y: f64| origin + ex * x + ey * y;
    let mut pts = Vec::new();
    for j in 0..3 {
        for i in 0..4 {
            pts.push(at(0.05 * i as f64 + 0.004 * j as f64, 0.05 * j as f64).to_array());
        }
    }
    pts.push(at(0.075, -0.02).to_array()); // 12: bends the bottom of the middle cell
    let faces = vec![
        vec![0, 1, 5, 4],
        vec![1, 12, 2, 6, 5],
        vec![2, 3, 7, 6],
        vec![4, 5, 9, 8],
        vec![5, 6, 7, 11, 10, 9],
    ];
    let q = pts.clone();
    let net = network_from_polygons(
        &pts,
        &faces,
        move |a, b| {
            let (pa, pb) = (v(q[a]), v(q[b]));
            let side = n.cross(pb - pa);
            (0..=10)
                .map(|k| {
                    let t = k as f64 / 10.0;
                    (pa * (1.0 - t) + pb * t + side * (0.15 * (std::f64::consts::PI * t).sin()))
                        .to_array()
                })
                .collect()
        },
        |_, _| 0.0,
    );
    (net, origin, n, 0.15)
}

#[test]
fn a_planar_network_gives_a_planar_surface() {
    let (net, origin, n, size) = planar_network();
    for levels in [1, 2] {
        let s = reconstruct_v1(
            &net,
            &V1Options {
                levels,
                ..V1Options::default()
            },
        )
        .unwrap();
        assert!(s.mesh.faces().all(|f| s.mesh.face_valence(f) == 4));
        let worst = s
            .mesh
            .vertices()
            .map(|x| (s.mesh.position(x) - origin).dot(n).abs())
            .fold(0.0, f64::max);
        assert!(worst <= 1e-9 * size, "off-plane {worst} at {levels} levels");
    }
}

/// A curved network: a 3 × 3 quad patch of a saddle.
fn saddle_network() -> Network {
    let f = |s: f64, t: f64| {
        let (x, y) = (s - 0.5, t - 0.5);
        [0.2 * x, 0.2 * y, 0.1 * (x * x - y * y)]
    };
    parametric_network(&f, 3, 3, (false, false), 12)
}

#[test]
fn nuliss_mod_keeps_old_vertices_and_puts_edge_points_on_the_polylines() {
    let net = saddle_network();
    let refined = refined_v1(&net, &V1Options::default()).unwrap();
    assert!(refined
        .mesh
        .faces()
        .all(|f| refined.mesh.face_valence(f) == 4));
    // The refined mesh's vertices are on the polylines (curve vertices) or patch centres.
    let s = nuliss_mod(&refined, &NulissOptions::default()).unwrap();
    let nv = refined.mesh.n_vertices();
    for x in refined.mesh.vertices() {
        assert_eq!(
            s.mesh.position(x),
            refined.mesh.position(x),
            "old vertex {x} moved"
        );
        assert_eq!(s.tag(x), refined.tag(x));
    }
    assert_eq!(
        s.mesh.n_vertices(),
        nv + refined.mesh.n_edges() + refined.mesh.n_faces()
    );
    let mut checked = 0;
    for e in refined.mesh.edges() {
        let Some(sp) = refined.span(e) else { continue };
        let ev = fires_recon::mesh::Vertex::new(nv + checked_index(&refined, e));
        let p = s.mesh.position(ev);
        let c = &refined.curves[sp.curve];
        let d = dist_polyline(p, &c.points);
        assert!(d <= 1e-12, "edge point {ev} is {d} m off its polyline");
        checked += 1;
    }
    assert!(
        checked == refined.mesh.n_edges(),
        "every refined edge follows a curve"
    );
    // Without snapping, the interpolatory edge points leave the curves.
    let plain = nuliss_mod(
        &refined,
        &NulissOptions {
            snap_to_curves: false,
        },
    )
    .unwrap();
    let off = refined
        .mesh
        .edges()
        .map(|e| {
            let sp = refined.span(e).unwrap();
            let p = plain
                .mesh
                .position(fires_recon::mesh::Vertex::new(nv + e.idx()));
            dist_polyline(p, &refined.curves[sp.curve].points)
        })
        .fold(0.0, f64::max);
    assert!(
        off > 1e-6,
        "the snap must matter on a curved network ({off})"
    );
}

/// Edge point of edge `e` is vertex `n_vertices + (rank of e among the edges)` (compact meshes: e.idx()).
fn checked_index(cm: &ControlMesh, e: fires_recon::mesh::Edge) -> usize {
    assert!(!cm.mesh.has_garbage());
    e.idx()
}

// ----- basic refinement, networks from the sketching tools ------------------------------------------

use fires_recon::surface::{refine, CurveKeeping, RefineOptions};
use std::f64::consts::TAU;

#[test]
fn basic_refinement_gives_quads_with_every_vertex_on_a_polyline() {
    for n in [4, 5, 7] {
        let tq = triquadrify(
            &base_mesh(&ngon_network(n)).unwrap(),
            &TriquadOptions::default(),
        )
        .unwrap();
        let (q, t) = tq.mesh.faces().fold((0, 0), |(q, t), f| {
            if tq.mesh.face_valence(f) == 4 {
                (q + 1, t)
            } else {
                (q, t + 1)
            }
        });
        for (steps, match_density) in [(1, true), (2, true), (2, false), (3, true)] {
            let r = refine(
                &tq,
                &RefineOptions {
                    steps,
                    match_density,
                },
            )
            .unwrap();
            assert!(r.mesh.faces().all(|f| r.mesh.face_valence(f) == 4));
            let p = 4usize.pow(steps as u32);
            assert_eq!(
                r.mesh.n_faces(),
                q * p + t * 3 * p / 4,
                "{n}-gon, {steps} steps"
            );
            assert!(
                r.mesh.edges().all(|e| r.span(e).is_some()),
                "every edge follows a polyline"
            );
            assert_spans_on_curves(&r, 1e-12);
        }
    }
}

#[test]
fn a_disc_sketched_with_the_tools_reconstructs_flat() {
    use common::disc::{vertical, Z};
    use fires_recon::network::tools::{insert_curve, InsertOptions};
    let mut net = Network::new();
    insert_boundary(
        &mut net,
        CurveInput::new(&circle(400)),
        &BoundaryOptions::default(),
    )
    .unwrap();
    for x in [-0.05, 0.0, 0.05] {
        insert_curve(
            &mut net,
            CurveInput::new(&vertical(x)),
            &InsertOptions::default(),
        )
        .unwrap();
    }
    for (a0, a1) in [(160.0f64, -20.0f64), (100.0, 250.0)] {
        let c = common::disc::chord(a0.to_radians(), a1.to_radians(), 0.0);
        insert_curve(&mut net, CurveInput::new(&c), &InsertOptions::default()).unwrap();
    }
    // A stroke from the top arc that stops on the first chord (overshooting it by 3 mm, trimmed): a
    // T-junction, so the faces beside it get five and more sides.
    let x = 0.025;
    let top = common::disc::B / common::disc::R * (common::disc::R.powi(2) - x * x).sqrt();
    let t = (x + 0.1 * 160f64.to_radians().cos().abs()) / (2.0 * 0.1 * 20f64.to_radians().cos());
    let y_chord = 0.097 * 20f64.to_radians().sin() * (1.0 - 2.0 * t);
    let stroke = common::disc::line([x, top, Z], [x, y_chord - 0.003, Z], 0.002);
    insert_curve(
        &mut net,
        CurveInput::new(&stroke),
        &InsertOptions::default(),
    )
    .unwrap();
    let base = base_mesh(&net).unwrap();
    let sides: Vec<usize> = base
        .mesh
        .faces()
        .map(|f| base.mesh.face_valence(f))
        .collect();
    assert!(
        sides.iter().any(|&n| n >= 5),
        "the sketch has faces to triquadrify: {sides:?}"
    );
    // Snapping keeps the curve vertices exactly on the curves (checked below).
    let mut opts = V1Options::default();
    opts.catmull_clark.keep = CurveKeeping::Snap;
    let s = reconstruct_v1(&net, &opts).unwrap();
    assert!(s.mesh.faces().all(|f| s.mesh.face_valence(f) == 4));
    let worst = s
        .mesh
        .vertices()
        .map(|x| (s.mesh.position(x).z - Z).abs())
        .fold(0.0, f64::max);
    assert!(worst <= 1e-9 * 0.2, "off-plane {worst}");
    // The drawn curves are kept: every curve vertex is on its curve.
    for x in s.mesh.vertices() {
        if let VertexTag::OnCurve(p) = s.tag(x) {
            let d = (s.mesh.position(x) - s.curves[p.curve].point_at(p.t)).norm();
            assert!(d <= 1e-12, "curve vertex {x} is {d} m off");
        }
    }
}

#[test]
fn a_sharp_cube_network_stays_on_the_cube_faces() {
    // Distance of a point to the surface of the cube [0, 0.1]³.
    let to_cube = |p: Vec3| {
        let d = [p.x, p.y, p.z]
            .iter()
            .map(|&c| c.abs().min((c - 0.1).abs()))
            .fold(f64::INFINITY, f64::min);
        let inside = [p.x, p.y, p.z]
            .iter()
            .all(|&c| (-1e-12..=0.1 + 1e-12).contains(&c));
        if inside {
            d
        } else {
            f64::INFINITY
        }
    };
    let worst_off = |s: &ControlMesh| {
        s.mesh
            .vertices()
            .map(|x| to_cube(s.mesh.position(x)))
            .fold(0.0, f64::max)
    };
    // The whole of V1 on the sharp cube keeps every vertex on the cube's faces.
    let sharp = reconstruct_v1(&cube_network(1.0), &V1Options::default()).unwrap();
    assert!(
        worst_off(&sharp) <= 1e-9 * 0.1,
        "sharp cube: {}",
        worst_off(&sharp)
    );
    // The interpolatory rules themselves (no snapping): the sharp rules keep each side of a crease to
    // itself; without sharp curves the four-point rule reaches across the cube's edges and bulges.
    let plain = NulissOptions {
        snap_to_curves: false,
    };
    let opts = V1Options::default();
    let s = nuliss_mod(&refined_v1(&cube_network(1.0), &opts).unwrap(), &plain).unwrap();
    assert!(
        worst_off(&s) <= 1e-9 * 0.1,
        "sharp rules: {}",
        worst_off(&s)
    );
    let s = nuliss_mod(&refined_v1(&cube_network(0.0), &opts).unwrap(), &plain).unwrap();
    assert!(worst_off(&s) > 1e-4, "smooth rules: {}", worst_off(&s));
}

#[test]
fn a_one_sided_loop_face_becomes_a_triangle_split_in_thirds() {
    let ring: Vec<[f64; 3]> = (0..=60)
        .map(|i| {
            let a = TAU * i as f64 / 60.0;
            [0.05 * a.cos(), 0.05 * a.sin(), 0.3]
        })
        .collect();
    let first = ring[0];
    let net = network_from_polygons(&[first], &[vec![0]], move |_, _| ring.clone(), |_, _| 0.0);
    let cm = base_mesh(&net).unwrap();
    assert_eq!((cm.mesh.n_vertices(), cm.mesh.n_faces()), (3, 1));
    let len = cm.curves[0].length();
    let mut ts: Vec<f64> = cm
        .vertex_tag
        .iter()
        .filter_map(|t| match t {
            VertexTag::OnCurve(p) => Some(p.t / len),
            _ => None,
        })
        .collect();
    ts.sort_by(f64::total_cmp);
    assert!((ts[0] - 1.0 / 3.0).abs() < 1e-15 && (ts[1] - 2.0 / 3.0).abs() < 1e-15);
    assert_spans_on_curves(&cm, 1e-15);
    let s = reconstruct_v1(&net, &V1Options::default()).unwrap();
    let worst = s
        .mesh
        .vertices()
        .map(|x| (s.mesh.position(x).z - 0.3).abs())
        .fold(0.0, f64::max);
    assert!(worst <= 1e-9 * 0.1, "off-plane {worst}");
}

#[test]
fn a_face_through_a_vertex_twice_is_refused_with_its_name() {
    // A bow tie: one loop through vertex 0 twice.
    let p = [
        [0.0, 0.0, 0.0],
        [0.1, 0.05, 0.0],
        [0.1, -0.05, 0.0],
        [-0.1, 0.05, 0.0],
        [-0.1, -0.05, 0.0],
    ];
    let net = network_from_polygons(
        &p,
        &[vec![0, 1, 2, 0, 4, 3]],
        move |a, b| straight(p[a], p[b], 4),
        |_, _| 0.0,
    );
    let e = base_mesh(&net).unwrap_err();
    assert!(
        matches!(&e, SurfaceError::UnsupportedFace { face, reason } if face == "f0" && reason.contains("twice")),
        "{e}"
    );
}
