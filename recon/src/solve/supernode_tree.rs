//! The supernodal elimination tree of a factor and its split into two sets of
//! independent subtrees, one per thread, for `supernodal_numeric` and `supernodal_solve`.
//!
//! A supernode reads only its descendants in the elimination tree (Liu, *The role of
//! elimination trees in sparse factorization*, 1990). A nested-dissection order's tree
//! branches under its top separators into parts that share nothing until those
//! separators, so whole subtrees can be factored (or, in a backward substitution, solved)
//! concurrently; the separators above them, the rest, come after (before, backward).

use std::ops::Range;

use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};

/// The supernodal structure in plain arrays, with each supernode's updating descendants.
#[derive(Debug)]
pub(crate) struct SupernodeLayout {
    /// First column of each supernode, plus `n` at the end.
    pub(crate) begin: Vec<usize>,
    /// Below-diagonal row pattern of supernode `s`: `rows[row_ptr[s]..row_ptr[s] + plen[s]]`.
    pub(crate) row_ptr: Vec<usize>,
    pub(crate) plen: Vec<usize>,
    pub(crate) rows: Vec<usize>,
    /// Values of supernode `s`: `val_ptr[s]..val_ptr[s + 1]`, column-major.
    pub(crate) val_ptr: Vec<usize>,
    /// Parent supernode in the elimination tree (`usize::MAX` for a root).
    pub(crate) parent: Vec<usize>,
    /// Descendants updating supernode `s`: `upd[upd_ptr[s]..upd_ptr[s + 1]]`, ascending.
    pub(crate) upd_ptr: Vec<usize>,
    pub(crate) upd: Vec<usize>,
    /// Estimated multiply-adds of each update in `upd`.
    pub(crate) upd_work: Vec<f64>,
    /// Estimated flops of factoring each supernode (its updates received and its own
    /// dense factorisation): what [`SubtreeSplit`] balances.
    pub(crate) work: Vec<f64>,
}

impl SupernodeLayout {
    /// The layout of a supernodal symbolic factor, or `None` if it is simplicial or not
    /// laid out as the kernels here expect.
    pub(crate) fn new(symbolic: &SymbolicCholesky<usize>) -> Option<Self> {
        let SymbolicCholeskyRaw::Supernodal(s) = symbolic.raw() else {
            return None;
        };
        let ns = s.supernode_begin().len();
        let n = symbolic.nrows();
        let mut begin = s.supernode_begin().to_vec();
        begin.push(*s.supernode_end().last()?);
        // Contiguous supernodes tiling the columns (faer's layout; anything else is
        // left to faer's own kernels).
        if begin[0] != 0
            || begin[ns] != n
            || s.supernode_end()
                .iter()
                .zip(&begin[1..])
                .any(|(e, b)| e != b)
        {
            return None;
        }
        let row_ptr = s.col_ptr_for_row_idx().to_vec();
        let val_ptr = s.col_ptr_for_val().to_vec();
        let all_rows = s.row_idx();
        let mut plen = Vec::with_capacity(ns);
        for k in 0..ns {
            let width = begin[k + 1].checked_sub(begin[k]).filter(|&w| w > 0)?;
            let len = val_ptr.get(k + 1)?.checked_sub(*val_ptr.get(k)?)?;
            let p = (len / width).checked_sub(width)?;
            if len != width * (width + p) || row_ptr.get(k)? + p > all_rows.len() {
                return None;
            }
            plen.push(p);
        }
        let mut col_super = vec![0usize; n];
        for k in 0..ns {
            col_super[begin[k]..begin[k + 1]].fill(k);
        }
        let pattern = |k: usize| &all_rows[row_ptr[k]..row_ptr[k] + plen[k]];
        // Updating descendants: d updates every supernode its pattern meets.
        let mut count = vec![0usize; ns + 1];
        let mut parent = vec![usize::MAX; ns];
        for (d, parent_d) in parent.iter_mut().enumerate() {
            // The kernels search the patterns: they must ascend (faer's do).
            if !pattern(d).windows(2).all(|w| w[0] < w[1]) {
                return None;
            }
            let mut last = usize::MAX;
            for &r in pattern(d) {
                let t = *col_super.get(r)?;
                if t <= d {
                    return None;
                }
                if t != last {
                    if last == usize::MAX {
                        *parent_d = t;
                    }
                    count[t] += 1;
                    last = t;
                }
            }
        }
        let mut upd_ptr = vec![0usize; ns + 1];
        for t in 0..ns {
            upd_ptr[t + 1] = upd_ptr[t] + count[t];
        }
        let mut fill = upd_ptr.clone();
        let mut upd = vec![0usize; upd_ptr[ns]];
        let mut upd_work = vec![0.0f64; upd_ptr[ns]];
        let mut work = vec![0.0f64; ns];
        for d in 0..ns {
            let dw = (begin[d + 1] - begin[d]) as f64;
            let p = pattern(d);
            let mut i = 0;
            while i < p.len() {
                let t = col_super[p[i]];
                let j = i + p[i..].partition_point(|&r| col_super[r] == t);
                // r × m1 × dw multiply-adds (the m1 × m1 block only half).
                let (r, m1) = ((p.len() - i) as f64, (j - i) as f64);
                upd[fill[t]] = d;
                upd_work[fill[t]] = dw * m1 * (r - m1 / 2.0);
                work[t] += upd_work[fill[t]];
                fill[t] += 1;
                i = j;
            }
        }
        for (k, wk) in work.iter_mut().enumerate() {
            let w = (begin[k + 1] - begin[k]) as f64;
            *wk += w * w * (w / 3.0 + plen[k] as f64 / 2.0);
        }
        Some(Self {
            begin,
            row_ptr,
            plen,
            rows: all_rows.to_vec(),
            val_ptr,
            parent,
            upd_ptr,
            upd,
            upd_work,
            work,
        })
    }

