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

use super::basis::{AffineBasis, AFFINE_PARAMETERS};
use super::implicit_systems::{first_system_order, FirstSystem, SecondSystem};
use super::local::{from_mat, gather};
use super::problem::{EditProblem, Role};
use super::session::EditMethod;
use super::similarity::{mat_vec, polar_rotation, to_na, Mat3, Similarity};
use super::system::{ms_since, FactorOrdering, FactoredQuadratic};
use super::EditError;
use crate::geometry::Vec3;
use crate::solve::{FixedSolver, SolveError, SubtreeThreads};

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
    /// Precompute the first system's response to every handle's affine parameters when
    /// factoring ([`AffineBasis`]), so a drag costs vector updates instead of a solve
    /// (transform handles only; a one-shot edit turns it off).
    pub drag_basis: bool,
    /// Where the first system's factor uses a second thread: by default its numeric
    /// factorisation; [`SubtreeThreads::FactorAndSolve`] also every drag's solve.
    pub threads: SubtreeThreads,
}

impl Default for ImplicitOptions {
    fn default() -> Self {
        Self {
            coherence_weight: 1.0,
            s_disp: 0.2,
            second_solve: true,
            scale_features: false,
            drag_basis: true,
            threads: SubtreeThreads::Factor,
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
    /// The first system's drag basis, if precomputed.
    basis: Option<AffineBasis>,
    /// Time to precompute it, ms.
    basis_ms: f64,
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
    /// while a handle is dragged. With a drag basis ([`ImplicitOptions::drag_basis`]) this is
    /// 12 vector updates per handle, otherwise one solve.
    pub fn solve_drag(
        &mut self,
        problem: &EditProblem,
        transforms: &[Similarity],
    ) -> Result<Vec<Vec3>, EditError> {
        problem.check_transforms(transforms)?;
        let xd = match &self.basis {
            Some(basis) => basis.combine(problem, transforms)?,
            None => self.first_solution(problem, transforms)?,
        };
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

    /// The first system's solution on the displaced geometry, by one solve.
    fn first_solution(
        &self,
        problem: &EditProblem,
        transforms: &[Similarity],
    ) -> Result<Vec<Vec3>, EditError> {
        let n_roi = problem.n_roi;
        // Targets on the displaced geometry.
        let targets: Vec<Vec3> = (0..problem.len())
            .map(|l| match problem.role[l] {
                Role::Handle(h) => problem.handle_target(l, h, self.displaced[l], transforms),
                _ => self.displaced[l],
            })
            .collect();
        let known = gather(&targets, self.first.known());
        // Fixed gradients are the only right-hand sides besides the targets; without them
        // both terms are zero (two dense n × 3 and 3n × 3 blocks not built per drag).
        if !problem.handles.iter().any(|h| h.fix_gradient) {
            let x = self.first.solve(&[None, None], known.as_ref())?;
            return Ok(from_mat(x.as_ref()));
        }
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
        let x = self
            .first
            .solve(&[Some(b_l.as_ref()), Some(m_c.as_ref())], known.as_ref())?;
        Ok(from_mat(x.as_ref()))
    }

    /// Precomputes the first system's response to the 12 affine parameters of every handle
    /// (see [`AffineBasis`]) by one solve with 12 right-hand sides per handle; afterwards
    /// [`Self::solve_drag`] uses it. Parameter `(A − I)_{ab}` or `τ_a` moves only column
    /// `a` of the targets, of the fixed gradients' `w δᵢ` and of `−w`. Fails for handles
    /// given by positions.
    pub fn precompute_drag_basis(&mut self, problem: &EditProblem) -> Result<(), EditError> {
        let clock = std::time::Instant::now();
        let basis = self.drag_basis(problem)?;
        self.basis = Some(basis);
        self.basis_ms = ms_since(clock);
        Ok(())
    }

    /// Time [`Self::precompute_drag_basis`] took, ms (0 without a basis).
    pub fn drag_basis_ms(&self) -> f64 {
        self.basis_ms
    }

    fn drag_basis(&self, problem: &EditProblem) -> Result<AffineBasis, EditError> {
        AffineBasis::check_handles(problem)?;
        let n_roi = problem.n_roi;
        let identity = vec![Similarity::identity(); problem.handles.len()];
        let base = self.first_solution(problem, &identity)?;
        let cols = AFFINE_PARAMETERS * problem.handles.len();
        let col = |h: usize, k: usize| AFFINE_PARAMETERS * h + k;
        let known = self.first.known();
        let mut dk = Mat::<f64>::zeros(known.len(), cols);
        for (r, &l) in known.iter().enumerate() {
            if let Role::Handle(h) = problem.role[l] {
                let p = problem.handle_target(l, h, self.displaced[l], &identity);
                for k in 0..AFFINE_PARAMETERS {
                    dk[(r, col(h, k))] = AffineBasis::target_delta(k, p)[AffineBasis::component(k)];
                }
            }
        }
        let mut b_l = Mat::<f64>::zeros(n_roi, cols);
        let mut m_c = Mat::<f64>::zeros(3 * n_roi, cols);
        for i in 0..n_roi {
            if let Role::Handle(h) = problem.role[i] {
                if problem.handles[h].fix_gradient {
                    for k in 0..9 {
                        let b = k % 3;
                        b_l[(i, col(h, k))] = self.delta[i][b];
                        m_c[(3 * i + b, col(h, k))] = -1.0;
                    }
                }
            }
        }
        let x = self
            .first
            .solve_response(&[Some(b_l.as_ref()), Some(m_c.as_ref())], dk.as_ref())?;
        let responses = (0..problem.handles.len())
            .map(|h| {
                (0..AFFINE_PARAMETERS)
                    .map(|k| {
                        (0..problem.len())
                            .map(|l| {
                                let mut v = [0.0; 3];
                                v[AffineBasis::component(k)] = x[(l, col(h, k))];
                                Vec3::from_array(v)
                            })
                            .collect()
                    })
                    .collect()
            })
            .collect();
        Ok(AffineBasis::new(base, responses))
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
        check_singular(problem)?;
        // The first system's fill-reducing order needs only the mesh graph, and the second
        // system is independent of the first: another thread computes the order while
        // this one builds the first system, then builds the second.
        let (send, receive) = std::sync::mpsc::channel();
        let (first, second) = std::thread::scope(|scope| {
            let second = scope.spawn(move || {
                // A closed receiver means the first system failed; its error is reported.
                let _ = send.send(first_system_order(problem));
                SecondSystem::build(problem)
            });
            let order = FactorOrdering::Given(Box::new(move || {
                receive.recv().map_err(|_| {
                    SolveError::Dimension("the ordering thread stopped without an order".into())
                })?
            }));
            let first = FirstSystem::build(problem, options, order);
            let second = second
                .join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
            (first, second)
        });
        let (first, second) = (first?, second?);
        let mut editor = Self {
            first: first.system,
            second: second.solver,
            first_ms: first.ms,
            second_ms: second.ms,
            basis: None,
            basis_ms: 0.0,
            displaced: first.displaced,
            stencil: first.stencil,
            q: first.q,
            delta: first.delta,
            kv: second.kv,
            n_degenerate: first.n_degenerate,
            n_still_degenerate: first.n_still_degenerate,
            mu: first.mu,
            options: *options,
            last_first: None,
        };
        if options.drag_basis && problem.handles.iter().all(|h| h.shape.is_none()) {
            editor.precompute_drag_basis(problem)?;
        }
        Ok(editor)
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
