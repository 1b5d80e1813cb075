//! Implicit Laplacian editing with derived similarity transforms (Fu, *Differential Methods
//! for Intuitive 3D Shape Modeling*, ch. 2, §2.4).
//!
//! Each ROI vertex gets the affine deformation gradient fitted to its 1-ring (Eq. 2.5),
//! linear in the unknown positions: `Mᵢ = Xᵢ Qᵢ` with the constant `Qᵢ = Gᵢ Vᵢᵀ(VᵢVᵢᵀ)⁻¹`.
//! The first system minimises `E_L + μ E_R` (Eqs. 2.6–2.8): `E_L = Σ ‖D(x′)ᵢ − Mᵢ δᵢ‖²`
//! (cotangent weights clamped at 0 and normalised to sum 1) and the coherence
//! `E_R = Σ_{2-ring pairs} ‖Mᵢ − Mⱼ‖²_F`, with `μ = coherence_weight · ē²` (ē the mean
//! edge length, which makes the energy scale-covariant). Positions of the ring, anchors and
//! handles are hard; handles with `fix_gradient` also fix `Mᵢ = sR` (substituted into both
//! terms). x, y and z share one matrix.
//!
//! Degenerate vertices (§2.4.3): a vertex whose `cond(VᵢVᵢᵀ) > 2e5` (a planar 1-ring) is
//! displaced along its normal by `s_disp` times its mean edge length (Eq. 2.9), visiting
//! vertices in index order with the already displaced positions; the system is built on
//! the displaced mesh and each displaced free vertex is pulled back by its own gradient,
//! `ṽᵢ = Mᵢ(vᵢ − vᵢ′) + ṽᵢ′`.
//!
//! Shear removal (§2.4.4): each `Mᵢ` of the first solution is replaced by its polar
//! rotation `Rᵢ` (times `sᵢ = ‖Mᵢ‖_F/√3` with `scale_features`) and a second, cotangent
//! Poisson system `K x = Rᵢ (K v)ᵢ` on the original mesh gives the result (Eqs. 2.10/2.11).
//! Interactively [`ImplicitEditor::solve_drag`] runs the first system per drag and
//! [`ImplicitEditor::solve_release`] the second on release.
//!
//! With no gradient constraint and all position constraints in one plane the first system
//! is singular (`x ↦ x + m (n·x − d)` costs nothing); this is reported as an error.

use faer::Mat;
use nalgebra::Matrix3;

use super::local::{cotan_stiffness, cotan_weights_at, from_mat, gather};
use super::problem::{EditProblem, Role};
use super::session::EditMethod;
use super::similarity::{mat_vec, polar_rotation, to_na, Mat3, Similarity};
use super::system::{ms_since, FactoredQuadratic, QuadTerm, RowBuilder};
use super::EditError;
use crate::geometry::{triangle_normal, Vec3};
use crate::solve::{sparse_mul_dense, CholeskyOptions, FixedSolver};

/// Condition number of `VᵢVᵢᵀ` above which a vertex is degenerate (Fu §2.4.3).
pub const DEGENERATE_COND: f64 = 2e5;

/// Options of [`ImplicitEditor`].
#[derive(Debug, Clone, Copy)]
pub struct ImplicitOptions {
    /// Weight of the coherence term in units of the squared mean edge length.
    pub coherence_weight: f64,
    /// Displacement of degenerate vertices in mean incident edge lengths (`s_disp`).
    pub s_disp: f64,
    /// Run the shear-removal second solve (false: return the first system's result).
    pub second_solve: bool,
    /// Keep the fitted scale in the second solve (Eq. 2.11) instead of only the rotation.
    pub scale_features: bool,
}

impl Default for ImplicitOptions {
    fn default() -> Self {
        Self {
            coherence_weight: 1.0,
            s_disp: 0.2,
            second_solve: true,
            scale_features: false,
        }
    }
}

/// Factored implicit Laplacian editing of one ROI.
#[derive(Debug, Clone)]
pub struct ImplicitEditor {
    first: FactoredQuadratic,
    second: FixedSolver,
    /// Time to build and factor the first system (Eq. 2.8), everything included, ms.
    first_ms: f64,
    /// Time to build and factor the second system (Eq. 2.10), ms.
    second_ms: f64,
    /// Positions after the degenerate-vertex displacement.
    displaced: Vec<Vec3>,
    /// Stencil (vertex then 1-ring) and `Qᵢ` ((k+1) × 3, row-major) per ROI vertex.
    stencil: Vec<Vec<usize>>,
    q: Vec<Vec<[f64; 3]>>,
    /// Laplacian coordinates of the displaced mesh, per ROI vertex.
    delta: Vec<Vec3>,
    /// `K v` of the original mesh (second system's rest coordinates).
    kv: Mat<f64>,
    /// Number of displaced (degenerate) vertices.
    pub n_degenerate: usize,
    /// Vertices still degenerate after the displacement pass.
    pub n_still_degenerate: usize,
    mu: f64,
    options: ImplicitOptions,
    last_first: Option<Vec<Vec3>>,
}

