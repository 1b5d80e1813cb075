//! Hole creation with and without crossings (FIRES thesis §5.2.2): invariants after every step, Euler
//! bookkeeping, transactional failures, the foot-point Newton solve, journal replay and the pen mode.

mod common;

use common::disc::{circle, line, vertical, Rng, B, R, Z};
use fires_recon::geometry::Vec3;
use fires_recon::network::tools::{
    create_hole, glue_borders, insert_boundary, insert_curve, BoundaryOptions, CurveInput,
    GlueOptions, HoleKind, HoleOptions, HoleReport, InsertOptions, ToolError,
};
use fires_recon::network::{
    build_network, replay, BuildOptions, FaceId, Journal, Network, NetworkFile, Origin, Step,
    StrokeInput,
};
use fires_recon::surface::{CoonsPatch, FootPointOptions, FootPointSolver, Side};
use std::f64::consts::PI;

fn disc() -> Network {
    let mut net = Network::new();
    let c = circle(400);
    insert_boundary(&mut net, CurveInput::new(&c), &BoundaryOptions::default()).unwrap();
    net.validate().unwrap();
    net
}

/// A closed circle of radius `r` about (cx, cy) in the disc's plane, `n` points, the last a copy of the
/// first, counter-clockwise (or clockwise).
fn ring(cx: f64, cy: f64, r: f64, n: usize, ccw: bool) -> Vec<[f64; 3]> {
    (0..=n)
        .map(|i| {
            let a = 2.0 * PI * i as f64 / n as f64 * if ccw { 1.0 } else { -1.0 };
            [cx + r * a.cos(), cy + r * a.sin(), Z]
        })
        .collect()
}

fn insert(net: &mut Network, pts: &[[f64; 3]]) {
    insert_curve(net, CurveInput::new(pts), &InsertOptions::default()).unwrap();
    net.validate().unwrap();
}

/// Applies a hole; checks validate() and that a refusal leaves the network bit for bit unchanged.
fn hole(net: &mut Network, pts: &[[f64; 3]]) -> Result<HoleReport, ToolError> {
    let before = net.clone();
    let before_json = NetworkFile::to_json(net);
    let r = create_hole(
        net,
        CurveInput {
            points: pts,
            stroke: Some(7),
            sigma_mm: None,
            untracked_mm: [0.0; 2],
        },
        &HoleOptions::default(),
    );
    net.validate().unwrap();
    if r.is_err() {
        assert_eq!(*net, before, "a refused hole changed the network");
        assert_eq!(NetworkFile::to_json(net), before_json);
    }
    r.map(|x| x.0)
}

fn counts(net: &Network) -> (i64, i64, i64) {
    let t = net.topology();
    (t.vertices as i64, t.edges as i64, t.faces as i64)
}

