//! The sparse kernels the editing systems are assembled with, against dense arithmetic:
//! triplet assembly, transposition and the lower triangle of a sum of products.

// Dense reference arithmetic reads clearest with explicit indices.
#![allow(clippy::needless_range_loop)]

use fires_recon::solve::{
    lower_product_sum, sparse_from_triplets, transpose, SolveError, SparseMatrix,
};

/// A small deterministic generator (64-bit LCG, high bits).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        self.0 >> 33
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    fn value(&mut self) -> f64 {
        self.next() as f64 / (1u64 << 31) as f64 * 2.0 - 1.0
    }
}

/// Random triplets with repeated positions (about a quarter of them).
fn triplets(g: &mut Lcg, m: usize, n: usize, count: usize) -> Vec<(usize, usize, f64)> {
    let mut t: Vec<(usize, usize, f64)> = Vec::with_capacity(count);
    for _ in 0..count {
        let (i, j) = match t.last() {
            Some(&(i, j, _)) if g.below(4) == 0 => (i, j),
            _ => (g.below(m), g.below(n)),
        };
        t.push((i, j, g.value()));
    }
    t
}

fn dense(a: &SparseMatrix) -> Vec<Vec<f64>> {
    let mut d = vec![vec![0.0; a.ncols()]; a.nrows()];
    for j in 0..a.ncols() {
        for (&i, &v) in a
            .as_ref()
            .row_idx_of_col_raw(j)
            .iter()
            .zip(a.as_ref().val_of_col(j))
        {
            d[i][j] += v;
        }
    }
    d
}

fn rows_sorted_and_unique(a: &SparseMatrix) -> bool {
    (0..a.ncols()).all(|j| {
        a.as_ref()
            .row_idx_of_col_raw(j)
            .windows(2)
            .all(|w| w[0] < w[1])
    })
}

/// A matrix whose columns hold their rows in reverse order (what a caller may pass).
fn reversed_columns(a: &SparseMatrix) -> SparseMatrix {
    let mut col_ptr = vec![0];
    let mut row_idx = Vec::new();
    let mut vals = Vec::new();
    for j in 0..a.ncols() {
        let r = a.as_ref().row_idx_of_col_raw(j);
        let v = a.as_ref().val_of_col(j);
        row_idx.extend(r.iter().rev());
        vals.extend(v.iter().rev());
        col_ptr.push(row_idx.len());
    }
    SparseMatrix::new(
        faer::sparse::SymbolicSparseColMat::new_unsorted_checked(
            a.nrows(),
            a.ncols(),
            col_ptr,
            None,
            row_idx,
        ),
        vals,
    )
}

#[test]
fn triplets_are_summed_into_sorted_columns() {
    let mut g = Lcg(7);
    let t = triplets(&mut g, 23, 17, 300);
    let a = sparse_from_triplets(23, 17, &t).unwrap();
    let mut want = vec![vec![0.0; 17]; 23];
    for &(i, j, v) in &t {
        want[i][j] += v;
    }
    let got = dense(&a);
    for i in 0..23 {
        for j in 0..17 {
            assert!((got[i][j] - want[i][j]).abs() < 1e-14, "({i}, {j})");
        }
    }
    assert!(rows_sorted_and_unique(&a));
    assert!(matches!(
        sparse_from_triplets(3, 3, &[(3, 0, 1.0)]),
        Err(SolveError::IndexOutOfRange { index: 3, size: 3 })
    ));
}

#[test]
fn transpose_swaps_entries_and_sorts_rows() {
    let mut g = Lcg(11);
    let a = sparse_from_triplets(31, 13, &triplets(&mut g, 31, 13, 200)).unwrap();
    // From unsorted columns too: the transpose's rows come out ascending either way.
    for a in [a.clone(), reversed_columns(&a)] {
        let at = transpose(a.as_ref());
        assert_eq!((at.nrows(), at.ncols()), (13, 31));
        assert!(rows_sorted_and_unique(&at));
        let (d, dt) = (dense(&a), dense(&at));
        for i in 0..31 {
            for j in 0..13 {
                assert_eq!(d[i][j], dt[j][i]);
            }
        }
    }
    // Transposing twice gives the same storage back.
    let back = transpose(transpose(a.as_ref()).as_ref());
    assert_eq!(back.as_ref().col_ptr(), a.as_ref().col_ptr());
    assert_eq!(back.as_ref().row_idx(), a.as_ref().row_idx());
    assert_eq!(back.as_ref().val(), a.as_ref().val());
}

