//! Triangular solves with a supernodal LLᵀ factor, column by column.
//!
//! faer's supernodal solve runs a small dense TRSM + GEMM per supernode; on mesh
//! Laplacians (many small supernodes) and 1–4 right-hand sides that overhead dominates,
//! and the same factor solved column by column (like a simplicial solve, but reading
//! faer's supernodal storage directly) is faster. The right-hand sides are
//! processed `K ≤ 4` at a time, interleaved row-major so each row update touches one
//! cache line.

use faer::reborrow::ReborrowMut;
use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};
use faer::MatMut;

/// One supernode: first column, width, its below-diagonal row pattern and its values
/// (column-major, `width + pattern.len()` rows).
struct Supernode<'a> {
    start: usize,
    width: usize,
    pattern: &'a [usize],
    values: &'a [f64],
}

/// All supernodes of a factor, or `None` if the storage is not supernodal or is not laid
/// out as expected (the caller then falls back to faer's solve).
fn supernodes<'a>(
    symbolic: &'a SymbolicCholesky<usize>,
    values: &'a [f64],
) -> Option<Vec<Supernode<'a>>> {
    let SymbolicCholeskyRaw::Supernodal(s) = symbolic.raw() else {
        return None;
    };
    let (begin, end) = (s.supernode_begin(), s.supernode_end());
    let (ptr_row, ptr_val) = (s.col_ptr_for_row_idx(), s.col_ptr_for_val());
    let mut out = Vec::with_capacity(begin.len());
    for k in 0..begin.len() {
        let width = end[k].checked_sub(begin[k]).filter(|&w| w > 0)?;
        let vals = values.get(*ptr_val.get(k)?..*ptr_val.get(k + 1)?)?;
        let plen = (vals.len() / width).checked_sub(width)?;
        let pattern = s.row_idx().get(*ptr_row.get(k)?..)?.get(..plen)?;
        // Row indices come from faer's own symbolic factorisation (always < n).
        if vals.len() != width * (width + plen) {
            return None;
        }
        out.push(Supernode {
            start: begin[k],
            width,
            pattern,
            values: vals,
        });
    }
    Some(out)
}

/// Supernode statistics: `(stored values in supernodes of width ≥ 16, all stored values)`.
pub(crate) fn wide_fraction(symbolic: &SymbolicCholesky<usize>) -> (usize, usize) {
    let SymbolicCholeskyRaw::Supernodal(s) = symbolic.raw() else {
        return (0, 0);
    };
    let ptr = s.col_ptr_for_val();
    let (mut wide, mut all) = (0, 0);
    for (k, (b, e)) in s
        .supernode_begin()
        .iter()
        .zip(s.supernode_end())
        .enumerate()
    {
        let len = ptr.get(k + 1).zip(ptr.get(k)).map_or(0, |(hi, lo)| hi - lo);
        all += len;
        if e - b >= WIDE {
            wide += len;
        }
    }
    (wide, all)
}

/// Width from which a supernode counts as wide.
const WIDE: usize = 16;

/// True when most of the factor lives in narrow supernodes, where the column-wise solve
/// beats per-supernode dense kernels.
pub(crate) fn prefers_columnwise(symbolic: &SymbolicCholesky<usize>) -> bool {
    let (wide, all) = wide_fraction(symbolic);
    all > 0 && (wide as f64) < 0.5 * all as f64
}

