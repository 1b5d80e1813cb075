//! The linear core every editing method shares: a quadratic energy
//! `Σₜ wₜ (Aₜx − bₜ)ᵀ Wₜ (Aₜx − bₜ)` with some entries of `x` fixed, factored once and
//! solved for many right-hand sides (libigl's precompute/solve split, as
//! [`crate::solve::FixedSolver`] does for an assembled matrix).
//!
//! The fixed columns of every `Aₜ` are split off: the factored matrix is
//! `Σ wₜ A_{t,u}ᵀ Wₜ A_{t,u}`, of which only the lower triangle is formed (one sparse
//! product pass over all terms, [`crate::solve::lower_product_sum`]); a solve forms
//! `Σ wₜ A_{t,u}ᵀ Wₜ (bₜ − A_{t,k} x_k)` and back-substitutes. A metric `Wₜ` enters only
//! through `AₜᵀWₜ`, which the caller builds from what it knows of `Wₜ` (implicit editing's
//! coherence Laplacian), since a general product with a wide metric costs more than the
//! factorisation's own analysis. Changing `bₜ` or the fixed values costs no factorisation;
//! [`FactoredQuadratic::refactor`] redoes only the numeric factorisation for new values
//! of the same pattern (LSE's re-fitting iterations).

use std::time::Instant;

use faer::sparse::SymbolicSparseColMat;
use faer::{Mat, MatRef};

use crate::solve::{
    lower_product_sum, sparse_mul_dense, transpose, CholeskyOptions, CholeskySolver, SharedRhs,
    SolveError, SparseMatrix, SubtreeThreads,
};

/// One term `w (A x − b)ᵀ W (A x − b)` (`W = I` when `a_t_w` is `None`).
#[derive(Debug, Clone)]
pub struct QuadTerm {
    /// `m × n` operator.
    pub a: SparseMatrix,
    /// `Aᵀ W` (`n × m`) for a symmetric positive semidefinite `m × m` metric `W`: the
    /// energy's gradient needs `W` only through it (`AᵀWA x = AᵀW b`), and a caller who
    /// knows `W`'s structure forms it far cheaper than a general product
    /// ([`super::RowBuilder::finish_transposed`] stores its columns as they are built).
    pub a_t_w: Option<SparseMatrix>,
    /// Weight `w ≥ 0`.
    pub weight: f64,
}

#[derive(Debug, Clone)]
struct TermParts {
    /// `w A_uᵀ W` (`n_u × m`).
    at_w: SparseMatrix,
    /// `A_k` (`m × n_k`).
    a_k: SparseMatrix,
    rows: usize,
    /// `w A_uᵀ W A x₀` of the reference solution (`n_u × c`), if one was given.
    rhs_x0: Option<Mat<f64>>,
}

/// A factored quadratic energy with fixed entries.
#[derive(Debug, Clone)]
pub struct FactoredQuadratic {
    n: usize,
    unknown: Vec<usize>,
    known: Vec<usize>,
    slot: Vec<usize>,
    parts: Vec<TermParts>,
    chol: CholeskySolver,
    x0: Option<Mat<f64>>,
    /// `−Σ w A_uᵀ W A x₀`, forward-substituted once per factorisation, so a solve
    /// forward-substitutes only the rows a move changes.
    shared: Option<SharedRhs>,
    timings: FactorTimings,
}

/// Where a [`FactoredQuadratic`]'s precomputation went, in milliseconds (for benchmarks).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FactorTimings {
    /// Splitting the terms and forming the lower triangle of the normal matrix.
    pub assemble_ms: f64,
    /// Fill-reducing ordering and symbolic analysis (with [`FactorOrdering::Given`], any
    /// wait for the order and the symbolic analysis).
    pub analyze_ms: f64,
    /// Numeric Cholesky factorisation.
    pub numeric_ms: f64,
    /// Forward substitution of the reference's shared right-hand side.
    pub shared_ms: f64,
}

