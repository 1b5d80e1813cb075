//! Factor size and analysis time of AMD and nested dissection on editing-shaped systems:
//! the cotangent pattern (1-ring, one unknown per vertex), the LSE pattern (2-ring,
//! dense 3×3 blocks) and the implicit-editing pattern (4-ring, one unknown per vertex,
//! also ordered by nested dissection on the mesh graph, `OrderingSkeleton`) of a geodesic
//! ball on an icosphere.
//!
//! `cargo run --release -p fires-recon --example ordering_fill -- 100000`

use std::time::Instant;

use fires_recon::solve::{
    sparse_from_triplets, CholeskyOptions, CholeskySolver, FactorMode, FillOrdering,
    OrderingSkeleton,
};

#[path = "common/ball.rs"]
mod ball;

use ball::{ball_rings, grow};

fn main() {
    let roi: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(30_000);
    let ring = ball_rings(roi);
    let grow = |near: &[Vec<usize>]| grow(&ring, near);
    let two_ring = grow(&ring);
    let mut cot = Vec::new();
    for (i, r) in ring.iter().enumerate() {
        for &j in r {
            if j <= i {
                cot.push((i, j, 1.0));
            }
        }
    }
    let mut lse = Vec::new();
    for (i, r) in two_ring.iter().enumerate() {
        for &j in r {
            for a in 0..3 {
                for b in 0..3 {
                    if 3 * j + b <= 3 * i + a {
                        lse.push((3 * i + a, 3 * j + b, 1.0));
                    }
                }
            }
        }
    }
    let four_ring = grow(&grow(&two_ring));
    let mut implicit = Vec::new();
    for (i, r) in four_ring.iter().enumerate() {
        implicit.extend(r.iter().filter(|&&j| j <= i).map(|&j| (i, j, 1.0)));
    }
    {
        let a = sparse_from_triplets(roi, roi, &implicit).expect("valid triplets");
        let t0 = Instant::now();
        let order = OrderingSkeleton::new(&ring, 4)
            .and_then(|s| s.order_free(&vec![false; roi]))
            .expect("skeleton order");
        let s = CholeskySolver::analyze_ordered(a.as_ref(), CholeskyOptions::default(), &order)
            .expect("analysis");
        println!(
            "{{\"pattern\":\"implicit\",\"unknowns\":{roi},\"ordering\":\"Skeleton\",\"factor_entries\":{},\"analyze_ms\":{:.1}}}",
            s.factor_len(),
            t0.elapsed().as_secs_f64() * 1e3
        );
    }
    for (name, n, t) in [
        ("cotan", roi, cot),
        ("lse", 3 * roi, lse),
        ("implicit", roi, implicit),
    ] {
        let a = sparse_from_triplets(n, n, &t).expect("valid triplets");
        for ordering in [FillOrdering::Amd, FillOrdering::NestedDissection] {
            let opts = CholeskyOptions {
                ordering,
                mode: FactorMode::Supernodal,
                ..Default::default()
            };
            let t0 = Instant::now();
            let s = CholeskySolver::analyze(a.as_ref(), opts).expect("analysis");
            println!(
                "{{\"pattern\":\"{name}\",\"unknowns\":{n},\"ordering\":\"{ordering:?}\",\"factor_entries\":{},\"analyze_ms\":{:.1}}}",
                s.factor_len(),
                t0.elapsed().as_secs_f64() * 1e3
            );
        }
    }
}
