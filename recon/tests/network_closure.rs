//! Mesh closure (FIRES thesis ch. 5): closed networks (a sphere, a cube) built from a boundary, curve
//! insertions, one closure and more insertions into the closing face; validate() after every step,
//! Euler bookkeeping of the closure (ΔF = +1, one boundary fewer, genus unchanged) and refusals that leave
//! the network bit for bit unchanged.

use fires_recon::network::tools::{
    close_boundary, insert_boundary, insert_curve, BoundaryOptions, CloseOptions, CurveInput,
    InsertOptions, ToolError,
};
use fires_recon::network::{Network, Topology};
use std::f64::consts::PI;

const R: f64 = 0.1;

fn curve(pts: &[[f64; 3]], id: u32) -> CurveInput<'_> {
    CurveInput {
        points: pts,
        stroke: Some(id),
        sigma_mm: None,
        untracked_mm: [0.0; 2],
    }
}

/// Points every ~2 mm along the polygon through `corners` (corners included exactly).
fn polygon(corners: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let mut out = vec![corners[0]];
    for w in corners.windows(2) {
        let (a, b) = (w[0], w[1]);
        let d = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt();
        let n = (d / 0.002).ceil() as usize;
        for i in 1..=n {
            let t = i as f64 / n as f64;
            out.push([
                a[0] + t * (b[0] - a[0]),
                a[1] + t * (b[1] - a[1]),
                a[2] + t * (b[2] - a[2]),
            ]);
        }
    }
    out
}

/// A great-circle arc of the sphere of radius R from `a` to `b` (unit directions, not antipodal) through
/// the direction `via` when given (two arcs a→via→b).
fn arc(a: [f64; 3], via: [f64; 3], b: [f64; 3]) -> Vec<[f64; 3]> {
    let slerp = |p: [f64; 3], q: [f64; 3], n: usize| -> Vec<[f64; 3]> {
        let c = (p[0] * q[0] + p[1] * q[1] + p[2] * q[2]).clamp(-1.0, 1.0);
        let w = c.acos();
        (0..=n)
            .map(|i| {
                let t = i as f64 / n as f64;
                let (s0, s1) = (((1.0 - t) * w).sin() / w.sin(), (t * w).sin() / w.sin());
                [
                    R * (s0 * p[0] + s1 * q[0]),
                    R * (s0 * p[1] + s1 * q[1]),
                    R * (s0 * p[2] + s1 * q[2]),
                ]
            })
            .collect()
    };
    let mut out = slerp(a, via, 80);
    out.extend(slerp(via, b, 80).into_iter().skip(1));
    out
}

