//! The options of [`super::CholeskySolver`]: which factorisation, storage, solve kernel,
//! fill-reducing ordering and threads.

use faer::{Par, Side};

/// Which factorisation to compute.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Factorization {
    /// `A = L Lᵀ`; fails with [`super::SolveError::NotPositiveDefinite`] unless `A` is SPD.
    #[default]
    Llt,
    /// `A = L D Lᵀ` with unit `L`; needs only non-zero pivots.
    Ldlt,
}

/// Simplicial (column by column) or supernodal (dense blocks) factor storage.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FactorMode {
    /// faer decides from the estimated flop count per nonzero (its default threshold).
    #[default]
    Auto,
    /// Always simplicial.
    Simplicial,
    /// Always supernodal.
    Supernodal,
}

/// Which triangular-solve kernel a supernodal LLᵀ factor uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SolveKernel {
    /// The column-blocked solve of `supernodal_solve` for sequential LLᵀ supernodal
    /// factors, faer's solve otherwise.
    #[default]
    Auto,
    /// Always faer's solve.
    Faer,
}

/// The fill-reducing ordering of the symbolic analysis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FillOrdering {
    /// From [`ND_MIN_DIM`] unknowns up, whichever of nested dissection and AMD gives the
    /// smaller factor (both symbolic analyses are run, on two threads; each costs a
    /// fraction of the numeric factorisation); AMD below.
    #[default]
    Auto,
    /// faer's approximate minimum degree.
    Amd,
    /// [`super::ordering::nested_dissection`].
    NestedDissection,
}

/// Where [`super::CholeskySolver`] puts a second thread to work on independent subtrees of the
/// elimination tree (supernodal LLᵀ factors only; see `supernodal_numeric`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SubtreeThreads {
    /// One thread throughout (faer's numeric factorisation).
    #[default]
    Off,
    /// The numeric factorisation (and [`super::CholeskySolver::share_rhs`]) on two threads;
    /// solves on one.
    Factor,
    /// The numeric factorisation and the substitutions of every solve on two (a forward
    /// substitution over a sparse right-hand side's reach stays on one).
    FactorAndSolve,
}

/// From this many unknowns [`FillOrdering::Auto`] tries nested dissection as well as AMD:
/// it wins on large mesh systems (0.76× AMD's factor on a 90k-unknown LSE system) but
/// not on every shape (1.1× on square grids), and below this size the second analysis
/// is not worth its time.
pub const ND_MIN_DIM: usize = 20_000;

/// Options of [`super::CholeskySolver`].
#[derive(Debug, Clone, Copy)]
pub struct CholeskyOptions {
    /// LLᵀ or LDLᵀ.
    pub factorization: Factorization,
    /// Which triangle of the input is read (the other is ignored).
    pub side: Side,
    /// Parallelism for factorisation and solves. Default `Par::Seq` (see module docs).
    pub par: Par,
    /// Simplicial or supernodal storage.
    pub mode: FactorMode,
    /// Triangular-solve kernel for supernodal LLᵀ factors.
    pub kernel: SolveKernel,
    /// Fill-reducing ordering.
    pub ordering: FillOrdering,
    /// A second thread on independent subtrees.
    pub threads: SubtreeThreads,
}

impl Default for CholeskyOptions {
    fn default() -> Self {
        Self {
            factorization: Factorization::Llt,
            side: Side::Lower,
            par: Par::Seq,
            mode: FactorMode::Auto,
            kernel: SolveKernel::Auto,
            ordering: FillOrdering::Auto,
            threads: SubtreeThreads::Off,
        }
    }
}
