//! The editing session: keeps one method's factorisation for an ROI and answers repeated
//! handle moves with solves only; it refactors only when the ROI or the anchors change.

use std::time::Instant;

use super::problem::EditProblem;
use super::similarity::Similarity;
use super::spec::EditSpec;
use super::EditError;
use crate::geometry::Vec3;
use crate::mesh::SurfaceMesh;

/// A differential editing method: factor once per ROI, solve per handle move.
pub trait EditMethod: Sized {
    /// Method options.
    type Options: Clone + Default;
    /// Builds and factors the method's systems for a resolved problem.
    fn factor(problem: &EditProblem, options: &Self::Options) -> Result<Self, EditError>;
    /// Solves for the local positions (ROI + ring) under the handle transforms.
    fn solve(
        &mut self,
        problem: &EditProblem,
        transforms: &[Similarity],
    ) -> Result<Vec<Vec3>, EditError>;
    /// Stored entries of the method's Cholesky factors (for reports).
    fn factor_len(&self) -> usize;
    /// Where the factorisation's time went, ms, by part (for benchmark reports; the parts
    /// a method does not break down are absent).
    fn factor_parts(&self) -> Vec<(&'static str, f64)> {
        Vec::new()
    }
}

/// Counters of the work a session did (the interactive contract: moves never factor).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SessionStats {
    /// Number of factorisations (one per ROI/anchor set).
    pub factorizations: usize,
    /// Number of solves (handle moves).
    pub solves: usize,
    /// Time of the last factorisation, ms (assembly included).
    pub factor_ms: f64,
    /// Time of the last solve, ms.
    pub solve_ms: f64,
}

/// An edit session over one mesh with one method.
#[derive(Debug)]
pub struct EditSession<M: EditMethod> {
    rest: Vec<Vec3>,
    mesh: SurfaceMesh,
    spec: EditSpec,
    problem: EditProblem,
    options: M::Options,
    method: M,
    stats: SessionStats,
}

impl<M: EditMethod> EditSession<M> {
    /// Resolves the specification and factors the method's systems.
    pub fn new(
        mesh: &SurfaceMesh,
        spec: &EditSpec,
        options: M::Options,
    ) -> Result<Self, EditError> {
        let problem = EditProblem::new(mesh, spec)?;
        let t = Instant::now();
        let method = M::factor(&problem, &options)?;
        let stats = SessionStats {
            factorizations: 1,
            factor_ms: t.elapsed().as_secs_f64() * 1e3,
            ..Default::default()
        };
        Ok(Self {
            rest: mesh.positions().to_vec(),
            mesh: mesh.clone(),
            spec: spec.clone(),
            problem,
            options,
            method,
            stats,
        })
    }

    /// The resolved problem (local numbering, roles, handles).
    pub fn problem(&self) -> &EditProblem {
        &self.problem
    }

    /// Work counters.
    pub fn stats(&self) -> SessionStats {
        self.stats
    }

    /// The method state (for method-specific queries).
    pub fn method(&self) -> &M {
        &self.method
    }

    /// Mutable method state.
    pub fn method_mut(&mut self) -> &mut M {
        &mut self.method
    }

    /// The handle transforms given in the specification.
    pub fn spec_transforms(&self) -> Vec<Similarity> {
        self.problem.spec_transforms.clone()
    }

    /// Moves the handles (one transform per handle) and returns all mesh positions.
    pub fn move_handles(&mut self, transforms: &[Similarity]) -> Result<Vec<Vec3>, EditError> {
        let t = Instant::now();
        let local = self.method.solve(&self.problem, transforms)?;
        self.stats.solves += 1;
        self.stats.solve_ms = t.elapsed().as_secs_f64() * 1e3;
        Ok(self.problem.scatter(&self.rest, &local))
    }

    /// The edit of the specification's own transforms.
    pub fn solve_spec(&mut self) -> Result<Vec<Vec3>, EditError> {
        let t = self.spec_transforms();
        self.move_handles(&t)
    }

    /// Changes the specification. Refactors only when the ROI, anchors or handle sets (or
    /// their weights or gradient flags) change; new transforms alone cost nothing.
    pub fn set_spec(&mut self, spec: &EditSpec) -> Result<(), EditError> {
        let same_sets = spec.roi == self.spec.roi
            && spec.anchors == self.spec.anchors
            && spec.anchor_weight == self.spec.anchor_weight
            && spec.handles.len() == self.spec.handles.len()
            && spec.handles.iter().zip(&self.spec.handles).all(|(a, b)| {
                a.select == b.select && a.weight == b.weight && a.fix_gradient == b.fix_gradient
            });
        let problem = EditProblem::new(&self.mesh, spec)?;
        if !same_sets {
            let t = Instant::now();
            self.method = M::factor(&problem, &self.options)?;
            self.stats.factorizations += 1;
            self.stats.factor_ms = t.elapsed().as_secs_f64() * 1e3;
        }
        self.problem = problem;
        self.spec = spec.clone();
        Ok(())
    }
}
