//! Laplacian Surface Editing (Sorkine, Cohen-Or, Lipman, Alexa, Rössl, Seidel 2004,
//! *Laplacian Surface Editing*, §3).
//!
//! Minimises `Σᵢ ‖Tᵢ(x′) δᵢ − L(x′)ᵢ‖² + Σ_c w_c² ‖x′_c − u_c‖²` over the ROI, where `δᵢ`
//! are the uniform Laplacian coordinates (Eqs. 1–2) and `Tᵢ` is the linearised similarity
//! `s I + [h]×` fitted to the 1-ring (Eqs. 6–12), which is linear in `x′`:
//! `(s, h) = Pᵢ x′_{ring}` with `Pᵢ` from the rest 1-ring (centred at `vᵢ`). Each ROI
//! vertex gives three rows `(Lᵢ ⊗ I₃) − D(δᵢ) Pᵢ` of one coupled `3n × 3n` system.
//! Handles (weight `w_h`) and anchors inside the ROI (`anchor_weight`) are soft; the ring
//! outside the ROI is hard. One factorisation per ROI; a handle move changes only the
//! right-hand side.
//!
//! Large rotations (§3.1): the linearised `Tᵢ` squashes along the rotation axis. With
//! `refit_iterations > 0` each solve re-linearises: the fitted `(s, h)` become exact
//! rotations `Rᵢ = exp(θ ĥ)` with `θ = atan2(‖h‖, s)`, accumulated per vertex; the 1-rings
//! and `δᵢ` are rotated by them and the system is refactored (numeric only) and solved.

use std::time::Instant;

use faer::Mat;
use nalgebra::DMatrix;

use super::basis::{AffineBasis, AFFINE_PARAMETERS};
use super::problem::{EditProblem, Role};
use super::session::EditMethod;
use super::similarity::{mat_vec, rotation_from_vector, Mat3, Similarity};
use super::system::{FactoredQuadratic, QuadTerm};
use super::EditError;
use super::RowBuilder;
use crate::geometry::Vec3;

/// Options of [`LseEditor`].
#[derive(Debug, Clone, Copy, Default)]
pub struct LseOptions {
    /// Re-linearisation iterations after each solve (0: the single-shot method).
    pub refit_iterations: usize,
}

/// Factored Laplacian surface editing of one ROI.
#[derive(Debug, Clone)]
pub struct LseEditor {
    base: FactoredQuadratic,
    lap_rhs: Vec<(usize, f64)>,
    /// Soft-constraint rows: (local vertex, weight).
    soft: Vec<(usize, f64)>,
    options: LseOptions,
    /// Time of the last solve's re-fitting iterations, ms.
    pub last_refit_ms: f64,
}

/// Rows `(Lᵢ ⊗ I₃) − D(R δᵢ) Pᵢ(R)` of every ROI vertex, rings rotated by `rot[i]`.
fn laplacian_rows(
    problem: &EditProblem,
    rot: &[Mat3],
    rhs: &mut Vec<(usize, f64)>,
) -> Result<RowBuilder, EditError> {
    let n = problem.len();
    let x = &problem.rest;
    let mut rows = RowBuilder::new(3 * n);
    let mut entries: Vec<(usize, f64)> = Vec::new();
    for i in 0..problem.n_roi {
        let nb = &problem.neighbors[i];
        let mut stencil = Vec::with_capacity(nb.len() + 1);
        stencil.push(i);
        stencil.extend_from_slice(nb);
        let m = stencil.len();
        let d = nb.len().max(1) as f64;
        let r = &rot[i];
        let mean = nb.iter().fold(Vec3::ZERO, |a, &j| a + x[j]) / d;
        let delta = mat_vec(r, x[i] - mean);
        let mut a = DMatrix::<f64>::zeros(3 * m, 7);
        for (k, &v) in stencil.iter().enumerate() {
            let c = mat_vec(r, x[v] - x[i]);
            let rows3 = [
                [c.x, 0.0, c.z, -c.y],
                [c.y, -c.z, 0.0, c.x],
                [c.z, c.y, -c.x, 0.0],
            ];
            for (rr, row) in rows3.iter().enumerate() {
                for (cc, &val) in row.iter().enumerate() {
                    a[(3 * k + rr, cc)] = val;
                }
                a[(3 * k + rr, 4 + rr)] = 1.0;
            }
        }
        let ata = a.transpose() * &a;
        // A collinear 1-ring leaves the fit undetermined: keep the plain Laplacian row
        // (T = I), the documented fallback.
        let p = ata.try_inverse().map(|inv| inv * a.transpose());
        let dmat = [
            [delta.x, 0.0, delta.z, -delta.y],
            [delta.y, -delta.z, 0.0, delta.x],
            [delta.z, delta.y, -delta.x, 0.0],
        ];
        for rr in 0..3 {
            entries.clear();
            entries.push((3 * i + rr, 1.0));
            for &j in nb {
                entries.push((3 * j + rr, -1.0 / d));
            }
            match &p {
                Some(p) => {
                    for (k, &v) in stencil.iter().enumerate() {
                        for cc in 0..3 {
                            let col = 3 * k + cc;
                            let mut s = 0.0;
                            for q in 0..4 {
                                s += dmat[rr][q] * p[(q, col)];
                            }
                            entries.push((3 * v + cc, -s));
                        }
                    }
                }
                // T = I: the residual is L(x′) − δ, δ goes to the right-hand side.
                None => rhs.push((3 * i + rr, delta[rr])),
            }
            rows.push(&entries)?;
        }
    }
    Ok(rows)
}