#[test]
fn foot_point_reproduces_bilinear_parameters_to_1e_12() {
    // A twisted (non-planar) bilinear patch, 1 m across.
    let p00 = Vec3::new(0.0, 0.0, 0.0);
    let p10 = Vec3::new(1.0, 0.1, 0.3);
    let p01 = Vec3::new(-0.1, 1.0, -0.2);
    let p11 = Vec3::new(1.2, 0.9, 0.5);
    let patch = CoonsPatch::new(
        Side::new(vec![p00, p10]),
        Side::new(vec![p10, p11]),
        Side::new(vec![p01, p11]),
        Side::new(vec![p00, p01]),
    );
    let solver = FootPointSolver::new(&patch, &FootPointOptions::default());
    let mut rng = Rng(0x5eed_0002);
    let (mut worst_on, mut worst_off, mut most_iter) = (0.0f64, 0.0f64, 0);
    for _ in 0..500 {
        let (u0, v0) = (rng.range(0.02, 0.98), rng.range(0.02, 0.98));
        let [x, xu, xv, _] = patch.eval_derivatives(u0, v0);
        // On the patch.
        let f = solver.solve(x);
        assert!(f.converged);
        worst_on = worst_on.max((f.u - u0).abs().max((f.v - v0).abs()));
        most_iter = most_iter.max(f.iterations);
        // Off the patch along its normal: (u0, v0) is still the foot point (the residual is normal to
        // x_u and x_v), 5 mm away, well inside the radius of curvature.
        let n = xu.cross(xv).try_normalize().unwrap();
        let f = solver.solve(x + n * 0.005);
        assert!(f.converged);
        assert!((f.distance - 0.005).abs() < 1e-12);
        worst_off = worst_off.max((f.u - u0).abs().max((f.v - v0).abs()));
    }
    println!(
        "foot point: max |Δ(u,v)| on {worst_on:e}, off {worst_off:e}, most iterations {most_iter}"
    );
    assert!(worst_on <= 1e-12, "on the patch: {worst_on:e}");
    assert!(worst_off <= 1e-12, "off the patch: {worst_off:e}");
    // Beyond the border: the parameters of the projection onto the border, clamped.
    let f = solver.solve(patch.eval(0.5, 0.0) + Vec3::new(0.0, -0.3, 0.0));
    assert_eq!(f.v, 0.0);
    assert!((0.0..=1.0).contains(&f.u));
}

#[test]
fn a_hole_without_crossings_in_a_disc_adds_a_boundary_and_keeps_genus_0() {
    let mut net = disc();
    let (cx, cy, r) = (0.012, -0.006, 0.03);
    for ccw in [true, false] {
        let mut net = net.clone();
        let drawn = ring(cx, cy, r, 120, ccw);
        let rep = hole(&mut net, &drawn).unwrap();
        let t = net.topology();
        // The boundary face has n = 2 sides: ΔV = n, ΔE = 2n, ΔF = n − 1.
        assert_eq!((t.vertices, t.edges, t.faces), (4, 6, 2));
        assert_eq!((t.boundaries, t.components, t.euler, t.genus), (2, 1, 0, 0));
        let HoleKind::Spokes {
            sides,
            max_distance_mm,
            ..
        } = rep.kind
        else {
            panic!("expected spokes: {:?}", rep.kind)
        };
        assert_eq!(sides, 2);
        assert!(max_distance_mm < 1e-9, "planar face: {max_distance_mm}");
        assert_eq!((rep.spokes.len(), rep.hole_edges.len()), (2, 2));
        // The hole's edges are the drawn curve: each point on the drawn polygon, and they have one face.
        for &e in &rep.hole_edges {
            assert_eq!(net.edge(e).unwrap().faces.len(), 1);
            let p = net.edge_polyline(e).unwrap();
            assert_eq!(p.attrs.origin, Origin::User);
            assert_eq!(p.attrs.stroke, Some(7));
            for q in &p.points {
                let d = ((q[0] - cx).powi(2) + (q[1] - cy).powi(2)).sqrt();
                assert!(d <= r + 1e-12 && d >= r * (PI / 120.0).cos() - 1e-12);
                assert_eq!(q[2], Z);
            }
        }
        // The spokes lie on the face's (planar) Coons patch and outside the hole but for their end.
        for &e in &rep.spokes {
            let p = net.edge_polyline(e).unwrap();
            assert_eq!(p.attrs.origin, Origin::Generated);
            for q in &p.points[..p.points.len() - 1] {
                assert!((q[2] - Z).abs() < 1e-12);
                let d = ((q[0] - cx).powi(2) + (q[1] - cy).powi(2)).sqrt();
                assert!(
                    d > r * (PI / 120.0).cos() - 1e-9,
                    "spoke point inside the hole"
                );
                assert!((q[0] / R).powi(2) + (q[1] / B).powi(2) <= 1.0 + 1e-9);
            }
        }
    }
    // The same drawing twice gives the same network (deterministic), and the hole can be undone.
    let before = net.clone();
    let drawn = ring(cx, cy, r, 120, true);
    let (_, t) = create_hole(&mut net, CurveInput::new(&drawn), &HoleOptions::default()).unwrap();
    let after = net.clone();
    net.undo(&t);
    assert_eq!(net, before);
    net.redo(&t);
    assert_eq!(net, after);
    net.validate().unwrap();
}

