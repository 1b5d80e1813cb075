//! Register-blocked kernels of the supernodal triangular solves, for `K ≤ 4` right-hand
//! sides interleaved row-major (`[f64; K]` per row).
//!
//! A supernode's values are column-major. Forward substitution subtracts `L[i, j]·xⱼ` from
//! every row `i` below column `j`; backward substitution takes the dot product of a column
//! with the rows below it. Done one column at a time, every row of the right-hand sides
//! is loaded (and, forward, stored) once per column: on 4-ring editing systems (85% of
//! the factor in supernodes 32–600 columns wide) that was the solve's cost, three times
//! the time of streaming the factor. Four columns at a time load each row once per four
//! columns and keep four independent accumulators; blocks of four columns also take the
//! place of faer's dense kernels for wide supernodes (which pack the block for a
//! matrix–matrix product, a copy that costs more than the product with ≤ 4 columns).
//!
//! The sweeps run under [`simd`]: compiled for the best instruction set the processor
//! has (AVX2 on x86-64 where present), chosen at run time, so a `[f64; 4]` row is one
//! vector register. Everything a sweep calls is `#[inline(always)]` so it is compiled
//! inside that dispatch.

/// Runs `f` compiled for the best SIMD instruction set available at run time (pulp's
/// dispatch; the portable baseline where there is none).
#[inline(always)]
pub(super) fn simd<R>(f: impl FnOnce() -> R) -> R {
    pulp::Arch::new().dispatch(f)
}

/// `t[i] −= Σ_b cols[b][i] · x[b]` for every row `i` of `t`; each column has at least
/// `t.len()` entries.
#[inline(always)]
pub(super) fn sub_columns<const K: usize, const B: usize>(
    t: &mut [[f64; K]],
    cols: [&[f64]; B],
    x: &[[f64; K]; B],
) {
    let n = t.len();
    let cols = cols.map(|c| &c[..n]);
    for (i, ti) in t.iter_mut().enumerate() {
        let mut acc = *ti;
        for b in 0..B {
            let l = cols[b][i];
            for c in 0..K {
                acc[c] -= l * x[b][c];
            }
        }
        *ti = acc;
    }
}

/// `Σ_i cols[b][i] · g[i]` for every column `b`; each column has at least `g.len()`
/// entries.
#[inline(always)]
pub(super) fn dot_columns<const K: usize, const B: usize>(
    g: &[[f64; K]],
    cols: [&[f64]; B],
) -> [[f64; K]; B] {
    let n = g.len();
    let cols = cols.map(|c| &c[..n]);
    // Two rows per step into two sets of accumulators: one set is a chain of dependent
    // additions per row, bounded by the adder's latency rather than by reading the factor.
    let mut acc = [[[0.0; K]; B]; 2];
    let pairs = n / 2;
    for p in 0..pairs {
        for (h, acc) in acc.iter_mut().enumerate() {
            let i = 2 * p + h;
            let gi = g[i];
            for b in 0..B {
                let l = cols[b][i];
                for c in 0..K {
                    acc[b][c] += l * gi[c];
                }
            }
        }
    }
    if n % 2 == 1 {
        let gi = g[n - 1];
        for b in 0..B {
            let l = cols[b][n - 1];
            for c in 0..K {
                acc[0][b][c] += l * gi[c];
            }
        }
    }
    let [mut a, d] = acc;
    for b in 0..B {
        for c in 0..K {
            a[b][c] += d[b][c];
        }
    }
    a
}

/// A supernode's columns `j..j + B` from row `from` on (`rows` rows per column).
#[inline(always)]
pub(super) fn column_block<const B: usize>(
    values: &[f64],
    rows: usize,
    j: usize,
    from: usize,
) -> [&[f64]; B] {
    std::array::from_fn(|b| &values[(j + b) * rows + from..(j + b + 1) * rows])
}

