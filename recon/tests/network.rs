//! The curve network: polyline mesh invariants, Euler bookkeeping and the boundary and curve-insertion
//! tools (FIRES thesis §3.3 and §5.1–5.2.1).

mod common;

use common::disc::{chord, circle, vertical, Rng, Z};
use fires_recon::network::tools::{
    insert_boundary, insert_curve, Adjustment, BoundaryOptions, CurveInput, End, InsertOptions,
    ToolError,
};
use fires_recon::network::{Network, NetworkFile, NetworkFileError};
use std::f64::consts::{PI, TAU};

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn disc() -> Network {
    let mut net = Network::new();
    let c = circle(400);
    insert_boundary(&mut net, CurveInput::new(&c), &BoundaryOptions::default()).unwrap();
    net.validate().unwrap();
    net
}

fn insert(
    net: &mut Network,
    pts: &[[f64; 3]],
) -> Result<fires_recon::network::tools::InsertReport, ToolError> {
    let before = net.clone();
    let before_json = NetworkFile::to_json(net);
    let r = insert_curve(net, CurveInput::new(pts), &InsertOptions::default());
    net.validate().unwrap();
    if r.is_err() {
        assert_eq!(*net, before, "a refused insertion changed the network");
        assert_eq!(NetworkFile::to_json(net), before_json);
    }
    r.map(|x| x.0)
}

#[test]
fn boundary_is_one_face_of_two_edges_split_at_the_diameter() {
    let net = disc();
    let t = net.topology();
    assert_eq!((t.vertices, t.edges, t.faces), (2, 2, 1));
    assert_eq!((t.boundaries, t.components, t.euler, t.genus), (1, 1, 1, 0));
    let p: Vec<[f64; 3]> = net.vertices().map(|(_, v)| v.position).collect();
    assert_eq!(
        p,
        vec![[0.1, 0.0, Z], [-0.1, 0.097 * PI.sin(), Z]],
        "split at the ellipse's major axis"
    );
    // An open curve is not a boundary.
    let mut net = Network::new();
    let open = chord(0.0, PI, 0.0);
    let e = insert_boundary(
        &mut net,
        CurveInput::new(&open),
        &BoundaryOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(e, ToolError::NotClosed { gap_mm, .. } if (gap_mm - 200.0).abs() < 1e-6));
    assert_eq!(net, Network::new());
}

#[test]
fn a_loop_whose_start_was_not_tracked_closes_across_the_untracked_length() {
    // A 50 mm circle missing its first 0.3 rad (15 mm of arc, a 14.99 mm chord): over the 10 mm limit as
    // drawn, a boundary once the pen is known to have drawn 16 mm unseen before the first point.
    let pts: Vec<[f64; 3]> = (0..=200)
        .map(|i| 0.3 + (TAU - 0.3) * i as f64 / 200.0)
        .map(|a| [0.05 * a.cos(), 0.05 * a.sin(), Z])
        .collect();
    let mut net = Network::new();
    let e =
        insert_boundary(&mut net, CurveInput::new(&pts), &BoundaryOptions::default()).unwrap_err();
    assert!(
        matches!(e, ToolError::NotClosed { gap_mm, limit_mm } if (gap_mm - 14.97).abs() < 0.05 && limit_mm == 10.0),
        "{e:?}"
    );
    assert_eq!(net, Network::new());
    let curve = CurveInput {
        untracked_mm: [16.0, 0.0],
        ..CurveInput::new(&pts)
    };
    let (r, _) = insert_boundary(&mut net, curve, &BoundaryOptions::default()).unwrap();
    let t = net.topology();
    assert_eq!((t.vertices, t.edges, t.faces, t.boundaries), (2, 2, 1, 1));
    // The loop is the drawn points closed by the chord across the gap.
    let face = net.face_points(r.face);
    let len: f64 = face
        .iter()
        .zip(face.iter().cycle().skip(1))
        .map(|(a, b)| dist(*a, *b))
        .sum();
    let drawn: f64 = pts.windows(2).map(|w| dist(w[0], w[1])).sum();
    assert!(
        (len - drawn - dist(pts[0], pts[200])).abs() < 1e-9,
        "{len} {drawn}"
    );
}