/// The smallest and largest eigenvalue of a symmetric 3×3 matrix, in closed form (the
/// trigonometric solution of the characteristic cubic; O. K. Smith, *Eigenvalues of a
/// symmetric 3 × 3 matrix*, CACM 1961). Absolute error about ε·‖A‖, so a condition
/// number up to [`DEGENERATE_COND`] is read to about 1e-10 relative.
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
fn stencil_condition(x: &[Vec3], stencil: &[usize]) -> f64 {
    centred_stencil(x, stencil).map_or(f64::INFINITY, |(_, vvt)| condition(&vvt))
}

/// `cond(V Vᵀ)` and `Qᵢ` of vertex `i` for positions `x`.
fn fit(x: &[Vec3], stencil: &[usize]) -> (f64, Option<Vec<[f64; 3]>>) {
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

/// `Qmᵀ (L ⊗ I₃)` (its column `3i + c` is row `3i + c` of `(L ⊗ I₃) Qm`), with `L` the graph Laplacian of the 2-ring pairs: row
/// `3i + c` is `Σ_k (Qᵢ[:, c] − Q_k[:, c])` over the ROI vertices `k` within two rings of
/// `i`, each `Qᵢ` spread over its stencil (zero where the gradient is fixed). Summed in one
/// dense accumulator per vertex, which is what makes the coherence term cheap to assemble.
fn coherence_rows(
    problem: &EditProblem,
    stencil: &[Vec<usize>],
    q: &[Vec<[f64; 3]>],
    fixed_grad: impl Fn(usize) -> bool,
) -> Result<crate::solve::SparseMatrix, EditError> {
    let n_roi = problem.n_roi;
    let n = problem.len();
    let mut mark = vec![usize::MAX; n_roi];
    let mut partners: Vec<Vec<usize>> = vec![Vec::new(); n_roi];
    for i in 0..n_roi {
        mark[i] = i;
        for &j in &problem.neighbors[i] {
            for &k in std::iter::once(&j).chain(problem.neighbors[j].iter()) {
                if k < n_roi && mark[k] != i {
                    mark[k] = i;
                    if k > i {
                        partners[i].push(k);
                        partners[k].push(i);
                    }
                }
            }
        }
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
    // Room for every row: a vertex's stencils overlap, so this bounds the entries.
    let bound: usize = (0..n_roi)
        .map(|i| {
            let own = ptr[i + 1] - ptr[i];
            own + partners[i]
                .iter()
                .map(|&k| ptr[k + 1] - ptr[k])
                .sum::<usize>()
        })
        .sum();
    let mut rows = RowBuilder::with_capacity(n, 3 * n_roi, 3 * bound.min(n * n_roi));
    let mut entries = Vec::new();
    for (i, partners_i) in partners.iter().enumerate() {
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

/// Area-weighted vertex normals of the local faces.
fn local_normals(problem: &EditProblem) -> Vec<Vec3> {
    let x = &problem.rest;
    let mut n = vec![Vec3::ZERO; problem.len()];
    for f in &problem.faces {
        let fnrm = triangle_normal(x[f[0]], x[f[1]], x[f[2]]);
        for &v in f {
            n[v] += fnrm;
        }
    }
    n.into_iter().map(Vec3::normalize_or_zero).collect()
}

/// Fails when no gradient is fixed and every position constraint lies in one plane.
fn check_singular(problem: &EditProblem) -> Result<(), EditError> {
    if problem.handles.iter().any(|h| h.fix_gradient) {
        return Ok(());
    }
    let pts: Vec<Vec3> = problem
        .constrained()
        .iter()
        .map(|&l| problem.rest[l])
        .collect();
    let c = pts.iter().fold(Vec3::ZERO, |a, &p| a + p) / pts.len().max(1) as f64;
    let mut cov = Matrix3::<f64>::zeros();
    for p in &pts {
        let d = to_na(*p - c);
        cov += d * d.transpose();
    }
    let eig = cov.symmetric_eigenvalues();
    if eig.min() <= 1e-10 * eig.max().max(1e-300) {
        return Err(EditError::Singular(
            "implicit editing: every position constraint lies in one plane and no handle fixes \
             its gradient (set \"fix_gradient\": true on a handle, or anchor off that plane)"
                .into(),
        ));
    }
    Ok(())
}

impl ImplicitEditor {
    fn gradient_of(&self, i: usize, x: &[Vec3]) -> Mat3 {
        let mut m = Mat3::zeros();
        for (s, q) in self.stencil[i].iter().zip(&self.q[i]) {
            for r in 0..3 {
                for c in 0..3 {
                    m[(r, c)] += x[*s][r] * q[c];
                }
            }
        }
        m
    }

    /// The first system (Eq. 2.8) with degenerate vertices pulled back: the positions shown
    /// while a handle is dragged.
    pub fn solve_drag(
        &mut self,
        problem: &EditProblem,
        transforms: &[Similarity],
    ) -> Result<Vec<Vec3>, EditError> {
        problem.check_transforms(transforms)?;
        let n_roi = problem.n_roi;
        // Targets on the displaced geometry.
        let targets: Vec<Vec3> = (0..problem.len())
            .map(|l| match problem.role[l] {
                Role::Handle(h) => problem.handle_target(l, h, self.displaced[l], transforms),
                _ => self.displaced[l],
            })
            .collect();
        let mut b_l = Mat::<f64>::zeros(n_roi, 3);
        let mut m_c = Mat::<f64>::zeros(3 * n_roi, 3);
        for i in 0..n_roi {
            if let Role::Handle(h) = problem.role[i] {
                if problem.handles[h].fix_gradient {
                    let w = transforms[h].linear();
                    let wd = mat_vec(&w, self.delta[i]);
                    for r in 0..3 {
                        b_l[(i, r)] = wd[r];
                        for c in 0..3 {
                            m_c[(3 * i + c, r)] = -w[(r, c)];
                        }
                    }
                }
            }
        }
        let known = gather(&targets, self.first.known());
        let x = self
            .first
            .solve(&[Some(b_l.as_ref()), Some(m_c.as_ref())], known.as_ref())?;
        let xd = from_mat(x.as_ref());
        let mut out = xd.clone();
        for l in 0..problem.len() {
            match problem.role[l] {
                Role::Free => {
                    let off = problem.rest[l] - self.displaced[l];
                    if off != Vec3::ZERO {
                        out[l] = xd[l] + mat_vec(&self.gradient_of(l, &xd), off);
                    }
                }
                Role::Handle(h) => {
                    out[l] = problem.handle_target(l, h, problem.rest[l], transforms)
                }
                _ => out[l] = problem.rest[l],
            }
        }
        self.last_first = Some(xd);
        Ok(out)
    }

    /// The shear-removal solve (Eq. 2.10, or 2.11 with `scale_features`) after
    /// [`Self::solve_drag`] with the same transforms.
    pub fn solve_release(
        &mut self,
        problem: &EditProblem,
        transforms: &[Similarity],
    ) -> Result<Vec<Vec3>, EditError> {
        let Some(xd) = self.last_first.as_ref() else {
            return self.solve(problem, transforms);
        };
        let targets = problem.targets(transforms)?;
        let mut b = Mat::<f64>::zeros(problem.len(), 3);
        for i in 0..problem.n_roi {
            if problem.role[i] != Role::Free {
                continue;
            }
            let (r, s) = polar_rotation(&self.gradient_of(i, xd));
            let s = if self.options.scale_features { s } else { 1.0 };
            let kv = Vec3::new(self.kv[(i, 0)], self.kv[(i, 1)], self.kv[(i, 2)]);
            let v = mat_vec(&r, kv) * s;
            for c in 0..3 {
                b[(i, c)] = v[c];
            }
        }
        let known = gather(&targets, self.second.known());
        let x = self.second.solve(b.as_ref(), known.as_ref())?;
        Ok(from_mat(x.as_ref()))
    }
}

impl EditMethod for ImplicitEditor {
    type Options = ImplicitOptions;

    fn factor(problem: &EditProblem, options: &ImplicitOptions) -> Result<Self, EditError> {
        let clock = std::time::Instant::now();
        check_singular(problem)?;
        let n = problem.len();
        let n_roi = problem.n_roi;
        let stencil: Vec<Vec<usize>> = (0..n_roi)
            .map(|i| {
                let mut s = vec![i];
                s.extend_from_slice(&problem.neighbors[i]);
                s
            })
            .collect();
        // Degenerate vertices: sequential displacement along the normal.
        let normals = local_normals(problem);
        let mut x = problem.rest.clone();
        let mut n_degenerate = 0;
        for i in 0..n_roi {
            if stencil_condition(&x, &stencil[i]) > DEGENERATE_COND {
                let nb = &problem.neighbors[i];
                let mean =
                    nb.iter().map(|&j| x[i].distance(x[j])).sum::<f64>() / nb.len().max(1) as f64;
                x[i] += normals[i] * (options.s_disp * mean);
                n_degenerate += 1;
            }
        }
        let mut q = Vec::with_capacity(n_roi);
        let mut n_still_degenerate = 0;
        for s in &stencil {
            let (cond, qi) = fit(&x, s);
            if cond > DEGENERATE_COND {
                n_still_degenerate += 1;
            }
            // A vertex that is still rank-deficient (e.g. collinear ring) gets Qᵢ = 0:
            // its gradient drops out of the coherence term.
            q.push(qi.unwrap_or_else(|| vec![[0.0; 3]; s.len()]));
        }
        // Clamped cotangent weights of the displaced mesh, normalised per row.
        let w = cotan_weights_at(problem, &x, true);
        let mut wsum = vec![0.0; n];
        for &(i, _, v) in &w {
            wsum[i] += v;
        }
        let mut lap: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n_roi];
        for &(i, j, v) in &w {
            if i < n_roi && wsum[i] > 0.0 {
                lap[i].push((j, v / wsum[i]));
            }
        }
        let delta: Vec<Vec3> = (0..n_roi)
            .map(|i| {
                lap[i]
                    .iter()
                    .fold(Vec3::ZERO, |a, &(j, v)| a + (x[j] - x[i]) * v)
            })
            .collect();
        let fixed_grad = |i: usize| match problem.role[i] {
            Role::Handle(h) => problem.handles[h].fix_gradient,
            _ => false,
        };
        // E_L rows.
        let mut al = RowBuilder::new(n);
        let mut qm = RowBuilder::new(n);
        let mut entries = Vec::new();
        for i in 0..n_roi {
            entries.clear();
            for &(j, v) in &lap[i] {
                entries.push((j, v));
                entries.push((i, -v));
            }
            if !fixed_grad(i) {
                for (m, &s) in stencil[i].iter().enumerate() {
                    let qd =
                        q[i][m][0] * delta[i].x + q[i][m][1] * delta[i].y + q[i][m][2] * delta[i].z;
                    entries.push((s, -qd));
                }
            }
            al.push(&entries)?;
            for c in 0..3 {
                entries.clear();
                if !fixed_grad(i) {
                    for (&s, qm_row) in stencil[i].iter().zip(&q[i]) {
                        entries.push((s, qm_row[c]));
                    }
                }
                qm.push(&entries)?;
            }
        }
        // Coherence: E_R = Σ_c Q_cᵀ L Q_c over the graph Laplacian L of the 2-ring pairs,
        // given to the solver as W·Qm with W = L ⊗ I₃ (the rows of Qm are 3i + c).
        let wqm = coherence_rows(problem, &stencil, &q, fixed_grad)?;
        let ebar = problem.mean_edge_length();
        let mu = options.coherence_weight * ebar * ebar;
        let terms = vec![
            QuadTerm {
                a: al.finish()?,
                a_t_w: None,
                weight: 1.0,
            },
            QuadTerm {
                a: qm.finish()?,
                a_t_w: Some(wqm),
                weight: mu,
            },
        ];
        let x0 = Mat::from_fn(n, 3, |i, c| x[i][c]);
        let first = FactoredQuadratic::new(n, terms, &problem.constrained(), Some(x0))?;
        let first_ms = ms_since(clock);
        let k = cotan_stiffness(problem)?;
        let kv = sparse_mul_dense(
            k.as_ref(),
            Mat::from_fn(n, 3, |i, c| problem.rest[i][c]).as_ref(),
        )?;
        let second = FixedSolver::precompute(
            k.as_ref(),
            &problem.constrained(),
            CholeskyOptions::default(),
        )?;
        let second_ms = ms_since(clock) - first_ms;
        Ok(Self {
            first,
            second,
            first_ms,
            second_ms,
            displaced: x,
            stencil,
            q,
            delta,
            kv,
            n_degenerate,
            n_still_degenerate,
            mu,
            options: *options,
            last_first: None,
        })
    }

    fn solve(
        &mut self,
        problem: &EditProblem,
        transforms: &[Similarity],
    ) -> Result<Vec<Vec3>, EditError> {
        let first = self.solve_drag(problem, transforms)?;
        if self.options.second_solve {
            self.solve_release(problem, transforms)
        } else {
            Ok(first)
        }
    }

    fn factor_len(&self) -> usize {
        self.first.factor_len()
    }

    fn factor_parts(&self) -> Vec<(&'static str, f64)> {
        let t = self.first.timings();
        vec![
            ("first_system", self.first_ms),
            ("first_assemble", t.assemble_ms),
            ("first_ordering", t.analyze_ms),
            ("first_cholesky", t.numeric_ms),
            ("first_shared_rhs", t.shared_ms),
            ("second_system", self.second_ms),
        ]
    }
}

impl ImplicitEditor {
    /// The coherence weight `μ` in absolute units.
    pub fn coherence_mu(&self) -> f64 {
        self.mu
    }
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