fn quarter(a: [f64; 3], b: [f64; 3]) -> Vec<[f64; 3]> {
    let m = [(a[0] + b[0]), (a[1] + b[1]), (a[2] + b[2])];
    let n = (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt();
    arc(a, [m[0] / n, m[1] / n, m[2] / n], b)
}

fn insert(net: &mut Network, pts: &[[f64; 3]], id: u32) {
    insert_curve(net, curve(pts, id), &InsertOptions::default())
        .unwrap_or_else(|e| panic!("stroke {id}: {e}"));
    net.validate().unwrap();
}

fn close(net: &mut Network, pts: &[[f64; 3]], id: u32) -> Topology {
    let before = net.topology();
    close_boundary(net, curve(pts, id), &CloseOptions::default())
        .unwrap_or_else(|e| panic!("closing with stroke {id}: {e}"));
    net.validate().unwrap();
    let after = net.topology();
    assert_eq!(
        (after.vertices, after.edges, after.faces),
        (before.vertices, before.edges, before.faces + 1)
    );
    assert_eq!(after.boundaries + 1, before.boundaries);
    assert_eq!(after.euler, before.euler + 1);
    assert_eq!(after.genus, before.genus);
    after
}

fn equator() -> Vec<[f64; 3]> {
    (0..=360)
        .map(|i| {
            let a = 2.0 * PI * i as f64 / 360.0;
            // y shrunk by 1e-6 so the diameter pair where the boundary is split is exactly ±x.
            [R * a.cos(), R * (1.0 - 1e-6) * a.sin(), 0.0]
        })
        .collect()
}

const X: [f64; 3] = [1.0, 0.0, 0.0];
const MX: [f64; 3] = [-1.0, 0.0, 0.0];
const Y: [f64; 3] = [0.0, 1.0, 0.0];
const MY: [f64; 3] = [0.0, -1.0, 0.0];
const N: [f64; 3] = [0.0, 0.0, 1.0];
const S: [f64; 3] = [0.0, 0.0, -1.0];

/// The octahedral network of a sphere: the equator, two northern arcs, closure across the south, two
/// southern arcs. V = 6, E = 12, F = 8, χ = 2.
fn sphere() -> Network {
    let mut net = Network::new();
    insert_boundary(&mut net, curve(&equator(), 0), &BoundaryOptions::default()).unwrap();
    net.validate().unwrap();
    insert(&mut net, &arc(Y, N, MY), 1);
    insert(&mut net, &quarter(N, X), 2);
    insert(&mut net, &quarter(N, MX), 3);
    let south = arc(Y, S, MY);
    close(&mut net, &south, 4);
    insert(&mut net, &south, 4);
    insert(&mut net, &quarter(S, X), 5);
    insert(&mut net, &quarter(S, MX), 6);
    net
}

#[test]
fn a_sphere_is_a_boundary_curves_and_the_closed_remaining_side() {
    let net = sphere();
    let t = net.topology();
    assert_eq!(
        (t.vertices, t.edges, t.faces, t.boundaries, t.components),
        (6, 12, 8, 0, 1)
    );
    assert_eq!((t.euler, t.genus), (2, 0));
    // Every face is a triangle of the octahedron.
    for (f, face) in net.faces() {
        assert_eq!(face.uses.len(), 3, "face {f}");
    }
}

#[test]
fn closing_a_bare_boundary_gives_a_two_face_sphere() {
    let mut net = Network::new();
    insert_boundary(&mut net, curve(&equator(), 0), &BoundaryOptions::default()).unwrap();
    let t = close(&mut net, &arc(Y, S, MY), 1);
    assert_eq!(
        (t.vertices, t.edges, t.faces, t.euler, t.genus),
        (2, 2, 2, 2, 0)
    );
    // The two faces traverse the loop in opposite directions.
    let faces: Vec<_> = net.faces().map(|(_, f)| f.uses.clone()).collect();
    for u in &faces[0] {
        let v = faces[1].iter().find(|x| x.edge == u.edge).unwrap();
        assert_ne!(u.reversed, v.reversed);
    }
}

#[test]
fn a_cube_is_a_silhouette_hexagon_two_corners_of_curves_and_a_closure() {
    let h = 0.05;
    let (t1, t2, t3) = ([-h, h, h], [h, -h, h], [h, h, -h]);
    let (b1, b2, b3) = ([h, -h, -h], [-h, h, -h], [-h, -h, h]);
    let (c, c2) = ([h, h, h], [-h, -h, -h]);
    // The silhouette seen along the main diagonal: six cube edges through the six corners other than
    // c and c2, splitting the surface into two halves of three squares.
    let hexagon = polygon(&[t1, b3, t2, b1, t3, b2, t1]);
    let mut net = Network::new();
    insert_boundary(&mut net, curve(&hexagon, 0), &BoundaryOptions::default()).unwrap();
    net.validate().unwrap();
    insert(&mut net, &polygon(&[t2, c, t3]), 1);
    insert(&mut net, &polygon(&[c, t1]), 2);
    let bottom = polygon(&[b3, c2, b2]);
    close(&mut net, &bottom, 3);
    insert(&mut net, &bottom, 3);
    insert(&mut net, &polygon(&[c2, b1]), 4);
    let t = net.topology();
    assert_eq!((t.vertices, t.edges, t.faces, t.boundaries), (8, 12, 6, 0));
    assert_eq!((t.euler, t.genus), (2, 0));
    for (f, face) in net.faces() {
        assert_eq!(face.uses.len(), 4, "face {f} is not a square");
    }
    // Every vertex is a cube corner with three edges.
    for (v, vx) in net.vertices() {
        assert_eq!(vx.edges.len(), 3, "vertex {v}");
        assert!(vx.position.iter().all(|c| (c.abs() - h).abs() < 1e-12));
    }
}

#[test]
fn refused_closures_leave_the_network_unchanged() {
    let mut net = Network::new();
    insert_boundary(&mut net, curve(&equator(), 0), &BoundaryOptions::default()).unwrap();
    insert(&mut net, &arc(Y, N, MY), 1);
    let before = net.clone();
    // An end 20 mm off the boundary.
    let off = polygon(&[[0.0, R, 0.0], [0.0, 0.0, -R], [0.0, -R + 0.02, -0.02]]);
    match close_boundary(&mut net, curve(&off, 2), &CloseOptions::default()) {
        Err(e @ ToolError::NotOnBoundary { .. }) => {
            assert_eq!(e.rule(), "ends on a boundary");
            assert!(e.distance_mm().unwrap() > 19.0);
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(net, before);
    // A second, disjoint boundary: a curve from one loop to the other is refused.
    let other: Vec<[f64; 3]> = equator().iter().map(|p| [p[0] + 0.5, p[1], p[2]]).collect();
    insert_boundary(&mut net, curve(&other, 5), &BoundaryOptions::default()).unwrap();
    let before = net.clone();
    let across = polygon(&[[R, 0.0, 0.0], [0.5 - R, 0.0, 0.0]]);
    match close_boundary(&mut net, curve(&across, 6), &CloseOptions::default()) {
        Err(e @ ToolError::DifferentBoundaries { .. }) => {
            assert_eq!(e.rule(), "one boundary loop")
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(net, before);
    // A closed network has no boundary left to close.
    let mut closed = sphere();
    let before = closed.clone();
    let e = close_boundary(
        &mut closed,
        curve(&arc(Y, S, MY), 9),
        &CloseOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(e, ToolError::NotOnBoundary { distance_mm, .. } if distance_mm.is_infinite()));
    assert_eq!(closed, before);
}

#[test]
fn undo_and_redo_of_a_closure_are_exact() {
    let mut net = Network::new();
    insert_boundary(&mut net, curve(&equator(), 0), &BoundaryOptions::default()).unwrap();
    insert(&mut net, &arc(Y, N, MY), 1);
    let before = net.clone();
    let (_, t) =
        close_boundary(&mut net, curve(&arc(Y, S, MY), 2), &CloseOptions::default()).unwrap();
    let after = net.clone();
    net.undo(&t);
    assert_eq!(net, before);
    net.redo(&t);
    assert_eq!(net, after);
    net.validate().unwrap();
}

#[test]
fn a_journal_with_a_closure_replays_bit_for_bit() {
    use fires_recon::network::{replay, Journal, Step, StrokeInput};
    let south = arc(Y, S, MY);
    let strokes: Vec<StrokeInput> = [
        equator(),
        arc(Y, N, MY),
        quarter(N, X),
        quarter(N, MX),
        south,
        quarter(S, X),
        quarter(S, MX),
    ]
    .into_iter()
    .enumerate()
    .map(|(i, points)| StrokeInput {
        id: i as u32,
        points,
        closed: i == 0,
        sigma_mm: None,
        mode: 0,
        untracked_mm: [0.0; 2],
    })
    .collect();
    let insert = |stroke| Step::Insert {
        stroke,
        options: InsertOptions::default(),
        mirror: false,
    };
    let journal = Journal {
        steps: vec![
            Step::Boundary {
                stroke: 0,
                close_mm: 10.0,
                mirror: false,
            },
            insert(1),
            insert(2),
            insert(3),
            Step::Close {
                stroke: 4,
                options: CloseOptions::default(),
            },
            insert(4),
            insert(5),
            insert(6),
        ],
        ..Journal::default()
    };
    let text = serde_json::to_string(&journal).unwrap();
    assert!(text.contains(r#""tool":"close""#), "{text}");
    let back: Journal = serde_json::from_str(&text).unwrap();
    assert_eq!(back, journal);
    let net = replay(&back, &strokes).unwrap();
    assert_eq!(net, sphere());
    assert_eq!(net.topology().euler, 2);
}
