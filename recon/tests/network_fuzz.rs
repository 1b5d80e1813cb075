//! Random sequences of every sketching tool on a disc (issue: "a fuzz-style test applies random
//! tool sequences and checks `validate()` after each"): insertions, holes, deletes, sharp tags,
//! border gluing, tubes and closures, with random and awkward curves. Each tool either applies and
//! leaves a valid network whose undo and redo are exact, or refuses and leaves it bit for bit as it
//! was; nothing panics.

mod common;

use common::disc::{chord, circle, line, Rng, Z};
use fires_recon::network::tools::{
    close_boundary, create_hole, delete_stroke, glue_borders, glue_tube, insert_boundary,
    insert_curve, tag_sharp, BoundaryOptions, CloseOptions, CurveInput, GlueOptions, HoleOptions,
    InsertOptions, ToolError, TubeOptions,
};
use fires_recon::network::{Network, NetworkFile, Transaction};
use std::f64::consts::PI;

fn ring(c: [f64; 2], r: f64, n: usize, ccw: bool) -> Vec<[f64; 3]> {
    (0..=n)
        .map(|i| {
            let a = 2.0 * PI * i as f64 / n as f64 * if ccw { 1.0 } else { -1.0 };
            [c[0] + r * a.cos(), c[1] + r * a.sin(), Z]
        })
        .collect()
}

fn with(points: &[[f64; 3]], id: u32) -> CurveInput<'_> {
    CurveInput {
        points,
        stroke: Some(id),
        sigma_mm: None,
        untracked_mm: [0.0; 2],
    }
}

/// The point of a hole's ring towards `p`.
fn toward(hole: ([f64; 2], f64), p: [f64; 2]) -> [f64; 3] {
    let (c, r) = hole;
    let (dx, dy) = (p[0] - c[0], p[1] - c[1]);
    let d = (dx * dx + dy * dy).sqrt().max(1e-9);
    [c[0] + r * dx / d, c[1] + r * dy / d, Z]
}

#[derive(Default)]
struct Counts {
    applied: [usize; 7],
    refused: [usize; 7],
}

const NAMES: [&str; 7] = ["insert", "hole", "delete", "sharp", "glue", "tube", "close"];