/// Solves `A x = b` for every column of `rhs` with `A = Pᵀ L Lᵀ P` (`P` the factor's
/// fill-reducing permutation). Returns `false`, leaving `rhs` untouched, if the factor is
/// not supernodal.
pub(crate) fn solve_supernodal_llt(
    symbolic: &SymbolicCholesky<usize>,
    values: &[f64],
    mut rhs: MatMut<'_, f64>,
) -> bool {
    let Some(nodes) = supernodes(symbolic, values) else {
        return false;
    };
    let n = rhs.nrows();
    let identity: Vec<usize>;
    let (fwd, inv) = match symbolic.perm() {
        Some(p) => p.arrays(),
        None => {
            identity = (0..n).collect();
            (identity.as_slice(), identity.as_slice())
        }
    };
    let mut col = 0;
    while col < rhs.ncols() {
        let k = (rhs.ncols() - col).min(4);
        let block = rhs.rb_mut().subcols_mut(col, k);
        match k {
            1 => solve_block::<1>(&nodes, fwd, inv, block),
            2 => solve_block::<2>(&nodes, fwd, inv, block),
            3 => solve_block::<3>(&nodes, fwd, inv, block),
            _ => solve_block::<4>(&nodes, fwd, inv, block),
        }
        col += k;
    }
    true
}

fn solve_block<const K: usize>(
    nodes: &[Supernode<'_>],
    fwd: &[usize],
    inv: &[usize],
    mut rhs: MatMut<'_, f64>,
) {
    let mut w: Vec<[f64; K]> = fwd
        .iter()
        .map(|&f| std::array::from_fn(|c| rhs[(f, c)]))
        .collect();
    forward(nodes, &mut w);
    backward(nodes, &mut w);
    for (i, &p) in inv.iter().enumerate() {
        for c in 0..K {
            rhs[(i, c)] = w[p][c];
        }
    }
}

/// `L y = b`: per supernode, a dense triangular solve on the diagonal block, then the
/// block's contribution to its pattern rows accumulated contiguously and scattered once.
fn forward<const K: usize>(nodes: &[Supernode<'_>], w: &mut [[f64; K]]) {
    let mut tmp: Vec<[f64; K]> = Vec::new();
    for s in nodes {
        let rows = s.width + s.pattern.len();
        tmp.clear();
        tmp.resize(s.pattern.len(), [0.0; K]);
        for jj in 0..s.width {
            let col = &s.values[jj * rows..(jj + 1) * rows];
            let mut xj = w[s.start + jj];
            for v in &mut xj {
                *v /= col[jj];
            }
            w[s.start + jj] = xj;
            let (block, below) = col.split_at(s.width);
            for (ii, &l) in block.iter().enumerate().skip(jj + 1) {
                sub_scaled(&mut w[s.start + ii], l, &xj);
            }
            for (t, &l) in tmp.iter_mut().zip(below) {
                sub_scaled(t, -l, &xj);
            }
        }
        for (&r, t) in s.pattern.iter().zip(&tmp) {
            sub_scaled(&mut w[r], 1.0, t);
        }
    }
}

/// `Lᵀ x = y`: per supernode in reverse, gather the pattern rows once, subtract their
/// contribution column by column, then a dense triangular solve on the diagonal block.
fn backward<const K: usize>(nodes: &[Supernode<'_>], w: &mut [[f64; K]]) {
    let mut tmp: Vec<[f64; K]> = Vec::new();
    for s in nodes.iter().rev() {
        let rows = s.width + s.pattern.len();
        tmp.clear();
        tmp.extend(s.pattern.iter().map(|&r| w[r]));
        for jj in (0..s.width).rev() {
            let col = &s.values[jj * rows..(jj + 1) * rows];
            let (block, below) = col.split_at(s.width);
            let mut acc = w[s.start + jj];
            for (t, &l) in tmp.iter().zip(below) {
                sub_scaled(&mut acc, l, t);
            }
            for (ii, &l) in block.iter().enumerate().skip(jj + 1) {
                sub_scaled(&mut acc, l, &w[s.start + ii]);
            }
            for v in &mut acc {
                *v /= block[jj];
            }
            w[s.start + jj] = acc;
        }
    }
}

#[inline(always)]
fn sub_scaled<const K: usize>(target: &mut [f64; K], l: f64, x: &[f64; K]) {
    for c in 0..K {
        target[c] -= l * x[c];
    }
}