#[test]
fn insertion_across_m_edges_gives_the_thesis_deltas() {
    for m in 1..=5usize {
        let mut net = disc();
        let xs = [-0.05, -0.025, 0.0, 0.025, 0.05];
        for &x in &xs[..m] {
            let before = net.topology();
            insert(&mut net, &vertical(x)).unwrap();
            let after = net.topology();
            assert_eq!(
                (
                    after.vertices - before.vertices,
                    after.edges - before.edges,
                    after.faces - before.faces
                ),
                (2, 3, 1)
            );
        }
        // A chord from 160° to -20° crosses all m verticals.
        let before = net.topology();
        let r = insert(
            &mut net,
            &chord(160f64.to_radians(), -20f64.to_radians(), 0.0),
        )
        .unwrap();
        let after = net.topology();
        assert_eq!(r.crossings, m);
        assert_eq!(r.snapped, 0);
        assert_eq!(after.faces - before.faces, m + 1, "ΔF, m = {m}");
        assert_eq!(after.edges - before.edges, 2 * m + 3, "ΔE, m = {m}");
        assert_eq!(after.vertices - before.vertices, m + 2, "ΔV, m = {m}");
        assert_eq!(after.euler, before.euler);
        assert_eq!((after.boundaries, after.genus), (1, 0));
        assert_eq!(r.edges.len(), m + 1);
        // Every new edge carries the curve's attributes; every face has at least 3 edges.
        assert!(net.faces().all(|(_, f)| f.uses.len() >= 3));
    }
}

#[test]
fn rule_one_same_polyline_is_refused_unchanged() {
    let mut net = disc();
    // Both ends on the top arc (the boundary is split at 0° and 180°), crossing nothing.
    let e = insert(
        &mut net,
        &chord(30f64.to_radians(), 150f64.to_radians(), 0.0),
    )
    .unwrap_err();
    assert!(matches!(e, ToolError::SamePolyline { .. }), "{e}");
    assert_eq!(e.rule(), "rule 1: not on the same polyline");
    // Once a vertical chord separates them the same stroke is fine: it crosses it once.
    insert(&mut net, &vertical(0.0)).unwrap();
    let r = insert(
        &mut net,
        &chord(30f64.to_radians(), 150f64.to_radians(), 0.0),
    )
    .unwrap();
    assert_eq!(r.crossings, 1);
    assert_eq!(net.topology().faces, 4);
}

#[test]
fn rule_two_a_crossing_without_intersection_is_refused_unchanged() {
    let mut net = disc();
    insert(&mut net, &vertical(0.0)).unwrap();
    // From 160° to -20°, lifted 30 mm over the vertical chord in the middle.
    let mut c = chord(160f64.to_radians(), -20f64.to_radians(), 0.0);
    let n = c.len();
    for (i, p) in c.iter_mut().enumerate() {
        p[2] = Z + 0.03 * (PI * i as f64 / (n - 1) as f64).sin();
    }
    let e = insert(&mut net, &c).unwrap_err();
    assert!(matches!(e, ToolError::NoCommonFace { piece: 0, .. }), "{e}");
    // Lowered to 3 mm (within the 5 mm threshold) it intersects.
    for (i, p) in c.iter_mut().enumerate() {
        p[2] = Z + 0.003 * (PI * i as f64 / (n - 1) as f64).sin();
    }
    assert_eq!(insert(&mut net, &c).unwrap().crossings, 1);
}

#[test]
fn ends_off_the_network_are_refused_with_the_distance() {
    let mut net = disc();
    let e = insert(
        &mut net,
        &chord(80f64.to_radians(), -80f64.to_radians(), -0.02),
    )
    .unwrap_err();
    match e {
        ToolError::EndNotOnNetwork {
            end: End::Start,
            distance_mm,
            limit_mm,
        } => {
            // 20 mm back along a chord at 10° to the radius: a little less than 20 mm from the boundary.
            assert!(distance_mm > 18.0 && distance_mm < 20.0, "{distance_mm}");
            assert_eq!(limit_mm, 8.0);
        }
        other => panic!("{other}"),
    }
}

