//! The curve network built from the simulator's true strokes has the faces the drawing's topology implies
//! (curve network issue, figures): a boundary plus insertions, each crossing c earlier curves, make
//! 1 + Σ(c + 1) faces, for every drawing scenario and 10 seeds of a 60 s session.

use fires_recon::network::{build_network, BuildOptions, StrokeInput};
use fires_record::{StrokeKind, StrokeTruth};
use fires_sim::session::build_trajectory;
use fires_sim::{scenario, true_strokes};

fn inputs(truth: &[StrokeTruth]) -> Vec<StrokeInput> {
    truth
        .iter()
        .map(|s| StrokeInput {
            id: s.id,
            points: s.tip_polyline_m.clone(),
            closed: s.kind == StrokeKind::Boundary,
            sigma_mm: None,
            mode: s.mode,
            untracked_mm: [0.0; 2],
        })
        .collect()
}

/// Faces of the network the plan describes: the boundary's disc, plus one face per piece of each
/// complete insertion.
fn implied_faces(truth: &[StrokeTruth]) -> usize {
    1 + truth
        .iter()
        .filter(|s| s.kind == StrokeKind::Crossing && s.complete)
        .map(|s| s.crosses.len() + 1)
        .sum::<usize>()
}

#[test]
fn networks_from_true_strokes_have_the_faces_their_topology_implies() {
    let mut mismatches = Vec::new();
    let mut sessions = 0;
    for name in ["webcam", "fires-v1", "fires-v2", "stress"] {
        for seed in 1..=10 {
            let sc = scenario(name, seed, 60.0, None).expect("scenario");
            let traj = build_trajectory(&sc, seed, 60.0);
            let truth = true_strokes(&traj, 60.0);
            let complete = truth.iter().filter(|s| s.complete).count();
            assert!(
                complete >= 8,
                "{name} seed {seed}: {complete} complete strokes"
            );
            let (net, report) = build_network(&inputs(&truth), &BuildOptions::default());
            net.validate().expect("valid network");
            assert_eq!(
                report.used.len(),
                complete,
                "{name} seed {seed}: {:?}",
                report.rejected
            );
            let (got, want) = (net.n_faces(), implied_faces(&truth));
            if got != want {
                mismatches.push(format!(
                    "{name} seed {seed}: {got} faces, topology implies {want}"
                ));
            }
            sessions += 1;
        }
    }
    assert!(mismatches.is_empty(), "of {sessions}: {mismatches:#?}");
}
