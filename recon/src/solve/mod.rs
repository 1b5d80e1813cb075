//! Sparse solvers (FIRES thesis, Part I §1.9; docs/architecture.md §8).
//!
//! libigl's precompute/solve split on top of faer's sparse Cholesky:
//! * [`CholeskySolver`]: symbolic analysis (AMD or [`nested_dissection`] ordering,
//!   elimination tree, supernodes) done once per sparsity pattern, numeric factorisation
//!   redone cheaply when only the values change, and solves of many right-hand sides at
//!   once (x, y, z together); a right-hand side part shared by many solves is
//!   forward-substituted once ([`CholeskySolver::share_rhs`]), so a solve whose own part
//!   has few nonzero rows visits only the supernodes they reach;
//! * [`FixedSolver`]: `min ½ xᵀAx − xᵀb` with some entries of `x` fixed (libigl
//!   `min_quad_with_fixed`), eliminating the fixed rows so the system stays SPD;
//! * [`LeastSquaresSolver`]: stacked soft constraints `Σ wₖ‖Aₖx − bₖ‖²` via the normal
//!   equations.
//!
//! Threading: everything defaults to one thread (`Par::Seq`). On the 2-core machines here
//! faer's parallel sparse factorisation and solves were measured slower than sequential
//! ones (faer issue #211). The exceptions: `FillOrdering::Auto`'s two independent symbolic
//! analyses run on two threads, and [`SubtreeThreads`] puts a second thread on
//! independent subtrees of the elimination tree (our own supernodal numeric factorisation
//! and backward substitution, same factor layout as faer's).

mod cholesky;
mod cholesky_options;
mod column_kernels;
mod error;
mod fixed;
mod least_squares;
mod ordering;
mod sparse;
mod supernodal_numeric;
mod supernodal_solve;
mod supernode_tree;

pub use cholesky::{CholeskySolver, SharedRhs};
pub use cholesky_options::{
    CholeskyOptions, FactorMode, Factorization, FillOrdering, SolveKernel, SubtreeThreads,
    ND_MIN_DIM,
};
pub use error::SolveError;
pub use fixed::FixedSolver;
pub use least_squares::LeastSquaresSolver;
pub use ordering::{nested_dissection, OrderingSkeleton};
pub use sparse::{
    lower_product_sum, sparse_from_triplets, sparse_mul_dense, sparse_triplets, transpose,
    weighted_gram, ProductTerm, SparseMatrix,
};

/// Runs `here` on this thread and `there` on a second one, and returns both results (a
/// panic on the second thread is resumed here).
pub(crate) fn join<A, B: Send>(
    here: impl FnOnce() -> A,
    there: impl FnOnce() -> B + Send,
) -> (A, B) {
    std::thread::scope(|scope| {
        let other = scope.spawn(there);
        let a = here();
        let b = other
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        (a, b)
    })
}
