//! The per-move part of Poisson editing ([`super::poisson`]), allocating only its result, in the
//! factor's own row order.
//!
//! Everything that does not depend on the handle transforms is laid out once per
//! factorisation. The local vertices are renumbered into *slots*: the free vertices in the
//! factor's row order ([`FixedSolver::solve_factor_rows`]), then the constrained ones in the
//! order of [`FixedSolver::known`]. The non-degenerate faces with a free vertex, with their
//! slots and area-weighted hat gradients, are stored in one array sorted by their smallest
//! slot. The
//! fill-reducing order is a nested dissection or minimum degree order, so neighbouring
//! vertices get nearby slots: the face pass reads and accumulates per-vertex buffers almost
//! sequentially, and the divergence of the free slots is already the triangular solves'
//! right-hand side (no gather, no scatter).
//!
//! Two face-map kernels, equal to round-off:
//! * [`Field::Quaternions`]: any per-vertex rotations and log-scales, [`face_map`] (the
//!   arithmetic of [`super::poisson::PoissonEditor::face_maps`]);
//! * [`Field::Axial`]: one transform handle, where a vertex of weight `λ` rotates about the
//!   handle's axis `a` by `λθ` and scales by `σ^λ` (free vertices: their propagated weight;
//!   handle vertices 1; fixed vertices 0). With `c_k, s_k` the cosine and sine of the
//!   half angles, a face's normalised quaternion sum is the rotation about `a` by `φ` with
//!   `sin φ = 2CS/(C² + S²)` and `1 − cos φ = 2S²/(C² + S²)` (`C = Σ c_k`, `S = Σ s_k`,
//!   signs aligned as in [`face_map`]), and `R = I + sin φ [a]× + (1 − cos φ) [a]×²`: with
//!   `[a]×` and `[a]×²` formed once per move, a face map costs two scalar-matrix products
//!   (no square root, no quaternion-to-matrix conversion). The per-face scalars are a pass
//!   of their own before the accumulation (each waits on a division; fused, the
//!   accumulation stalls behind it).
//!
//! Faces store two gradients (the third is minus their sum, the hat functions summing to
//! one), 64 bytes a face, and images of the third gradient are minus the sum of the
//! others'.

use nalgebra::UnitQuaternion;

use super::local::{hat_gradients, unit_normal};
use super::problem::{EditProblem, Role};
use super::similarity::{mat_vec, Mat3, Similarity};
use super::EditError;
use crate::geometry::Vec3;
use crate::solve::{FixedSolver, SolveError};

/// One face's precomputed part of the divergence: 64 bytes.
#[derive(Debug, Clone, Copy)]
struct FaceTerm {
    /// Slots of its vertices.
    slots: [u32; 3],
    /// The first two area-weighted hat gradients `|T| ∇B_k` ([`hat_gradients`]); the
    /// third is minus their sum (the hat functions sum to one).
    grads: [Vec3; 2],
}

impl FaceTerm {
    /// The three gradients.
    #[inline(always)]
    fn gradients(&self) -> [Vec3; 3] {
        let [g0, g1] = self.grads;
        [g0, g1, -(g0 + g1)]
    }
}