/// How a [`FactoredQuadratic`] orders its factor.
pub enum FactorOrdering<'a> {
    /// The Cholesky solver's own choice ([`crate::solve::FillOrdering::Auto`]).
    Auto,
    /// An elimination order of the `n` entries (fixed ones are skipped; it must hold
    /// every unknown once), asked for only when the assembled system is analysed, so it
    /// can be computed on another thread meanwhile (implicit editing's
    /// [`crate::solve::OrderingSkeleton::order_free`]).
    Given(Box<dyn FnOnce() -> Result<Vec<usize>, SolveError> + 'a>),
}

/// Milliseconds elapsed since `t`, the unit every factor timing is reported in.
pub(crate) fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// The rows of `p` whose `slot` is an unknown's (`< nu`), renumbered to it, in place.
/// Unknown slots grow with the index, so sorted columns stay sorted.
fn unknown_rows(p: SparseMatrix, slot: &[usize], nu: usize) -> SparseMatrix {
    let (symbolic, mut vals) = p.into_parts();
    let (_, ncols, mut col_ptr, col_nnz, mut row_idx) = symbolic.into_parts();
    let mut out = 0;
    let mut start = col_ptr[0];
    for j in 0..ncols {
        let end = col_nnz
            .as_ref()
            .map_or(col_ptr[j + 1], |nnz| start + nnz[j]);
        let next = col_ptr[j + 1];
        col_ptr[j] = out;
        for k in start..end {
            let i = row_idx[k];
            if slot[i] < nu {
                row_idx[out] = slot[i];
                vals[out] = vals[k];
                out += 1;
            }
        }
        start = next;
    }
    col_ptr[ncols] = out;
    row_idx.truncate(out);
    vals.truncate(out);
    SparseMatrix::new(
        SymbolicSparseColMat::new_checked(nu, ncols, col_ptr, None, row_idx),
        vals,
    )
}

/// `a` scaled by `s`.
fn scaled(mut a: SparseMatrix, s: f64) -> SparseMatrix {
    for v in a.parts_mut().1 {
        *v *= s;
    }
    a
}

/// Columns of `a` split by `slot` (unknown slot < n, known slot − n otherwise).
fn split_columns(
    a: &SparseMatrix,
    slot: &[usize],
    nu: usize,
    nk: usize,
) -> Result<(SparseMatrix, SparseMatrix), SolveError> {
    let n = slot.len();
    if a.ncols() != n {
        return Err(SolveError::Dimension(format!(
            "term has {} columns, expected {n}",
            a.ncols()
        )));
    }
    let mut order_u = vec![usize::MAX; nu];
    let mut order_k = vec![usize::MAX; nk];
    for (j, &s) in slot.iter().enumerate() {
        if s < n {
            order_u[s] = j;
        } else {
            order_k[s - n] = j;
        }
    }
    let pick = |order: &[usize]| {
        let mut col_ptr = Vec::with_capacity(order.len() + 1);
        let mut row_idx = Vec::new();
        let mut vals = Vec::new();
        col_ptr.push(0);
        for &j in order {
            row_idx.extend_from_slice(a.as_ref().row_idx_of_col_raw(j));
            vals.extend_from_slice(a.as_ref().val_of_col(j));
            col_ptr.push(row_idx.len());
        }
        SparseMatrix::new(
            SymbolicSparseColMat::new_unsorted_checked(
                a.nrows(),
                order.len(),
                col_ptr,
                None,
                row_idx,
            ),
            vals,
        )
    };
    Ok((pick(&order_u), pick(&order_k)))
}

impl FactoredQuadratic {
    /// Assembles and factors the energy over `n` unknowns with the entries `known` fixed.
    ///
    /// With a reference solution `x0` (`n × c`, e.g. the rest shape) solves are done for
    /// the correction `x − x₀`, so an edit that leaves the rest shape optimal returns it to
    /// round-off instead of to the conditioning of the normal equations.
    pub fn new(
        n: usize,
        terms: Vec<QuadTerm>,
        known: &[usize],
        x0: Option<Mat<f64>>,
    ) -> Result<Self, SolveError> {
        Self::with_ordering(
            n,
            terms,
            known,
            x0,
            FactorOrdering::Auto,
            SubtreeThreads::Off,
        )
    }