#[test]
fn overshoot_is_trimmed_and_short_stop_extended() {
    let (a0, a1) = (70f64.to_radians(), -110f64.to_radians());
    let mut net = disc();
    let r = insert(&mut net, &chord(a0, a1, 0.015)).unwrap();
    assert_eq!(r.adjustments.len(), 2);
    for a in &r.adjustments {
        assert!(
            matches!(a, Adjustment::Trimmed { length_mm, .. } if (length_mm - 15.0).abs() < 0.01),
            "{a:?}"
        );
    }
    let exact = {
        let mut n = disc();
        insert(&mut n, &chord(a0, a1, 0.0)).unwrap();
        n
    };
    assert_eq!(net.topology(), exact.topology());
    let mut net = disc();
    let r = insert(&mut net, &chord(a0, a1, -0.006)).unwrap();
    assert_eq!(r.adjustments.len(), 2);
    for a in &r.adjustments {
        assert!(
            matches!(a, Adjustment::Extended { gap_mm, .. } if (gap_mm - 6.0).abs() < 0.2),
            "{a:?}"
        );
    }
    assert_eq!(net.topology(), exact.topology());
    // The extended polyline ends on the boundary exactly (validate checks 1e-12) and starts there.
    let e = r.edges[0];
    let p = net.edge_polyline(e).unwrap();
    let q = p.points[0];
    let on_ellipse = (q[0] / 0.1).powi(2) + (q[1] / 0.097).powi(2);
    assert!((on_ellipse - 1.0).abs() < 1e-3, "{on_ellipse}");
}

/// A stroke whose first 26 mm the tracker lost (`untracked_mm`) starts 26 mm inside the disc and
/// crosses a curve 19 mm later: taken as drawn, its start is an overshoot and is trimmed (one face
/// short); told that up to 30 mm went untracked, the insertion continues the start along its tangent
/// to the boundary and the network has the faces of the whole stroke. A shorter untracked length
/// than the gap does not reach the boundary, and the start is trimmed as before.
#[test]
fn an_untracked_start_is_continued_to_the_curve_it_began_on() {
    let whole = common::disc::line([-0.1, 0.0, Z], [0.1, 0.0, Z], 0.002);
    let tracked: Vec<[f64; 3]> = whole.iter().copied().filter(|p| p[0] >= -0.075).collect();
    let build = |untracked: f64| {
        let mut net = disc();
        insert(&mut net, &vertical(-0.055)).unwrap();
        let curve = CurveInput {
            untracked_mm: [untracked, 0.0],
            ..CurveInput::new(&tracked)
        };
        let (r, _) = insert_curve(&mut net, curve, &InsertOptions::default()).unwrap();
        net.validate().unwrap();
        (net, r)
    };
    let exact = {
        let mut n = disc();
        insert(&mut n, &vertical(-0.055)).unwrap();
        insert(&mut n, &whole).unwrap();
        n
    };
    let (trimmed, r) = build(0.0);
    assert_eq!(trimmed.n_faces() + 1, exact.n_faces());
    assert!(
        matches!(
            r.adjustments[..],
            [Adjustment::Trimmed {
                end: End::Start,
                ..
            }]
        ),
        "{r:?}"
    );
    let (short, _) = build(20.0);
    assert_eq!(short.topology(), trimmed.topology());
    let (net, r) = build(30.0);
    assert_eq!(net.topology(), exact.topology());
    assert!(
        matches!(r.adjustments[..], [Adjustment::Extended { end: End::Start, gap_mm }] if (gap_mm - (tracked[0][0] + 0.1) * 1e3).abs() < 1e-6),
        "{r:?}"
    );
}

/// A stroke that ends on a curve a few millimetres from where that curve meets the boundary ends on
/// that curve. Its end (a hair past the curve, as drawn) is within the intersection threshold of the
/// boundary, and nearest the boundary there, but nearer still to the curve: the boundary approach is
/// no meeting of its own (before, the end went onto the boundary, 4.6 mm from the junction, and the
/// curve counted as crossed: one face too many).
#[test]
fn an_end_on_a_curve_near_a_junction_stays_on_that_curve() {
    let mut net = disc();
    // A chord meeting the boundary at about 40 degrees (its arc spans 80 degrees).
    let (a, b) = (
        common::disc::at(40f64.to_radians()),
        common::disc::at(-40f64.to_radians()),
    );
    insert(&mut net, &common::disc::line(a, b, 0.002)).unwrap();
    let faces = net.n_faces();
    // The end: 6 mm along the chord from its start (about 3.9 mm from the boundary), from the left,
    // 0.3 mm past the chord.
    let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
    let p = [
        a[0] + (b[0] - a[0]) * 0.006 / len,
        a[1] + (b[1] - a[1]) * 0.006 / len,
        Z,
    ];
    let start = common::disc::at(190f64.to_radians());
    let d = ((p[0] - start[0]).powi(2) + (p[1] - start[1]).powi(2)).sqrt();
    let end = [
        p[0] + (p[0] - start[0]) * 0.0003 / d,
        p[1] + (p[1] - start[1]) * 0.0003 / d,
        Z,
    ];
    let r = insert(&mut net, &common::disc::line(start, end, 0.002)).unwrap();
    assert_eq!(net.n_faces(), faces + 1, "{r:?}");
    let last = *net
        .edge_polyline(*r.edges.last().unwrap())
        .unwrap()
        .points
        .last()
        .unwrap();
    let off = ((last[0] - p[0]).powi(2) + (last[1] - p[1]).powi(2)).sqrt();
    assert!(off < 1e-3, "ends {off} m from the chord point");
}

