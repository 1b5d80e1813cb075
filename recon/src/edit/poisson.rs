//! Poisson gradient-field editing (Yu, Zhou, Xu, Shi, Bao, Guo, Shum 2004, *Mesh Editing
//! with Poisson-Based Gradient Field Manipulation*, §3).
//!
//! Each triangle's coordinate gradients are transformed by a per-face linear map `M_T`
//! and the mesh is re-stitched by the Poisson equation `K x = Σ_T M_T |T|∇B_T` over the
//! cotangent stiffness `K`, with hard (Dirichlet) constraints at the ring, anchors and
//! handles (§3.1–3.2; the right-hand side `b_i = Σ_{T∋i} M_T ½ n̂_T × e_i` is the
//! closed form of the divergence of the transformed gradients).
//!
//! Transform propagation (§3.3): every boundary condition (the fixed set with the identity,
//! each handle with its rotation `q_h` and scale `σ_h`) is weighted at a free vertex by the
//! inverse of its distance to that vertex (the paper's "linear" scheme); rotations are
//! averaged by the sequential slerp of footnote 3 (for one handle: the slerp from the
//! identity), scales by the weighted geometric mean. A face takes the chordal mean of its
//! three vertices' quaternions and the geometric mean of their scales. Distances are shortest edge paths
//! over the ROI (a documented substitute for the paper's fast-marching distance; both are
//! only used as weights). A single handle rotated by θ therefore rotates a free vertex by
//! `θ·d₀/(d₀ + d_h)`.
//!
//! Boundary-condition editing with local frames (§3.3, §4.1): a handle given as explicit
//! positions has one frame change per vertex, its fitted similarity times the vertex's local
//! frame change ([`super::frames`]). Within such a handle a free vertex takes the value of its
//! nearest handle vertex (the paper's *Nearest* scheme, by the same edge-path distance), and
//! that value is weighted against the other boundary conditions exactly as a transform
//! handle's. A handle given as a similarity of its rest positions therefore edits like the
//! equivalent transform, to round-off. (The paper's smoother *Linear* weighting within a
//! boundary condition would need one distance field per handle vertex.)
//!
//! A move ([`EditMethod::solve`]) runs the same arithmetic, allocating only its result, in the
//! factor's row order, with the face maps of a single transform handle in closed form
//! (`poisson_rhs.rs`); [`PoissonEditor::vertex_transforms`],
//! [`PoissonEditor::face_maps`] and [`PoissonEditor::solve_with_face_maps`] are the plain
//! steps, equal to it to round-off.

use faer::Mat;
use nalgebra::{UnitQuaternion, Vector3};

use super::local::{
    cotan_stiffness, face_gradients, from_mat, gather, graph_distance, graph_distance_nearest,
};
use super::poisson_rhs::{face_map, Field, PoissonRhs};
use super::problem::{EditProblem, Role};
use super::session::EditMethod;
use super::similarity::{mat_vec, weighted_average, Mat3, Similarity};
use super::EditError;
use crate::geometry::Vec3;
use crate::solve::{CholeskyOptions, FixedSolver};

/// Options of [`PoissonEditor`].
#[derive(Debug, Clone, Copy)]
pub struct PoissonOptions {
    /// Propagate handle rotations and scales to the faces (false: "naive Poisson", which
    /// keeps the rest gradients and only moves the constraints).
    pub propagate: bool,
}

impl Default for PoissonOptions {
    fn default() -> Self {
        Self { propagate: true }
    }
}

/// Factored Poisson editing of one ROI.
#[derive(Debug, Clone)]
pub struct PoissonEditor {
    solver: FixedSolver,
    /// Area-weighted hat gradients of the rest faces.
    grads: Vec<Option<(f64, [Vec3; 3])>>,
    /// Per local vertex, `1 + handles` consecutive entries: normalised weights of
    /// [fixed, handle 0, handle 1, ...].
    weights: Vec<f64>,
    /// Per handle, per local vertex: the position in the handle of its nearest handle vertex.
    nearest: Vec<Vec<usize>>,
    options: PoissonOptions,
    /// The per-move layout and buffers.
    rhs: PoissonRhs,
    /// Reused buffer of [`Self::vertex_transforms`].
    vertex: Vec<(UnitQuaternion<f64>, f64)>,
}