#[test]
fn every_face_of_a_grid_takes_a_hole_with_n_spokes() {
    // Faces of 3, 4 and 5 sides: two vertical chords and a horizontal one crossing both.
    let mut base = disc();
    insert(&mut base, &vertical(-0.05));
    insert(&mut base, &vertical(0.05));
    let yl = 0.02;
    let xl = R * (1.0 - (yl / B).powi(2)).sqrt();
    insert(&mut base, &line([-xl, yl, Z], [xl, yl, Z], 0.002));
    let faces: Vec<FaceId> = base.faces().map(|(f, _)| f).collect();
    let mut seen = std::collections::BTreeSet::new();
    for f in faces {
        let n = base.face(f).unwrap().uses.len() as i64;
        seen.insert(n);
        let pts = base.face_points(f);
        let c = pts
            .iter()
            .fold([0.0; 3], |a, p| [a[0] + p[0], a[1] + p[1], a[2] + p[2]]);
        let c = [c[0] / pts.len() as f64, c[1] / pts.len() as f64];
        let near = pts
            .iter()
            .map(|p| ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2)).sqrt())
            .fold(f64::INFINITY, f64::min);
        let mut net = base.clone();
        let (v0, e0, f0) = counts(&net);
        let b0 = net.topology().boundaries;
        let rep = hole(&mut net, &ring(c[0], c[1], 0.4 * near, 90, true))
            .unwrap_or_else(|e| panic!("face {f} ({n} sides): {e}"));
        assert!(
            matches!(rep.kind, HoleKind::Spokes { face, sides, .. } if face == f && sides as i64 == n)
        );
        let (v1, e1, f1) = counts(&net);
        assert_eq!(
            (v1 - v0, e1 - e0, f1 - f0),
            (n, 2 * n, n - 1),
            "face {f}, {n} sides"
        );
        let t = net.topology();
        assert_eq!((t.boundaries, t.genus), (b0 + 1, 0));
    }
    assert!(
        seen.contains(&3) && seen.contains(&4),
        "sides seen: {seen:?}"
    );
}

#[test]
fn a_hole_with_crossings_cuts_the_faces_inside() {
    let mut net = disc();
    insert(&mut net, &vertical(0.0));
    assert_eq!(counts(&net), (4, 5, 2));
    let (cx, cy, r) = (0.0, 0.01, 0.03);
    let before = net.clone();
    let rep = hole(&mut net, &ring(cx, cy, r, 120, true)).unwrap();
    assert_eq!(rep.kind, HoleKind::Cut { crossings: 2 });
    assert_eq!(
        (rep.removed_faces, rep.removed_edges, rep.removed_vertices),
        (2, 1, 0)
    );
    // Insertion of the loop: +2 V, +4 E, +2 F; removal of the inside: −2 F, −1 E.
    assert_eq!(counts(&net), (6, 8, 2));
    let t = net.topology();
    assert_eq!((t.boundaries, t.euler, t.genus), (2, 0, 0));
    // Nothing is left inside the hole.
    for (_, p) in net.polylines() {
        for q in &p.points {
            let d = ((q[0] - cx).powi(2) + (q[1] - cy).powi(2)).sqrt();
            assert!(
                d >= r * (PI / 120.0).cos() - 1e-3,
                "a point {d} m from the hole's centre"
            );
        }
    }
    // One transaction: undo gives the network before, bit for bit.
    let mut again = before.clone();
    let (_, t) = create_hole(
        &mut again,
        CurveInput {
            points: &ring(cx, cy, r, 120, true),
            stroke: Some(7),
            sigma_mm: None,
            untracked_mm: [0.0; 2],
        },
        &HoleOptions::default(),
    )
    .unwrap();
    assert_eq!(again, net);
    again.undo(&t);
    assert_eq!(again, before);
    again.redo(&t);
    assert_eq!(again, net);
}

