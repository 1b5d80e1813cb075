//! Row-by-row assembly of the sparse operators the editing methods stack
//! ([`super::system::QuadTerm`]), without a triplet list.

use faer::sparse::SymbolicSparseColMat;

use crate::solve::{transpose, SolveError, SparseMatrix};

/// Builds a sparse matrix row by row (entries of a row in any order, duplicates summed),
/// without a triplet list.
#[derive(Debug, Clone)]
pub struct RowBuilder {
    ncols: usize,
    row_ptr: Vec<usize>,
    col_idx: Vec<usize>,
    vals: Vec<f64>,
    buf: Vec<(usize, f64)>,
}

impl RowBuilder {
    /// An empty matrix with `ncols` columns.
    pub fn new(ncols: usize) -> Self {
        Self {
            ncols,
            row_ptr: vec![0],
            col_idx: Vec::new(),
            vals: Vec::new(),
            buf: Vec::new(),
        }
    }

    /// An empty matrix with `ncols` columns and room for `rows` rows of `nnz` entries in all.
    pub fn with_capacity(ncols: usize, rows: usize, nnz: usize) -> Self {
        let mut row_ptr = Vec::with_capacity(rows + 1);
        row_ptr.push(0);
        Self {
            ncols,
            row_ptr,
            col_idx: Vec::with_capacity(nnz),
            vals: Vec::with_capacity(nnz),
            buf: Vec::new(),
        }
    }

    /// Number of rows pushed.
    pub fn nrows(&self) -> usize {
        self.row_ptr.len() - 1
    }

    /// Appends a row; fails on a column out of range, leaving the matrix as it was.
    pub fn push(&mut self, entries: &[(usize, f64)]) -> Result<(), SolveError> {
        // Rows already sorted without duplicates (the coherence rows) need no copy.
        let row: &[(usize, f64)] = if entries.windows(2).all(|w| w[0].0 < w[1].0) {
            entries
        } else {
            self.buf.clear();
            self.buf.extend_from_slice(entries);
            self.buf.sort_unstable_by_key(|e| e.0);
            &self.buf
        };
        if let Some(&(j, _)) = row.last().filter(|e| e.0 >= self.ncols) {
            return Err(SolveError::IndexOutOfRange {
                index: j,
                size: self.ncols,
            });
        }
        let start = self.col_idx.len();
        for &(j, v) in row {
            match self.vals.last_mut() {
                Some(x) if self.col_idx.len() > start && self.col_idx.last() == Some(&j) => *x += v,
                _ => {
                    self.col_idx.push(j);
                    self.vals.push(v);
                }
            }
        }
        self.row_ptr.push(self.col_idx.len());
        Ok(())
    }

    /// The transpose of the matrix (`ncols × nrows`, column `i` is row `i` as pushed, rows
    /// ascending), at no cost: what [`super::system::QuadTerm::a_t_w`] takes.
    pub fn finish_transposed(self) -> SparseMatrix {
        let nrows = self.nrows();
        SparseMatrix::new(
            SymbolicSparseColMat::new_checked(self.ncols, nrows, self.row_ptr, None, self.col_idx),
            self.vals,
        )
    }

    /// The matrix in column-major storage (rows ascending in every column).
    pub fn finish(self) -> Result<SparseMatrix, SolveError> {
        Ok(transpose(self.finish_transposed().as_ref()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_in_any_order_sum_duplicates_and_sorted_rows_are_stored_as_given() {
        let mut b = RowBuilder::new(4);
        b.push(&[(3, 1.0), (0, 2.0), (3, 0.5)]).unwrap();
        b.push(&[(0, -1.0), (1, 4.0), (2, 5.0)]).unwrap();
        b.push(&[]).unwrap();
        // A rejected row leaves nothing behind.
        for bad in [&[(0, 1.0), (4, 1.0)][..], &[(4, 1.0), (0, 1.0)][..]] {
            assert!(matches!(
                b.push(bad),
                Err(SolveError::IndexOutOfRange { index: 4, size: 4 })
            ));
        }
        let a = b.finish().unwrap();
        assert_eq!((a.nrows(), a.ncols(), a.compute_nnz()), (3, 4, 5));
        let mut dense = [[0.0; 4]; 3];
        for (i, j, v) in crate::solve::sparse_triplets(a.as_ref()) {
            dense[i][j] += v;
        }
        assert_eq!(
            dense,
            [
                [2.0, 0.0, 0.0, 1.5],
                [-1.0, 4.0, 5.0, 0.0],
                [0.0, 0.0, 0.0, 0.0]
            ]
        );
    }
}