/// Whether a move's rotation field is [`Field::Axial`]: one handle, given as a transform.
fn axial(problem: &EditProblem) -> bool {
    matches!(problem.handles.as_slice(), [h] if h.shape.is_none())
}

impl PoissonEditor {
    /// Solves with an explicit linear map per local face and explicit positions of every
    /// constrained vertex (`targets` holds one position per local vertex; free entries are
    /// ignored).
    pub fn solve_with_face_maps(
        &self,
        problem: &EditProblem,
        face_maps: &[Mat3],
        targets: &[Vec3],
    ) -> Result<Vec<Vec3>, EditError> {
        if face_maps.len() != problem.faces.len() || targets.len() != problem.len() {
            return Err(EditError::Spec("face map or target count mismatch".into()));
        }
        let mut b = Mat::<f64>::zeros(problem.len(), 3);
        for ((f, g), m) in problem.faces.iter().zip(&self.grads).zip(face_maps) {
            let Some((_, g)) = g else { continue };
            for k in 0..3 {
                let v = mat_vec(m, g[k]);
                for c in 0..3 {
                    b[(f[k], c)] += v[c];
                }
            }
        }
        let known = gather(targets, self.solver.known());
        let x = self.solver.solve(b.as_ref(), known.as_ref())?;
        Ok(from_mat(x.as_ref()))
    }

    /// The per-vertex rotation and log-scale propagated from the handle transforms (and,
    /// for handles given as positions, their per-vertex local frames).
    pub fn vertex_transforms(
        &self,
        problem: &EditProblem,
        transforms: &[Similarity],
    ) -> Vec<(UnitQuaternion<f64>, f64)> {
        let mut out = Vec::with_capacity(problem.len());
        self.vertex_transforms_into(problem, transforms, &mut out);
        out
    }

    /// [`Self::vertex_transforms`] into a reused buffer.
    fn vertex_transforms_into(
        &self,
        problem: &EditProblem,
        transforms: &[Similarity],
        out: &mut Vec<(UnitQuaternion<f64>, f64)>,
    ) {
        // The value of handle h seen from local vertex l.
        let value = |h: usize, l: usize| -> (UnitQuaternion<f64>, f64) {
            let (q, ls) = (transforms[h].rotation, transforms[h].scale.ln());
            let frame = problem.handles[h]
                .shape
                .as_ref()
                .zip(self.nearest.get(h).and_then(|n| n.get(l)))
                .and_then(|(s, &k)| s.frames.get(k));
            match frame {
                Some(&(dq, dls)) => (q * dq, ls + dls),
                None => (q, ls),
            }
        };
        // One handle: slerp(1, q_h; λ) is the rotation about q_h's axis by λ·θ_h.
        let single = (transforms.len() == 1).then(|| {
            let (axis, angle) = transforms[0]
                .rotation
                .axis_angle()
                .map_or((Vector3::z_axis(), 0.0), |(a, t)| (a, t));
            (axis, angle, transforms[0].scale.ln())
        });
        let per_vertex = problem.handles.first().is_some_and(|h| h.shape.is_some());
        let stride = 1 + problem.handles.len();
        out.clear();
        out.extend((0..problem.len()).map(|l| match problem.role[l] {
            Role::Handle(h) => value(h, l),
            Role::Ring | Role::Anchor => (UnitQuaternion::identity(), 0.0),
            Role::Free if !self.options.propagate => (UnitQuaternion::identity(), 0.0),
            Role::Free => {
                let w = &self.weights[l * stride..(l + 1) * stride];
                if let Some((axis, angle, log_s)) = single {
                    let (axis, angle, log_s) = if per_vertex {
                        let (q, ls) = value(0, l);
                        let (a, t) = q.axis_angle().map_or((Vector3::z_axis(), 0.0), |x| x);
                        (a, t, ls)
                    } else {
                        (axis, angle, log_s)
                    };
                    return (
                        UnitQuaternion::from_axis_angle(&axis, w[1] * angle),
                        w[1] * log_s,
                    );
                }
                let mut items = Vec::with_capacity(w.len());
                items.push((UnitQuaternion::identity(), w[0]));
                let mut log_s = 0.0;
                for h in 0..transforms.len() {
                    let (q, ls) = value(h, l);
                    items.push((q, w[h + 1]));
                    log_s += w[h + 1] * ls;
                }
                (weighted_average(&items), log_s)
            }
        }));
    }

