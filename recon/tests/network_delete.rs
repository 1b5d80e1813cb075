//! Curve delete: faces merge, crossings re-merge, refusals leave the network unchanged.

mod common;

use common::disc::{chord, circle, vertical, Rng};
use fires_recon::network::tools::{
    delete_stroke, insert_boundary, insert_curve, BoundaryOptions, CurveInput, InsertOptions,
    ToolError,
};
use fires_recon::network::Network;
use std::f64::consts::PI;

fn add(net: &mut Network, pts: &[[f64; 3]], id: u32) -> bool {
    let c = CurveInput {
        points: pts,
        stroke: Some(id),
        sigma_mm: None,
        untracked_mm: [0.0; 2],
    };
    let ok = insert_curve(net, c, &InsertOptions::default()).is_ok();
    net.validate().unwrap();
    ok
}

fn disc() -> Network {
    let mut net = Network::new();
    let c = circle(400);
    let curve = CurveInput {
        points: &c,
        stroke: Some(0),
        sigma_mm: None,
        untracked_mm: [0.0; 2],
    };
    insert_boundary(&mut net, curve, &BoundaryOptions::default()).unwrap();
    net
}

#[test]
fn deleting_a_crossing_stroke_restores_the_topology_before_it() {
    let mut net = disc();
    assert!(add(&mut net, &vertical(0.0), 1));
    let one = net.topology();
    assert!(add(
        &mut net,
        &chord(160f64.to_radians(), -20f64.to_radians(), 0.0),
        2
    ));
    assert_eq!(net.topology().faces, 4);
    let (r, _) = delete_stroke(&mut net, 2).unwrap();
    net.validate().unwrap();
    assert_eq!(r.removed_edges, 2);
    // Its two ends and the crossing go; the vertical chord is one polyline again.
    assert_eq!(r.removed_vertices, 3);
    assert_eq!(net.topology(), one);
    let verticals: Vec<_> = net
        .edges()
        .filter(|(_, e)| net.polyline(e.polyline).unwrap().attrs.stroke == Some(1))
        .collect();
    assert_eq!(verticals.len(), 1);
    // And the vertical too: back to the bare boundary (its split vertices stay).
    delete_stroke(&mut net, 1).unwrap();
    net.validate().unwrap();
    assert_eq!(net.topology(), disc().topology());
}

#[test]
fn tagging_a_stroke_sharp_sets_all_its_pieces_and_replays() {
    use fires_recon::network::tools::tag_sharp;
    let mut net = disc();
    assert!(add(&mut net, &vertical(0.0), 1));
    assert!(add(
        &mut net,
        &chord(160f64.to_radians(), -20f64.to_radians(), 0.0),
        2
    ));
    let before = net.clone();
    let (n, t) = tag_sharp(&mut net, 1, 1.0).unwrap();
    assert_eq!(n, 2, "the vertical is split in two by the crossing");
    net.validate().unwrap();
    let sharp = |net: &Network| {
        net.polylines()
            .filter(|(_, p)| p.attrs.sharpness == 1.0)
            .map(|(_, p)| p.attrs.stroke)
            .collect::<Vec<_>>()
    };
    assert_eq!(sharp(&net), vec![Some(1), Some(1)]);
    net.undo(&t);
    assert_eq!(net, before);
    assert!(tag_sharp(&mut net, 1, 1.5).is_err());
    assert!(matches!(
        tag_sharp(&mut net, 7, 1.0),
        Err(ToolError::NoSuchStroke { stroke: 7 })
    ));
    assert_eq!(net, before);
}

#[test]
fn refused_deletes_leave_the_network_unchanged() {
    let mut net = disc();
    assert!(add(&mut net, &vertical(0.0), 1));
    let before = net.clone();
    assert!(matches!(
        delete_stroke(&mut net, 0),
        Err(ToolError::CannotDelete { .. })
    ));
    assert_eq!(net, before);
    assert!(matches!(
        delete_stroke(&mut net, 9),
        Err(ToolError::NoSuchStroke { stroke: 9 })
    ));
    assert_eq!(net, before);
}

#[test]
fn random_inserts_and_deletes_keep_the_invariants() {
    for seed in 1..=4u64 {
        let mut rng = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
        let mut net = disc();
        let mut live: Vec<u32> = Vec::new();
        let mut deleted = 0;
        for id in 1..80u32 {
            if !live.is_empty() && rng.unit() < 0.3 {
                let k = (rng.next_u64() % live.len() as u64) as usize;
                let before = net.clone();
                match delete_stroke(&mut net, live[k]) {
                    Ok(_) => {
                        live.remove(k);
                        deleted += 1;
                    }
                    // Refused only where another stroke ends on this one (it would dangle).
                    Err(e) => {
                        assert!(matches!(e, ToolError::CannotDelete { .. }), "{e}");
                        assert_eq!(net, before);
                    }
                }
            } else {
                let a0 = rng.range(0.0, 2.0 * PI);
                let a1 = a0 + rng.range(0.5, 2.0 * PI - 0.5);
                if add(&mut net, &chord(a0, a1, rng.range(-0.005, 0.01)), id) {
                    live.push(id);
                }
            }
            net.validate().unwrap();
            let t = net.topology();
            assert_eq!((t.euler, t.boundaries, t.genus), (1, 1, 0), "seed {seed}");
        }
        assert!(deleted >= 3, "seed {seed}: {deleted} deletes");
    }
}
