//! Numeric supernodal LLᵀ factorisation on faer's symbolic structure, on two threads.
//!
//! The algorithm is the left-looking supernodal Cholesky of CHOLMOD (Chen, Davis, Hager &
//! Rajamanickam, *Algorithm 887: CHOLMOD, supernodal sparse Cholesky factorization and
//! update/downdate*, 2008, §3): supernode `s` gathers its columns of `P A Pᵀ`, subtracts
//! the update `L_d[rows ≥ s] L_d[rows in s]ᵀ` of every descendant `d` whose pattern
//! meets its columns, then factors its diagonal block and solves for the rows below it.
//! faer runs the same loop on one thread (its values layout is kept, so every solve
//! reads this factor as faer's own).
//!
//! The two threads (docs/architecture.md §8):
//! * the [`SubtreeSplit`]'s two sets of subtrees are factored concurrently, each into its
//!   own slices of the value array (a subtree's supernodes are one contiguous range);
//! * the rest (the separators above them) follows in order; a heavy supernode there
//!   shares its updates between the threads (each into its own block, summed) and
//!   factors its dense block with faer's two-thread kernels.
//!
//! Each thread zeroes the blocks it writes just before assembling them, so a fresh value
//! array is first touched (its pages faulted in) by the thread that fills it.

use std::ops::Range;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch, LltError};
use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::SymbolicCholesky;
use faer::sparse::SparseColMatRef;
use faer::{Accum, MatMut, MatRef, Par, Side};

use super::supernode_tree::{SubtreeSlice, SubtreeSplit, SupernodeLayout};
use super::SolveError;

/// Below this many multiply-adds an update is a plain loop; from it, a faer product into
/// a scratch block, then subtracted along runs of consecutive target rows.
const GEMM_MIN_FLOPS: usize = 4096;

/// From this many estimated multiply-adds of updates, a supernode outside the two
/// threads' subtrees shares its updates between the threads.
const SHARED_NODE_WORK: f64 = 2e6;

/// Supernodes at least this wide, outside the subtrees, factor their dense block on two
/// threads.
const SHARED_DENSE_WIDTH: usize = 256;

/// `P A Pᵀ`'s lower triangle in compressed columns (rows unsorted), from the triangle
/// `side` of `a` and the factor's inverse order `inv` (`inv[i]` is row `i`'s new index).
struct Lower {
    ptr: Vec<usize>,
    rows: Vec<usize>,
    vals: Vec<f64>,
}

impl Lower {
    fn new(a: SparseColMatRef<'_, usize, f64>, side: Side, inv: Option<&[usize]>) -> Self {
        let n = a.ncols();
        let map = |i: usize| inv.map_or(i, |p| p[i]);
        let keep = |i: usize, j: usize| match side {
            Side::Lower => i >= j,
            Side::Upper => i <= j,
        };
        let mut ptr = vec![0usize; n + 1];
        for j in 0..n {
            for i in a.row_idx_of_col(j) {
                if keep(i, j) {
                    ptr[map(i).min(map(j)) + 1] += 1;
                }
            }
        }
        for j in 0..n {
            ptr[j + 1] += ptr[j];
        }
        let mut fill = ptr.clone();
        let mut rows = vec![0usize; ptr[n]];
        let mut vals = vec![0.0; ptr[n]];
        for j in 0..n {
            for (i, &v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
                if keep(i, j) {
                    let (pi, pj) = (map(i), map(j));
                    let c = pi.min(pj);
                    rows[fill[c]] = pi.max(pj);
                    vals[fill[c]] = v;
                    fill[c] += 1;
                }
            }
        }
        Self { ptr, rows, vals }
    }

    /// Column `j`'s rows and values.
    fn col(&self, j: usize) -> (&[usize], &[f64]) {
        let r = self.ptr[j]..self.ptr[j + 1];
        (&self.rows[r.clone()], &self.vals[r])
    }
}

/// Scratch of one descendant's update: its rows' block positions, their runs of
/// consecutive positions, and the dense product.
#[derive(Default)]
struct UpdateScratch {
    local: Vec<usize>,
    runs: Vec<(usize, usize)>,
    product: Vec<f64>,
}

/// One thread's scratch.
struct Scratch {
    /// Block row of each pattern row of the supernode being factored (`usize::MAX` else).
    global_to_local: Vec<usize>,
    update: UpdateScratch,
    /// The helper thread's share of a supernode's updates, added to the supernode after.
    block: Vec<f64>,
    dense: MemBuffer,
}

impl Scratch {
    fn new(n: usize, max_width: usize) -> Result<Self, SolveError> {
        let req = cholesky_in_place_scratch::<f64>(max_width, Par::Seq, Default::default()).or(
            cholesky_in_place_scratch::<f64>(max_width, Par::rayon(2), Default::default()),
        );
        Ok(Self {
            global_to_local: vec![usize::MAX; n],
            update: UpdateScratch::default(),
            block: Vec::new(),
            dense: MemBuffer::try_new(req).map_err(|_| SolveError::OutOfMemory)?,
        })
    }

