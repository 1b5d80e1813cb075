//! The two systems of implicit Laplacian editing (Fu, *Differential Methods for Intuitive
//! 3D Shape Modeling*, ch. 2), built and factored: the first (Eq. 2.8, gradients and
//! coherence; solved per drag) and the second (Eq. 2.10, the shear-removal cotangent
//! system; solved on release), each with the fill-reducing order it is factored in.

use faer::Mat;

use super::implicit::{ImplicitOptions, DEGENERATE_COND};
use super::implicit_fit::{coherence_rows, fit, stencil_condition};
use super::local::{cotan_stiffness, cotan_weights_at};
use super::problem::{EditProblem, Role};
use super::system::{ms_since, FactorOrdering, FactoredQuadratic, QuadTerm};
use super::EditError;
use super::RowBuilder;
use crate::geometry::{triangle_normal, Vec3};
use crate::solve::{sparse_mul_dense, CholeskyOptions, FixedSolver, OrderingSkeleton, SolveError};

/// How many rings apart the first system's normal matrix couples two vertices: `E_L`'s
/// rows span a 1-ring (its normal matrix two), the coherence term's a gradient's 1-ring
/// on each side of a 2-ring pair (four).
const COUPLING_RINGS: usize = 4;

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

/// The first system (Eq. 2.8), factored, with what its solves need.
pub(super) struct FirstSystem {
    pub(super) system: FactoredQuadratic,
    pub(super) displaced: Vec<Vec3>,
    pub(super) stencil: Vec<Vec<usize>>,
    pub(super) q: Vec<Vec<[f64; 3]>>,
    pub(super) delta: Vec<Vec3>,
    pub(super) n_degenerate: usize,
    pub(super) n_still_degenerate: usize,
    pub(super) mu: f64,
    /// Time to build and factor it, ms.
    pub(super) ms: f64,
}

impl FirstSystem {
    /// Degenerate-vertex displacement, gradient fits, the `E_L` and coherence rows, and the
    /// factorisation.
    pub(super) fn build(
        problem: &EditProblem,
        options: &ImplicitOptions,
        order: FactorOrdering<'_>,
    ) -> Result<Self, EditError> {
        let clock = std::time::Instant::now();
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
        let first = FactoredQuadratic::with_ordering(
            n,
            terms,
            &problem.constrained(),
            Some(x0),
            order,
            options.threads,
        )?;
        Ok(Self {
            system: first,
            displaced: x,
            stencil,
            q,
            delta,
            n_degenerate,
            n_still_degenerate,
            mu,
            ms: ms_since(clock),
        })
    }
}

/// The first system's elimination order: nested dissection of the free vertices on the
/// mesh graph, whose separators are [`COUPLING_RINGS`] rings wide
/// ([`OrderingSkeleton::order_free`]); the normal matrix is not needed.
pub(super) fn first_system_order(problem: &EditProblem) -> Result<Vec<usize>, SolveError> {
    free_order(problem, COUPLING_RINGS)
}

/// Nested dissection of the free vertices on the mesh graph, for a system coupling
/// vertices up to `rings` rings apart (separators that wide).
fn free_order(problem: &EditProblem, rings: usize) -> Result<Vec<usize>, SolveError> {
    let fixed: Vec<bool> = (0..problem.len())
        .map(|l| problem.is_constrained(l))
        .collect();
    OrderingSkeleton::new(&problem.neighbors, rings)?.order_free(&fixed)
}

/// The shear-removal system (Eq. 2.10): the cotangent stiffness of the original mesh,
/// factored, and its rest coordinates `K v`.
pub(super) struct SecondSystem {
    pub(super) solver: FixedSolver,
    pub(super) kv: Mat<f64>,
    /// Time to build and factor it, ms.
    pub(super) ms: f64,
}

impl SecondSystem {
    pub(super) fn build(problem: &EditProblem) -> Result<Self, EditError> {
        let clock = std::time::Instant::now();
        let k = cotan_stiffness(problem)?;
        let kv = sparse_mul_dense(
            k.as_ref(),
            Mat::from_fn(problem.len(), 3, |i, c| problem.rest[i][c]).as_ref(),
        )?;
        // The cotangent system couples 1-rings: nested dissection on the mesh graph is
        // that of its own graph, and no third thread races AMD against it (which the
        // default ordering would do, beside the first system's thread).
        let solver = FixedSolver::precompute_ordered(
            k.as_ref(),
            &problem.constrained(),
            CholeskyOptions::default(),
            &free_order(problem, 1)?,
        )?;
        Ok(Self {
            solver,
            kv,
            ms: ms_since(clock),
        })
    }
}
