//! Sparse Cholesky (LLᵀ / LDLᵀ) with symbolic analysis reused across numeric
//! refactorisations; factor once, solve many right-hand sides.

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::LdltError;
use faer::linalg::cholesky::llt::factor::LltError;
use faer::perm::PermRef;
use faer::reborrow::ReborrowMut;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LdltRef, LltRef, SymbolicCholesky,
    SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::SparseColMatRef;
use faer::{Conj, Mat, MatMut, MatRef, Par};

use super::cholesky_options::{
    CholeskyOptions, FactorMode, Factorization, FillOrdering, SolveKernel, SubtreeThreads,
    ND_MIN_DIM,
};
use super::ordering::nested_dissection;
use super::supernodal_numeric::factorize_supernodal_llt;
use super::supernodal_solve::{
    forward_supernodal_llt, solve_supernodal_llt, solve_supernodal_llt_permuted,
    solve_supernodal_llt_plus,
};
use super::supernode_tree::{SubtreeSplit, SupernodeLayout};
use super::SolveError;

/// A right-hand side part shared by many solves (see [`CholeskySolver::share_rhs`]).
#[derive(Debug, Clone)]
pub enum SharedRhs {
    /// `L⁻¹ P B₀`, in the factor's row order (supernodal LLᵀ factors).
    Forward(Mat<f64>),
    /// `B₀` itself (other factors: added before a full solve).
    Plain(Mat<f64>),
}

/// Fails unless `a` is square.
fn check_square(a: SparseColMatRef<'_, usize, f64>) -> Result<(), SolveError> {
    if a.nrows() != a.ncols() {
        return Err(SolveError::Dimension(format!(
            "{}x{} matrix is not square",
            a.nrows(),
            a.ncols()
        )));
    }
    Ok(())
}

/// faer's symbolic parameters for `options.mode`.
fn symbolic_params(options: CholeskyOptions) -> CholeskySymbolicParams<'static> {
    let mut params = CholeskySymbolicParams::default();
    params.supernodal_flop_ratio_threshold = match options.mode {
        FactorMode::Auto => params.supernodal_flop_ratio_threshold,
        FactorMode::Simplicial => SupernodalThreshold::FORCE_SIMPLICIAL,
        FactorMode::Supernodal => SupernodalThreshold::FORCE_SUPERNODAL,
    };
    params
}

/// Symbolic analysis of `a`'s pattern in the elimination order `fwd` (`fwd[k]` eliminated
/// `k`-th).
fn symbolic_ordered(
    a: SparseColMatRef<'_, usize, f64>,
    options: CholeskyOptions,
    fwd: &[usize],
) -> Result<SymbolicCholesky<usize>, SolveError> {
    let n = a.nrows();
    let mut inv = vec![0usize; n];
    for (k, &i) in fwd.iter().enumerate() {
        inv[i] = k;
    }
    let perm = SymmetricOrdering::Custom(PermRef::new_checked(fwd, &inv, n));
    factorize_symbolic_cholesky(a.symbolic(), options.side, perm, symbolic_params(options))
        .map_err(|_| SolveError::OutOfMemory)
}

/// A supernodal factor's elimination tree and its splits over two threads.
#[derive(Debug)]
struct SupernodeTree {
    layout: SupernodeLayout,
    /// Balancing the numeric factorisation's flops.
    split: Option<SubtreeSplit>,
    /// Balancing the values a substitution reads (its cost: it streams the factor once).
    solve_split: Option<SubtreeSplit>,
}

/// A symmetric sparse factorisation: [`Self::analyze`] once per pattern,
/// [`Self::factorize`] per set of values, [`Self::solve_in_place`] per right-hand side.
#[derive(Debug, Clone)]
pub struct CholeskySolver {
    symbolic: Arc<SymbolicCholesky<usize>>,
    /// The supernodal tree and its split, when `options.threads` asks for them.
    tree: Option<Arc<SupernodeTree>>,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    options: CholeskyOptions,
    values: Vec<f64>,
    factored: bool,
}