/// One supernode's step of `L y = b`: its `width` columns (rows `width + plen` each,
/// column-major in `values`) solved in place in `own` (the supernode's rows), and minus
/// their contributions to the `plen` pattern rows written to `below`.
#[inline(always)]
pub(super) fn forward_supernode<const K: usize>(
    values: &[f64],
    width: usize,
    own: &mut [[f64; K]],
    below: &mut [[f64; K]],
) {
    let rows = width + below.len();
    below.fill([0.0; K]);
    let mut j = 0;
    while j < width {
        let b = (width - j).min(4);
        match b {
            4 => forward_block::<K, 4>(values, rows, width, j, own, below),
            3 => forward_block::<K, 3>(values, rows, width, j, own, below),
            2 => forward_block::<K, 2>(values, rows, width, j, own, below),
            _ => forward_block::<K, 1>(values, rows, width, j, own, below),
        }
        j += b;
    }
}

/// Columns `j..j + B` of [`forward_supernode`]: the `B × B` triangle one column at a time,
/// then the rows below it four columns at a time.
#[inline(always)]
fn forward_block<const K: usize, const B: usize>(
    values: &[f64],
    rows: usize,
    width: usize,
    j: usize,
    own: &mut [[f64; K]],
    below: &mut [[f64; K]],
) {
    for a in j..j + B {
        let col = &values[a * rows..a * rows + j + B];
        let mut xa = own[a];
        for v in &mut xa {
            *v /= col[a];
        }
        own[a] = xa;
        for r in a + 1..j + B {
            for c in 0..K {
                own[r][c] -= col[r] * xa[c];
            }
        }
    }
    let x: [[f64; K]; B] = std::array::from_fn(|b| own[j + b]);
    let (_, rest) = own.split_at_mut(j + B);
    let cols = column_block::<B>(values, rows, j, j + B);
    sub_columns(&mut rest[..width - j - B], cols, &x);
    let cols = column_block::<B>(values, rows, j, width);
    sub_columns(below, cols, &x);
}

/// One supernode's step of `Lᵀ x = y`: `own` (the supernode's rows) solved in place given
/// `below`, the final values of its pattern rows.
#[inline(always)]
pub(super) fn backward_supernode<const K: usize>(
    values: &[f64],
    width: usize,
    own: &mut [[f64; K]],
    below: &[[f64; K]],
) {
    let rows = width + below.len();
    // Blocks of four columns from the first, visited last to first.
    let mut j1 = width;
    while j1 > 0 {
        let b = match j1 % 4 {
            0 => 4,
            r => r,
        };
        match b {
            4 => backward_block::<K, 4>(values, rows, width, j1 - 4, own, below),
            3 => backward_block::<K, 3>(values, rows, width, j1 - 3, own, below),
            2 => backward_block::<K, 2>(values, rows, width, j1 - 2, own, below),
            _ => backward_block::<K, 1>(values, rows, width, j1 - 1, own, below),
        }
        j1 -= b;
    }
}

/// Columns `j..j + B` of [`backward_supernode`]: their dot products with the final rows
/// (below the block) four columns at a time, then the `B × B` triangle in reverse.
#[inline(always)]
fn backward_block<const K: usize, const B: usize>(
    values: &[f64],
    rows: usize,
    width: usize,
    j: usize,
    own: &mut [[f64; K]],
    below: &[[f64; K]],
) {
    let inner = dot_columns(
        &own[j + B..width],
        column_block::<B>(values, rows, j, j + B),
    );
    let outer = dot_columns(below, column_block::<B>(values, rows, j, width));
    for a in (j..j + B).rev() {
        let col = &values[a * rows..a * rows + j + B];
        let mut acc = own[a];
        for c in 0..K {
            acc[c] -= inner[a - j][c] + outer[a - j][c];
        }
        for r in a + 1..j + B {
            for c in 0..K {
                acc[c] -= col[r] * own[r][c];
            }
        }
        for v in &mut acc {
            *v /= col[a];
        }
        own[a] = acc;
    }
}