    /// Per-face maps `σ_T R(q_T)` from per-vertex rotations and log-scales: `q_T` is the
    /// normalised, hemisphere-aligned sum of the three vertex quaternions (the chordal
    /// mean, equal to the sequential slerp average to second order in their spread and
    /// exact when they agree), `σ_T` their geometric mean.
    pub fn face_maps(problem: &EditProblem, vertex: &[(UnitQuaternion<f64>, f64)]) -> Vec<Mat3> {
        problem.faces.iter().map(|&f| face_map(vertex, f)).collect()
    }
}

impl EditMethod for PoissonEditor {
    type Options = PoissonOptions;

    fn factor(problem: &EditProblem, options: &PoissonOptions) -> Result<Self, EditError> {
        let k = cotan_stiffness(problem)?;
        let solver = FixedSolver::precompute(
            k.as_ref(),
            &problem.constrained(),
            CholeskyOptions::default(),
        )?;
        let grads = face_gradients(problem, &problem.rest);
        let fixed: Vec<usize> = (0..problem.len())
            .filter(|&l| matches!(problem.role[l], Role::Ring | Role::Anchor))
            .collect();
        let mut dists = vec![graph_distance(problem, &fixed)];
        let mut nearest = Vec::with_capacity(problem.handles.len());
        for h in &problem.handles {
            let (d, near) = graph_distance_nearest(problem, &h.vertices);
            dists.push(d);
            nearest.push(near);
        }
        let mut weights = Vec::with_capacity(problem.len() * dists.len());
        for l in 0..problem.len() {
            let raw = dists
                .iter()
                .map(|d| if d[l] > 0.0 { 1.0 / d[l] } else { 0.0 });
            let s: f64 = raw.clone().sum();
            if s > 0.0 && s.is_finite() {
                weights.extend(raw.map(|w| w / s));
            } else {
                weights.extend(raw.map(|_| 0.0));
            }
        }
        // One transform handle: every vertex rotates about its axis, by its weight.
        let axial_weight: Vec<f64> = if axial(problem) {
            (0..problem.len())
                .map(|l| match problem.role[l] {
                    Role::Handle(_) => 1.0,
                    Role::Free if options.propagate => weights[2 * l + 1],
                    _ => 0.0,
                })
                .collect()
        } else {
            Vec::new()
        };
        let rhs = PoissonRhs::new(problem, &solver, &axial_weight)?;
        Ok(Self {
            solver,
            grads,
            weights,
            nearest,
            options: *options,
            rhs,
            vertex: Vec::new(),
        })
    }

    fn solve(
        &mut self,
        problem: &EditProblem,
        transforms: &[Similarity],
    ) -> Result<Vec<Vec3>, EditError> {
        problem.check_transforms(transforms)?;
        if let [t] = transforms {
            if axial(problem) {
                return self
                    .rhs
                    .solve(problem, &self.solver, transforms, Field::Axial(t));
            }
        }
        let mut vertex = std::mem::take(&mut self.vertex);
        self.vertex_transforms_into(problem, transforms, &mut vertex);
        let x = self.rhs.solve(
            problem,
            &self.solver,
            transforms,
            Field::Quaternions(&vertex),
        );
        self.vertex = vertex;
        x
    }

    fn factor_len(&self) -> usize {
        self.solver.factor_len()
    }
}
