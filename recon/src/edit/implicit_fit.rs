//! The per-vertex pieces of implicit Laplacian editing (Fu, *Differential Methods for
//! Intuitive 3D Shape Modeling*, ch. 2): the affine deformation gradient fitted to a
//! vertex's 1-ring (Eq. 2.5), the degenerate-vertex test on its condition (§2.4.3) and the
//! coherence term's rows over 2-ring pairs (Eq. 2.7). [`super::implicit`] assembles them.

use nalgebra::Matrix3;

use super::problem::EditProblem;
use super::similarity::to_na;
use super::EditError;
use super::RowBuilder;
use crate::geometry::Vec3;

/// The smallest and largest eigenvalue of a symmetric 3×3 matrix, in closed form (the
/// trigonometric solution of the characteristic cubic; O. K. Smith, *Eigenvalues of a
/// symmetric 3 × 3 matrix*, CACM 1961). Absolute error about ε·‖A‖, so a condition
/// number up to [`super::implicit::DEGENERATE_COND`] is read to about 1e-10 relative.
fn eigen_extremes(a: &Matrix3<f64>) -> (f64, f64) {
    let off = a[(0, 1)].powi(2) + a[(0, 2)].powi(2) + a[(1, 2)].powi(2);
    let q = (a[(0, 0)] + a[(1, 1)] + a[(2, 2)]) / 3.0;
    let d = [a[(0, 0)] - q, a[(1, 1)] - q, a[(2, 2)] - q];
    let p2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + 2.0 * off;
    if p2 <= 0.0 || !p2.is_finite() {
        return (q, q);
    }
    let p = (p2 / 6.0).sqrt();
    let b = (a - Matrix3::identity() * q) / p;
    let r = (b.determinant() / 2.0).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    let hi = q + 2.0 * p * phi.cos();
    let lo = q + 2.0 * p * (phi + 2.0 * std::f64::consts::FRAC_PI_3).cos();
    (lo, hi)
}

/// The stencil of vertex `i` about its ring's centroid (`V`'s columns) and `V Vᵀ`;
/// `None` for a vertex without neighbours.
fn centred_stencil(
    x: &[Vec3],
    stencil: &[usize],
) -> Option<(Vec<nalgebra::Vector3<f64>>, Matrix3<f64>)> {
    let k = stencil.len() - 1;
    if k == 0 {
        return None;
    }
    let c0 = stencil[1..].iter().fold(Vec3::ZERO, |a, &j| a + x[j]) / k as f64;
    let v: Vec<nalgebra::Vector3<f64>> = stencil.iter().map(|&s| to_na(x[s] - c0)).collect();
    let vvt: Matrix3<f64> = v.iter().map(|d| d * d.transpose()).sum();
    Some((v, vvt))
}

/// `cond(V Vᵀ)` from its extreme eigenvalues (infinite when singular).
fn condition(vvt: &Matrix3<f64>) -> f64 {
    let (lo, hi) = eigen_extremes(vvt);
    if lo > 0.0 {
        hi / lo
    } else {
        f64::INFINITY
    }
}

/// `cond(V Vᵀ)` of vertex `i` for positions `x`, without fitting `Qᵢ`: the degenerate-vertex test.
pub(super) fn stencil_condition(x: &[Vec3], stencil: &[usize]) -> f64 {
    centred_stencil(x, stencil).map_or(f64::INFINITY, |(_, vvt)| condition(&vvt))
}

/// `cond(V Vᵀ)` and `Qᵢ` of vertex `i` for positions `x`.
pub(super) fn fit(x: &[Vec3], stencil: &[usize]) -> (f64, Option<Vec<[f64; 3]>>) {
    let Some((v, vvt)) = centred_stencil(x, stencil) else {
        return (f64::INFINITY, None);
    };
    let k = stencil.len() - 1;
    let cond = condition(&vvt);
    let Some(inv) = vvt.try_inverse() else {
        return (cond, None);
    };
    // P = Vᵀ (V Vᵀ)⁻¹, Q = P − a (1ᵀ P) with a = (0, 1/k, …, 1/k).
    let p: Vec<[f64; 3]> = v
        .iter()
        .map(|d| {
            let row = inv * d;
            [row[0], row[1], row[2]]
        })
        .collect();
    let mut sum = [0.0; 3];
    for row in &p {
        for c in 0..3 {
            sum[c] += row[c];
        }
    }
    let q = p
        .iter()
        .enumerate()
        .map(|(m, row)| {
            let a = if m == 0 { 0.0 } else { 1.0 / k as f64 };
            [
                row[0] - a * sum[0],
                row[1] - a * sum[1],
                row[2] - a * sum[2],
            ]
        })
        .collect();
    (cond, Some(q))
}