    fn map_pattern(&mut self, pattern: &[usize], width: usize) {
        for (i, &r) in pattern.iter().enumerate() {
            self.global_to_local[r] = width + i;
        }
    }

    fn unmap_pattern(&mut self, pattern: &[usize]) {
        for &r in pattern {
            self.global_to_local[r] = usize::MAX;
        }
    }
}

/// The supernode an update is subtracted from: its columns and its block's row count.
#[derive(Clone, Copy)]
struct Target {
    start: usize,
    end: usize,
    nrows: usize,
}

/// Numeric LLᵀ factorisation of `a` (its triangle `side` read) into `values`, which is
/// resized to the factor's length (a fresh array is left to the threads to touch). With
/// a `split`, its two sets of subtrees are factored on two threads.
pub(crate) fn factorize_supernodal_llt(
    symbolic: &SymbolicCholesky<usize>,
    layout: &SupernodeLayout,
    split: Option<&SubtreeSplit>,
    a: SparseColMatRef<'_, usize, f64>,
    side: Side,
    values: &mut Vec<f64>,
) -> Result<(), SolveError> {
    let n = symbolic.nrows();
    let len = symbolic.len_val();
    if values.len() != len {
        // Zeroed lazily by the allocator, so its pages are first touched by the thread
        // that fills them (every block is zeroed again before it is assembled); the old
        // array is freed first.
        *values = Vec::new();
        *values = vec![0.0; len];
    }
    let lower = Lower::new(a, side, symbolic.perm().map(|p| p.arrays().1));
    let max_width = (0..layout.len())
        .map(|k| layout.width(k))
        .max()
        .unwrap_or(0);
    let ns = layout.len();
    let mut scratch = Scratch::new(n, max_width)?;
    let Some(split) = split else {
        return factor_range(layout, &lower, 0..ns, 0, values, &mut scratch, None);
    };
    let mut helper = Scratch::new(n, max_width)?;
    let [jobs0, jobs1] = split.cut(values, |r| layout.val_ptr[r.start]..layout.val_ptr[r.end]);
    let run = |jobs: Vec<SubtreeSlice<'_, f64>>, scratch: &mut Scratch| {
        jobs.into_iter().try_for_each(|(r, _, v)| {
            factor_range(layout, &lower, r.clone(), r.start, v, scratch, None)
        })
    };
    let (r0, r1) = super::join(|| run(jobs0, &mut scratch), || run(jobs1, &mut helper));
    r0?;
    r1?;
    // The rest, in order: maximal runs of supernodes outside the bins.
    let in_bin = split.in_bins(ns);
    let mut k = 0;
    while k < ns {
        if in_bin[k] {
            k += 1;
            continue;
        }
        let e = (k..ns).find(|&e| in_bin[e]).unwrap_or(ns);
        factor_range(
            layout,
            &lower,
            k..e,
            0,
            values,
            &mut scratch,
            Some(&mut helper),
        )?;
        k = e;
    }
    Ok(())
}

/// Factors supernodes `nodes` into `values`, which holds the values of supernodes
/// `base..nodes.end` (every supernode of `nodes` and all its descendants lie in that
/// range). With a `helper` scratch, heavy supernodes share their work with a second thread.
fn factor_range(
    layout: &SupernodeLayout,
    a: &Lower,
    nodes: Range<usize>,
    base: usize,
    values: &mut [f64],
    scratch: &mut Scratch,
    mut helper: Option<&mut Scratch>,
) -> Result<(), SolveError> {
    let off0 = layout.val_ptr[base];
    for s in nodes {
        let (start, end) = (layout.begin[s], layout.begin[s + 1]);
        let w = end - start;
        let pattern = layout.pattern(s);
        let nrows = w + pattern.len();
        scratch.map_pattern(pattern, w);
        let (head, tail) = values.split_at_mut(layout.val_ptr[s] - off0);
        let head: &[f64] = head;
        let ls = &mut tail[..nrows * w];
        ls.fill(0.0);
        for j in start..end {
            let col = &mut ls[(j - start) * nrows..(j - start + 1) * nrows];
            let (rows, vals) = a.col(j);
            for (&i, &v) in rows.iter().zip(vals) {
                let local = if i < end {
                    i - start
                } else {
                    scratch.global_to_local[i]
                };
                col[local] += v;
            }
        }
        let target = Target { start, end, nrows };
        let ups = layout.upd_ptr[s]..layout.upd_ptr[s + 1];
        // Subtracts the updates `layout.upd[k]`, `k` in `which`, from `block`.
        let updates =
            |which: Range<usize>, block: &mut [f64], g2l: &[usize], up: &mut UpdateScratch| {
                for &d in &layout.upd[which] {
                    let ld = &head[layout.val_ptr[d] - off0..layout.val_ptr[d + 1] - off0];
                    update(layout, d, ld, target, block, g2l, up);
                }
            };
        let shared = helper
            .as_deref_mut()
            .filter(|_| layout.work[s] >= SHARED_NODE_WORK);
        let par = match shared {
            Some(h) => {
                // Two halves of the update work, the helper's into its own block.
                let work = &layout.upd_work[ups.clone()];
                let half = work.iter().sum::<f64>() / 2.0;
                let mut acc = 0.0;
                let cut = ups.start
                    + work
                        .iter()
                        .position(|&x| {
                            acc += x;
                            acc >= half
                        })
                        .map_or(work.len(), |p| p + 1);
                h.map_pattern(pattern, w);
                h.block.clear();
                h.block.resize(nrows * w, 0.0);
                let (g2l, up) = (&scratch.global_to_local, &mut scratch.update);
                let (h_g2l, h_up, block) = (&h.global_to_local, &mut h.update, &mut h.block);
                super::join(
                    || updates(ups.start..cut, ls, g2l, up),
                    || updates(cut..ups.end, block, h_g2l, h_up),
                );
                for (x, &y) in ls.iter_mut().zip(h.block.iter()) {
                    *x += y;
                }
                h.unmap_pattern(pattern);
                if w >= SHARED_DENSE_WIDTH {
                    Par::rayon(2)
                } else {
                    Par::Seq
                }
            }
            None => {
                updates(ups, ls, &scratch.global_to_local, &mut scratch.update);
                Par::Seq
            }
        };
        scratch.unmap_pattern(pattern);
        let (mut top, bot) = MatMut::from_column_major_slice_mut(ls, nrows, w).split_at_row_mut(w);
        if let Err(LltError::NonPositivePivot { index }) = cholesky_in_place(
            top.rb_mut(),
            Default::default(),
            par,
            MemStack::new(&mut scratch.dense),
            Default::default(),
        ) {
            return Err(SolveError::NotPositiveDefinite {
                column: start + index,
            });
        }
        solve_lower_triangular_in_place(top.rb(), bot.transpose_mut(), par);
    }
    Ok(())
}