#[test]
fn refused_holes_name_their_rule_and_change_nothing() {
    let mut net = disc();
    // Not closed.
    let open: Vec<[f64; 3]> = ring(0.0, 0.0, 0.03, 120, true)[..100].to_vec();
    let e = hole(&mut net, &open).unwrap_err();
    assert_eq!(e.rule(), "closed boundary");
    // Far above the surface: in no face.
    let high: Vec<[f64; 3]> = ring(0.0, 0.0, 0.03, 120, true)
        .into_iter()
        .map(|p| [p[0], p[1], p[2] + 0.2])
        .collect();
    let e = hole(&mut net, &high).unwrap_err();
    assert_eq!(e.rule(), "hole inside one face");
    assert!(e.distance_mm().unwrap() > 150.0);
    // Across the border: curve insertion refuses the pieces outside the surface (rule 2).
    let e = hole(&mut net, &ring(0.09, 0.0, 0.03, 120, true)).unwrap_err();
    assert_eq!(e.rule(), "rule 2: crossings intersect");
    // A crescent: its centroid is outside it.
    let mut crescent: Vec<[f64; 3]> = (0..=60)
        .map(|i| {
            let a = -0.45 * PI + 0.9 * PI * i as f64 / 60.0;
            [0.04 * a.cos(), 0.04 * a.sin(), Z]
        })
        .collect();
    crescent.extend((0..=60).map(|i| {
        let a = 0.45 * PI - 0.9 * PI * i as f64 / 60.0;
        [0.01 + 0.035 * a.cos(), 0.035 * a.sin(), Z]
    }));
    crescent.push(crescent[0]);
    let e = hole(&mut net, &crescent).unwrap_err();
    assert_eq!(e.rule(), "hole is convex");
    // And the network still takes a good hole.
    hole(&mut net, &ring(0.0, 0.0, 0.03, 120, true)).unwrap();
    // A cut that snaps onto a vertex of an earlier hole's border (1.5 mm from it) after crossing that
    // hole's spoke: refused inside the transaction, after the splits and the removal, and rolled back.
    let mut net = disc();
    hole(&mut net, &ring(-0.04, 0.0, 0.02, 100, true)).unwrap();
    let e = hole(&mut net, &ring(0.0, 0.0, 0.0185, 100, true)).unwrap_err();
    assert_eq!(e.rule(), "hole keeps clear of the border", "{e}");
}

#[test]
fn two_holes_in_a_disc() {
    // Both without crossings: the second hole lies in one of the first one's two faces (a 4-gon).
    let mut net = disc();
    hole(&mut net, &ring(-0.04, 0.0, 0.02, 100, true)).unwrap();
    let rep = hole(&mut net, &ring(0.03, 0.05, 0.015, 100, false)).unwrap();
    assert!(matches!(rep.kind, HoleKind::Spokes { sides: 4, .. }));
    let t = net.topology();
    assert_eq!((t.vertices, t.edges, t.faces), (8, 14, 5));
    assert_eq!(
        (t.boundaries, t.components, t.euler, t.genus),
        (3, 1, -1, 0)
    );
    // The second across a spoke of the first: the crossing case, through generated curves.
    let mut net = disc();
    hole(&mut net, &ring(-0.04, 0.0, 0.02, 100, true)).unwrap();
    let rep = hole(&mut net, &ring(0.05, 0.0, 0.015, 100, true)).unwrap();
    assert_eq!(rep.kind, HoleKind::Cut { crossings: 2 });
    let t = net.topology();
    assert_eq!((t.boundaries, t.components, t.genus), (3, 1, 0));
}