/// Entries expected per coherence row (see [`coherence_rows`]).
const ROW_ESTIMATE: usize = 40;

/// `Qmᵀ (L ⊗ I₃)` (its column `3i + c` is row `3i + c` of `(L ⊗ I₃) Qm`), with `L` the graph Laplacian of the 2-ring pairs: row
/// `3i + c` is `Σ_k (Qᵢ[:, c] − Q_k[:, c])` over the ROI vertices `k` within two rings of
/// `i`, each `Qᵢ` spread over its stencil (zero where the gradient is fixed). Summed in one
/// dense accumulator per vertex, which is what makes the coherence term cheap to assemble.
pub(super) fn coherence_rows(
    problem: &EditProblem,
    stencil: &[Vec<usize>],
    q: &[Vec<[f64; 3]>],
    fixed_grad: impl Fn(usize) -> bool,
) -> Result<crate::solve::SparseMatrix, EditError> {
    let n_roi = problem.n_roi;
    let n = problem.len();
    // Each vertex's 2-ring partners, one flat list (`partner_ptr` delimits vertex i's).
    let mut mark = vec![usize::MAX; n_roi];
    let mut partner_ptr = Vec::with_capacity(n_roi + 1);
    let mut partners = Vec::with_capacity(20 * n_roi);
    partner_ptr.push(0);
    for i in 0..n_roi {
        mark[i] = i;
        for &j in &problem.neighbors[i] {
            for &k in std::iter::once(&j).chain(problem.neighbors[j].iter()) {
                if k < n_roi && mark[k] != i {
                    mark[k] = i;
                    partners.push(k);
                }
            }
        }
        partner_ptr.push(partners.len());
    }
    // Each free gradient's stencil and Qᵢ rows side by side, in one array.
    let mut ptr = Vec::with_capacity(n_roi + 1);
    let mut flat: Vec<(usize, [f64; 3])> = Vec::new();
    ptr.push(0);
    for i in 0..n_roi {
        if !fixed_grad(i) {
            flat.extend(stencil[i].iter().copied().zip(q[i].iter().copied()));
        }
        ptr.push(flat.len());
    }
    let mut acc = vec![[0.0; 3]; n];
    let mut seen = vec![usize::MAX; n];
    let mut touched = Vec::new();
    // Room for the rows of a regular mesh (a row spans the 1-rings of a 2-ring: 37
    // vertices at valence 6); more grows the arrays. An upper bound (the stencils' sizes
    // summed over the partners) is four times that, and fresh memory is slow to touch.
    let mut rows = RowBuilder::with_capacity(n, 3 * n_roi, 3 * n_roi * ROW_ESTIMATE);
    let mut entries = Vec::new();
    for i in 0..n_roi {
        let partners_i = &partners[partner_ptr[i]..partner_ptr[i + 1]];
        touched.clear();
        let mut add = |k: usize, f: f64| {
            for &(s, qk) in &flat[ptr[k]..ptr[k + 1]] {
                if seen[s] != i {
                    seen[s] = i;
                    acc[s] = [0.0; 3];
                    touched.push(s);
                }
                for (a, q) in acc[s].iter_mut().zip(qk) {
                    *a += f * q;
                }
            }
        };
        add(i, partners_i.len() as f64);
        for &k in partners_i {
            add(k, -1.0);
        }
        touched.sort_unstable();
        for c in [0, 1, 2] {
            entries.clear();
            entries.extend(touched.iter().map(|&s| (s, acc[s][c])));
            rows.push(&entries)?;
        }
    }
    Ok(rows.finish_transposed())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::edit::run::bench_spec;
    use crate::generate::icosphere;

    #[test]
    fn closed_form_eigenvalues_agree_with_the_iterative_ones() {
        let mut seed = 1u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for case in 0..200 {
            // V Vᵀ of a ring flattened towards a plane by up to 1e-4: cond up to ~1e8.
            let flat = 10f64.powi(-(case % 5));
            let mut m = Matrix3::zeros();
            for _ in 0..6 {
                let d = nalgebra::Vector3::new(rnd(), rnd(), rnd() * flat);
                m += d * d.transpose();
            }
            let (lo, hi) = eigen_extremes(&m);
            let e = m.symmetric_eigenvalues();
            assert!((hi - e.max()).abs() <= 1e-12 * e.max(), "case {case}");
            assert!((lo - e.min()).abs() <= 1e-12 * e.max(), "case {case}");
            let (c, c_ref) = (hi / lo, e.max() / e.min());
            assert!(
                (c - c_ref).abs() <= 1e-6 * c_ref,
                "case {case}: {c} vs {c_ref}"
            );
        }
        let d = Matrix3::from_diagonal(&nalgebra::Vector3::new(3.0, 1.0, 2.0));
        assert_eq!(eigen_extremes(&d), (1.0, 3.0));
        assert_eq!(eigen_extremes(&(Matrix3::identity() * 2.0)), (2.0, 2.0));
    }

    #[test]
    fn coherence_rows_are_the_pair_laplacian_times_the_gradient_rows() {
        let mesh = icosphere(2, 1.0);
        let spec = bench_spec(&mesh, 0.6).unwrap();
        let p = EditProblem::new(&mesh, &spec).unwrap();
        let (n, n_roi) = (p.len(), p.n_roi);
        let stencil: Vec<Vec<usize>> = (0..n_roi)
            .map(|i| {
                std::iter::once(i)
                    .chain(p.neighbors[i].iter().copied())
                    .collect()
            })
            .collect();
        let q: Vec<Vec<[f64; 3]>> = stencil.iter().map(|s| fit(&p.rest, s).1.unwrap()).collect();
        for every in [usize::MAX, 5] {
            // Some gradients fixed: their rows of Qm are zero.
            let fixed = |i: usize| every != usize::MAX && i % every == 0;
            let got = coherence_rows(&p, &stencil, &q, fixed).unwrap();
            assert_eq!((got.nrows(), got.ncols()), (n, 3 * n_roi));
            // Dense reference: L of the pairs within graph distance 2 (ROI only), times Qm.
            let mut lap = vec![vec![0.0; n_roi]; n_roi];
            for (i, row) in lap.iter_mut().enumerate() {
                let mut near: Vec<usize> = Vec::new();
                for &j in &p.neighbors[i] {
                    near.push(j);
                    near.extend(p.neighbors[j].iter().copied());
                }
                near.sort_unstable();
                near.dedup();
                for k in near.into_iter().filter(|&k| k < n_roi && k != i) {
                    row[k] = -1.0;
                    row[i] += 1.0;
                }
            }
            let mut qm = vec![vec![0.0; n]; 3 * n_roi];
            for i in (0..n_roi).filter(|&i| !fixed(i)) {
                for (&s, row) in stencil[i].iter().zip(&q[i]) {
                    for c in 0..3 {
                        qm[3 * i + c][s] = row[c];
                    }
                }
            }
            let mut dense = vec![vec![0.0; 3 * n_roi]; n];
            for (s, col, v) in crate::solve::sparse_triplets(got.as_ref()) {
                dense[s][col] += v;
            }
            let mut worst = 0.0f64;
            for i in 0..n_roi {
                for c in 0..3 {
                    for s in 0..n {
                        let want: f64 = (0..n_roi).map(|k| lap[i][k] * qm[3 * k + c][s]).sum();
                        worst = worst.max((dense[s][3 * i + c] - want).abs());
                    }
                }
            }
            assert!(worst < 1e-9, "largest difference {worst}");
        }
    }
}