    /// [`Self::new`] with the factor's fill-reducing order chosen by `ordering` and a
    /// second thread where `threads` says.
    pub fn with_ordering(
        n: usize,
        terms: Vec<QuadTerm>,
        known: &[usize],
        x0: Option<Mat<f64>>,
        ordering: FactorOrdering<'_>,
        threads: SubtreeThreads,
    ) -> Result<Self, SolveError> {
        let options = CholeskyOptions {
            threads,
            ..Default::default()
        };
        let mut slot = vec![usize::MAX; n];
        let mut kept = Vec::new();
        for &k in known {
            if k >= n {
                return Err(SolveError::IndexOutOfRange { index: k, size: n });
            }
            if slot[k] == usize::MAX {
                slot[k] = n + kept.len();
                kept.push(k);
            }
        }
        let mut unknown = Vec::with_capacity(n - kept.len());
        for (i, s) in slot.iter_mut().enumerate() {
            if *s == usize::MAX {
                *s = unknown.len();
                unknown.push(i);
            }
        }
        if x0.as_ref().is_some_and(|x| x.nrows() != n) {
            return Err(SolveError::Dimension("reference has the wrong size".into()));
        }
        let clock = Instant::now();
        let (parts, gram) = Self::assemble(&slot, unknown.len(), kept.len(), terms, x0.as_ref())?;
        let assemble_ms = ms_since(clock);
        let mut chol = match ordering {
            FactorOrdering::Auto => CholeskySolver::analyze(gram.as_ref(), options)?,
            FactorOrdering::Given(order) => {
                // The given order of all entries, over the unknowns' slots.
                let nu = unknown.len();
                let perm: Vec<usize> = order()?
                    .into_iter()
                    .filter_map(|v| slot.get(v).copied().filter(|&s| s < nu))
                    .collect();
                CholeskySolver::analyze_ordered(gram.as_ref(), options, &perm)?
            }
        };
        let analyze_ms = ms_since(clock) - assemble_ms;
        chol.factorize(gram.as_ref())?;
        let numeric_ms = ms_since(clock) - assemble_ms - analyze_ms;
        let shared = Self::shared_rhs(&chol, &parts)?;
        let timings = FactorTimings {
            assemble_ms,
            analyze_ms,
            numeric_ms,
            shared_ms: ms_since(clock) - assemble_ms - analyze_ms - numeric_ms,
        };
        Ok(Self {
            timings,
            n,
            unknown,
            known: kept,
            slot,
            parts,
            chol,
            x0,
            shared,
        })
    }

    /// The reference's constant right-hand side `−Σ w A_uᵀ W A x₀`, prepared by the factor.
    fn shared_rhs(
        chol: &CholeskySolver,
        parts: &[TermParts],
    ) -> Result<Option<SharedRhs>, SolveError> {
        let mut sum: Option<Mat<f64>> = None;
        for r0 in parts.iter().filter_map(|p| p.rhs_x0.as_ref()) {
            match &mut sum {
                Some(s) => *s -= r0,
                None => sum = Some(-r0),
            }
        }
        sum.map(|b| chol.share_rhs(b.as_ref())).transpose()
    }