impl CholeskySolver {
    /// Symbolic analysis (fill-reducing ordering, elimination tree, supernodes) of `a`'s pattern.
    pub fn analyze(
        a: SparseColMatRef<'_, usize, f64>,
        options: CholeskyOptions,
    ) -> Result<Self, SolveError> {
        check_square(a)?;
        let params = symbolic_params(options);
        let n = a.nrows();
        let symbolic_with = |nd: bool| -> Result<SymbolicCholesky<usize>, SolveError> {
            if !nd {
                return factorize_symbolic_cholesky(
                    a.symbolic(),
                    options.side,
                    SymmetricOrdering::Amd,
                    params,
                )
                .map_err(|_| SolveError::OutOfMemory);
            }
            symbolic_ordered(a, options, &nested_dissection(a.symbolic())?)
        };
        let symbolic = match options.ordering {
            FillOrdering::Amd => symbolic_with(false)?,
            FillOrdering::NestedDissection => symbolic_with(true)?,
            FillOrdering::Auto if n < ND_MIN_DIM => symbolic_with(false)?,
            FillOrdering::Auto => {
                // Both analyses, concurrently (they are independent and neither wins on
                // every mesh); the smaller factor is the cheaper factorisation and solve.
                let (amd, nd) = super::join(|| symbolic_with(false), || symbolic_with(true));
                let (amd, nd) = (amd?, nd?);
                if nd.len_val() < amd.len_val() {
                    nd
                } else {
                    amd
                }
            }
        };
        Ok(Self::from_symbolic(a, options, symbolic))
    }

    /// Symbolic analysis in the elimination order `order` (`order[k]` eliminated `k`-th,
    /// e.g. from [`super::OrderingSkeleton::order_free`]), whatever `options.ordering`
    /// says. Fails unless `order` is a permutation of the unknowns.
    pub fn analyze_ordered(
        a: SparseColMatRef<'_, usize, f64>,
        options: CholeskyOptions,
        order: &[usize],
    ) -> Result<Self, SolveError> {
        check_square(a)?;
        let n = a.nrows();
        if order.len() != n {
            return Err(SolveError::Dimension(format!(
                "an order of {} unknowns for a {n}x{n} matrix",
                order.len()
            )));
        }
        let mut seen = vec![false; n];
        for &i in order {
            if i >= n || std::mem::replace(&mut seen[i], true) {
                return Err(SolveError::IndexOutOfRange { index: i, size: n });
            }
        }
        let symbolic = symbolic_ordered(a, options, order)?;
        Ok(Self::from_symbolic(a, options, symbolic))
    }

    fn from_symbolic(
        a: SparseColMatRef<'_, usize, f64>,
        options: CholeskyOptions,
        symbolic: SymbolicCholesky<usize>,
    ) -> Self {
        let tree = (options.threads != SubtreeThreads::Off
            && options.factorization == Factorization::Llt)
            .then(|| SupernodeLayout::new(&symbolic))
            .flatten()
            .map(|layout| {
                let split = SubtreeSplit::choose(&layout, &layout.work);
                let values: Vec<f64> = layout
                    .val_ptr
                    .windows(2)
                    .map(|w| (w[1] - w[0]) as f64)
                    .collect();
                let solve_split = SubtreeSplit::choose(&layout, &values);
                Arc::new(SupernodeTree {
                    layout,
                    split,
                    solve_split,
                })
            });
        Self {
            symbolic: Arc::new(symbolic),
            tree,
            col_ptr: a.col_ptr().to_vec(),
            row_idx: a.row_idx().to_vec(),
            options,
            values: Vec::new(),
            factored: false,
        }
    }

    /// Analysis followed by numeric factorisation.
    pub fn new(
        a: SparseColMatRef<'_, usize, f64>,
        options: CholeskyOptions,
    ) -> Result<Self, SolveError> {
        let mut s = Self::analyze(a, options)?;
        s.factorize(a)?;
        Ok(s)
    }

    /// Matrix dimension.
    pub fn dim(&self) -> usize {
        self.symbolic.nrows()
    }

    /// Number of stored entries of the factor `L` (fill), for reporting.
    pub fn factor_len(&self) -> usize {
        self.symbolic.len_val()
    }

    /// With [`SubtreeThreads`] on: the estimated time of the two-thread numeric
    /// factorisation relative to one thread (the heavier thread's subtrees plus the rest,
    /// in flops); `None` when the factor is not split (threads off, a simplicial factor,
    /// or an elimination tree with no two heavy independent subtrees).
    pub fn subtree_split_cost(&self) -> Option<f64> {
        Some(self.tree.as_ref()?.split.as_ref()?.cost)
    }

    /// A copy of this solver sharing the symbolic analysis but with no numeric factor.
    pub fn share_symbolic(&self) -> Self {
        Self {
            values: Vec::new(),
            factored: false,
            ..self.clone()
        }
    }

    /// Numeric factorisation of `a`, which must have exactly the analysed pattern.
    pub fn factorize(&mut self, a: SparseColMatRef<'_, usize, f64>) -> Result<(), SolveError> {
        if a.col_ptr() != self.col_ptr.as_slice()
            || a.row_idx() != self.row_idx.as_slice()
            || a.col_nnz().is_some()
        {
            return Err(SolveError::PatternChanged);
        }
        self.factored = false;
        if let Some(tree) = &self.tree {
            factorize_supernodal_llt(
                &self.symbolic,
                &tree.layout,
                tree.split.as_ref(),
                a,
                self.options.side,
                &mut self.values,
            )?;
            self.factored = true;
            return Ok(());
        }
        self.values.clear();
        self.values
            .try_reserve_exact(self.symbolic.len_val())
            .map_err(|_| SolveError::OutOfMemory)?;
        self.values.resize(self.symbolic.len_val(), 0.0);
        let par = self.options.par;
        match self.options.factorization {
            Factorization::Llt => self.factorize_llt(a, par)?,
            Factorization::Ldlt => self.factorize_ldlt(a, par)?,
        }
        self.factored = true;
        Ok(())
    }