/// Subtracts descendant `d`'s update (`ld` its values) from the block `ls` of the
/// supernode `t`, whose pattern rows `global_to_local` maps to block rows.
fn update(
    layout: &SupernodeLayout,
    d: usize,
    ld: &[f64],
    t: Target,
    ls: &mut [f64],
    global_to_local: &[usize],
    scratch: &mut UpdateScratch,
) {
    let Target { start, end, nrows } = t;
    let dw = layout.width(d);
    let dp = layout.pattern(d);
    let dn = dw + dp.len();
    let q = dp.partition_point(|&r| r < start);
    let below = &dp[q..];
    let m1 = below.partition_point(|&r| r < end);
    let r = below.len();
    scratch.local.clear();
    scratch
        .local
        .extend(below.iter().enumerate().map(|(i, &row)| {
            if i < m1 {
                row - start
            } else {
                global_to_local[row]
            }
        }));
    let local = &scratch.local;
    let first = dw + q;
    if dw * r * m1 < GEMM_MIN_FLOPS {
        for k in 0..dw {
            let lk = &ld[k * dn + first..k * dn + first + r];
            for jj in 0..m1 {
                let cj = below[jj] - start;
                let col = &mut ls[cj * nrows..(cj + 1) * nrows];
                let ljk = lk[jj];
                for ii in jj..r {
                    col[local[ii]] -= lk[ii] * ljk;
                }
            }
        }
        return;
    }
    // The product: its top m1 × m1 block is symmetric, so only its lower half.
    let ldm = MatRef::from_column_major_slice(ld, dn, dw);
    let mid = ldm.subrows(first, m1);
    scratch.product.clear();
    scratch.product.resize(r * m1, 0.0);
    let prod = MatMut::from_column_major_slice_mut(&mut scratch.product, r, m1);
    let (ptop, pbot) = prod.split_at_row_mut(m1);
    triangular::matmul(
        ptop,
        BlockStructure::TriangularLower,
        Accum::Replace,
        mid,
        BlockStructure::Rectangular,
        mid.transpose(),
        BlockStructure::Rectangular,
        1.0,
        Par::Seq,
    );
    if r > m1 {
        let bot = ldm.subrows(first + m1, r - m1);
        matmul(pbot, Accum::Replace, bot, mid.transpose(), 1.0, Par::Seq);
    }
    // Subtracted along runs of consecutive block rows (contiguous, vectorised).
    scratch.runs.clear();
    let mut ii = 0;
    while ii < r {
        let e = (ii + 1..r)
            .find(|&e| local[e] != local[e - 1] + 1)
            .unwrap_or(r);
        scratch.runs.push((ii, e));
        ii = e;
    }
    for (jj, (&row, pc)) in below[..m1]
        .iter()
        .zip(scratch.product.chunks_exact(r))
        .enumerate()
    {
        let cj = row - start;
        let col = &mut ls[cj * nrows..(cj + 1) * nrows];
        for &(a, b) in &scratch.runs {
            if b <= jj {
                continue;
            }
            let a = a.max(jj);
            let l0 = local[a];
            for (x, &y) in col[l0..l0 + (b - a)].iter_mut().zip(&pc[a..b]) {
                *x -= y;
            }
        }
    }
}
