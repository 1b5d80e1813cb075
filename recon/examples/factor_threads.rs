//! One thread against two (`SubtreeThreads`) on implicit editing's first-system shape: a
//! 4-ring operator on a geodesic ball of an icosphere, ordered on the mesh graph as the
//! editor orders it. Prints one JSON line per configuration with the median numeric
//! factorisation (into a fresh value array, and again into the same one: the arithmetic
//! without first touching the memory) and 3-right-hand-side solve times; the runs are
//! interleaved so machine noise hits both alike.
//!
//! `cargo run --release -p fires-recon --example factor_threads -- 48000 5`

use std::time::Instant;

use faer::Mat;
use fires_recon::solve::{
    sparse_from_triplets, CholeskyOptions, CholeskySolver, OrderingSkeleton, SubtreeThreads,
};

#[path = "common/ball.rs"]
mod ball;

use ball::{ball_rings, grow};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let mut args = std::env::args().skip(1);
    let roi: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(48_000);
    let runs: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(5).max(1);
    let ring = ball_rings(roi);
    let four_ring = grow(&ring, &grow(&ring, &grow(&ring, &ring)));
    // Diagonally dominant, so SPD: −1 off the diagonal, the row's count plus one on it.
    let mut t = Vec::new();
    for (i, r) in four_ring.iter().enumerate() {
        t.extend(r.iter().filter(|&&j| j < i).map(|&j| (i, j, -1.0)));
        t.push((i, i, r.len() as f64 + 1.0));
    }
    let a = sparse_from_triplets(roi, roi, &t).expect("valid triplets");
    let order = OrderingSkeleton::new(&ring, 4)
        .and_then(|s| s.order_free(&vec![false; roi]))
        .expect("skeleton order");
    let b = Mat::from_fn(roi, 3, |i, c| ((i * (c + 3)) % 17) as f64);
    let configs = [
        SubtreeThreads::Off,
        SubtreeThreads::Factor,
        SubtreeThreads::FactorAndSolve,
    ];
    let mut solvers: Vec<CholeskySolver> = configs
        .iter()
        .map(|&threads| {
            let opts = CholeskyOptions {
                threads,
                ..Default::default()
            };
            CholeskySolver::analyze_ordered(a.as_ref(), opts, &order).expect("analysis")
        })
        .collect();
    let mut factor_ms = vec![Vec::new(); configs.len()];
    let mut refactor_ms = vec![Vec::new(); configs.len()];
    let mut solve_ms = vec![Vec::new(); configs.len()];
    for _ in 0..runs {
        for (k, s) in solvers.iter_mut().enumerate() {
            // A fresh value array each time, as a first factorisation has.
            let mut fresh = s.share_symbolic();
            let t0 = Instant::now();
            fresh.factorize(a.as_ref()).expect("SPD");
            factor_ms[k].push(t0.elapsed().as_secs_f64() * 1e3);
            let mut x = b.clone();
            let t0 = Instant::now();
            fresh.solve_in_place(x.as_mut()).expect("factored");
            solve_ms[k].push(t0.elapsed().as_secs_f64() * 1e3);
            // Again into the same, already touched array: the arithmetic alone.
            let t0 = Instant::now();
            fresh.factorize(a.as_ref()).expect("SPD");
            refactor_ms[k].push(t0.elapsed().as_secs_f64() * 1e3);
            *s = fresh;
        }
    }
    for (k, threads) in configs.iter().enumerate() {
        println!(
            "{{\"unknowns\":{roi},\"threads\":\"{threads:?}\",\"factor_entries\":{},\"split_cost\":{},\"numeric_ms\":{:.1},\"refactor_ms\":{:.1},\"solve_ms\":{:.2}}}",
            solvers[k].factor_len(),
            solvers[k]
                .subtree_split_cost()
                .map_or("null".into(), |c| format!("{c:.3}")),
            median(factor_ms[k].clone()),
            median(refactor_ms[k].clone()),
            median(solve_ms[k].clone())
        );
    }
}
