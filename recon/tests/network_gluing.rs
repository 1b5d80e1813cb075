//! Border gluing (FIRES thesis §5.1.3, §5.2.3): a strip on a torus glued along its two θ sides is a
//! cylinder (genus 0, 2 boundaries); its two circles glued are a torus (genus 1, no boundary); half of
//! them glued and the rest closed is a torus too. Survivor choices (A's curve, B's, the average),
//! validate() after every step, Euler bookkeeping, refusals that leave the network unchanged, undo/redo
//! and journal replay.

use fires_recon::network::tools::{
    close_boundary, glue_borders, insert_boundary, insert_curve, BoundaryOptions, CloseOptions,
    CurveInput, GlueOptions, GluePart, InsertOptions, Survivor, ToolError,
};
use fires_recon::network::{replay, Journal, Network, Step, StrokeInput, Topology};
use std::f64::consts::PI;

const RM: f64 = 0.1;
const RT: f64 = 0.04;
/// The strip leaves a gap of 0.15 rad in θ (9–21 mm) and 0.3 rad in φ (12 mm).
const TH: f64 = 2.0 * PI - 0.15;
const PH: f64 = 2.0 * PI - 0.3;

fn torus(th: f64, ph: f64) -> [f64; 3] {
    let r = RM + RT * ph.cos();
    [r * th.cos(), r * th.sin(), RT * ph.sin()]
}

/// The image of the parameter segment (θ₀, φ₀) → (θ₁, φ₁), about every 2 mm.
fn seg(a: (f64, f64), b: (f64, f64)) -> Vec<[f64; 3]> {
    let n = (((b.0 - a.0) * RM).abs().max(((b.1 - a.1) * RT).abs()) / 0.002).ceil() as usize;
    (0..=n.max(1))
        .map(|i| {
            let t = i as f64 / n.max(1) as f64;
            torus(a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1))
        })
        .collect()
}

fn path(corners: &[(f64, f64)]) -> Vec<[f64; 3]> {
    let mut out = vec![torus(corners[0].0, corners[0].1)];
    for w in corners.windows(2) {
        out.extend(seg(w[0], w[1]).into_iter().skip(1));
    }
    out
}

fn curve(pts: &[[f64; 3]], id: u32) -> CurveInput<'_> {
    CurveInput {
        points: pts,
        stroke: Some(id),
        sigma_mm: None,
        untracked_mm: [0.0; 2],
    }
}

/// The strokes: 0 the strip's boundary, 1 and 2 curves across it, 3.. gluing markers.
fn strokes() -> Vec<Vec<[f64; 3]>> {
    vec![
        path(&[(0.0, 0.0), (TH, 0.0), (TH, PH), (0.0, PH), (0.0, 0.0)]),
        seg((PI, 0.0), (PI, PH)),
        seg((0.0, PI), (TH, PI)),
        // 3, 4: the θ sides' corners, a₁ → b₁ and a₂ → b₂.
        vec![torus(0.0, 0.0), torus(TH, 0.0)],
        vec![torus(0.0, PH), torus(TH, PH)],
        // 5: the two circles at θ = 0; 6: at θ = π.
        vec![torus(0.0, 0.0), torus(0.0, PH)],
        vec![torus(PI, 0.0), torus(PI, PH)],
    ]
}

fn strip() -> Network {
    let s = strokes();
    let mut net = Network::new();
    insert_boundary(&mut net, curve(&s[0], 0), &BoundaryOptions::default()).unwrap();
    net.validate().unwrap();
    for id in [1, 2] {
        insert_curve(
            &mut net,
            curve(&s[id], id as u32),
            &InsertOptions::default(),
        )
        .unwrap();
        net.validate().unwrap();
    }
    net
}

fn glue(net: &mut Network, a: usize, b: Option<usize>, options: &GlueOptions) -> Topology {
    let s = strokes();
    let before = net.topology();
    let (r, _) = glue_borders(
        net,
        curve(&s[a], a as u32),
        b.map(|b| curve(&s[b], b as u32)),
        options,
    )
    .unwrap_or_else(|e| panic!("gluing {a}, {b:?}: {e}"));
    net.validate().unwrap();
    let t = net.topology();
    // Bookkeeping: m glued edges remove m edges and m (closed paths) or m + 1 (open paths) vertices,
    // plus the splits the markers and the matching made (each +1 V, +1 E).
    assert_eq!(t.faces, before.faces);
    let (dv, de) = (
        t.vertices as i64 - before.vertices as i64,
        t.edges as i64 - before.edges as i64,
    );
    assert_eq!(de - dv, r.merged_vertices as i64 - r.glued_edges as i64);
    t
}