#[test]
fn two_holes_glued_give_a_handle() {
    // Thesis §5.1.3: two holes in a disc, their borders glued, make a torus with one boundary.
    let mut net = disc();
    hole(&mut net, &ring(-0.04, 0.0, 0.02, 100, true)).unwrap();
    hole(&mut net, &ring(0.03, 0.05, 0.015, 100, false)).unwrap();
    // One marker curve from hole A's border to hole B's: the whole loops are glued.
    let marker = line(
        [-0.02, 0.0, Z],
        [0.03 - 0.015 * 0.6, 0.05 - 0.015 * 0.8, Z],
        0.002,
    );
    glue_borders(
        &mut net,
        CurveInput::new(&marker),
        None,
        &GlueOptions::default(),
    )
    .unwrap();
    net.validate().unwrap();
    let t = net.topology();
    assert_eq!(
        (t.boundaries, t.components, t.euler, t.genus),
        (1, 1, -1, 1),
        "{t:?}"
    );
}

fn strokes() -> Vec<StrokeInput> {
    let s = |id, points, closed, mode| StrokeInput {
        id,
        points,
        closed,
        sigma_mm: None,
        mode,
        untracked_mm: [0.0; 2],
    };
    vec![
        s(0, circle(400), true, 0),
        s(1, vertical(0.0), false, 0),
        s(2, ring(0.0, 0.01, 0.03, 120, true), true, 3),
        s(3, ring(0.055, -0.02, 0.015, 90, true), true, 3),
    ]
}

fn with_id(s: &StrokeInput) -> CurveInput<'_> {
    CurveInput {
        points: &s.points,
        stroke: Some(s.id),
        sigma_mm: None,
        untracked_mm: [0.0; 2],
    }
}

