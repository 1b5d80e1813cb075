//! Hole creation (FIRES thesis §5.2.2) on a drawn disc: one hole without crossings (joined by spokes),
//! one across a curve (cut), optionally writing the network.
//!
//! ```text
//! cargo run --release -p fires-recon --example network_hole -- [OUT.json]
//! ```
//!
//! Prints one JSON line per step with the topology, the case and the tool's time.

use std::f64::consts::TAU;
use std::time::Instant;

use fires_recon::network::tools::{
    create_hole, insert_boundary, insert_curve, BoundaryOptions, CurveInput, HoleKind, HoleOptions,
    InsertOptions,
};
use fires_recon::network::{Network, NetworkFile};
use serde_json::json;

/// A closed circle of radius `r` about (cx, cy) in the plane z = 0.5 m, `n` points plus the closing one.
fn ring(cx: f64, cy: f64, r: f64, n: usize) -> Vec<[f64; 3]> {
    (0..=n)
        .map(|i| {
            let a = TAU * i as f64 / n as f64;
            [cx + r * a.cos(), cy + r * a.sin(), 0.5]
        })
        .collect()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut net = Network::new();
    let boundary = ring(0.0, 0.0, 0.1, 400);
    insert_boundary(
        &mut net,
        CurveInput::new(&boundary),
        &BoundaryOptions::default(),
    )?;
    // A chord across the disc, x = 0.03 m.
    let y = (0.1f64.powi(2) - 0.03f64.powi(2)).sqrt();
    let chord: Vec<[f64; 3]> = (0..=100)
        .map(|i| [0.03, y - 2.0 * y * i as f64 / 100.0, 0.5])
        .collect();
    insert_curve(&mut net, CurveInput::new(&chord), &InsertOptions::default())?;
    let holes = [
        ("left, no crossing", ring(-0.04, 0.0, 0.025, 120)),
        ("across the chord", ring(0.035, 0.02, 0.02, 120)),
    ];
    for (name, pts) in &holes {
        let t0 = Instant::now();
        let (report, _) = create_hole(&mut net, CurveInput::new(pts), &HoleOptions::default())?;
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        net.validate()?;
        let kind = match report.kind {
            HoleKind::Spokes {
                sides,
                max_distance_mm,
                ..
            } => json!({"case": "spokes", "sides": sides, "max_distance_mm": max_distance_mm}),
            HoleKind::Cut { crossings } => json!({"case": "cut", "crossings": crossings}),
        };
        println!(
            "{}",
            json!({"hole": name, "kind": kind, "topology": net.topology(), "ms": ms})
        );
    }
    if let Some(out) = std::env::args().nth(1) {
        std::fs::write(out, NetworkFile::to_json(&net))?;
    }
    Ok(())
}