/// The rotation field of a move.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Field<'a> {
    /// A rotation and log-scale per local vertex (local numbering).
    Quaternions(&'a [(UnitQuaternion<f64>, f64)]),
    /// One handle's rotation and scale, spread by the per-vertex weights given to
    /// [`PoissonRhs::new`].
    Axial(&'a Similarity),
}

/// The precomputed layout and the reused buffers of a Poisson move.
#[derive(Debug, Clone)]
pub(crate) struct PoissonRhs {
    faces: Vec<FaceTerm>,
    /// Per local vertex: its slot.
    slot: Vec<usize>,
    /// Per slot: its local vertex.
    local: Vec<usize>,
    /// Number of free slots (the reduced system's size).
    n_free: usize,
    /// Per slot, for [`Field::Axial`]: the weight `λ` of the handle's transform.
    weight: Vec<f64>,
    /// Per slot: rotation and log-scale ([`Field::Quaternions`]).
    quats: Vec<(UnitQuaternion<f64>, f64)>,
    /// Per slot: the cosine and sine of half the angle about the axis and the log-scale
    /// ([`Field::Axial`]).
    vert: Vec<[f64; 3]>,
    /// Divergence per slot; its free part is the reduced right-hand side, then solution.
    b: Vec<[f64; 3]>,
    /// [`Field::Axial`]: per face `σ`, `σ sin φ`, `σ (1 − cos φ)`.
    scalars: Vec<[f64; 3]>,
}

fn index(i: usize) -> Result<u32, EditError> {
    u32::try_from(i).map_err(|_| EditError::Spec(format!("index {i} exceeds 32 bits")))
}

impl PoissonRhs {
    /// Lays out the faces of `problem` (degenerate faces are skipped, as in the plain
    /// path) for `solver`'s row order. `weight` gives, per local vertex, the weight of a
    /// single transform handle for [`Field::Axial`] (empty when that field is not used).
    pub(crate) fn new(
        problem: &EditProblem,
        solver: &FixedSolver,
        weight: &[f64],
    ) -> Result<Self, EditError> {
        let n = problem.len();
        let mut slot = solver.factor_rows();
        let n_free = solver.unknown().len();
        for (k, &l) in solver.known().iter().enumerate() {
            slot[l] = n_free + k;
        }
        let mut local = vec![0; n];
        for (l, &s) in slot.iter().enumerate() {
            if s >= n {
                return Err(EditError::Spec("vertex without a slot".into()));
            }
            local[s] = l;
        }
        let mut faces = Vec::with_capacity(problem.faces.len());
        let x = &problem.rest;
        for f in &problem.faces {
            let Some((normal, _)) = unit_normal(x[f[0]], x[f[1]], x[f[2]]) else {
                continue;
            };
            let s = f.map(|l| slot[l]);
            if s.iter().all(|&v| v >= n_free) {
                // Only constrained vertices: nothing reaches the reduced system.
                continue;
            }
            let g = hat_gradients(normal, f.map(|l| x[l]));
            let t = FaceTerm {
                slots: [index(s[0])?, index(s[1])?, index(s[2])?],
                grads: [g[0], g[1]],
            };
            faces.push(t);
        }
        faces.sort_by_key(|t| t.slots.iter().copied().min());
        Ok(Self {
            faces,
            n_free,
            weight: local
                .iter()
                .map(|&l| weight.get(l).copied().unwrap_or(0.0))
                .collect(),
            slot,
            local,
            quats: Vec::with_capacity(n),
            vert: vec![[1.0, 0.0, 0.0]; n],
            b: vec![[0.0; 3]; n],
            scalars: Vec::new(),
        })
    }

    /// Solves for the local positions with the rotation `field` and the handle
    /// `transforms`.
    pub(crate) fn solve(
        &mut self,
        problem: &EditProblem,
        solver: &FixedSolver,
        transforms: &[Similarity],
        field: Field<'_>,
    ) -> Result<Vec<Vec3>, EditError> {
        problem.check_transforms(transforms)?;
        if self.slot.len() != problem.len() {
            return Err(EditError::Spec("problem size changed".into()));
        }
        match field {
            Field::Quaternions(q) => {
                if q.len() != problem.len() {
                    return Err(EditError::Spec("vertex transform count mismatch".into()));
                }
                self.quats.clear();
                self.quats.extend(self.local.iter().map(|&l| q[l]));
                self.b.fill([0.0; 3]);
                for t in &self.faces {
                    let f = t.slots.map(|v| v as usize);
                    let m = face_map(&self.quats, f);
                    let grads = t.gradients();
                    for (&v, &g) in t.slots.iter().zip(&grads) {
                        let x = mat_vec(&m, g);
                        let r = &mut self.b[v as usize];
                        r[0] += x.x;
                        r[1] += x.y;
                        r[2] += x.z;
                    }
                }
            }
            Field::Axial(t) => self.assemble_axial(t),
        }
        // The constrained slots hold their targets.
        for (s, &l) in self.local.iter().enumerate().skip(self.n_free) {
            let x = match problem.role[l] {
                Role::Handle(h) => problem.handle_target(l, h, problem.rest[l], transforms),
                _ => problem.rest[l],
            };
            self.b[s] = [x.x, x.y, x.z];
        }
        let (free, known) = self.b.split_at_mut(self.n_free);
        solver
            .solve_factor_rows(free, known)
            .map_err(|e: SolveError| EditError::Solve(e))?;
        Ok(self
            .slot
            .iter()
            .map(|&s| {
                let x = self.b[s];
                Vec3::new(x[0], x[1], x[2])
            })
            .collect())
    }

    /// The [`Field::Axial`] divergence of `t` into the free slots of `b`.
    fn assemble_axial(&mut self, t: &Similarity) {
        let (axis, angle) = t
            .rotation
            .axis_angle()
            .map_or((nalgebra::Vector3::z_axis(), 0.0), |(a, t)| (a, t));
        let a = Vec3::new(axis.x, axis.y, axis.z);
        let log_s = t.scale.ln();
        for (v, &w) in self.vert.iter_mut().zip(&self.weight) {
            let (s, c) = (w * angle / 2.0).sin_cos();
            *v = [c, s, w * log_s];
        }
        // [a]× and [a]×²: every face map is σ(I + sin φ [a]× + (1 − cos φ)[a]×²).
        let k = Mat3::new(0.0, -a.z, a.y, a.z, 0.0, -a.x, -a.y, a.x, 0.0);
        let k2 = k * k;
        // Two passes: the face scalars first (short independent chains through a
        // division), then the accumulation; fused, every face waits for its division
        // (measured 25% more cycles).
        self.scalars.clear();
        self.scalars.extend(self.faces.iter().map(|t| {
            let (sigma, sin, one_minus_cos) = axial_face(t.slots.map(|v| &self.vert[v as usize]));
            [sigma, sigma * sin, sigma * one_minus_cos]
        }));
        self.b.fill([0.0; 3]);
        for (t, &[sigma, p, q]) in self.faces.iter().zip(&self.scalars) {
            let mut m = k * p + k2 * q;
            for d in 0..3 {
                m[(d, d)] += sigma;
            }
            let [g0, g1] = t.grads;
            let (m0, m1) = (mat_vec(&m, g0), mat_vec(&m, g1));
            // The third gradient is −(g0 + g1), so its image is −(m0 + m1).
            for (&v, x) in t.slots.iter().zip([m0, m1, -(m0 + m1)]) {
                let r = &mut self.b[v as usize];
                r[0] += x.x;
                r[1] += x.y;
                r[2] += x.z;
            }
        }
    }
}

/// Face `f`'s scale `σ`, `sin φ` and `1 − cos φ` of its rotation about the common axis
/// (see the module doc; [`face_map`] for one axis).
#[inline(always)]
fn axial_face(f: [&[f64; 3]; 3]) -> (f64, f64, f64) {
    let [c0, s0, e0] = *f[0];
    let (mut c, mut s, mut e) = (c0, s0, e0);
    for v in &f[1..] {
        let [cv, sv, ev] = **v;
        if c0 * cv + s0 * sv < 0.0 {
            c -= cv;
            s -= sv;
        } else {
            c += cv;
            s += sv;
        }
        e += ev;
    }
    let inv = 2.0 / (c * c + s * s);
    let sigma = if e == 0.0 { 1.0 } else { (e / 3.0).exp() };
    (sigma, c * s * inv, s * s * inv)
}

/// The face map `σ_T R(q_T)` of face `f` from per-vertex rotations and log-scales (see
/// [`super::poisson::PoissonEditor::face_maps`]).
pub(crate) fn face_map(vertex: &[(UnitQuaternion<f64>, f64)], f: [usize; 3]) -> Mat3 {
    let q0 = vertex[f[0]].0.into_inner();
    let mut q = q0;
    for &v in &f[1..] {
        let qv = vertex[v].0.into_inner();
        q += if q0.dot(&qv) < 0.0 { -qv } else { qv };
    }
    let r = UnitQuaternion::new_normalize(q)
        .to_rotation_matrix()
        .into_inner();
    let ls = vertex[f[0]].1 + vertex[f[1]].1 + vertex[f[2]].1;
    if ls == 0.0 {
        r
    } else {
        r * (ls / 3.0).exp()
    }
}
