//! Solver errors.

/// What went wrong in a factorisation or solve.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// A non-positive pivot was met in the LLᵀ factorisation: the matrix is not positive
    /// definite (`column` is in the fill-reducing permuted order).
    #[error("matrix is not positive definite (non-positive pivot at permuted column {column})")]
    NotPositiveDefinite {
        /// Permuted column of the failing pivot.
        column: usize,
    },
    /// A zero pivot was met in the LDLᵀ factorisation.
    #[error("matrix is singular (zero pivot at permuted column {column})")]
    Singular {
        /// Permuted column of the failing pivot.
        column: usize,
    },
    /// The matrix is not square, or a right-hand side has the wrong number of rows.
    #[error("dimension mismatch: {0}")]
    Dimension(String),
    /// `factorize` was given a matrix whose sparsity pattern differs from the analysed one.
    #[error("sparsity pattern differs from the one analysed")]
    PatternChanged,
    /// `solve` was called before a successful `factorize`.
    #[error("no numeric factorisation available")]
    NotFactorized,
    /// An index is out of range (fixed-value lists, triplets).
    #[error("index {index} out of range for size {size}")]
    IndexOutOfRange {
        /// Offending index.
        index: usize,
        /// Valid range is `0..size`.
        size: usize,
    },
    /// Memory for the factor could not be allocated, or an index overflowed.
    #[error("out of memory or index overflow in the sparse factorisation")]
    OutOfMemory,
}
