//! Triangular solves with a supernodal LLᵀ factor, straight from faer's supernodal storage.
//!
//! faer's supernodal solve runs a small dense TRSM + GEMM per supernode; on mesh systems
//! (thousands of supernodes, most a few to a few hundred columns wide) and 1–4
//! right-hand sides its per-call overhead and the packing of each block for the product
//! dominate. Here every supernode is solved by the register-blocked kernels of
//! [`super::column_kernels`] (four columns at a time), gathering and scattering its
//! below-diagonal rows once. The right-hand sides are processed `K ≤ 4` at a time,
//! interleaved row-major (three travel in four lanes) so a row is one vector.
//!
//! A right-hand side with few nonzero rows (an editing move changes only its handles'
//! rows) is forward-substituted over the supernodes that can receive a nonzero: the
//! ancestors in the supernodal elimination tree of the supernodes holding its nonzero
//! rows (the reach of Gilbert & Peierls, *Sparse partial pivoting in time proportional to
//! arithmetic operations*, 1988, applied to the etree). The others stay zero, so skipping
//! them changes no value; the backward substitution still reads the whole factor.

use faer::reborrow::ReborrowMut;
use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};
use faer::{Mat, MatMut, MatRef};

use super::column_kernels::{backward_supernode, forward_supernode, simd};
use super::supernode_tree::{SubtreeSlice, SubtreeSplit};

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

/// Solves `A x = b` for every column of `rhs` with `A = Pᵀ L Lᵀ P` (`P` the factor's
/// fill-reducing permutation). Returns `false`, leaving `rhs` untouched, if the factor is
/// not supernodal.
pub(crate) fn solve_supernodal_llt(
    symbolic: &SymbolicCholesky<usize>,
    values: &[f64],
    rhs: MatMut<'_, f64>,
    split: Option<&SubtreeSplit>,
) -> bool {
    solve_supernodal_llt_plus(symbolic, values, rhs, None, split)
}

/// [`solve_supernodal_llt`] of `b + rhs` where `shared` is `L⁻¹ P b` from
/// [`forward_supernodal_llt`]: only `rhs` is forward-substituted (over its reach).
pub(crate) fn solve_supernodal_llt_plus(
    symbolic: &SymbolicCholesky<usize>,
    values: &[f64],
    mut rhs: MatMut<'_, f64>,
    shared: Option<MatRef<'_, f64>>,
    split: Option<&SubtreeSplit>,
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
        let base = shared.map(|b| b.subcols(col, k));
        match k {
            1 => solve_block::<1>(&nodes, fwd, inv, block, base, split),
            2 => solve_block::<2>(&nodes, fwd, inv, block, base, split),
            // Three columns travel in four lanes: a row is then one 256-bit vector.
            _ => solve_block::<4>(&nodes, fwd, inv, block, base, split),
        }
        col += k;
    }
    true
}

/// `L⁻¹ P b` in the factor's (permuted) row order, or `None` if the factor is not
/// supernodal.
pub(crate) fn forward_supernodal_llt(
    symbolic: &SymbolicCholesky<usize>,
    values: &[f64],
    b: MatRef<'_, f64>,
    split: Option<&SubtreeSplit>,
) -> Option<Mat<f64>> {
    let nodes = supernodes(symbolic, values)?;
    let mut out = Mat::zeros(b.nrows(), b.ncols());
    let mut col = 0;
    while col < b.ncols() {
        let k = (b.ncols() - col).min(4);
        match k {
            1 => forward_columns::<1>(symbolic, &nodes, b, col, k, out.as_mut(), split),
            2 => forward_columns::<2>(symbolic, &nodes, b, col, k, out.as_mut(), split),
            _ => forward_columns::<4>(symbolic, &nodes, b, col, k, out.as_mut(), split),
        }
        col += k;
    }
    Some(out)
}

