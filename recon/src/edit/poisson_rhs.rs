//! The per-move part of Poisson editing ([`super::poisson`]), allocating only its result, in the
//! factor's own row order.
//!
//! Everything that does not depend on the handle transforms is laid out once per
//! factorisation. The local vertices are renumbered into *slots*: the free vertices in the
//! factor's row order ([`FixedSolver::solve_factor_rows`]), then the constrained ones in the
//! order of [`FixedSolver::known`]. The non-degenerate faces with a free vertex are sorted
//! by their smallest slot and stored as their slots and, in blocks of [`BLOCK`] faces,
//! their area-weighted hat gradients component by component. The
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
//!   (no square root, no quaternion-to-matrix conversion). This pass runs under pulp's
//!   run-time choice of instruction set, a block at a time: the vertex values are
//!   gathered by component, the face scalars (through a division each) and the images of
//!   the gradients are computed across the block's faces in SIMD lanes, and only the
//!   scatter into the divergence goes face by face (see [`axial_faces`]).
//!
//! Faces store two gradients (the third is minus their sum, the hat functions summing to
//! one), 48 bytes a face beside 12 of slots, and images of the third gradient are minus
//! the sum of the others'.

use nalgebra::UnitQuaternion;

use super::local::{hat_gradients, unit_normal};
use super::problem::{EditProblem, Role};
use super::similarity::{mat_vec, Mat3, Similarity};
use super::EditError;
use crate::geometry::Vec3;
use crate::solve::{FixedSolver, SolveError};

/// Faces per block: a block's gradients are stored component by component (so the
/// axial pass computes a block's face maps in SIMD lanes), and its intermediate values stay
/// in L1. Measured on the 100k-vertex benchmark ROI, the face pass took 3.9, 3.7, 4.5 and
/// 5.2 ms with blocks of 4, 16, 32 and 64 faces.
const BLOCK: usize = 16;

/// The first two area-weighted hat gradients `|T| ∇B_k` ([`hat_gradients`]) of a block of
/// faces, by component: `g[3k + c][j]` is component `c` of gradient `k` of face `j`. The
/// third gradient is minus their sum (the hat functions sum to one). Padding faces of the
/// last block are zero.
#[derive(Debug, Clone)]
struct GradientBlock {
    g: [[f64; BLOCK]; 6],
}

impl GradientBlock {
    /// The three gradients of face `j`.
    #[inline(always)]
    fn gradients(&self, j: usize) -> [Vec3; 3] {
        let g = &self.g;
        let g0 = Vec3::new(g[0][j], g[1][j], g[2][j]);
        let g1 = Vec3::new(g[3][j], g[4][j], g[5][j]);
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
    /// Per face: the slots of its vertices.
    slots: Vec<[u32; 3]>,
    /// Per block of [`BLOCK`] faces: their gradients.
    grads: Vec<GradientBlock>,
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
    /// Per slot: the cosine and sine of half the angle about the axis and the cube root
    /// of the scale, `σ^{λ/3}` ([`Field::Axial`]).
    vert: Vec<[f64; 3]>,
    /// Divergence per slot; its free part is the reduced right-hand side, then solution.
    b: Vec<[f64; 3]>,
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
        let mut faces: Vec<([u32; 3], [Vec3; 2])> = Vec::with_capacity(problem.faces.len());
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
            faces.push(([index(s[0])?, index(s[1])?, index(s[2])?], [g[0], g[1]]));
        }
        faces.sort_by_key(|(s, _)| s.iter().copied().min());
        let slots = faces.iter().map(|(s, _)| *s).collect();
        let grads = faces
            .chunks(BLOCK)
            .map(|chunk| {
                let mut g = [[0.0; BLOCK]; 6];
                for (j, (_, [g0, g1])) in chunk.iter().enumerate() {
                    for c in 0..3 {
                        g[c][j] = g0[c];
                        g[3 + c][j] = g1[c];
                    }
                }
                GradientBlock { g }
            })
            .collect();
        Ok(Self {
            slots,
            grads,
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
                for (f, slots) in self.slots.iter().enumerate() {
                    let m = face_map(&self.quats, slots.map(|v| v as usize));
                    let g = self.grads[f / BLOCK].gradients(f % BLOCK);
                    for (&v, g) in slots.iter().zip(g) {
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
        self.b.fill([0.0; 3]);
        pulp::Arch::new().dispatch(AxialMove {
            a: [axis.x, axis.y, axis.z],
            half_angle: angle / 2.0,
            log_s: t.scale.ln(),
            weight: &self.weight,
            slots: &self.slots,
            grads: &self.grads,
            vert: &mut self.vert,
            b: &mut self.b,
        });
    }
}

/// A [`Field::Axial`] move, run by pulp's dispatch so that it is compiled for the best
/// instruction set the processor has (a closure would not be inlined into it).
struct AxialMove<'a> {
    /// The rotation axis, its half angle and the log-scale of the handle's transform.
    a: [f64; 3],
    half_angle: f64,
    log_s: f64,
    weight: &'a [f64],
    slots: &'a [[u32; 3]],
    grads: &'a [GradientBlock],
    vert: &'a mut [[f64; 3]],
    b: &'a mut [[f64; 3]],
}

impl pulp::WithSimd for AxialMove<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        vertex_values(self.half_angle, self.log_s, self.weight, self.vert);
        axial_faces(self.a, self.slots, self.grads, self.vert, self.b);
    }
}