#[test]
fn random_sequences_of_every_tool_keep_the_invariants_and_are_transactional() {
    let mut counts = Counts::default();
    for seed in 1..=8u64 {
        let mut rng = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
        let mut net = Network::new();
        insert_boundary(&mut net, with(&circle(400), 0), &BoundaryOptions::default()).unwrap();
        let mut holes: Vec<([f64; 2], f64)> = Vec::new();
        let mut used: Vec<u32> = vec![0];
        for step in 0..50u32 {
            let id = step + 1;
            let tool = match rng.unit() {
                u if u < 0.35 => 0,
                u if u < 0.55 => 1,
                u if u < 0.65 => 2,
                u if u < 0.72 => 3,
                u if u < 0.82 => 4,
                u if u < 0.92 => 5,
                _ => 6,
            };
            let before = NetworkFile::to_json(&net);
            let snapshot = net.clone();
            let result: Result<Transaction, ToolError> = match tool {
                0 => {
                    let a0 = rng.range(0.0, 2.0 * PI);
                    let a1 = a0 + rng.range(0.3, 2.0 * PI - 0.3);
                    let c = chord(a0, a1, rng.range(-0.012, 0.02));
                    insert_curve(&mut net, with(&c, id), &InsertOptions::default()).map(|r| r.1)
                }
                1 => {
                    let c = [rng.range(-0.07, 0.07), rng.range(-0.07, 0.07)];
                    let r = rng.range(0.006, 0.025);
                    let pts = ring(c, r, 90, rng.unit() < 0.5);
                    let out = create_hole(&mut net, with(&pts, id), &HoleOptions::default());
                    if out.is_ok() {
                        holes.push((c, r));
                    }
                    out.map(|r| r.1)
                }
                2 => {
                    let s = used[(rng.next_u64() % used.len() as u64) as usize];
                    delete_stroke(&mut net, s).map(|r| r.1)
                }
                3 => {
                    let s = used[(rng.next_u64() % used.len() as u64) as usize];
                    tag_sharp(&mut net, s, rng.unit()).map(|r| r.1)
                }
                4 | 5 if holes.len() >= 2 => {
                    let i = (rng.next_u64() % holes.len() as u64) as usize;
                    let j = (i + 1 + (rng.next_u64() % (holes.len() as u64 - 1)) as usize)
                        % holes.len();
                    let (a, b) = (holes[i], holes[j]);
                    let m1 = line(toward(a, b.0), toward(b, a.0), 0.002);
                    if tool == 4 {
                        glue_borders(&mut net, with(&m1, id), None, &GlueOptions::default())
                            .map(|r| r.1)
                    } else {
                        // A second marker a little to the side.
                        let side = |h: ([f64; 2], f64), o: [f64; 2]| {
                            let p = toward(h, o);
                            let d = [p[0] - h.0[0], p[1] - h.0[1]];
                            [h.0[0] - d[1], h.0[1] + d[0]]
                        };
                        let m2 = line(toward(a, side(a, b.0)), toward(b, side(b, a.0)), 0.002);
                        glue_tube(
                            &mut net,
                            with(&m1, id),
                            with(&m2, id + 1000),
                            &TubeOptions::default(),
                        )
                        .map(|r| r.1)
                    }
                }
                _ => {
                    // A curve whose ends are near some boundary: a chord of the outer loop or a
                    // marker between two holes' points, or a random short curve.
                    let c = if rng.unit() < 0.5 || holes.is_empty() {
                        chord(rng.range(0.0, PI), rng.range(PI, 2.0 * PI), 0.0)
                    } else {
                        let h = holes[(rng.next_u64() % holes.len() as u64) as usize];
                        line(toward(h, [0.0, 0.0]), toward(h, [0.1, 0.1]), 0.002)
                    };
                    close_boundary(&mut net, with(&c, id), &CloseOptions::default()).map(|r| r.1)
                }
            };
            match result {
                Ok(t) => {
                    counts.applied[tool] += 1;
                    net.validate()
                        .unwrap_or_else(|e| panic!("seed {seed} step {step} {}: {e}", NAMES[tool]));
                    let topo = net.topology();
                    assert_eq!(
                        topo.euler,
                        topo.vertices as i64 - topo.edges as i64 + topo.faces as i64,
                        "seed {seed} step {step}"
                    );
                    if !used.contains(&id) {
                        used.push(id);
                    }
                    if rng.unit() < 0.4 {
                        let after = net.clone();
                        net.undo(&t);
                        assert_eq!(
                            net, snapshot,
                            "seed {seed} step {step}: undo {}",
                            NAMES[tool]
                        );
                        net.redo(&t);
                        assert_eq!(net, after, "seed {seed} step {step}: redo {}", NAMES[tool]);
                    }
                }
                Err(_) => {
                    counts.refused[tool] += 1;
                    assert_eq!(
                        NetworkFile::to_json(&net),
                        before,
                        "seed {seed} step {step}: a refused {} changed the network",
                        NAMES[tool]
                    );
                }
            }
        }
    }
    for (k, name) in NAMES.iter().enumerate() {
        eprintln!(
            "{name}: {} applied, {} refused",
            counts.applied[k], counts.refused[k]
        );
    }
    // The sequences exercise the tools, not only their refusals.
    for k in [0, 1, 2, 3] {
        assert!(counts.applied[k] > 0, "{} never applied", NAMES[k]);
    }
    assert!(
        counts.applied[4] + counts.applied[5] + counts.applied[6] > 0,
        "no gluing, tube or closure ever applied"
    );
}