#[test]
fn thresholds_widen_with_the_stroke_uncertainty() {
    let c = chord(70f64.to_radians(), -110f64.to_radians(), -0.012);
    let mut net = disc();
    assert!(matches!(
        insert(&mut net, &c),
        Err(ToolError::EndNotOnNetwork { .. })
    ));
    let curve = CurveInput {
        points: &c,
        stroke: Some(7),
        sigma_mm: Some(5.0),
        untracked_mm: [0.0; 2],
    };
    let (r, _) = insert_curve(&mut net, curve, &InsertOptions::default()).unwrap();
    net.validate().unwrap();
    assert!(matches!(r.adjustments[0], Adjustment::Extended { .. }));
    assert!(r
        .edges
        .iter()
        .all(|&e| net.edge_polyline(e).unwrap().attrs.stroke == Some(7)));
}

#[test]
fn a_curve_through_a_vertex_snaps_to_it() {
    let mut net = disc();
    insert(
        &mut net,
        &chord(60f64.to_radians(), 240f64.to_radians(), 0.0),
    )
    .unwrap();
    insert(
        &mut net,
        &chord(120f64.to_radians(), 300f64.to_radians(), 0.0),
    )
    .unwrap();
    assert_eq!(net.topology().faces, 4);
    let before = net.topology();
    // Through the centre, where the two chords cross.
    let r = insert(
        &mut net,
        &chord(88.8f64.to_radians(), 268.8f64.to_radians(), 0.0),
    )
    .unwrap();
    let after = net.topology();
    assert_eq!(r.snapped, 1);
    assert_eq!(r.vertices.len(), 3);
    assert_eq!(after.vertices - before.vertices, 2);
    assert_eq!(after.edges - before.edges, 4);
    assert_eq!(after.faces - before.faces, 2);
}

#[test]
fn undo_and_redo_restore_every_state_bit_for_bit() {
    let mut net = disc();
    let mut states = vec![net.clone()];
    let mut txns = Vec::new();
    for c in [
        vertical(0.0),
        chord(160f64.to_radians(), -20f64.to_radians(), 0.0),
        vertical(0.05),
    ] {
        let (_, t) =
            insert_curve(&mut net, CurveInput::new(&c), &InsertOptions::default()).unwrap();
        txns.push(t);
        states.push(net.clone());
    }
    for (k, t) in txns.iter().enumerate().rev() {
        net.undo(t);
        net.validate().unwrap();
        assert_eq!(net, states[k]);
    }
    for (k, t) in txns.iter().enumerate() {
        net.redo(t);
        net.validate().unwrap();
        assert_eq!(net, states[k + 1]);
    }
}

#[test]
fn network_json_round_trips_and_is_checked() {
    let mut net = disc();
    insert(&mut net, &vertical(0.0)).unwrap();
    insert(
        &mut net,
        &chord(160f64.to_radians(), -20f64.to_radians(), 0.0),
    )
    .unwrap();
    let text = NetworkFile::to_json(&net);
    let back = NetworkFile::parse(&text).unwrap();
    assert_eq!(back, net);
    assert_eq!(NetworkFile::to_json(&back), text);
    // A polyline end moved by 1 µm breaks invariant 2.
    let mut file: NetworkFile = serde_json::from_str(&text).unwrap();
    file.polylines[0].points[0][0] += 1e-6;
    assert!(matches!(
        file.to_network(),
        Err(NetworkFileError::Invalid(_))
    ));
    // A dangling vertex breaks invariant 3; a wrong format is refused.
    let mut file: NetworkFile = serde_json::from_str(&text).unwrap();
    file.vertices[0].edges.pop();
    assert!(file.to_network().is_err());
    let mut file: NetworkFile = serde_json::from_str(&text).unwrap();
    file.format = "x".into();
    assert!(matches!(
        file.to_network(),
        Err(NetworkFileError::NotANetworkFile(_))
    ));
}