/// Per slot of weight `λ`: the cosine and sine of `λ·half_angle` and `σ^{λ/3}`. The
/// sine and cosine are branch-free Taylor polynomials (exact to round-off for arguments up
/// to π/2, which a weight in [0, 1] and a rotation angle in [0, π] keep to; 0.5 ms for 100k
/// slots where the library took 0.9 ms), with the library's functions for any argument beyond.
#[inline(always)]
fn vertex_values(half_angle: f64, log_s: f64, weight: &[f64], vert: &mut [[f64; 3]]) {
    for (v, &w) in vert.iter_mut().zip(weight) {
        let (s, c) = sin_cos_to_half_pi(w * half_angle);
        *v = [c, s, 1.0];
    }
    // Arguments beyond the polynomials' range (not NaN: the library gives NaN alike).
    let beyond = |x: f64| x.abs() > std::f64::consts::FRAC_PI_2;
    let max_weight = weight.iter().fold(0.0_f64, |m, w| m.max(w.abs()));
    if beyond(max_weight * half_angle) {
        for (v, &w) in vert.iter_mut().zip(weight) {
            let x = w * half_angle;
            if beyond(x) {
                let (s, c) = x.sin_cos();
                v[0] = c;
                v[1] = s;
            }
        }
    }
    if log_s != 0.0 {
        for (v, &w) in vert.iter_mut().zip(weight) {
            v[2] = (w * log_s / 3.0).exp();
        }
    }
}

/// `(sin x, cos x)` for `|x| ≤ π/2` from their Taylor series through `x²¹` and `x²⁰`: the
/// remainders are below `(π/2)²³/23! ≈ 1.3e-18` and `(π/2)²²/22! ≈ 1.8e-17`. Branch-free,
/// so that it vectorises.
#[inline(always)]
fn sin_cos_to_half_pi(x: f64) -> (f64, f64) {
    // sin x = x (1 − x²/(2·3) (1 − x²/(4·5) (1 − …))), cos x = 1 − x²/(1·2) (1 − x²/(3·4) (…)):
    // the factors 1/(2n(2n + 1)) and 1/((2n − 1)2n), n = 1..10.
    const SIN: [f64; 10] = {
        let mut f = [0.0; 10];
        let mut n = 0;
        while n < 10 {
            let k = 2.0 * (n + 1) as f64;
            f[n] = 1.0 / (k * (k + 1.0));
            n += 1;
        }
        f
    };
    const COS: [f64; 10] = {
        let mut f = [0.0; 10];
        let mut n = 0;
        while n < 10 {
            let k = 2.0 * (n + 1) as f64;
            f[n] = 1.0 / ((k - 1.0) * k);
            n += 1;
        }
        f
    };
    let x2 = x * x;
    let (mut s, mut c) = (1.0, 1.0);
    for n in (0..10).rev() {
        s = 1.0 - x2 * SIN[n] * s;
        c = 1.0 - x2 * COS[n] * c;
    }
    (x * s, c)
}