fn cylinder(survivor: Survivor) -> Network {
    let mut net = strip();
    let t0 = net.topology();
    assert_eq!((t0.euler, t0.boundaries, t0.genus), (1, 1, 0));
    let t = glue(
        &mut net,
        3,
        Some(4),
        &GlueOptions {
            survivor,
            ..GlueOptions::default()
        },
    );
    assert_eq!(
        (t.euler, t.boundaries, t.genus, t.components),
        (0, 2, 0, 1),
        "{t:?}"
    );
    net
}

fn angles(net: &Network) -> Vec<f64> {
    net.polylines()
        .flat_map(|(_, p)| p.points.iter().map(|q| q[1].atan2(q[0])))
        .collect()
}

#[test]
fn a_strip_glued_along_two_sides_is_a_cylinder_with_the_chosen_curve() {
    let near = |a: f64, b: f64| {
        let d = (a - b).rem_euclid(2.0 * PI);
        d.min(2.0 * PI - d) < 1e-9
    };
    // A: the θ = 0 side; B: the θ = TH side (angle −0.15).
    let first = angles(&cylinder(Survivor::First));
    assert!(first.iter().any(|&a| near(a, 0.0)));
    assert!(!first.iter().any(|&a| near(a, TH)));
    let second = angles(&cylinder(Survivor::Second));
    assert!(second.iter().any(|&a| near(a, TH)));
    assert!(!second.iter().any(|&a| near(a, 0.0)));
    let average = angles(&cylinder(Survivor::Average));
    assert!(!average.iter().any(|&a| near(a, 0.0) || near(a, TH)));
    assert!(average.iter().any(|&a| near(a, TH / 2.0 + PI)));
}

#[test]
fn the_cylinder_glued_along_its_circles_is_a_torus() {
    let mut net = cylinder(Survivor::Average);
    let t = glue(&mut net, 5, None, &GlueOptions::default());
    assert_eq!(
        (t.euler, t.boundaries, t.genus, t.components),
        (0, 0, 1, 1),
        "{t:?}"
    );
    // Every edge now has two faces.
    assert!(net.edges().all(|(_, e)| e.faces.len() == 2));
}

#[test]
fn half_the_circles_glued_and_the_rest_closed_is_a_torus() {
    for part in [GluePart::FirstHalf, GluePart::SecondHalf] {
        let mut net = cylinder(Survivor::First);
        let t = glue(
            &mut net,
            5,
            Some(6),
            &GlueOptions {
                part,
                ..GlueOptions::default()
            },
        );
        // A torus with one hole: χ = −1, one boundary, genus 1.
        assert_eq!((t.euler, t.boundaries, t.genus), (-1, 1, 1), "{part:?}");
        // Close it: locate the remaining loop with a point of one of its edges.
        let (_, e) = net.edges().find(|(_, e)| e.faces.len() == 1).unwrap();
        let p = net.polyline(e.polyline).unwrap().points[1];
        close_boundary(&mut net, curve(&[p], 9), &CloseOptions::default()).unwrap();
        net.validate().unwrap();
        let t = net.topology();
        assert_eq!((t.euler, t.boundaries, t.genus), (0, 0, 1), "{part:?}");
    }
}