#[test]
fn random_tool_sequences_keep_the_invariants() {
    for seed in 1..=6u64 {
        let mut rng = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let mut net = disc();
        let mut ok = 0;
        for _ in 0..60 {
            let a0 = rng.range(0.0, 2.0 * PI);
            let a1 = a0 + rng.range(0.3, 2.0 * PI - 0.3);
            let extra = rng.range(-0.012, 0.02);
            let mut c = chord(a0, a1, extra);
            // Sometimes bend or lift the curve, sometimes add noise.
            let bend = if rng.unit() < 0.3 {
                rng.range(-0.02, 0.02)
            } else {
                0.0
            };
            let lift = if rng.unit() < 0.2 {
                rng.range(0.0, 0.02)
            } else {
                0.0
            };
            let n = c.len();
            for (i, p) in c.iter_mut().enumerate() {
                let s = (PI * i as f64 / (n - 1).max(1) as f64).sin();
                p[0] += bend * s;
                p[2] += lift * s + rng.range(-5e-4, 5e-4);
            }
            let before = net.clone();
            if let Ok((_, t)) =
                insert_curve(&mut net, CurveInput::new(&c), &InsertOptions::default())
            {
                ok += 1;
                net.validate().unwrap();
                // Undo and redo every few tools.
                if rng.unit() < 0.3 {
                    let after = net.clone();
                    net.undo(&t);
                    assert_eq!(net, before, "seed {seed}: undo");
                    net.redo(&t);
                    assert_eq!(net, after, "seed {seed}: redo");
                }
            } else {
                assert_eq!(
                    net, before,
                    "seed {seed}: a refused insertion changed the network"
                );
            }
            net.validate().unwrap();
            let t = net.topology();
            assert_eq!((t.euler, t.boundaries, t.genus), (1, 1, 0), "seed {seed}");
        }
        assert!(ok >= 10, "seed {seed}: only {ok} insertions succeeded");
    }
}

#[test]
fn awkward_curves_are_refused_or_inserted_never_panic() {
    let base = disc();
    let boundary: Vec<[f64; 3]> = base
        .edge_polyline(base.edges().next().unwrap().0)
        .unwrap()
        .points
        .clone();
    let v0 = base.vertices().next().unwrap().1.position;
    let cases: Vec<Vec<[f64; 3]>> = vec![
        vec![],
        vec![[0.0, 0.0, Z]],
        vec![[0.0, 0.0, Z], [f64::NAN, 0.0, Z]],
        vec![[0.0, 0.0, Z]; 5],
        vec![[1e300, 1e300, 1e300], [-1e300, 0.0, 0.0]],
        // Along the boundary itself (tangential overlap).
        boundary[10..120].to_vec(),
        // From a boundary vertex straight across, with repeated points.
        {
            let mut c = chord(0.0, PI * 0.9, 0.0);
            c.insert(1, c[0]);
            c.push(*c.last().unwrap());
            c
        },
        // Starting exactly at the split vertex.
        common::disc::line(v0, [-0.05, -0.08, Z], 0.002),
        // A closed loop inside the disc touching nothing.
        circle(50)
            .iter()
            .map(|p| [p[0] * 0.3, p[1] * 0.3, Z])
            .collect(),
    ];
    for c in &cases {
        let mut net = base.clone();
        let _ = insert(&mut net, c);
        let mut empty = Network::new();
        let r = insert_curve(&mut empty, CurveInput::new(c), &InsertOptions::default());
        assert!(r.is_err());
        assert_eq!(empty, Network::new());
        let _ = insert_boundary(&mut empty, CurveInput::new(c), &BoundaryOptions::default());
        empty.validate().unwrap();
    }
}

