//! Affine drag bases: a method whose solution is affine in each handle's transform
//! precomputes its response to the transform's 12 parameters once per factorisation, and a
//! move becomes 12 vector updates per handle instead of a solve (the basis-function idea of
//! Botsch & Kobbelt 2004, *An Intuitive Framework for Real-Time Freeform Modeling*, §4).
//!
//! A handle's target `u = A v + τ` is linear in `(A, τ)`. Parameter `k < 9` is
//! `(A − I)_{ab}` with `a = k / 3`, `b = k % 3`; parameters 9–11 are `τ_a`. Laplacian surface
//! editing's single-shot solution and implicit editing's first system (Fu, ch. 2, Eq. 2.8)
//! are both affine in these parameters, so the combination is exact to round-off.

use super::problem::EditProblem;
use super::similarity::Similarity;
use super::EditError;
use crate::geometry::Vec3;

/// The number of affine parameters of one handle's transform.
pub const AFFINE_PARAMETERS: usize = 12;

/// Precomputed responses of a solution to the 12 affine parameters of every handle.
#[derive(Debug, Clone)]
pub struct AffineBasis {
    base: Vec<Vec3>,
    /// Per handle: 9 responses to `(A − I)_{ab}`, then 3 to the translation `τ_a`.
    responses: Vec<Vec<Vec<Vec3>>>,
}

impl AffineBasis {
    /// A basis from the solution at identity transforms and, per handle, the 12 responses.
    pub(crate) fn new(base: Vec<Vec3>, responses: Vec<Vec<Vec<Vec3>>>) -> Self {
        Self { base, responses }
    }

    /// Fails if a handle is given by positions (a shape), which no affine basis covers.
    pub(crate) fn check_handles(problem: &EditProblem) -> Result<(), EditError> {
        if problem.handles.iter().any(|h| h.shape.is_some()) {
            return Err(EditError::Spec(
                "the affine basis covers transform handles only, not positions".into(),
            ));
        }
        Ok(())
    }

    /// The component `a` of the targets that parameter `k` moves (`(A − I)_{ab}` or `τ_a`).
    pub(crate) fn component(k: usize) -> usize {
        if k < 9 {
            k / 3
        } else {
            k - 9
        }
    }

    /// The change of a target at `p` per unit of parameter `k`: `p_b` in component `a` for
    /// `(A − I)_{ab}`, 1 in component `a` for `τ_a`.
    pub(crate) fn target_delta(k: usize, p: Vec3) -> Vec3 {
        let mut d = [0.0; 3];
        d[Self::component(k)] = if k < 9 { p[k % 3] } else { 1.0 };
        Vec3::from_array(d)
    }

    /// The solution for `transforms`: the base plus each parameter's response.
    pub fn combine(
        &self,
        problem: &EditProblem,
        transforms: &[Similarity],
    ) -> Result<Vec<Vec3>, EditError> {
        problem.check_transforms(transforms)?;
        Self::check_handles(problem)?;
        if self.responses.len() != transforms.len() {
            return Err(EditError::TransformCount {
                expected: self.responses.len(),
                got: transforms.len(),
            });
        }
        let mut x = self.base.clone();
        for (t, per) in transforms.iter().zip(&self.responses) {
            let a = t.linear();
            let tau = t.apply(Vec3::ZERO);
            for (k, response) in per.iter().enumerate() {
                let coef = if k < 9 {
                    a[(k / 3, k % 3)] - if k / 3 == k % 3 { 1.0 } else { 0.0 }
                } else {
                    tau[k - 9]
                };
                if coef != 0.0 {
                    for (xi, r) in x.iter_mut().zip(response) {
                        *xi += *r * coef;
                    }
                }
            }
        }
        Ok(x)
    }
}