    /// Each term's parts and the lower triangle of `Σ w A_uᵀ W A_u` (all a factor reads).
    fn assemble(
        slot: &[usize],
        nu: usize,
        nk: usize,
        terms: Vec<QuadTerm>,
        x0: Option<&Mat<f64>>,
    ) -> Result<(Vec<TermParts>, SparseMatrix), SolveError> {
        let mut parts = Vec::with_capacity(terms.len());
        let mut ops = Vec::with_capacity(terms.len());
        for mut t in terms {
            let (a_u, a_k) = split_columns(&t.a, slot, nu, nk)?;
            let at_w = match t.a_t_w.take() {
                Some(p) if p.nrows() != slot.len() || p.ncols() != t.a.nrows() => {
                    return Err(SolveError::Dimension(format!(
                        "AᵀW is {}x{}, A {}x{}",
                        p.nrows(),
                        p.ncols(),
                        t.a.nrows(),
                        t.a.ncols()
                    )))
                }
                Some(p) => unknown_rows(p, slot, nu),
                None => unknown_rows(transpose(t.a.as_ref()), slot, nu),
            };
            let at_w = if t.weight == 1.0 {
                at_w
            } else {
                scaled(at_w, t.weight)
            };
            let rhs_x0 = match x0 {
                Some(x) => {
                    let ax = sparse_mul_dense(t.a.as_ref(), x.as_ref())?;
                    Some(sparse_mul_dense(at_w.as_ref(), ax.as_ref())?)
                }
                None => None,
            };
            parts.push(TermParts {
                at_w,
                a_k,
                rows: t.a.nrows(),
                rhs_x0,
            });
            ops.push(a_u);
        }
        let pairs: Vec<_> = parts
            .iter()
            .zip(&ops)
            .map(|(p, a_u)| (p.at_w.as_ref(), a_u.as_ref()))
            .collect();
        let gram = lower_product_sum(nu, &pairs)?;
        Ok((parts, gram))
    }

    /// New values for terms of the same shapes and patterns: numeric refactorisation only.
    pub fn refactor(&mut self, terms: Vec<QuadTerm>) -> Result<(), SolveError> {
        let (parts, gram) = Self::assemble(
            &self.slot,
            self.unknown.len(),
            self.known.len(),
            terms,
            self.x0.as_ref(),
        )?;
        self.chol.factorize(gram.as_ref())?;
        self.shared = Self::shared_rhs(&self.chol, &parts)?;
        self.parts = parts;
        Ok(())
    }

    /// Where the first factorisation's time went.
    pub fn timings(&self) -> FactorTimings {
        self.timings
    }

    /// Number of unknowns that are solved for.
    pub fn n_unknown(&self) -> usize {
        self.unknown.len()
    }

    /// Stored entries of the Cholesky factor.
    pub fn factor_len(&self) -> usize {
        self.chol.factor_len()
    }

    /// The fixed indices, in the order `known_values` rows are read.
    pub fn known(&self) -> &[usize] {
        &self.known
    }

