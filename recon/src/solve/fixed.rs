//! Quadratic minimisation with fixed values (libigl `min_quad_with_fixed`).
//!
//! Solves `A x = b` where the entries `x_k` (k ∈ known) are prescribed: the known
//! columns move to the right-hand side, `A_uu x_u = b_u − A_uk x_k`, and `A_uu` (SPD when
//! `A` is symmetric positive semidefinite with every null-space component pinned) is
//! factorised once; [`FixedSolver::solve`] then costs two triangular solves.

use faer::sparse::SparseColMatRef;
use faer::{Mat, MatRef};

use super::sparse::{sparse_from_triplets, sparse_mul_dense, sparse_triplets};
use super::{CholeskyOptions, CholeskySolver, SolveError, SparseMatrix};

const NONE: usize = usize::MAX;

/// Precomputed factorisation of `A_uu` for a fixed set of known indices.
#[derive(Debug, Clone)]
pub struct FixedSolver {
    n: usize,
    slot: Vec<usize>,
    known: Vec<usize>,
    unknown: Vec<usize>,
    a_uk: SparseMatrix,
    chol: CholeskySolver,
    /// Per unknown slot: its row in the factor's order.
    factor_row: Vec<usize>,
}

impl FixedSolver {
    /// Splits `a` (full symmetric storage, `n × n`) by the `known` indices and factorises
    /// the free block. Duplicate known indices are ignored.
    pub fn precompute(
        a: SparseColMatRef<'_, usize, f64>,
        known: &[usize],
        options: CholeskyOptions,
    ) -> Result<Self, SolveError> {
        Self::precompute_with(a, known, |a_uu, _| CholeskySolver::new(a_uu, options))
    }

    /// [`Self::precompute`] with the factor's elimination order given over all `n`
    /// indices (the known ones are skipped; e.g. from
    /// [`super::OrderingSkeleton::order_free`]). Fails unless it holds every free index once.
    pub fn precompute_ordered(
        a: SparseColMatRef<'_, usize, f64>,
        known: &[usize],
        options: CholeskyOptions,
        order: &[usize],
    ) -> Result<Self, SolveError> {
        Self::precompute_with(a, known, |a_uu, slot| {
            let nu = a_uu.nrows();
            let perm: Vec<usize> = order
                .iter()
                .filter_map(|&i| slot.get(i).copied().filter(|&s| s < nu))
                .collect();
            let mut chol = CholeskySolver::analyze_ordered(a_uu, options, &perm)?;
            chol.factorize(a_uu)?;
            Ok(chol)
        })
    }

    fn precompute_with(
        a: SparseColMatRef<'_, usize, f64>,
        known: &[usize],
        factor: impl FnOnce(
            SparseColMatRef<'_, usize, f64>,
            &[usize],
        ) -> Result<CholeskySolver, SolveError>,
    ) -> Result<Self, SolveError> {
        let n = a.nrows();
        if a.ncols() != n {
            return Err(SolveError::Dimension("matrix is not square".into()));
        }
        let (slot, known, unknown) = partition(n, known)?;
        let (a_uu, a_uk) = split_blocks(a, &slot, unknown.len(), known.len())?;
        let chol = factor(a_uu.as_ref(), &slot)?;
        let mut factor_row = vec![NONE; unknown.len()];
        for (k, u) in chol.factor_order().into_iter().enumerate() {
            factor_row[u] = k;
        }
        Ok(Self {
            n,
            slot,
            known,
            unknown,
            a_uk,
            chol,
            factor_row,
        })
    }

    /// New values for a matrix with the same pattern and known set (e.g. new weights or
    /// a new time step): only the numeric factorisation is redone, the symbolic analysis
    /// is reused. Fails with [`SolveError::PatternChanged`] if the pattern differs.
    pub fn refactorize(&mut self, a: SparseColMatRef<'_, usize, f64>) -> Result<(), SolveError> {
        if a.nrows() != self.n || a.ncols() != self.n {
            return Err(SolveError::Dimension("matrix size changed".into()));
        }
        let (a_uu, a_uk) = split_blocks(a, &self.slot, self.unknown.len(), self.known.len())?;
        self.chol.factorize(a_uu.as_ref())?;
        self.a_uk = a_uk;
        Ok(())
    }

    /// Indices of the free unknowns, in the order of the reduced system.
    pub fn unknown(&self) -> &[usize] {
        &self.unknown
    }

    /// The known indices, in the order `known_values` rows are read.
    pub fn known(&self) -> &[usize] {
        &self.known
    }

