//! Stacked soft constraints: minimise `Σₖ wₖ ‖Aₖ x − bₖ‖²` through the normal equations
//! `(Σ wₖ AₖᵀAₖ) x = Σ wₖ Aₖᵀ bₖ`, factorised once (the Laplacian-editing pattern of
//! Differential Methods for Intuitive 3D Shape Modeling, ch. 1: Laplacian rows plus weighted positional rows).

use faer::sparse::SparseColMatRef;
use faer::{Mat, MatRef};

use super::sparse::{sparse_triplets, weighted_gram};
use super::{CholeskyOptions, CholeskySolver, SolveError, SparseMatrix};

/// Factorised normal equations of a stack of weighted sparse least-squares terms.
#[derive(Debug, Clone)]
pub struct LeastSquaresSolver {
    weights: Vec<f64>,
    transposed_terms: Vec<Vec<(usize, usize, f64)>>,
    rows: Vec<usize>,
    n: usize,
    chol: CholeskySolver,
}

impl LeastSquaresSolver {
    /// Builds and factorises `Σ wₖ AₖᵀAₖ`; every `Aₖ` must have `n` columns.
    /// Fails with [`SolveError::NotPositiveDefinite`] if the stack does not determine `x`.
    pub fn new(
        n: usize,
        terms: &[(f64, SparseColMatRef<'_, usize, f64>)],
        options: CholeskyOptions,
    ) -> Result<Self, SolveError> {
        let gram: SparseMatrix = weighted_gram(n, terms)?;
        let chol = CholeskySolver::new(gram.as_ref(), options)?;
        Ok(Self {
            weights: terms.iter().map(|t| t.0).collect(),
            transposed_terms: terms.iter().map(|t| sparse_triplets(t.1)).collect(),
            rows: terms.iter().map(|t| t.1.nrows()).collect(),
            n,
            chol,
        })
    }

    /// Solves for one right-hand side `bₖ` per term (each `mₖ × c`, same `c`).
    pub fn solve(&self, rhs: &[MatRef<'_, f64>]) -> Result<Mat<f64>, SolveError> {
        if rhs.len() != self.weights.len() {
            return Err(SolveError::Dimension(format!(
                "{} right-hand sides for {} terms",
                rhs.len(),
                self.weights.len()
            )));
        }
        let c = rhs.first().map_or(1, |b| b.ncols());
        let mut x = Mat::zeros(self.n, c);
        for (k, b) in rhs.iter().enumerate() {
            if b.nrows() != self.rows[k] || b.ncols() != c {
                return Err(SolveError::Dimension(format!(
                    "right-hand side {k} has the wrong shape"
                )));
            }
            for &(i, j, v) in &self.transposed_terms[k] {
                for col in 0..c {
                    x[(j, col)] += self.weights[k] * v * b[(i, col)];
                }
            }
        }
        self.chol.solve_in_place(x.as_mut())?;
        Ok(x)
    }
}