#[test]
fn holes_replay_from_the_journal_bit_for_bit() {
    let strokes = strokes();
    let mut net = Network::new();
    let opts = HoleOptions::default();
    insert_boundary(&mut net, with_id(&strokes[0]), &BoundaryOptions::default()).unwrap();
    insert_curve(&mut net, with_id(&strokes[1]), &InsertOptions::default()).unwrap();
    for s in &strokes[2..] {
        let c = CurveInput {
            points: &s.points,
            stroke: Some(s.id),
            sigma_mm: None,
            untracked_mm: [0.0; 2],
        };
        create_hole(&mut net, c, &opts).unwrap();
        net.validate().unwrap();
    }
    let journal = Journal {
        steps: vec![
            Step::Boundary {
                stroke: 0,
                close_mm: 10.0,
                mirror: false,
            },
            Step::Insert {
                stroke: 1,
                options: InsertOptions::default(),
                mirror: false,
            },
            Step::Hole {
                stroke: 2,
                options: opts.clone(),
            },
            Step::Hole {
                stroke: 3,
                options: opts.clone(),
            },
        ],
        ..Journal::default()
    };
    let text = serde_json::to_string(&journal).unwrap();
    assert!(text.contains(r#""tool":"hole""#));
    let back: Journal = serde_json::from_str(&text).unwrap();
    assert_eq!(back, journal);
    let replayed = replay(&back, &strokes).unwrap();
    assert!(replayed == net, "the replay differs");
    assert_eq!(NetworkFile::to_json(&replayed), NetworkFile::to_json(&net));
    // A hole step with no options takes the defaults.
    let bare: Step = serde_json::from_str(r#"{"tool":"hole","stroke":2}"#).unwrap();
    assert_eq!(
        bare,
        Step::Hole {
            stroke: 2,
            options: HoleOptions::default()
        }
    );
}

#[test]
fn pen_mode_3_makes_holes_when_building_from_strokes() {
    let strokes = strokes();
    let (net, report) = build_network(&strokes, &BuildOptions::default());
    net.validate().unwrap();
    assert_eq!(report.boundary, Some(0));
    assert_eq!(report.used, vec![0, 1, 2, 3]);
    assert!(report.rejected.is_empty(), "{:?}", report.rejected);
    assert_eq!(report.topology.boundaries, 3);
    assert_eq!(report.topology.genus, 0);
    assert!(report
        .journal
        .steps
        .iter()
        .any(|s| matches!(s, Step::Hole { stroke: 3, .. })));
    assert_eq!(replay(&report.journal, &strokes).unwrap(), net);
    // A closed hole-mode stroke is never the boundary.
    let mut first_hole = strokes.clone();
    first_hole.swap(0, 2);
    let (_, report) = build_network(&first_hole, &BuildOptions::default());
    assert_eq!(report.boundary, Some(0));
}

/// The benchmark's network of exactly 100 faces: a circle of radius 0.2 m with 9 + 9 lines 30 mm apart.
fn hundred_faces() -> Network {
    let (drawing, _) = common::disc::grid_drawing(0.2, 9, 0.03, 0, 0.003);
    let strokes: Vec<StrokeInput> = drawing
        .into_iter()
        .enumerate()
        .map(|(id, (points, closed))| StrokeInput {
            id: id as u32,
            points,
            closed,
            sigma_mm: None,
            mode: 0,
            untracked_mm: [0.0; 2],
        })
        .collect();
    let (net, report) = build_network(&strokes, &BuildOptions::default());
    assert_eq!(report.topology.faces, 100);
    net
}

#[test]
fn random_holes_keep_the_invariants_and_the_bookkeeping() {
    let mut net = hundred_faces();
    let mut rng = Rng(0x401e_5eed);
    let (mut spokes, mut cuts, mut refused) = (0, 0, 0);
    for _ in 0..60 {
        // Half the holes anywhere (mostly crossing curves), half near a grid cell's centre and small
        // enough to cross nothing.
        let (cx, cy, r) = if rng.unit() < 0.5 {
            (
                rng.range(-0.15, 0.15),
                rng.range(-0.15, 0.15),
                rng.range(0.003, 0.025),
            )
        } else {
            let cell = |u: f64| -0.105 + 0.03 * (u * 8.0).floor().min(7.0);
            (
                cell(rng.unit()) + rng.range(-0.003, 0.003),
                cell(rng.unit()) + rng.range(-0.003, 0.003),
                rng.range(0.003, 0.006),
            )
        };
        let before = net.topology();
        match hole(&mut net, &ring(cx, cy, r, 80, rng.unit() < 0.5)) {
            Ok(rep) => {
                let t = net.topology();
                assert_eq!(
                    t.genus, 0,
                    "hole ({cx}, {cy}) r {r}: {:?}\n{before:?}\n{t:?}",
                    rep.kind
                );
                match rep.kind {
                    HoleKind::Spokes { sides, .. } => {
                        let n = sides as i64;
                        let d = (
                            t.vertices as i64 - before.vertices as i64,
                            t.edges as i64 - before.edges as i64,
                            t.faces as i64 - before.faces as i64,
                        );
                        assert_eq!(d, (n, 2 * n, n - 1));
                        assert_eq!(t.boundaries, before.boundaries + 1);
                        spokes += 1;
                    }
                    HoleKind::Cut { crossings } => {
                        assert!(crossings >= 2);
                        cuts += 1;
                    }
                }
            }
            Err(_) => refused += 1,
        }
    }
    let t = net.topology();
    println!("random holes: {spokes} with spokes, {cuts} cut, {refused} refused; now {t:?}");
    assert!(spokes >= 5 && cuts >= 5, "{spokes} spokes, {cuts} cuts");
}

#[test]
#[ignore = "benchmark: run in release with --ignored --nocapture"]
fn bench_hole_on_100_faces() {
    let net = hundred_faces();
    let cases = [
        ("hole_spokes", ring(0.015, 0.015, 0.008, 80, true)),
        ("hole_cut", ring(0.0, 0.0, 0.012, 80, true)),
    ];
    for (name, c) in &cases {
        let mut times = Vec::new();
        let mut kind = None;
        for _ in 0..51 {
            let mut n = net.clone();
            let t0 = std::time::Instant::now();
            let (r, _) = create_hole(&mut n, CurveInput::new(c), &HoleOptions::default()).unwrap();
            times.push(t0.elapsed().as_secs_f64() * 1e3);
            kind = Some(r.kind);
        }
        times.sort_by(f64::total_cmp);
        println!(
            "{{\"tool\":\"{name}\",\"faces\":100,\"points\":{},\"median_ms\":{:.4},\"kind\":\"{:?}\"}}",
            c.len(),
            times[times.len() / 2],
            kind
        );
    }
}

#[test]
fn foot_points_on_a_curved_patch_are_local_minima() {
    // Four circular arcs (piecewise-linear sides with many knots) bounding a dome-like patch.
    let arc = |a0: f64, a1: f64, z: f64| -> Vec<Vec3> {
        (0..=40)
            .map(|i| {
                let a = a0 + (a1 - a0) * i as f64 / 40.0;
                Vec3::new(a.cos(), a.sin(), z + 0.3 * (2.0 * a).cos())
            })
            .collect()
    };
    let q = PI / 2.0;
    let patch = CoonsPatch::from_loop([
        arc(-q * 1.5, -q * 0.5, 0.0),
        arc(-q * 0.5, q * 0.5, 0.0),
        arc(q * 0.5, q * 1.5, 0.0),
        arc(q * 1.5, q * 2.5, 0.0),
    ]);
    let solver = FootPointSolver::new(&patch, &FootPointOptions::default());
    let mut rng = Rng(0xc00e_5002);
    let mut most = 0;
    for _ in 0..300 {
        let (u0, v0) = (rng.range(0.05, 0.95), rng.range(0.05, 0.95));
        let c = patch.eval(u0, v0) + Vec3::new(rng.range(-0.05, 0.05), rng.range(-0.05, 0.05), 0.1);
        let f = solver.solve(c);
        most = most.max(f.iterations);
        assert!(f.converged, "({u0}, {v0}) -> {f:?}");
        assert!(((patch.eval(f.u, f.v) - c).norm() - f.distance).abs() < 1e-15);
        // No nearby parameter is closer (by more than rounding).
        for (du, dv) in [(1e-4, 0.0), (-1e-4, 0.0), (0.0, 1e-4), (0.0, -1e-4)] {
            let (u, v) = ((f.u + du).clamp(0.0, 1.0), (f.v + dv).clamp(0.0, 1.0));
            let d = (patch.eval(u, v) - c).norm();
            assert!(
                d >= f.distance - 1e-12,
                "{f:?}: ({du}, {dv}) is {:e} closer",
                f.distance - d
            );
        }
    }
    // A minimum on a knot line (a kink) takes the 2-D iterations, then the 1-D ones on the line.
    println!("curved patch: most Newton iterations {most}");
}

#[test]
fn a_hole_in_a_saddle_shaped_face() {
    // A boundary on the saddle z = Z + h (x²/R² − y²/B²); the hole drawn on the saddle.
    let h = 0.02;
    let saddle = |x: f64, y: f64| Z + h * ((x / R).powi(2) - (y / B).powi(2));
    let boundary: Vec<[f64; 3]> = circle(400)
        .into_iter()
        .map(|p| [p[0], p[1], saddle(p[0], p[1])])
        .collect();
    let mut net = Network::new();
    insert_boundary(
        &mut net,
        CurveInput::new(&boundary),
        &BoundaryOptions::default(),
    )
    .unwrap();
    let drawn: Vec<[f64; 3]> = ring(0.01, -0.01, 0.03, 120, true)
        .into_iter()
        .map(|p| [p[0], p[1], saddle(p[0], p[1])])
        .collect();
    let rep = hole(&mut net, &drawn).unwrap();
    let HoleKind::Spokes {
        sides,
        max_distance_mm,
        newton_iterations,
        ..
    } = rep.kind
    else {
        panic!("expected spokes")
    };
    println!("saddle: hole ≤ {max_distance_mm:.3} mm from the Coons patch, ≤ {newton_iterations} Newton iterations");
    assert_eq!(sides, 2);
    assert!(max_distance_mm > 0.0 && max_distance_mm < 5.0);
    let t = net.topology();
    assert_eq!(
        (t.vertices, t.edges, t.faces, t.boundaries, t.genus),
        (4, 6, 2, 2, 0)
    );
    // The spokes run from a boundary vertex to a point of the drawn hole, near the saddle.
    for &e in &rep.spokes {
        let p = &net.edge_polyline(e).unwrap().points;
        let end = p[p.len() - 1];
        assert!(drawn.windows(2).any(|w| {
            let (a, b) = (w[0], w[1]);
            let ab = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let ap = [end[0] - a[0], end[1] - a[1], end[2] - a[2]];
            let l2 = ab.iter().map(|x| x * x).sum::<f64>();
            let t = (ab.iter().zip(&ap).map(|(x, y)| x * y).sum::<f64>() / l2).clamp(0.0, 1.0);
            (0..3)
                .map(|k| (ap[k] - t * ab[k]).powi(2))
                .sum::<f64>()
                .sqrt()
                < 1e-12
        }));
        for q in p {
            assert!(
                (q[2] - saddle(q[0], q[1])).abs() < 0.005,
                "spoke off the saddle"
            );
        }
    }
}

#[test]
fn pen_modes_make_a_handle_and_a_tube_that_replay() {
    // Modes 3 (hole) and 4 (glue): a disc, two holes, one marker between their borders.
    let s = |id, points, closed, mode| StrokeInput {
        id,
        points,
        closed,
        sigma_mm: None,
        mode,
        untracked_mm: [0.0; 2],
    };
    let marker = line([-0.02, 0.0, Z], [0.021, 0.038, Z], 0.002);
    let strokes = vec![
        s(0, circle(400), true, 0),
        s(1, ring(-0.04, 0.0, 0.02, 100, true), true, 3),
        s(2, marker, false, 4),
        s(3, ring(0.03, 0.05, 0.015, 100, false), true, 3),
    ];
    let (net, report) = build_network(&strokes, &BuildOptions::default());
    net.validate().unwrap();
    assert!(report.rejected.is_empty(), "{:?}", report.rejected);
    let t = report.topology;
    assert_eq!((t.boundaries, t.genus), (1, 1), "{t:?}");
    assert_eq!(replay(&report.journal, &strokes).unwrap(), net);

    // Mode 5 (skin): three circular profiles and two straight spines make an open tube.
    let profile = |z: f64| -> Vec<[f64; 3]> {
        (0..=120)
            .map(|i| {
                let a = 2.0 * PI * i as f64 / 120.0;
                [0.03 * a.cos(), 0.03 * a.sin(), z]
            })
            .collect()
    };
    let spine = |x: f64| line([x, 0.0, -0.01], [x, 0.0, 0.11], 0.002);
    let strokes = vec![
        s(0, profile(0.0), true, 5),
        s(1, profile(0.05), true, 5),
        s(2, profile(0.1), true, 5),
        s(3, spine(0.03), false, 5),
        s(4, spine(-0.03), false, 5),
    ];
    let (net, report) = build_network(&strokes, &BuildOptions::default());
    net.validate().unwrap();
    assert!(report.rejected.is_empty(), "{:?}", report.rejected);
    let t = report.topology;
    assert_eq!(
        (t.faces, t.boundaries, t.euler, t.genus),
        (4, 2, 0, 0),
        "{t:?}"
    );
    assert_eq!(replay(&report.journal, &strokes).unwrap(), net);
    // One spine too few: every skin-mode stroke is reported.
    let (_, report) = build_network(&strokes[..4], &BuildOptions::default());
    assert_eq!(report.rejected.len(), 4);
}