    /// Number of supernodes.
    pub(crate) fn len(&self) -> usize {
        self.parent.len()
    }

    /// Below-diagonal row pattern of supernode `k`.
    pub(crate) fn pattern(&self, k: usize) -> &[usize] {
        &self.rows[self.row_ptr[k]..self.row_ptr[k] + self.plen[k]]
    }

    /// Number of columns of supernode `k`.
    pub(crate) fn width(&self, k: usize) -> usize {
        self.begin[k + 1] - self.begin[k]
    }
}

/// The least estimated work (multiply-adds, about 0.1 ms) worth a second thread.
pub(crate) const MIN_SPLIT_WORK: f64 = 1e6;

/// Two sets of whole subtrees of the supernodal elimination tree, one per thread, then
/// the rest on one thread. Each subtree is a contiguous range of supernodes ending at
/// its root (so its values are one slice), and no supernode of one set is an ancestor of
/// one in the other, so both sets are factored concurrently.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SubtreeSplit {
    /// Supernode ranges of each thread, ascending.
    pub bins: [Vec<Range<usize>>; 2],
    /// Estimated cost: the heavier bin plus the rest, relative to the sequential total.
    pub cost: f64,
}

/// One subtree range of a thread: its supernodes, where its slice starts in the array
/// cut, and the slice.
pub(crate) type SubtreeSlice<'a, T> = (Range<usize>, usize, &'a mut [T]);