#[test]
fn one_long_segment_among_short_ones_does_not_blow_up_the_grid() {
    let mut net = disc();
    // 500 points 1 µm apart, then one diagonal jump across the disc, then 500 more.
    let mut c: Vec<[f64; 3]> = (0..500)
        .map(|i| [0.0, 0.097 - 1e-6 * i as f64, Z])
        .collect();
    c.extend((0..500).map(|i| [0.05 + 1e-6 * i as f64, -0.08, Z + 0.05]));
    let t0 = std::time::Instant::now();
    let _ = insert(&mut net, &c);
    assert!(t0.elapsed().as_secs_f64() < 5.0);
}

#[test]
fn a_closed_curve_round_a_crossing_splits_four_faces() {
    let mut net = disc();
    insert(&mut net, &vertical(0.0)).unwrap();
    insert(
        &mut net,
        &chord(160f64.to_radians(), -20f64.to_radians(), 0.0),
    )
    .unwrap();
    let before = net.topology();
    // A ring of radius 30 mm round the chords' crossing, starting away from both: 4 crossings on 4 edges.
    let ring: Vec<[f64; 3]> = (0..=200)
        .map(|i| {
            let a = 0.5 + 2.0 * PI * i as f64 / 200.0;
            [0.03 * a.cos(), 0.03 * a.sin(), Z]
        })
        .collect();
    let r = insert(&mut net, &ring).unwrap();
    let after = net.topology();
    assert_eq!(r.edges.len(), 4);
    assert_eq!(r.vertices.first(), r.vertices.last());
    assert_eq!(
        (
            after.vertices - before.vertices,
            after.edges - before.edges,
            after.faces - before.faces
        ),
        (4, 8, 4)
    );
    assert_eq!((after.euler, after.boundaries, after.genus), (1, 1, 0));
    // A ring crossing one chord twice would make two-sided faces (rule 1); one touching nothing is refused.
    let mut net = disc();
    insert(&mut net, &vertical(0.0)).unwrap();
    let twice: Vec<[f64; 3]> = ring.iter().map(|p| [p[0] + 0.01, p[1], p[2]]).collect();
    assert!(matches!(
        insert(&mut net, &twice),
        Err(ToolError::SamePolyline { .. })
    ));
    let lone: Vec<[f64; 3]> = ring.iter().map(|p| [p[0] + 0.05, p[1], p[2]]).collect();
    assert!(insert(&mut net, &lone).is_err());
}

/// A disc split by a vertical and a horizontal diameter (4 faces), and a straight curve through
/// `(0, y0)` and `(x1, 0)`: it crosses the vertical diameter `y0` from the centre junction and the
/// horizontal one `x1` from it.
fn across_the_junction(
    y0: f64,
    x1: f64,
) -> (
    Network,
    Result<fires_recon::network::tools::InsertReport, ToolError>,
) {
    let mut net = disc();
    insert(&mut net, &vertical(0.0)).unwrap();
    insert(&mut net, &chord(0.0, PI, 0.0)).unwrap();
    assert_eq!(net.topology().faces, 4);
    let (dx, dy) = (x1, -y0);
    let (a, b) = (-0.105 / dx, 0.105 / dx);
    let c = common::disc::line([a * dx, y0 + a * dy, Z], [b * dx, y0 + b * dy, Z], 0.002);
    let r = insert(&mut net, &c);
    (net, r)
}

#[test]
fn a_curve_crossing_near_a_junction_keeps_its_crossings_where_snapping_would_break_rule_one() {
    // 3 mm from the junction on one curve (within vertex snapping), 10 mm on the other: snapping the
    // first would leave a piece from the junction to an edge at it; both crossings are kept instead.
    let (net, r) = across_the_junction(0.003, 0.010);
    let r = r.expect("inserted");
    assert_eq!(r.snapped, 0);
    assert_eq!(r.crossings, 2);
    assert_eq!(net.topology().faces, 7);
}

#[test]
fn a_curve_grazing_a_junction_passes_through_it() {
    // 3 mm and 6 mm from the junction: the sliver between the crossings is shorter than twice the
    // vertex snapping distance, so the curve passes through the junction.
    let (net, r) = across_the_junction(0.003, 0.006);
    let r = r.expect("inserted");
    assert_eq!(r.snapped, 1);
    assert_eq!(r.crossings, 1);
    assert_eq!(net.topology().faces, 6);
}