fn soft_rows(problem: &EditProblem) -> (Vec<(usize, f64)>, RowBuilder) {
    let mut soft = Vec::new();
    for l in 0..problem.len() {
        match problem.role[l] {
            Role::Handle(h) => soft.push((l, problem.handles[h].weight)),
            Role::Anchor => soft.push((l, problem.anchor_weight)),
            _ => {}
        }
    }
    let mut b = RowBuilder::new(3 * problem.len());
    for &(l, w) in &soft {
        for c in 0..3 {
            // Infallible: columns are < 3n by construction.
            let _ = b.push(&[(3 * l + c, w)]);
        }
    }
    (soft, b)
}

/// Quadratic terms and constant right-hand-side entries `(row, value)`.
type Terms = (Vec<QuadTerm>, Vec<(usize, f64)>);

/// The two terms (Laplacian rows, soft rows) and the constant right-hand side entries of
/// the Laplacian rows (collinear 1-rings only).
fn terms(problem: &EditProblem, rot: &[Mat3]) -> Result<Terms, EditError> {
    let mut rhs = Vec::new();
    let lap = laplacian_rows(problem, rot, &mut rhs)?.finish()?;
    let (_, s) = soft_rows(problem);
    let t = vec![
        QuadTerm {
            a: lap,
            a_t_w: None,
            weight: 1.0,
        },
        QuadTerm {
            a: s.finish()?,
            a_t_w: None,
            weight: 1.0,
        },
    ];
    Ok((t, rhs))
}

fn ring_dofs(problem: &EditProblem) -> Vec<usize> {
    (0..problem.len())
        .filter(|&l| problem.role[l] == Role::Ring)
        .flat_map(|l| [3 * l, 3 * l + 1, 3 * l + 2])
        .collect()
}

impl LseEditor {
    fn solve_with(
        &self,
        system: &FactoredQuadratic,
        lap_rhs: &[(usize, f64)],
        problem: &EditProblem,
        targets: &[Vec3],
    ) -> Result<Vec<Vec3>, EditError> {
        let lap_b = (!lap_rhs.is_empty()).then(|| {
            let mut m = Mat::<f64>::zeros(3 * problem.n_roi, 1);
            for &(r, v) in lap_rhs {
                m[(r, 0)] = v;
            }
            m
        });
        let mut b = Mat::<f64>::zeros(3 * self.soft.len(), 1);
        for (r, &(l, w)) in self.soft.iter().enumerate() {
            for c in 0..3 {
                b[(3 * r + c, 0)] = w * targets[l][c];
            }
        }
        let known = Mat::from_fn(system.known().len(), 1, |r, _| {
            let d = system.known()[r];
            targets[d / 3][d % 3]
        });
        let x = system.solve(
            &[lap_b.as_ref().map(|m| m.as_ref()), Some(b.as_ref())],
            known.as_ref(),
        )?;
        Ok((0..problem.len())
            .map(|l| Vec3::new(x[(3 * l, 0)], x[(3 * l + 1, 0)], x[(3 * l + 2, 0)]))
            .collect())
    }