    /// Stored entries of the Cholesky factor of `A_uu`.
    pub fn factor_len(&self) -> usize {
        self.chol.factor_len()
    }

    /// Per index of the full system: its row in the layout of [`Self::solve_factor_rows`],
    /// or `usize::MAX` for a known index.
    pub fn factor_rows(&self) -> Vec<usize> {
        let mut rows = vec![NONE; self.n];
        for (&i, &r) in self.unknown.iter().zip(&self.factor_row) {
            rows[i] = r;
        }
        rows
    }

    /// [`Self::solve`] for `K` right-hand sides in place, without allocating: `w` holds the
    /// free rows of `b`, row-interleaved, each at its [`Self::factor_rows`] position, and
    /// becomes the free part of the solution in the same layout; `known_values` has one row
    /// per [`Self::known`] index.
    pub fn solve_factor_rows<const K: usize>(
        &self,
        w: &mut [[f64; K]],
        known_values: &[[f64; K]],
    ) -> Result<(), SolveError> {
        if w.len() != self.unknown.len() || known_values.len() != self.known.len() {
            return Err(SolveError::Dimension(
                "rhs or known values have the wrong length".into(),
            ));
        }
        let a = self.a_uk.as_ref();
        for (j, x) in known_values.iter().enumerate() {
            for (&u, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
                let r = &mut w[self.factor_row[u]];
                for c in 0..K {
                    r[c] -= v * x[c];
                }
            }
        }
        self.chol.solve_factor_rows(w)
    }

    /// Solves for all columns of `b` (`n × c`) with `known_values` (`k × c`, rows in the
    /// order of [`Self::known`]). Returns the full `n × c` solution.
    pub fn solve(
        &self,
        b: MatRef<'_, f64>,
        known_values: MatRef<'_, f64>,
    ) -> Result<Mat<f64>, SolveError> {
        let c = b.ncols();
        if b.nrows() != self.n
            || known_values.nrows() != self.known.len()
            || known_values.ncols() != c
        {
            return Err(SolveError::Dimension(
                "rhs or known values have the wrong shape".into(),
            ));
        }
        let coupling = sparse_mul_dense(self.a_uk.as_ref(), known_values)?;
        let mut rhs = Mat::from_fn(self.unknown.len(), c, |r, col| {
            b[(self.unknown[r], col)] - coupling[(r, col)]
        });
        self.chol.solve_in_place(rhs.as_mut())?;
        let mut x = Mat::zeros(self.n, c);
        for (r, &i) in self.unknown.iter().enumerate() {
            for col in 0..c {
                x[(i, col)] = rhs[(r, col)];
            }
        }
        for (r, &i) in self.known.iter().enumerate() {
            for col in 0..c {
                x[(i, col)] = known_values[(r, col)];
            }
        }
        Ok(x)
    }
}

/// `(slot of every index, known indices, unknown indices)`.
type Partition = (Vec<usize>, Vec<usize>, Vec<usize>);

/// Maps each index to its slot in the unknown or known list (known slots offset by n).
fn partition(n: usize, known: &[usize]) -> Result<Partition, SolveError> {
    let mut slot = vec![NONE; n];
    let mut kept_known = Vec::new();
    for &k in known {
        if k >= n {
            return Err(SolveError::IndexOutOfRange { index: k, size: n });
        }
        if slot[k] == NONE {
            slot[k] = n + kept_known.len();
            kept_known.push(k);
        }
    }
    let mut unknown = Vec::with_capacity(n - kept_known.len());
    for (i, s) in slot.iter_mut().enumerate() {
        if *s == NONE {
            *s = unknown.len();
            unknown.push(i);
        }
    }
    Ok((slot, kept_known, unknown))
}

fn split_blocks(
    a: SparseColMatRef<'_, usize, f64>,
    slot: &[usize],
    nu: usize,
    nk: usize,
) -> Result<(SparseMatrix, SparseMatrix), SolveError> {
    let n = slot.len();
    let (mut uu, mut uk) = (Vec::new(), Vec::new());
    for (i, j, v) in sparse_triplets(a) {
        let (si, sj) = (slot[i], slot[j]);
        match (si < n, sj < n) {
            (true, true) => uu.push((si, sj, v)),
            (true, false) => uk.push((si, sj - n, v)),
            _ => {}
        }
    }
    Ok((
        sparse_from_triplets(nu, nu, &uu)?,
        sparse_from_triplets(nu, nk, &uk)?,
    ))
}
