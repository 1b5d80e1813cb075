//! Sparse matrix type used throughout the crate and a checked triplet constructor.

use faer::sparse::{SparseColMat, SparseColMatRef};
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
    // Counting sort by column, then each column's rows sorted and duplicates summed.
    let mut col_ptr = vec![0usize; ncols + 1];
    for &(_, c, _) in triplets {
        col_ptr[c + 1] += 1;
    }
    for c in 0..ncols {
        col_ptr[c + 1] += col_ptr[c];
    }
    let mut next = col_ptr.clone();
    let mut entries = vec![(0usize, 0.0f64); triplets.len()];
    for &(r, c, v) in triplets {
        entries[next[c]] = (r, v);
        next[c] += 1;
    }
    let mut out_ptr = Vec::with_capacity(ncols + 1);
    let mut row_idx = Vec::with_capacity(triplets.len());
    let mut vals = Vec::with_capacity(triplets.len());
    out_ptr.push(0);
    for c in 0..ncols {
        let col = &mut entries[col_ptr[c]..col_ptr[c + 1]];
        col.sort_unstable_by_key(|e| e.0);
        let mut last = usize::MAX;
        for &(r, v) in col.iter() {
            if r == last {
                if let Some(x) = vals.last_mut() {
                    *x += v;
                }
            } else {
                row_idx.push(r);
                vals.push(v);
                last = r;
            }
        }
        out_ptr.push(row_idx.len());
    }
    Ok(SparseMatrix::new(
        faer::sparse::SymbolicSparseColMat::new_checked(nrows, ncols, out_ptr, None, row_idx),
        vals,
    ))
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

/// `Aᵀ` in column-major storage with every column's rows ascending (duplicates kept), by a
/// counting sort over the rows: linear in the entries, with none of a general conversion's
/// sorting and deduplication.
pub fn transpose(a: SparseColMatRef<'_, usize, f64>) -> SparseMatrix {
    let (m, n) = (a.nrows(), a.ncols());
    let mut count = vec![0usize; m + 1];
    for j in 0..n {
        for &i in a.row_idx_of_col_raw(j) {
            count[i + 1] += 1;
        }
    }
    for i in 0..m {
        count[i + 1] += count[i];
    }
    let col_ptr = count.clone();
    let nnz = count[m];
    let mut row_idx = vec![0usize; nnz];
    let mut vals = vec![0.0; nnz];
    for j in 0..n {
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            let at = count[i];
            row_idx[at] = j;
            vals[at] = v;
            count[i] += 1;
        }
    }
    SparseMatrix::new(
        faer::sparse::SymbolicSparseColMat::new_checked(n, m, col_ptr, None, row_idx),
        vals,
    )
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

/// One `(Pₜ, Aₜ)` of [`lower_product_sum`].
pub type ProductTerm<'a> = (
    SparseColMatRef<'a, usize, f64>,
    SparseColMatRef<'a, usize, f64>,
);

/// The lower triangle (row ≥ column, rows sorted) of `Σₜ Pₜ Aₜ` for `Pₜ` (`n × mₜ`) and
/// `Aₜ` (`mₜ × n`): the normal matrix `Σ wₜ Aₜᵀ Wₜ Aₜ` of stacked terms given
/// `Pₜ = wₜ Aₜᵀ Wₜ`, of which a Cholesky factor reads one triangle.
///
/// Gustavson's column-by-column product (F. G. Gustavson, *Two fast algorithms for sparse
/// matrices*, ACM TOMS 1978) with one dense accumulator for all terms at once: half the
/// work of the full products and no separate sum. Every product that touches an entry
/// stores it, so the pattern depends only on the input patterns (a numeric
/// refactorisation with new values finds the analysed pattern).
pub fn lower_product_sum(n: usize, terms: &[ProductTerm<'_>]) -> Result<SparseMatrix, SolveError> {
    for (p, a) in terms {
        if p.nrows() != n || a.ncols() != n || p.ncols() != a.nrows() {
            return Err(SolveError::Dimension(format!(
                "{}x{} times {}x{} is not {n}x{n}",
                p.nrows(),
                p.ncols(),
                a.nrows(),
                a.ncols()
            )));
        }
    }
    // With sorted columns of `P`, a cursor per column skips the rows above the diagonal:
    // the columns `j` come in increasing order, so each cursor only moves forward.
    let sorted: Vec<bool> = terms
        .iter()
        .map(|(p, _)| (0..p.ncols()).all(|c| p.row_idx_of_col_raw(c).is_sorted()))
        .collect();
    let mut cursors: Vec<Vec<usize>> = terms.iter().map(|(p, _)| vec![0; p.ncols()]).collect();
    // Per row: the column that last touched it and the running sum, side by side.
    let mut acc = vec![(usize::MAX, 0.0f64); n];
    let mut list = Vec::new();
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::new();
    let mut vals = Vec::new();
    col_ptr.push(0);
    for j in 0..n {
        list.clear();
        for (((p, a), &sorted), cursor) in terms.iter().zip(&sorted).zip(&mut cursors) {
            for (&i, &aij) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
                let rows = p.row_idx_of_col_raw(i);
                let from = if sorted {
                    let c = &mut cursor[i];
                    while *c < rows.len() && rows[*c] < j {
                        *c += 1;
                    }
                    *c
                } else {
                    0
                };
                for (&u, &v) in rows[from..].iter().zip(&p.val_of_col(i)[from..]) {
                    if u < j {
                        continue;
                    }
                    let e = &mut acc[u];
                    if e.0 != j {
                        *e = (j, 0.0);
                        list.push(u);
                    }
                    e.1 += v * aij;
                }
            }
        }
        list.sort_unstable();
        row_idx.extend_from_slice(&list);
        vals.extend(list.iter().map(|&u| acc[u].1));
        col_ptr.push(row_idx.len());
    }
    Ok(SparseMatrix::new(
        faer::sparse::SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx),
        vals,
    ))
}