    /// Per ROI vertex, the exact rotation of the linearised similarity fitted from rest to
    /// `deformed` (rings rotated by `rot`).
    fn fitted_rotations(problem: &EditProblem, deformed: &[Vec3], rot: &[Mat3]) -> Vec<Mat3> {
        let x = &problem.rest;
        (0..problem.len())
            .map(|i| {
                if i >= problem.n_roi {
                    return rot[i];
                }
                let nb = &problem.neighbors[i];
                let mut stencil = vec![i];
                stencil.extend_from_slice(nb);
                // Linear fit of s, h, t: solve the 7×7 normal equations.
                let m = stencil.len();
                let mut a = DMatrix::<f64>::zeros(3 * m, 7);
                let mut bv = nalgebra::DVector::<f64>::zeros(3 * m);
                for (k, &v) in stencil.iter().enumerate() {
                    let c = mat_vec(&rot[i], x[v] - x[i]);
                    let rows3 = [
                        [c.x, 0.0, c.z, -c.y],
                        [c.y, -c.z, 0.0, c.x],
                        [c.z, c.y, -c.x, 0.0],
                    ];
                    for (rr, row) in rows3.iter().enumerate() {
                        for (cc, &val) in row.iter().enumerate() {
                            a[(3 * k + rr, cc)] = val;
                        }
                        a[(3 * k + rr, 4 + rr)] = 1.0;
                        bv[3 * k + rr] = deformed[v][rr];
                    }
                }
                let ata = a.transpose() * &a;
                let Some(inv) = ata.try_inverse() else {
                    return rot[i];
                };
                let p = inv * (a.transpose() * bv);
                let (s, hv) = (p[0], Vec3::new(p[1], p[2], p[3]));
                let theta = hv.norm().atan2(s);
                let r = match hv.try_normalize() {
                    Some(axis) => rotation_from_vector(axis * theta),
                    None => Mat3::identity(),
                };
                r * rot[i]
            })
            .collect()
    }
}

impl LseEditor {
    /// Precomputes the response of the (single-shot) solution to each of the 12 affine
    /// parameters of every handle (see [`AffineBasis`]): 12 solves per handle, once per
    /// factorisation; afterwards [`AffineBasis::combine`] answers a move exactly.
    pub fn precompute_basis(&self, problem: &EditProblem) -> Result<AffineBasis, EditError> {
        AffineBasis::check_handles(problem)?;
        let rest = problem.rest.clone();
        let base = self.solve_with(&self.base, &self.lap_rhs, problem, &rest)?;
        let mut responses = Vec::with_capacity(problem.handles.len());
        for h in &problem.handles {
            let mut per = Vec::with_capacity(AFFINE_PARAMETERS);
            for k in 0..AFFINE_PARAMETERS {
                let mut t = rest.clone();
                for &c in &h.vertices {
                    t[c] += AffineBasis::target_delta(k, rest[c]);
                }
                let x = self.solve_with(&self.base, &self.lap_rhs, problem, &t)?;
                per.push(x.iter().zip(&base).map(|(a, b)| *a - *b).collect());
            }
            responses.push(per);
        }
        Ok(AffineBasis::new(base, responses))
    }
}

impl EditMethod for LseEditor {
    type Options = LseOptions;

    fn factor(problem: &EditProblem, options: &LseOptions) -> Result<Self, EditError> {
        let rot = vec![Mat3::identity(); problem.len()];
        let (t, lap_rhs) = terms(problem, &rot)?;
        let x0 = Mat::from_fn(3 * problem.len(), 1, |d, _| problem.rest[d / 3][d % 3]);
        let base = FactoredQuadratic::new(3 * problem.len(), t, &ring_dofs(problem), Some(x0))?;
        let (soft, _) = soft_rows(problem);
        Ok(Self {
            base,
            lap_rhs,
            soft,
            options: *options,
            last_refit_ms: 0.0,
        })
    }

    fn solve(
        &mut self,
        problem: &EditProblem,
        transforms: &[Similarity],
    ) -> Result<Vec<Vec3>, EditError> {
        let targets = problem.targets(transforms)?;
        let mut x = self.solve_with(&self.base, &self.lap_rhs, problem, &targets)?;
        let t = Instant::now();
        if self.options.refit_iterations > 0 {
            let mut rot = vec![Mat3::identity(); problem.len()];
            let mut work = self.base.clone();
            for _ in 0..self.options.refit_iterations {
                rot = Self::fitted_rotations(problem, &x, &rot);
                let (t, lap_rhs) = terms(problem, &rot)?;
                work.refactor(t)?;
                x = self.solve_with(&work, &lap_rhs, problem, &targets)?;
            }
        }
        self.last_refit_ms = t.elapsed().as_secs_f64() * 1e3;
        Ok(x)
    }

    fn factor_len(&self) -> usize {
        self.base.factor_len()
    }

    fn factor_parts(&self) -> Vec<(&'static str, f64)> {
        let t = self.base.timings();
        vec![
            ("assemble", t.assemble_ms),
            ("ordering", t.analyze_ms),
            ("cholesky", t.numeric_ms),
            ("shared_rhs", t.shared_ms),
        ]
    }
}