/// The [`Field::Axial`] face pass: every face's map `σ(I + sin φ [a]× + (1 − cos φ)[a]×²)`
/// applied to its gradients and accumulated into `b`, a block of faces at a time: the
/// vertex values are gathered by component, the face scalars and the images of the
/// gradients are computed in loops over the block (which the compiler vectorises across
/// faces, the divisions included), and only the gather and the scatter into `b` go face by
/// face. On the 100k-vertex benchmark ROI this pass takes 3.7 ms, where face by face (one
/// array of faces, a scalar pass, then the accumulation) took 7.6 ms. Everything here is
/// inlined into the caller's SIMD dispatch.
#[inline(always)]
fn axial_faces(
    a: [f64; 3],
    slots: &[[u32; 3]],
    grads: &[GradientBlock],
    vert: &[[f64; 3]],
    b: &mut [[f64; 3]],
) {
    // [a]× and [a]×² (= a aᵀ − I for a unit axis), row-major.
    let k = [0.0, -a[2], a[1], a[2], 0.0, -a[0], -a[1], a[0], 0.0];
    let mut k2 = [0.0; 9];
    for r in 0..3 {
        for c in 0..3 {
            k2[3 * r + c] = (0..3).map(|j| k[3 * r + j] * k[3 * j + c]).sum();
        }
    }
    // Per corner and component: the vertex values (cosine, sine, scale root), by face.
    // Padding faces get the identity's values (no division by zero).
    let mut v = [[[0.0; BLOCK]; 3]; 3];
    let mut image = [[0.0; BLOCK]; 6];
    for (slots, block) in slots.chunks(BLOCK).zip(grads) {
        for corner in &mut v {
            corner[0].fill(1.0);
            corner[1].fill(0.0);
            corner[2].fill(1.0);
        }
        for (j, f) in slots.iter().enumerate() {
            for (corner, &s) in v.iter_mut().zip(f) {
                let [c, sn, r] = vert[s as usize];
                corner[0][j] = c;
                corner[1][j] = sn;
                corner[2][j] = r;
            }
        }
        let g = &block.g;
        for j in 0..BLOCK {
            let (sigma, sin, one_minus_cos) =
                axial_face([0, 1, 2].map(|k| [v[k][0][j], v[k][1][j], v[k][2][j]]));
            let (p, q) = (sigma * sin, sigma * one_minus_cos);
            for r in 0..3 {
                let m = [0, 1, 2].map(|c| {
                    let e = 3 * r + c;
                    let diagonal = if r == c { sigma } else { 0.0 };
                    k[e] * p + k2[e] * q + diagonal
                });
                image[r][j] = m[0] * g[0][j] + m[1] * g[1][j] + m[2] * g[2][j];
                image[3 + r][j] = m[0] * g[3][j] + m[1] * g[4][j] + m[2] * g[5][j];
            }
        }
        // The third gradient is −(g0 + g1), so its image is −(m0 + m1).
        for (j, f) in slots.iter().enumerate() {
            let [v0, v1, v2] = *f;
            for c in 0..3 {
                let (m0, m1) = (image[c][j], image[3 + c][j]);
                b[v0 as usize][c] += m0;
                b[v1 as usize][c] += m1;
                b[v2 as usize][c] -= m0 + m1;
            }
        }
    }
}

/// Face `f`'s scale `σ`, `sin φ` and `1 − cos φ` of its rotation about the common axis
/// from its corners' cosine, sine and scale root (see the module doc; [`face_map`] for one
/// axis); branch-free, so that it vectorises across faces.
#[inline(always)]
fn axial_face(f: [[f64; 3]; 3]) -> (f64, f64, f64) {
    let [c0, s0, r0] = f[0];
    let (mut c, mut s, mut sigma) = (c0, s0, r0);
    for &[cv, sv, rv] in &f[1..] {
        let sign = if c0 * cv + s0 * sv < 0.0 { -1.0 } else { 1.0 };
        c += sign * cv;
        s += sign * sv;
        sigma *= rv;
    }
    let inv = 2.0 / (c * c + s * s);
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

#[cfg(test)]
mod tests {
    use super::{sin_cos_to_half_pi, vertex_values};
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn the_polynomials_match_the_library_to_two_ulps_up_to_half_pi() {
        let mut worst = 0.0f64;
        for i in 0..=20_000 {
            let x = -FRAC_PI_2 + 2.0 * FRAC_PI_2 * i as f64 / 20_000.0;
            let (s, c) = sin_cos_to_half_pi(x);
            worst = worst.max((s - x.sin()).abs()).max((c - x.cos()).abs());
        }
        assert!(worst <= 2.0 * f64::EPSILON, "{worst:e}");
    }

    #[test]
    fn vertex_values_beyond_half_pi_and_with_a_scale_use_the_library() {
        // A weight above 1 takes the argument past the polynomials' range.
        let weight = [0.0, 0.5, 1.0, 1.5, 2.0];
        let (half_angle, log_s) = (1.4, 0.3_f64);
        let mut vert = vec![[0.0; 3]; weight.len()];
        vertex_values(half_angle, log_s, &weight, &mut vert);
        for (v, &w) in vert.iter().zip(&weight) {
            let x = w * half_angle;
            assert!((v[0] - x.cos()).abs() <= 2.0 * f64::EPSILON, "{w}");
            assert!((v[1] - x.sin()).abs() <= 2.0 * f64::EPSILON, "{w}");
            assert!(
                (v[2] - (w * log_s / 3.0).exp()).abs() <= 4.0 * f64::EPSILON,
                "{w}"
            );
        }
    }
}