/// Columns `col..col + kc` (`kc ≤ K`) of [`forward_supernodal_llt`], in one sweep over
/// the factor (lanes past `kc` carry zeros).
fn forward_columns<const K: usize>(
    symbolic: &SymbolicCholesky<usize>,
    nodes: &[Supernode<'_>],
    b: MatRef<'_, f64>,
    col: usize,
    kc: usize,
    mut out: MatMut<'_, f64>,
    split: Option<&SubtreeSplit>,
) {
    let fwd = symbolic.perm().map(|p| p.arrays().0);
    let mut w: Vec<[f64; K]> = (0..b.nrows())
        .map(|k| {
            let i = fwd.map_or(k, |f| f[k]);
            lanes(|c| b[(i, col + c)], kc)
        })
        .collect();
    forward(nodes, &mut w, split);
    for (k, v) in w.iter().enumerate() {
        for (c, &x) in v.iter().enumerate().take(kc) {
            out[(k, col + c)] = x;
        }
    }
}

/// A row of `K` lanes holding `value(c)` in its first `kc` lanes and zeros after.
#[inline(always)]
fn lanes<const K: usize>(value: impl Fn(usize) -> f64, kc: usize) -> [f64; K] {
    std::array::from_fn(|c| if c < kc { value(c) } else { 0.0 })
}

/// Solves `L Lᵀ y = w` in place for `K` interleaved right-hand sides whose rows are already
/// in the factor's (permuted) order: no gather or scatter. Returns `false`, leaving `w`
/// untouched, if the factor is not supernodal or `w` has the wrong length.
pub(crate) fn solve_supernodal_llt_permuted<const K: usize>(
    symbolic: &SymbolicCholesky<usize>,
    values: &[f64],
    w: &mut [[f64; K]],
    split: Option<&SubtreeSplit>,
) -> bool {
    if w.len() != symbolic.nrows() {
        return false;
    }
    let Some(nodes) = supernodes(symbolic, values) else {
        return false;
    };
    if K == 3 {
        // In four lanes, as [`solve_supernodal_llt`] runs three columns.
        let mut w4: Vec<[f64; 4]> = w.iter().map(|r| lanes(|c| r[c], K)).collect();
        forward_reach(&nodes, &mut w4, split);
        backward(&nodes, &mut w4, split);
        for (r, v) in w.iter_mut().zip(&w4) {
            r.copy_from_slice(&v[..K]);
        }
    } else {
        forward_reach(&nodes, w, split);
        backward(&nodes, w, split);
    }
    true
}

/// The forward substitution over the supernodes `w`'s nonzero rows reach.
fn forward_reach<const K: usize>(
    nodes: &[Supernode<'_>],
    w: &mut [[f64; K]],
    split: Option<&SubtreeSplit>,
) {
    match reach(nodes, w) {
        Some(visit) => forward_on(nodes, w, &visit),
        None => forward(nodes, w, split),
    }
}

/// Solves for the columns of `rhs` (at most `K`; lanes past them carry zeros).
fn solve_block<const K: usize>(
    nodes: &[Supernode<'_>],
    fwd: &[usize],
    inv: &[usize],
    mut rhs: MatMut<'_, f64>,
    shared: Option<MatRef<'_, f64>>,
    split: Option<&SubtreeSplit>,
) {
    let kc = rhs.ncols();
    // Gather and scatter read `rhs` and `w` in order and write through the permutation
    // (independent stores instead of dependent random loads).
    let mut w: Vec<[f64; K]> = vec![[0.0; K]; fwd.len()];
    for (i, &p) in inv.iter().enumerate() {
        w[p] = lanes(|c| rhs[(i, c)], kc);
    }
    forward_reach(nodes, &mut w, split);
    if let Some(b) = shared {
        for (k, r) in w.iter_mut().enumerate() {
            for (c, v) in r.iter_mut().enumerate().take(kc) {
                *v += b[(k, c)];
            }
        }
    }
    backward(nodes, &mut w, split);
    for (r, &f) in w.iter().zip(fwd) {
        for (c, &v) in r.iter().enumerate().take(kc) {
            rhs[(f, c)] = v;
        }
    }
}

/// The supernodes a forward substitution of `w` must visit, in ascending order, or `None`
/// when that is most of them (the plain sweep is then cheaper than the bookkeeping).
fn reach<const K: usize>(nodes: &[Supernode<'_>], w: &[[f64; K]]) -> Option<Vec<usize>> {
    let nonzero = w.iter().filter(|r| r.iter().any(|&v| v != 0.0)).count();
    if nonzero * 4 > w.len() {
        return None;
    }
    // The supernode holding column i (supernodes are ascending, contiguous column ranges;
    // a search per visited column instead of an n-long table per solve).
    let node_of_col = |i: usize| {
        let k = nodes.partition_point(|s| s.start + s.width <= i);
        nodes
            .get(k)
            .filter(|s| s.start <= i)
            .map_or(usize::MAX, |_| k)
    };
    let mut marked = vec![false; nodes.len()];
    let mut count = 0;
    for (i, r) in w.iter().enumerate() {
        if r.iter().all(|&v| v == 0.0) {
            continue;
        }
        let mut k = node_of_col(i);
        // The parent of a supernode holds its first below-diagonal row.
        while k != usize::MAX && !marked[k] {
            marked[k] = true;
            count += 1;
            k = nodes[k]
                .pattern
                .first()
                .map_or(usize::MAX, |&r| node_of_col(r));
        }
    }
    if count * 2 > nodes.len() {
        return None;
    }
    Some((0..nodes.len()).filter(|&k| marked[k]).collect())
}

/// [`forward`] over the supernodes `visit` only (ascending; all others hold zeros).
fn forward_on<const K: usize>(nodes: &[Supernode<'_>], w: &mut [[f64; K]], visit: &[usize]) {
    simd(
        #[inline(always)]
        || {
            let mut tmp: Vec<[f64; K]> = Vec::new();
            for &k in visit {
                forward_node(&nodes[k], w, 0, &mut [], &mut tmp);
            }
        },
    )
}

/// `L y = b`: per supernode, the triangular solve on its diagonal block, then the block's
/// contribution to its pattern rows accumulated contiguously and scattered once
/// ([`forward_supernode`]). With a `split`, the two sets of subtrees first, on two
/// threads (each spills its contributions to rows outside its subtrees, which belong to
/// the rest, into its own array, added after), then the rest in order.
fn forward<const K: usize>(
    nodes: &[Supernode<'_>],
    w: &mut [[f64; K]],
    split: Option<&SubtreeSplit>,
) {
    let sweep = |nodes: &mut dyn Iterator<Item = &Supernode<'_>>, w: &mut [[f64; K]]| {
        simd(
            #[inline(always)]
            || {
                let mut tmp: Vec<[f64; K]> = Vec::new();
                for s in nodes {
                    forward_node(s, w, 0, &mut [], &mut tmp);
                }
            },
        )
    };
    let Some(split) = split else {
        return sweep(&mut nodes.iter(), w);
    };
    let n = w.len();
    let [jobs0, jobs1] = subtree_jobs(nodes, split, w);
    let run = |jobs: Vec<Job<'_, K>>| {
        simd(
            #[inline(always)]
            || {
                let mut tmp: Vec<[f64; K]> = Vec::new();
                let mut spill = vec![[0.0; K]; n];
                for (r, c0, own) in jobs {
                    for s in &nodes[r] {
                        forward_node(s, own, c0, &mut spill, &mut tmp);
                    }
                }
                spill
            },
        )
    };
    let (spill0, spill1) = super::join(|| run(jobs0), || run(jobs1));
    for ((x, a), b) in w.iter_mut().zip(&spill0).zip(&spill1) {
        for c in 0..K {
            x[c] += a[c] + b[c];
        }
    }
    let in_bin = split.in_bins(nodes.len());
    let mut rest = nodes.iter().zip(in_bin).filter(|(_, b)| !b).map(|(s, _)| s);
    sweep(&mut rest, w);
}

/// One supernode's step of the forward substitution. `own` holds the rows from `c0` on
/// (the supernode's columns among them); a contribution `t` to a row `r` outside it is
/// added to `spill[r]` instead (to be added to `r` later). `tmp` is scratch.
#[inline(always)]
fn forward_node<const K: usize>(
    s: &Supernode<'_>,
    own: &mut [[f64; K]],
    c0: usize,
    spill: &mut [[f64; K]],
    tmp: &mut Vec<[f64; K]>,
) {
    let start = s.start - c0;
    tmp.resize(s.pattern.len(), [0.0; K]);
    forward_supernode(s.values, s.width, &mut own[start..start + s.width], tmp);
    for (&r, t) in s.pattern.iter().zip(tmp.iter()) {
        let x = match r.checked_sub(c0).and_then(|i| own.get_mut(i)) {
            Some(x) => x,
            None => &mut spill[r],
        };
        for c in 0..K {
            x[c] += t[c];
        }
    }
}

/// The rows of `w` cut into each subtree range's own slice, grouped by thread.
fn subtree_jobs<'w, const K: usize>(
    nodes: &[Supernode<'_>],
    split: &SubtreeSplit,
    w: &'w mut [[f64; K]],
) -> [Vec<Job<'w, K>>; 2] {
    split.cut(w, |r| {
        nodes[r.start].start..nodes[r.end - 1].start + nodes[r.end - 1].width
    })
}

/// One subtree range of a thread: its supernodes, its first row and its rows of `w`.
type Job<'w, const K: usize> = SubtreeSlice<'w, [f64; K]>;

/// `Lᵀ x = y`: the supernodes in reverse ([`backward_supernode`]). With a `split`, the
/// supernodes outside its subtrees first, then the two sets of subtrees on two threads: a
/// subtree's supernodes read only rows of their own subtree and of the rest, which is
/// final by then.
fn backward<const K: usize>(
    nodes: &[Supernode<'_>],
    w: &mut [[f64; K]],
    split: Option<&SubtreeSplit>,
) {
    let sweep = |nodes: &mut dyn Iterator<Item = &Supernode<'_>>, w: &mut [[f64; K]]| {
        simd(
            #[inline(always)]
            || {
                let mut tmp: Vec<[f64; K]> = Vec::new();
                for s in nodes {
                    backward_node(s, w, 0, &[], &mut tmp);
                }
            },
        )
    };
    let Some(split) = split else {
        return sweep(&mut nodes.iter().rev(), w);
    };
    let in_bin = split.in_bins(nodes.len());
    let mut rest = nodes
        .iter()
        .zip(in_bin)
        .rev()
        .filter(|(_, b)| !b)
        .map(|(s, _)| s);
    sweep(&mut rest, w);
    let frozen = w.to_vec();
    let [jobs0, jobs1] = subtree_jobs(nodes, split, w);
    let frozen = &frozen;
    let run = |jobs: Vec<Job<'_, K>>| {
        simd(
            #[inline(always)]
            || {
                let mut tmp: Vec<[f64; K]> = Vec::new();
                for (r, c0, own) in jobs {
                    for s in nodes[r].iter().rev() {
                        backward_node(s, own, c0, frozen, &mut tmp);
                    }
                }
            },
        )
    };
    super::join(|| run(jobs0), || run(jobs1));
}

/// One supernode's step of the backward substitution. `own` holds the rows from `c0` on
/// (the supernode's own columns among them); rows outside it are read from `frozen`.
/// `tmp` is scratch.
#[inline(always)]
fn backward_node<const K: usize>(
    s: &Supernode<'_>,
    own: &mut [[f64; K]],
    c0: usize,
    frozen: &[[f64; K]],
    tmp: &mut Vec<[f64; K]>,
) {
    tmp.clear();
    tmp.extend(
        s.pattern
            .iter()
            .map(|&r| match r.checked_sub(c0).and_then(|i| own.get(i)) {
                Some(v) => *v,
                None => frozen[r],
            }),
    );
    let start = s.start - c0;
    backward_supernode(s.values, s.width, &mut own[start..start + s.width], tmp);
}
