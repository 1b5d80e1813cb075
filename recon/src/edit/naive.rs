//! Naive Laplacian editing, the baseline: the uniform (umbrella) Laplacian coordinates of
//! the rest mesh are kept unrotated, `L(x')ᵢ = δᵢ` at every free ROI vertex, with hard
//! position constraints at the ring, anchors and handles (Fu, *Differential Methods for
//! Intuitive 3D Shape Modeling*, Eq. 2.1; Sorkine et al. 2004, *Laplacian Surface
//! Editing*, §2). Scaled by the valence, the uniform Laplacian is the symmetric graph
//! Laplacian `D − A`, so the system is one SPD matrix with three right-hand sides.

use faer::Mat;

use super::local::{from_mat, gather, graph_laplacian, to_mat};
use super::problem::EditProblem;
use super::session::EditMethod;
use super::similarity::Similarity;
use super::EditError;
use crate::geometry::Vec3;
use crate::solve::{sparse_mul_dense, CholeskyOptions, FixedSolver};

/// Options of [`NaiveLaplacian`] (none yet).
#[derive(Debug, Clone, Copy, Default)]
pub struct NaiveOptions {}

/// Factored naive Laplacian editing of one ROI.
#[derive(Debug, Clone)]
pub struct NaiveLaplacian {
    solver: FixedSolver,
    delta: Mat<f64>,
}

impl NaiveLaplacian {
    /// One solve of `(D − A) x = c` at the free vertices with given coordinates `c`
    /// (indexed by *global* vertex, the `Σⱼ (xᵢ − xⱼ)` form) and every constrained vertex
    /// at rest; returns local positions.
    pub fn solve_with_coordinates(
        problem: &EditProblem,
        coords: &[Vec3],
    ) -> Result<Vec<Vec3>, EditError> {
        let k = graph_laplacian(problem)?;
        let solver = FixedSolver::precompute(
            k.as_ref(),
            &problem.constrained(),
            CholeskyOptions::default(),
        )?;
        let b = Mat::from_fn(problem.len(), 3, |l, c| {
            coords.get(problem.global[l]).map_or(0.0, |v| v[c])
        });
        let known = gather(&problem.rest, solver.known());
        let x = solver.solve(b.as_ref(), known.as_ref())?;
        Ok(from_mat(x.as_ref()))
    }
}

impl EditMethod for NaiveLaplacian {
    type Options = NaiveOptions;

    fn factor(problem: &EditProblem, _: &NaiveOptions) -> Result<Self, EditError> {
        let k = graph_laplacian(problem)?;
        let delta = sparse_mul_dense(k.as_ref(), to_mat(&problem.rest).as_ref())?;
        let solver = FixedSolver::precompute(
            k.as_ref(),
            &problem.constrained(),
            CholeskyOptions::default(),
        )?;
        Ok(Self { solver, delta })
    }

    fn solve(
        &mut self,
        problem: &EditProblem,
        transforms: &[Similarity],
    ) -> Result<Vec<Vec3>, EditError> {
        let targets = problem.targets(transforms)?;
        let known = gather(&targets, self.solver.known());
        let x = self.solver.solve(self.delta.as_ref(), known.as_ref())?;
        Ok(from_mat(x.as_ref()))
    }

    fn factor_len(&self) -> usize {
        0
    }
}