    fn factorize_llt(
        &mut self,
        a: SparseColMatRef<'_, usize, f64>,
        par: Par,
    ) -> Result<(), SolveError> {
        let req = self
            .symbolic
            .factorize_numeric_llt_scratch::<f64>(par, Default::default());
        let mut mem = MemBuffer::try_new(req).map_err(|_| SolveError::OutOfMemory)?;
        let r = self.symbolic.factorize_numeric_llt::<f64>(
            &mut self.values,
            a,
            self.options.side,
            Default::default(),
            par,
            MemStack::new(&mut mem),
            Default::default(),
        );
        match r {
            Ok(_) => Ok(()),
            Err(LltError::NonPositivePivot { index }) => {
                Err(SolveError::NotPositiveDefinite { column: index })
            }
        }
    }

    fn factorize_ldlt(
        &mut self,
        a: SparseColMatRef<'_, usize, f64>,
        par: Par,
    ) -> Result<(), SolveError> {
        let req = self
            .symbolic
            .factorize_numeric_ldlt_scratch::<f64>(par, Default::default());
        let mut mem = MemBuffer::try_new(req).map_err(|_| SolveError::OutOfMemory)?;
        let r = self.symbolic.factorize_numeric_ldlt::<f64>(
            &mut self.values,
            a,
            self.options.side,
            Default::default(),
            par,
            MemStack::new(&mut mem),
            Default::default(),
        );
        match r {
            Ok(_) => Ok(()),
            Err(LdltError::ZeroPivot { index }) => Err(SolveError::Singular { column: index }),
        }
    }

    /// Solves `A X = B` in place for every column of `rhs` at once.
    pub fn solve_in_place(&self, mut rhs: MatMut<'_, f64>) -> Result<(), SolveError> {
        if !self.factored {
            return Err(SolveError::NotFactorized);
        }
        if rhs.nrows() != self.dim() {
            return Err(SolveError::Dimension(format!(
                "rhs has {} rows, matrix {}",
                rhs.nrows(),
                self.dim()
            )));
        }
        if self.options.factorization == Factorization::Llt
            && self.solve_llt_columnwise(rhs.rb_mut())
        {
            return Ok(());
        }
        let par = self.options.par;
        let req = self
            .symbolic
            .solve_in_place_scratch::<f64>(rhs.ncols(), par);
        let mut mem = MemBuffer::try_new(req).map_err(|_| SolveError::OutOfMemory)?;
        let stack = MemStack::new(&mut mem);
        match self.options.factorization {
            Factorization::Llt => LltRef::new(&self.symbolic, &self.values)
                .solve_in_place_with_conj(Conj::No, rhs, par, stack),
            Factorization::Ldlt => LdltRef::new(&self.symbolic, &self.values)
                .solve_in_place_with_conj(Conj::No, rhs, par, stack),
        }
        Ok(())
    }

    /// The factor's row order: row `k` of a [`Self::solve_factor_rows`] right-hand side is
    /// row `order[k]` of the system (the fill-reducing permutation; identity without one).
    pub fn factor_order(&self) -> Vec<usize> {
        match self.symbolic.perm() {
            Some(p) => p.arrays().0.to_vec(),
            None => (0..self.dim()).collect(),
        }
    }

    /// Solves `A X = B` in place for `K` right-hand sides stored row-interleaved with the
    /// rows in the factor's order ([`Self::factor_order`]). A caller that assembles its
    /// right-hand side straight into this layout saves the gather, the scatter and the
    /// allocations of [`Self::solve_in_place`]; the result equals it to round-off.
    pub fn solve_factor_rows<const K: usize>(&self, w: &mut [[f64; K]]) -> Result<(), SolveError> {
        if !self.factored {
            return Err(SolveError::NotFactorized);
        }
        if w.len() != self.dim() {
            return Err(SolveError::Dimension(format!(
                "rhs has {} rows, matrix {}",
                w.len(),
                self.dim()
            )));
        }
        if self.uses_columnwise_kernel()
            && solve_supernodal_llt_permuted(&self.symbolic, &self.values, w, self.solve_split())
        {
            return Ok(());
        }
        let order = self.factor_order();
        let mut y = Mat::<f64>::zeros(w.len(), K);
        for (&i, r) in order.iter().zip(w.iter()) {
            for (c, &v) in r.iter().enumerate() {
                y[(i, c)] = v;
            }
        }
        self.solve_in_place(y.as_mut())?;
        for (&i, r) in order.iter().zip(w.iter_mut()) {
            *r = std::array::from_fn(|c| y[(i, c)]);
        }
        Ok(())
    }

