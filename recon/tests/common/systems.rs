//! Sparse SPD test systems shaped like the mesh systems the solvers meet, and helpers to
//! compare solutions.

#![allow(dead_code)]

use faer::Mat;
use fires_recon::solve::{sparse_from_triplets, sparse_triplets, SparseMatrix};
use fires_recon::SurfaceMesh;

use super::disc::Rng;

/// A uniform integer below `n`.
pub fn below(rng: &mut Rng, n: usize) -> usize {
    (rng.next_u64() % n as u64) as usize
}

/// The lower triangle of the mesh graph Laplacian plus `shift`·I (SPD), with `block`
/// unknowns per vertex coupled densely, over the `rings`-ring neighbourhoods.
pub fn mesh_system(m: &SurfaceMesh, rings: usize, block: usize, shift: f64) -> SparseMatrix {
    let n = m.n_vertices();
    let one: Vec<Vec<usize>> = m
        .vertices()
        .map(|v| m.vertex_vertices(v).map(|u| u.idx()).collect())
        .collect();
    let mut t = Vec::new();
    for i in 0..n {
        let mut near = vec![i];
        for _ in 0..rings {
            let mut next = near.clone();
            for &u in &near {
                next.extend_from_slice(&one[u]);
            }
            next.sort_unstable();
            next.dedup();
            near = next;
        }
        for &j in &near {
            if j == i {
                continue;
            }
            for a in 0..block {
                for b in 0..block {
                    let (r, c) = (block * i + a, block * j + b);
                    if c < r {
                        t.push((r, c, -1.0 / (1.0 + (a + b) as f64)));
                    }
                }
            }
        }
        for a in 0..block {
            for b in 0..a {
                t.push((block * i + a, block * i + b, 0.1));
            }
        }
    }
    // Diagonal dominance makes it SPD.
    let mut diag = vec![shift; block * n];
    for &(r, c, v) in &t {
        let v: f64 = v;
        diag[r] += v.abs();
        diag[c] += v.abs();
    }
    for (r, d) in diag.into_iter().enumerate() {
        t.push((r, r, d));
    }
    sparse_from_triplets(block * n, block * n, &t).expect("valid triplets")
}

/// `n × c` right-hand sides with entries in [-10, 10].
pub fn rhs(n: usize, c: usize, seed: u64) -> Mat<f64> {
    let mut rng = Rng(seed);
    Mat::from_fn(n, c, |_, _| (below(&mut rng, 2001) as f64 - 1000.0) / 100.0)
}

/// Largest entry difference relative to `b`'s largest entry.
pub fn max_rel_diff(a: &Mat<f64>, b: &Mat<f64>) -> f64 {
    let mut scale = 0.0f64;
    let mut diff = 0.0f64;
    for j in 0..a.ncols() {
        for i in 0..a.nrows() {
            scale = scale.max(b[(i, j)].abs());
            diff = diff.max((a[(i, j)] - b[(i, j)]).abs());
        }
    }
    diff / scale
}

/// `A x` for `A` stored as its lower triangle.
pub fn sparse_mul_dense_sym(a: &SparseMatrix, x: &Mat<f64>) -> Mat<f64> {
    let mut y = Mat::zeros(a.nrows(), x.ncols());
    for (i, j, v) in sparse_triplets(a.as_ref()) {
        for c in 0..x.ncols() {
            y[(i, c)] += v * x[(j, c)];
            if i != j {
                y[(j, c)] += v * x[(i, c)];
            }
        }
    }
    y
}
