//! Sparse matrix type used throughout the crate and a checked triplet constructor.

use faer::sparse::{SparseColMat, SparseColMatRef, Triplet};
use faer::{Mat, MatRef};

use super::SolveError;

/// Column-major (CSC) sparse matrix of `f64` with `usize` indices: the type every
/// operator returns.
pub type SparseMatrix = SparseColMat<usize, f64>;

/// Builds an `nrows × ncols` matrix from `(row, col, value)` triplets; duplicates are
/// summed. Fails on an out-of-range index instead of panicking.
pub fn sparse_from_triplets(
    nrows: usize,
    ncols: usize,
    triplets: &[(usize, usize, f64)],
) -> Result<SparseMatrix, SolveError> {
    for &(r, c, _) in triplets {
        if r >= nrows {
            return Err(SolveError::IndexOutOfRange {
                index: r,
                size: nrows,
            });
        }
        if c >= ncols {
            return Err(SolveError::IndexOutOfRange {
                index: c,
                size: ncols,
            });
        }
    }
    let t: Vec<Triplet<usize, usize, f64>> = triplets
        .iter()
        .map(|&(r, c, v)| Triplet::new(r, c, v))
        .collect();
    SparseColMat::try_new_from_triplets(nrows, ncols, &t).map_err(|_| SolveError::OutOfMemory)
}

/// `y = A x` for a dense multi-column `x` (`A` is `m × n`, `x` is `n × c`).
pub fn sparse_mul_dense(
    a: SparseColMatRef<'_, usize, f64>,
    x: MatRef<'_, f64>,
) -> Result<Mat<f64>, SolveError> {
    if a.ncols() != x.nrows() {
        return Err(SolveError::Dimension(format!(
            "{}x{} times {}x{}",
            a.nrows(),
            a.ncols(),
            x.nrows(),
            x.ncols()
        )));
    }
    let mut y = Mat::zeros(a.nrows(), x.ncols());
    for j in 0..a.ncols() {
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            for c in 0..x.ncols() {
                y[(i, c)] += v * x[(j, c)];
            }
        }
    }
    Ok(y)
}

/// All stored entries `(row, col, value)` of `a`.
pub fn sparse_triplets(a: SparseColMatRef<'_, usize, f64>) -> Vec<(usize, usize, f64)> {
    let mut t = Vec::with_capacity(a.compute_nnz());
    for j in 0..a.ncols() {
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            t.push((i, j, v));
        }
    }
    t
}

/// The `n × n` matrix `Σ wₖ Aₖᵀ Aₖ` (normal equations of stacked least squares).
pub fn weighted_gram(
    n: usize,
    terms: &[(f64, SparseColMatRef<'_, usize, f64>)],
) -> Result<SparseMatrix, SolveError> {
    let mut t = Vec::new();
    for &(w, a) in terms {
        if a.ncols() != n {
            return Err(SolveError::Dimension(format!(
                "term has {} columns, expected {n}",
                a.ncols()
            )));
        }
        let mut rows: Vec<Vec<(usize, f64)>> = vec![Vec::new(); a.nrows()];
        for (i, j, v) in sparse_triplets(a) {
            rows[i].push((j, v));
        }
        for row in rows {
            for &(j, vj) in &row {
                for &(k, vk) in &row {
                    t.push((j, k, w * vj * vk));
                }
            }
        }
    }
    sparse_from_triplets(n, n, &t)
}