#[test]
fn lower_product_sum_is_the_lower_triangle_of_the_dense_sum() {
    let mut g = Lcg(3);
    let n = 40;
    // Two terms of different row counts, as a normal matrix Σ wₜ Aₜᵀ Wₜ Aₜ is built.
    let a1 = sparse_from_triplets(25, n, &triplets(&mut g, 25, n, 120)).unwrap();
    let a2 = sparse_from_triplets(60, n, &triplets(&mut g, 60, n, 300)).unwrap();
    let w2 = sparse_from_triplets(60, 60, &triplets(&mut g, 60, 60, 200)).unwrap();
    let p1 = transpose(a1.as_ref());
    // P₂ = A₂ᵀ W₂, formed densely and stored sparse.
    let (da2, dw2) = (dense(&a2), dense(&w2));
    let mut p2t = Vec::new();
    for u in 0..n {
        for i in 0..60 {
            let v: f64 = (0..60).map(|k| da2[k][u] * dw2[k][i]).sum();
            if v != 0.0 {
                p2t.push((u, i, v));
            }
        }
    }
    let p2 = sparse_from_triplets(n, 60, &p2t).unwrap();
    let (dp1, dp2, da1) = (dense(&p1), dense(&p2), dense(&a1));
    let mut want = vec![vec![0.0; n]; n];
    for u in 0..n {
        for j in 0..n {
            want[u][j] = (0..25).map(|i| dp1[u][i] * da1[i][j]).sum::<f64>()
                + (0..60).map(|i| dp2[u][i] * da2[i][j]).sum::<f64>();
        }
    }
    // Sorted and unsorted columns of P give the same matrix.
    for (q1, q2) in [
        (p1.clone(), p2.clone()),
        (reversed_columns(&p1), reversed_columns(&p2)),
    ] {
        let got = lower_product_sum(n, &[(q1.as_ref(), a1.as_ref()), (q2.as_ref(), a2.as_ref())])
            .unwrap();
        assert!(rows_sorted_and_unique(&got));
        let d = dense(&got);
        let scale = want.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for u in 0..n {
            for j in 0..n {
                if u >= j {
                    assert!((d[u][j] - want[u][j]).abs() <= 1e-13 * scale, "({u}, {j})");
                } else {
                    assert_eq!(d[u][j], 0.0, "({u}, {j}) is above the diagonal");
                }
            }
        }
    }
    // Shapes that do not chain are an error, not a panic.
    assert!(matches!(
        lower_product_sum(n, &[(p1.as_ref(), a2.as_ref())]),
        Err(SolveError::Dimension(_))
    ));
}

#[test]
fn lower_product_sum_pattern_depends_only_on_the_input_patterns() {
    // A numeric refactorisation needs the analysed pattern back whatever the values are,
    // including products that cancel to exactly zero.
    let mut g = Lcg(5);
    let a = sparse_from_triplets(30, 20, &triplets(&mut g, 30, 20, 90)).unwrap();
    let p = transpose(a.as_ref());
    let mut zeroed = a.clone();
    for v in zeroed.val_mut() {
        *v = 0.0;
    }
    let pz = transpose(zeroed.as_ref());
    let g1 = lower_product_sum(20, &[(p.as_ref(), a.as_ref())]).unwrap();
    let g0 = lower_product_sum(20, &[(pz.as_ref(), zeroed.as_ref())]).unwrap();
    assert_eq!(g1.as_ref().col_ptr(), g0.as_ref().col_ptr());
    assert_eq!(g1.as_ref().row_idx(), g0.as_ref().row_idx());
    assert!(g0.as_ref().val().iter().all(|&v| v == 0.0));
}