#[test]
fn refused_gluings_leave_the_network_unchanged() {
    let s = strokes();
    let mut net = strip();
    let before = net.clone();
    // One loop needs the second curve.
    let e = glue_borders(&mut net, curve(&s[3], 3), None, &GlueOptions::default()).unwrap_err();
    assert_eq!(e, ToolError::NeedsSecondCurve);
    assert_eq!(net, before);
    // Crossed curves would glue a Möbius band.
    let crossed = vec![torus(0.0, PH), torus(TH, 0.0)];
    let crossed2 = vec![torus(0.0, 0.0), torus(TH, PH)];
    let e = glue_borders(
        &mut net,
        curve(&crossed, 7),
        Some(curve(&crossed2, 8)),
        &GlueOptions::default(),
    )
    .unwrap_err();
    assert_eq!(e.rule(), "orientable gluing");
    assert_eq!(net, before);
    // An end off the boundary (in the middle of the strip).
    let off = vec![torus(0.0, 0.0), torus(PI / 2.0, PI / 2.0)];
    let e = glue_borders(&mut net, curve(&off, 9), None, &GlueOptions::default()).unwrap_err();
    assert!(matches!(e, ToolError::NotOnBoundary { .. }), "{e}");
    assert_eq!(net, before);
    // Half-loops need two curves.
    let mut cyl = cylinder(Survivor::First);
    let before = cyl.clone();
    let e = glue_borders(
        &mut cyl,
        curve(&s[5], 5),
        None,
        &GlueOptions {
            part: GluePart::FirstHalf,
            ..GlueOptions::default()
        },
    )
    .unwrap_err();
    assert_eq!(e.rule(), "gluing needs two curves");
    assert_eq!(cyl, before);
}

#[test]
fn undo_redo_and_journal_replay_of_gluings_are_exact() {
    let s = strokes();
    let mut net = strip();
    let before = net.clone();
    let (_, t) = glue_borders(
        &mut net,
        curve(&s[3], 3),
        Some(curve(&s[4], 4)),
        &GlueOptions::default(),
    )
    .unwrap();
    let after = net.clone();
    net.undo(&t);
    assert_eq!(net, before);
    net.redo(&t);
    assert_eq!(net, after);
    net.validate().unwrap();
    let inputs: Vec<StrokeInput> = s
        .iter()
        .enumerate()
        .map(|(i, p)| StrokeInput {
            id: i as u32,
            points: p.clone(),
            closed: i == 0,
            sigma_mm: None,
            mode: 0,
            untracked_mm: [0.0; 2],
        })
        .collect();
    let average = GlueOptions {
        survivor: Survivor::Average,
        ..GlueOptions::default()
    };
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
            Step::Insert {
                stroke: 2,
                options: InsertOptions::default(),
                mirror: false,
            },
            Step::Glue {
                strokes: vec![3, 4],
                options: average.clone(),
            },
            Step::Glue {
                strokes: vec![5],
                options: GlueOptions::default(),
            },
        ],
        ..Journal::default()
    };
    let text = serde_json::to_string_pretty(&journal).unwrap();
    let back: Journal = serde_json::from_str(&text).unwrap();
    assert_eq!(back, journal);
    let replayed = replay(&back, &inputs).unwrap();
    let mut direct = cylinder(Survivor::Average);
    glue(&mut direct, 5, None, &GlueOptions::default());
    assert_eq!(replayed, direct);
    assert_eq!(replayed.topology().genus, 1);
}

// ---- The thesis's tube gluing: two inserted curves and two faces on the same four vertices. ----

use fires_recon::network::tools::{glue_tube, TubeHalves, TubeOptions};

fn tube(
    net: &mut Network,
    c1: &[[f64; 3]],
    c2: &[[f64; 3]],
    halves: TubeHalves,
) -> Result<bool, ToolError> {
    let options = TubeOptions {
        halves,
        ..TubeOptions::default()
    };
    let before = net.topology();
    let (r, _) = glue_tube(net, curve(c1, 20), curve(c2, 21), &options)?;
    net.validate().unwrap();
    let t = net.topology();
    assert_eq!(t.faces, before.faces + 2);
    assert_eq!(t.boundaries + 2, before.boundaries);
    // f1 and f2 have exactly the same vertices: a1, a2, b1, b2.
    let verts = |f| {
        let mut v: Vec<_> = net
            .face(f)
            .unwrap()
            .uses
            .iter()
            .map(|u| net.use_start(*u).unwrap())
            .filter(|v| r.vertices.contains(v))
            .collect();
        v.sort();
        v
    };
    assert_eq!(verts(r.faces[0]), verts(r.faces[1]));
    assert_eq!(verts(r.faces[0]).len(), 4);
    Ok(r.flipped)
}