impl SubtreeSplit {
    /// `data` cut into each subtree range's own slice, grouped by thread; `extent(r)` is
    /// the part of `data` the supernodes `r` own (consecutive ranges own consecutive
    /// parts), e.g. their values or their rows.
    pub(crate) fn cut<'a, T>(
        &self,
        data: &'a mut [T],
        extent: impl Fn(&Range<usize>) -> Range<usize>,
    ) -> [Vec<SubtreeSlice<'a, T>>; 2] {
        let mut ranges: Vec<(usize, Range<usize>)> = self
            .bins
            .iter()
            .enumerate()
            .flat_map(|(b, rs)| rs.iter().map(move |r| (b, r.clone())))
            .collect();
        ranges.sort_by_key(|(_, r)| r.start);
        let mut out: [Vec<SubtreeSlice<'a, T>>; 2] = [Vec::new(), Vec::new()];
        let mut left: &'a mut [T] = data;
        let mut at = 0;
        for (b, r) in ranges {
            let e = extent(&r);
            let (_, tail) = std::mem::take(&mut left).split_at_mut(e.start - at);
            let (mine, tail) = tail.split_at_mut(e.len());
            at = e.end;
            out[b].push((r, e.start, mine));
            left = tail;
        }
        out
    }

    /// Per supernode (of `len`): whether it is in one of the two sets of subtrees.
    pub(crate) fn in_bins(&self, len: usize) -> Vec<bool> {
        let mut in_bin = vec![false; len];
        for r in self.bins.iter().flatten() {
            in_bin[r.clone()].fill(true);
        }
        in_bin
    }

    /// Splits the elimination tree for the per-supernode weights `weight`: starting from
    /// the roots, the heaviest subtree is repeatedly replaced by its children (its root
    /// joins the rest), and after each step the subtrees are packed into two bins
    /// (heaviest first, into the lighter bin); the packing minimising the heavier bin
    /// plus the rest is kept. A subtree whose supernodes are not numbered contiguously is
    /// always expanded (faer numbers supernodes in the order given, which need not be a
    /// postorder; nested dissection's parts are contiguous). `None` unless the split
    /// saves a tenth of the sequential weight, or below [`MIN_SPLIT_WORK`] (where a
    /// thread costs more than it saves).
    pub(crate) fn choose(layout: &SupernodeLayout, weight: &[f64]) -> Option<Self> {
        const MAX_STEPS: usize = 256;
        let ns = layout.len();
        if ns < 2 || weight.len() != ns {
            return None;
        }
        // Subtree weights, sizes and children (children come before parents).
        let mut sub = weight.to_vec();
        let mut size = vec![1usize; ns];
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); ns];
        for k in 0..ns {
            let p = layout.parent[k];
            if p != usize::MAX {
                sub[p] += sub[k];
                size[p] += size[k];
                children[p].push(k);
            }
        }
        // A subtree can go to a thread only if it is one contiguous range of supernodes,
        // ending at its root (always so in a postorder; nested dissection's parts are).
        let mut lowest: Vec<usize> = (0..ns).collect();
        for k in 0..ns {
            let p = layout.parent[k];
            if p != usize::MAX {
                lowest[p] = lowest[p].min(lowest[k]);
            }
        }
        let contiguous = |k: usize| k + 1 - lowest[k] == size[k];
        let total: f64 = weight.iter().sum();
        if total < MIN_SPLIT_WORK {
            return None;
        }
        let mut front: Vec<usize> = (0..ns)
            .filter(|&k| layout.parent[k] == usize::MAX)
            .collect();
        let mut rest = 0.0;
        let mut best: Option<(f64, Vec<usize>, Vec<bool>)> = None;
        for _ in 0..MAX_STEPS {
            // Subtrees that are not contiguous give their roots to the rest.
            while let Some(pos) = front.iter().position(|&r| !contiguous(r)) {
                let r = front.swap_remove(pos);
                rest += weight[r];
                front.extend_from_slice(&children[r]);
            }
            front.sort_by(|&a, &b| sub[b].total_cmp(&sub[a]));
            let mut load = [0.0f64; 2];
            let mut side = Vec::with_capacity(front.len());
            for &r in &front {
                let b = usize::from(load[1] < load[0]);
                load[b] += sub[r];
                side.push(b == 1);
            }
            let cost = load[0].max(load[1]) + rest;
            if best.as_ref().is_none_or(|(c, _, _)| cost < *c) {
                best = Some((cost, front.clone(), side));
            }
            // Expand the heaviest subtree that has children.
            let Some(pos) = front.iter().position(|&r| !children[r].is_empty()) else {
                break;
            };
            let r = front.swap_remove(pos);
            rest += weight[r];
            if rest >= best.as_ref().map_or(total, |b| b.0) {
                break;
            }
            front.extend_from_slice(&children[r]);
        }
        let (cost, front, side) = best?;
        if cost >= 0.9 * total {
            return None;
        }
        let mut bins: [Vec<Range<usize>>; 2] = [Vec::new(), Vec::new()];
        for (&r, &b) in front.iter().zip(&side) {
            bins[usize::from(b)].push(r + 1 - size[r]..r + 1);
        }
        for b in &mut bins {
            b.sort_by_key(|r| r.start);
        }
        Some(Self {
            bins,
            cost: cost / total,
        })
    }
}