    /// Solves with one right-hand side `bₜ` per term (`mₜ × c`; `None` means zero) and the
    /// fixed values (`n_k × c`, rows in the order of [`Self::known`]); returns all `n × c`.
    pub fn solve(
        &self,
        b: &[Option<MatRef<'_, f64>>],
        known_values: MatRef<'_, f64>,
    ) -> Result<Mat<f64>, SolveError> {
        let c = known_values.ncols();
        if b.len() != self.parts.len() || known_values.nrows() != self.known.len() {
            return Err(SolveError::Dimension(
                "right-hand sides or fixed values have the wrong shape".into(),
            ));
        }
        if self.x0.as_ref().is_some_and(|x| x.ncols() != c) {
            return Err(SolveError::Dimension(
                "reference has the wrong width".into(),
            ));
        }
        // Fixed values relative to the reference.
        let dk = Mat::from_fn(self.known.len(), c, |r, col| {
            known_values[(r, col)] - self.x0.as_ref().map_or(0.0, |x| x[(self.known[r], col)])
        });
        let mut rhs = self.unknown_rhs(b, dk.as_ref(), self.shared.is_none())?;
        match &self.shared {
            Some(shared) => self.chol.solve_in_place_plus(shared, rhs.as_mut())?,
            None => self.chol.solve_in_place(rhs.as_mut())?,
        }
        Ok(self.scatter(rhs.as_ref(), known_values, self.x0.as_ref()))
    }

    /// The linear part of [`Self::solve`]: the change of the solution (`n × c`) when the
    /// right-hand sides change by `b` and the fixed values by `known_delta`, without the
    /// reference. The solution is affine in both, so this is how a caller precomputes its
    /// response to each parameter of a move (implicit editing's drag basis); any `c`.
    pub fn solve_response(
        &self,
        b: &[Option<MatRef<'_, f64>>],
        known_delta: MatRef<'_, f64>,
    ) -> Result<Mat<f64>, SolveError> {
        if b.len() != self.parts.len() || known_delta.nrows() != self.known.len() {
            return Err(SolveError::Dimension(
                "right-hand sides or fixed values have the wrong shape".into(),
            ));
        }
        let mut rhs = self.unknown_rhs(b, known_delta, false)?;
        self.chol.solve_in_place(rhs.as_mut())?;
        Ok(self.scatter(rhs.as_ref(), known_delta, None))
    }

    /// `Σ w A_uᵀ W (bₜ − A_k Δx_k)` over the unknowns, minus each term's reference part when
    /// `with_x0`.
    fn unknown_rhs(
        &self,
        b: &[Option<MatRef<'_, f64>>],
        dk: MatRef<'_, f64>,
        with_x0: bool,
    ) -> Result<Mat<f64>, SolveError> {
        let c = dk.ncols();
        // rhs = Σ w A_uᵀ W (b − A x₀ − A_k Δx_k); the residual b − A_k Δx_k is sparse in
        // practice (only moved handles and gradient rows), so only its nonzero rows are
        // multiplied.
        let mut rhs = Mat::<f64>::zeros(self.unknown.len(), c);
        let dk_nonzero: Vec<usize> = (0..self.known.len())
            .filter(|&r| (0..c).any(|col| dk[(r, col)] != 0.0))
            .collect();
        for (p, bt) in self.parts.iter().zip(b) {
            if with_x0 {
                if let Some(r0) = &p.rhs_x0 {
                    rhs -= r0;
                }
            }
            let mut r = vec![0.0; p.rows * c];
            let mut touched = vec![false; p.rows];
            let mut list = Vec::new();
            let ak = p.a_k.as_ref();
            for &kc in &dk_nonzero {
                for (&i, &v) in ak.row_idx_of_col_raw(kc).iter().zip(ak.val_of_col(kc)) {
                    for col in 0..c {
                        r[i * c + col] -= v * dk[(kc, col)];
                    }
                    if !touched[i] {
                        touched[i] = true;
                        list.push(i);
                    }
                }
            }
            if let Some(bt) = bt {
                if bt.nrows() != p.rows || bt.ncols() != c {
                    return Err(SolveError::Dimension("right-hand side shape".into()));
                }
                for i in 0..p.rows {
                    for col in 0..c {
                        let v = bt[(i, col)];
                        if v != 0.0 {
                            r[i * c + col] += v;
                            if !touched[i] {
                                touched[i] = true;
                                list.push(i);
                            }
                        }
                    }
                }
            }
            let at = p.at_w.as_ref();
            for &i in &list {
                for (&u, &v) in at.row_idx_of_col_raw(i).iter().zip(at.val_of_col(i)) {
                    for col in 0..c {
                        rhs[(u, col)] += v * r[i * c + col];
                    }
                }
            }
        }
        Ok(rhs)
    }

    /// All `n` entries: the unknowns from `u` (plus the reference), the fixed ones from `known`.
    fn scatter(
        &self,
        u: MatRef<'_, f64>,
        known: MatRef<'_, f64>,
        x0: Option<&Mat<f64>>,
    ) -> Mat<f64> {
        let c = u.ncols();
        let mut x = Mat::zeros(self.n, c);
        for (r, &i) in self.unknown.iter().enumerate() {
            for col in 0..c {
                x[(i, col)] = u[(r, col)] + x0.map_or(0.0, |x| x[(i, col)]);
            }
        }
        for (r, &i) in self.known.iter().enumerate() {
            for col in 0..c {
                x[(i, col)] = known[(r, col)];
            }
        }
        x
    }
}