#[test]
fn a_tube_between_the_cylinders_ends_is_a_torus() {
    let c1 = seg((0.0, PH), (0.0, 2.0 * PI));
    let c2 = seg((PI, PH), (PI, 2.0 * PI));
    let mut oriented = cylinder(Survivor::First);
    let before = oriented.clone();
    assert!(!tube(&mut oriented, &c1, &c2, TubeHalves::Oriented).unwrap());
    let t = oriented.topology();
    assert_eq!((t.euler, t.boundaries, t.genus), (0, 0, 1), "{t:?}");
    // The geometric choice agrees here; the other pairing on one surface is a Möbius band.
    let mut auto = before.clone();
    assert!(!tube(&mut auto, &c1, &c2, TubeHalves::Auto).unwrap());
    assert_eq!(auto, oriented);
    let mut flipped = before.clone();
    let e = tube(&mut flipped, &c1, &c2, TubeHalves::Flipped).unwrap_err();
    assert_eq!(e.rule(), "orientable gluing");
    assert_eq!(flipped, before);
    // Both curves on one border.
    let mut same = before.clone();
    let c3 = seg((0.0, PH), (PI / 2.0, PH));
    let e = glue_tube(
        &mut same,
        curve(&c1, 20),
        curve(&c3, 21),
        &TubeOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(e, ToolError::DifferentBoundaries { .. }), "{e}");
    assert_eq!(same, before);
}

#[test]
fn a_tube_between_two_discs_pairs_the_halves_by_geometry() {
    let disc = |z: f64, sign: f64| -> Vec<[f64; 3]> {
        (0..=200)
            .map(|i| {
                let a = sign * 2.0 * PI * i as f64 / 200.0;
                [0.1 * a.cos(), 0.097 * a.sin(), z]
            })
            .collect()
    };
    let c1 = vec![[0.0, 0.097, 0.0], [0.0, 0.097, 0.1]];
    let c2 = vec![[0.0, -0.097, 0.0], [0.0, -0.097, 0.1]];
    for (sign, expect_flip) in [(1.0, true), (-1.0, false)] {
        let mut net = Network::new();
        for (z, s, id) in [(0.0, 1.0, 0), (0.1, sign, 1)] {
            let d = disc(z, s);
            insert_boundary(&mut net, curve(&d, id), &BoundaryOptions::default()).unwrap();
        }
        // Discs drawn the same way round face the same way: a straight tube reverses one.
        let t0 = net.topology();
        let flipped = tube(&mut net, &c1, &c2, TubeHalves::Auto).unwrap();
        // The four ends split four edges (no vertex near): ΔV = 4, ΔE = 4 + 2, ΔF = 2, Δχ = 0.
        let t1 = net.topology();
        assert_eq!(
            (
                t1.vertices - t0.vertices,
                t1.edges - t0.edges,
                t1.faces - t0.faces
            ),
            (4, 6, 2)
        );
        assert_eq!(t1.euler, t0.euler);
        assert_eq!(flipped, expect_flip, "sign {sign}");
        let t = net.topology();
        assert_eq!((t.components, t.euler, t.boundaries, t.genus), (1, 2, 0, 0));
        // Each tube face holds the same side (x > 0 or x < 0) of both discs.
        let mut tubes = 0;
        for (_, face) in net.faces() {
            let all: Vec<[f64; 3]> = face
                .uses
                .iter()
                .flat_map(|u| net.edge_polyline(u.edge).unwrap().points.clone())
                .collect();
            // The tube faces reach both discs; the discs' own faces one.
            if !(all.iter().any(|p| p[2] < 0.05) && all.iter().any(|p| p[2] > 0.05)) {
                continue;
            }
            tubes += 1;
            let pts: Vec<&[f64; 3]> = all.iter().filter(|p| p[0].abs() > 0.01).collect();
            assert!(
                pts.iter().all(|p| p[0] > 0.0) || pts.iter().all(|p| p[0] < 0.0),
                "a twisted tube face"
            );
        }
        assert_eq!(tubes, 2);
    }
}