    /// Prepares `b`, a right-hand side part that many solves share, for
    /// [`Self::solve_in_place_plus`]: its forward substitution is done here, once (on two
    /// threads with any [`SubtreeThreads`] on, as part of preparing the factor).
    pub fn share_rhs(&self, b: MatRef<'_, f64>) -> Result<SharedRhs, SolveError> {
        if !self.factored {
            return Err(SolveError::NotFactorized);
        }
        if b.nrows() != self.dim() {
            return Err(SolveError::Dimension(format!(
                "shared rhs has {} rows, matrix {}",
                b.nrows(),
                self.dim()
            )));
        }
        let forward = (self.uses_columnwise_kernel())
            .then(|| forward_supernodal_llt(&self.symbolic, &self.values, b, self.share_split()))
            .flatten();
        Ok(match forward {
            Some(f) => SharedRhs::Forward(f),
            None => SharedRhs::Plain(b.to_owned()),
        })
    }

    /// Solves `A X = B₀ + R` in place of `R` (`rhs`), with `B₀` prepared by
    /// [`Self::share_rhs`]. When `R` has few nonzero rows (a handle move) the forward
    /// substitution visits only the supernodes they reach; the result equals
    /// [`Self::solve_in_place`] of `B₀ + R` to round-off.
    pub fn solve_in_place_plus(
        &self,
        shared: &SharedRhs,
        mut rhs: MatMut<'_, f64>,
    ) -> Result<(), SolveError> {
        let b = match shared {
            SharedRhs::Forward(f) | SharedRhs::Plain(f) => f,
        };
        if b.nrows() != rhs.nrows() || b.ncols() != rhs.ncols() {
            return Err(SolveError::Dimension(format!(
                "rhs is {}x{}, the shared part {}x{}",
                rhs.nrows(),
                rhs.ncols(),
                b.nrows(),
                b.ncols()
            )));
        }
        if !self.factored {
            return Err(SolveError::NotFactorized);
        }
        if let SharedRhs::Forward(f) = shared {
            if self.uses_columnwise_kernel()
                && solve_supernodal_llt_plus(
                    &self.symbolic,
                    &self.values,
                    rhs.rb_mut(),
                    Some(f.as_ref()),
                    self.solve_split(),
                )
            {
                return Ok(());
            }
            return Err(SolveError::Dimension(
                "shared rhs was prepared for another factor".into(),
            ));
        }
        rhs += b;
        self.solve_in_place(rhs)
    }

    /// The split of [`Self::share_rhs`]'s forward substitution, with any
    /// [`SubtreeThreads`] on (it is part of preparing the factor).
    fn share_split(&self) -> Option<&SubtreeSplit> {
        self.tree.as_ref()?.solve_split.as_ref()
    }

    /// The split the substitutions use, if solves are to use two threads.
    fn solve_split(&self) -> Option<&SubtreeSplit> {
        (self.options.threads == SubtreeThreads::FactorAndSolve)
            .then(|| self.share_split())
            .flatten()
    }

    fn uses_columnwise_kernel(&self) -> bool {
        self.options.factorization == Factorization::Llt
            && matches!(self.options.kernel, SolveKernel::Auto)
            && matches!(self.options.par, Par::Seq)
    }

    /// Sequential supernodal LLᵀ solve through [`solve_supernodal_llt`]; `false` if the
    /// factor is simplicial or the caller asked for threads.
    fn solve_llt_columnwise(&self, rhs: MatMut<'_, f64>) -> bool {
        let wanted = match self.options.kernel {
            SolveKernel::Faer => false,
            SolveKernel::Auto => true,
        };
        wanted
            && matches!(self.options.par, Par::Seq)
            && solve_supernodal_llt(&self.symbolic, &self.values, rhs, self.solve_split())
    }

    /// Solves `A X = B`, returning `X`.
    pub fn solve(&self, rhs: MatRef<'_, f64>) -> Result<Mat<f64>, SolveError> {
        let mut x = rhs.to_owned();
        self.solve_in_place(x.as_mut())?;
        Ok(x)
    }

    /// Solves `A x = b` for one vector.
    pub fn solve_vec(&self, b: &[f64]) -> Result<Vec<f64>, SolveError> {
        let mut x = Mat::from_fn(b.len(), 1, |i, _| b[i]);
        self.solve_in_place(x.as_mut())?;
        Ok((0..b.len()).map(|i| x[(i, 0)]).collect())
    }
}