#[test]
fn a_journal_tube_step_replays_bit_for_bit() {
    let c1 = seg((0.0, PH), (0.0, 2.0 * PI));
    let c2 = seg((PI, PH), (PI, 2.0 * PI));
    let mut inputs: Vec<StrokeInput> = strokes()
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
    for (id, points) in [(20, c1.clone()), (21, c2.clone())] {
        inputs.push(StrokeInput {
            id,
            points,
            closed: false,
            sigma_mm: None,
            mode: 0,
            untracked_mm: [0.0; 2],
        });
    }
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
            Step::Glue {
                strokes: vec![3, 4],
                options: GlueOptions::default(),
            },
            Step::Tube {
                strokes: [20, 21],
                options: TubeOptions::default(),
            },
        ],
        ..Journal::default()
    };
    let back: Journal = serde_json::from_str(&serde_json::to_string(&journal).unwrap()).unwrap();
    let replayed = replay(&back, &inputs).unwrap();
    let mut direct = cylinder(Survivor::First);
    tube(&mut direct, &c1, &c2, TubeHalves::Oriented).unwrap();
    assert_eq!(replayed, direct);
}

/// A small deterministic generator (xorshift64*).
struct Rng(u64);

impl Rng {
    fn unit(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

#[test]
fn randomised_strips_glue_into_cylinders_and_tori() {
    let mut rng = Rng(0x61_0E5);
    let (mut tori, mut inserted) = (0, 0);
    for case in 0..120 {
        // A strip with 0–3 curves across θ and 0–2 along it, at random places.
        let s = strokes();
        let mut net = Network::new();
        insert_boundary(&mut net, curve(&s[0], 0), &BoundaryOptions::default()).unwrap();
        let mut id = 1;
        let n_th = (rng.unit() * 4.0) as usize;
        for k in 0..n_th {
            let th = (k as f64 + rng.range(0.2, 0.8)) * TH / n_th as f64;
            let c = seg((th, 0.0), (th, PH));
            // Rule 1 may refuse a curve whose ends are on one boundary edge; it is then left out.
            inserted += usize::from(
                insert_curve(&mut net, curve(&c, id), &InsertOptions::default()).is_ok(),
            );
            net.validate().unwrap();
            id += 1;
        }
        let n_ph = (rng.unit() * 3.0) as usize;
        for k in 0..n_ph {
            let ph = (k as f64 + rng.range(0.2, 0.8)) * PH / n_ph as f64;
            let c = seg((0.0, ph), (TH, ph));
            // Rule 1 may refuse a curve whose ends are on one boundary edge; it is then left out.
            inserted += usize::from(
                insert_curve(&mut net, curve(&c, id), &InsertOptions::default()).is_ok(),
            );
            net.validate().unwrap();
            id += 1;
        }
        let survivor = [Survivor::First, Survivor::Second, Survivor::Average][case % 3];
        let options = GlueOptions {
            survivor,
            ..GlueOptions::default()
        };
        // Whole sides (corner to corner) or a random part of them, the curves in either order.
        let whole = rng.unit() < 0.5;
        let (mut p1, mut p2) = if whole {
            (0.0, PH)
        } else {
            let a = rng.range(0.0, PH - 0.5);
            (a, rng.range(a + 0.4, PH))
        };
        if rng.unit() < 0.5 {
            std::mem::swap(&mut p1, &mut p2);
        }
        let m1 = vec![torus(0.0, p1), torus(TH, p1)];
        let m2 = vec![torus(0.0, p2), torus(TH, p2)];
        let before = net.topology();
        let (r, _) = glue_borders(&mut net, curve(&m1, 90), Some(curve(&m2, 91)), &options)
            .unwrap_or_else(|e| panic!("case {case}: {e}"));
        net.validate().unwrap();
        let t = net.topology();
        assert_eq!(
            (t.euler, t.boundaries, t.genus),
            (0, 2, 0),
            "case {case}: {t:?}"
        );
        assert_eq!(t.faces, before.faces);
        assert!(r.same_loop);
        if whole {
            let c = vec![torus(0.0, 0.0), torus(0.0, PH)];
            glue_borders(&mut net, curve(&c, 92), None, &options)
                .unwrap_or_else(|e| panic!("case {case}: {e}"));
            net.validate().unwrap();
            let t = net.topology();
            assert_eq!((t.euler, t.boundaries, t.genus), (0, 0, 1), "case {case}");
            tori += 1;
        }
    }
    assert!(tori > 30, "{tori}");
    eprintln!("{tori} tori, {inserted} curves inserted");
    assert!(inserted > 150, "{inserted}");
}
