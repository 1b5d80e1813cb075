//! The cotangent Laplacian of a polygon (quad) mesh by a symmetric local triangulation: each quad is split
//! along both of its diagonals and the two triangulations are averaged (weight ½ each), so the operator
//! does not depend on which diagonal an arbitrary triangulation would pick (FIRES thesis §6.4: "a local
//! triangulation built around each vertex"; the thesis does not say which, this is the symmetric choice).
//! Where one split has a degenerate triangle (three nearly collinear corners) only the other is used.
//! Triangles are used as they are; larger polygons are fanned around their first vertex.
//!
//! Conventions (as in [`crate::operators`]): `C_ij = ½(cot α + cot β)` summed over the triangles sharing
//! the pair, `C_ii = −Σ_j C_ij` (symmetric, negative semidefinite); the vertex areas are barycentric
//! (a third of each triangle's area, with the same ½ weights); `L = M⁻¹C ≈ Δ`. Negative weights are kept
//! for linear precision (a planar mesh has `L X = 0` at every interior vertex); callers that need an
//! M-matrix clamp them.

use faer::sparse::SymbolicSparseColMat;

use crate::geometry::{cot_of_angle_between, triangle_area, Vec3};
use crate::mesh::SurfaceMesh;
use crate::solve::{sparse_from_triplets, SolveError, SparseMatrix};

/// The pair weights and vertex areas of the averaged triangulation.
#[derive(Clone, Debug)]
pub struct QuadCotan {
    /// `(i, j, ½cot)` contributions, `i ≠ j`, one per triangle side (a pair may repeat: sum them).
    pub pairs: Vec<(usize, usize, f64)>,
    /// Barycentric vertex areas.
    pub area: Vec<f64>,
}

impl QuadCotan {
    /// The weights of `mesh`'s faces at the positions `x` (one per vertex).
    pub fn new(mesh: &SurfaceMesh, x: &[Vec3]) -> Self {
        let mut pairs = Vec::with_capacity(mesh.n_faces() * 12);
        let mut area = vec![0.0; mesh.vertices_size()];
        let mut add = |[a, b, c]: [usize; 3], [ca, cb, cc]: [f64; 3], w: f64| {
            pairs.extend([
                (b, c, 0.5 * w * ca),
                (c, a, 0.5 * w * cb),
                (a, b, 0.5 * w * cc),
            ]);
            let t = w * triangle_area(x[a], x[b], x[c]) / 3.0;
            area[a] += t;
            area[b] += t;
            area[c] += t;
        };
        let mut vs = Vec::with_capacity(8);
        for f in mesh.faces() {
            vs.clear();
            vs.extend(mesh.face_vertices(f).map(|v| v.idx()));
            match vs.len() {
                3 => {
                    let t = [vs[0], vs[1], vs[2]];
                    add(t, corner_cots(x, t), 1.0);
                }
                4 => {
                    let [a, b, c, d] = [vs[0], vs[1], vs[2], vs[3]];
                    // The two diagonal splits, `a c` and `b d`.
                    let split = [[[a, b, c], [a, c, d]], [[a, b, d], [b, c, d]]];
                    let cots = split.map(|s| s.map(|t| corner_cots(x, t)));
                    let w = split_weights(&cots);
                    for ((s, c), w) in split.into_iter().zip(cots).zip(w) {
                        for (t, ct) in s.into_iter().zip(c) {
                            add(t, ct, w);
                        }
                    }
                }
                n => {
                    for k in 1..n - 1 {
                        let t = [vs[0], vs[k], vs[k + 1]];
                        add(t, corner_cots(x, t), 1.0);
                    }
                }
            }
        }
        QuadCotan { pairs, area }
    }

    /// Triplets of `Σ wᵢⱼ·k(i, j)` as a Laplacian-like matrix (off-diagonal `w·k`, diagonal minus the row
    /// sum), with `k` a per-pair factor and negative products clamped to 0 when `clamp`. The triplet list
    /// has the same length and order for the same mesh, so the sparsity pattern never changes.
    pub fn triplets(
        &self,
        k: impl Fn(usize, usize) -> f64,
        clamp: bool,
    ) -> Vec<(usize, usize, f64)> {
        let mut t = Vec::with_capacity(self.pairs.len() * 4);
        for &(i, j, w) in &self.pairs {
            let mut v = w * k(i, j);
            if clamp {
                v = v.max(0.0);
            }
            t.extend([(i, j, v), (j, i, v), (i, i, -v), (j, j, -v)]);
        }
        t
    }
}

/// Largest cotangent magnitude of a sound triangle corner (an angle of 0.057° or 179.943°); past it the
/// triangle is degenerate for the operator (its weights reach 10⁸ at the clamp of
/// [`cot_of_angle_between`] and make the diffusion systems singular in practice).
const MAX_SOUND_COT: f64 = 1e3;

/// The cotangents of triangle `t`'s corners, in its vertex order.
fn corner_cots(x: &[Vec3], [a, b, c]: [usize; 3]) -> [f64; 3] {
    let (pa, pb, pc) = (x[a], x[b], x[c]);
    [
        cot_of_angle_between(pb - pa, pc - pa),
        cot_of_angle_between(pc - pb, pa - pb),
        cot_of_angle_between(pa - pc, pb - pc),
    ]
}

/// The weights of a quad's two diagonal splits from their triangles' corner cotangents: ½ each, or 1
/// for the only split whose triangles are sound. A quad with three (nearly) collinear corners, which the tessellation makes where a
/// curve continues straight through a network vertex, has one split with a zero-area triangle; that split
/// alone would give weights of 10⁷ (webcam seed 18's tracked network: the flow diverged, a vertex moved
/// 321 m), while the other split describes the quad exactly.
fn split_weights(cots: &[[[f64; 3]; 2]; 2]) -> [f64; 2] {
    let sound = |split: &[[f64; 3]; 2]| split.iter().flatten().all(|c| c.abs() <= MAX_SOUND_COT);
    match (sound(&cots[0]), sound(&cots[1])) {
        (true, false) => [1.0, 0.0],
        (false, true) => [0.0, 1.0],
        _ => [0.5, 0.5],
    }
}

/// Area-weighted vertex normals of a polygon mesh at positions `x` (Newell's face normals summed over the
/// faces around each vertex), unit length (zero where undefined).
pub fn vertex_normals_at(mesh: &SurfaceMesh, x: &[Vec3]) -> Vec<Vec3> {
    let mut n = vec![Vec3::ZERO; mesh.vertices_size()];
    let mut vs = Vec::with_capacity(8);
    for f in mesh.faces() {
        vs.clear();
        vs.extend(mesh.face_vertices(f).map(|v| v.idx()));
        let mut fnrm = Vec3::ZERO;
        for k in 0..vs.len() {
            fnrm += x[vs[k]].cross(x[vs[(k + 1) % vs.len()]]);
        }
        for &v in &vs {
            n[v] += fnrm;
        }
    }
    n.into_iter().map(Vec3::normalize_or_zero).collect()
}

/// The fixed sparsity pattern of a Laplacian-like matrix over a list of vertex pairs, with the value slot
/// of every pair's four entries: rebuilding the matrix for new weights is then one pass over the pairs
/// (no triplet sorting), and the pattern never changes (so symbolic factorisations stay valid).
#[derive(Clone, Debug)]
pub struct Assembly {
    symbolic: SymbolicSparseColMat<usize>,
    slots: Vec<[usize; 4]>,
    diag: Vec<usize>,
}

impl Assembly {
    /// The pattern of the pairs `(i, j, _)` plus the whole diagonal, `n × n`.
    pub fn new(n: usize, pairs: &[(usize, usize, f64)]) -> Result<Self, SolveError> {
        let mut t: Vec<(usize, usize, f64)> = Vec::with_capacity(2 * pairs.len() + n);
        for &(i, j, _) in pairs {
            t.extend([(i, j, 1.0), (j, i, 1.0)]);
        }
        t.extend((0..n).map(|i| (i, i, 1.0)));
        let m = sparse_from_triplets(n, n, &t)?;
        let cp = m.col_ptr();
        let ri = m.row_idx();
        let slot = |r: usize, c: usize| -> Result<usize, SolveError> {
            let col = &ri[cp[c]..cp[c + 1]];
            col.binary_search(&r)
                .map(|k| cp[c] + k)
                .map_err(|_| SolveError::IndexOutOfRange { index: r, size: n })
        };
        let slots = pairs
            .iter()
            .map(|&(i, j, _)| Ok([slot(i, j)?, slot(j, i)?, slot(i, i)?, slot(j, j)?]))
            .collect::<Result<Vec<_>, SolveError>>()?;
        let diag = (0..n).map(|i| slot(i, i)).collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            symbolic: m
                .symbolic()
                .to_owned()
                .map_err(|_| SolveError::OutOfMemory)?,
            slots,
            diag,
        })
    }

    /// `scale·(Σ_pairs w·k(i, j))` as a Laplacian (off-diagonal `scale·w·k`, diagonal minus the row sum)
    /// plus `diag_add` on the diagonal; `w·k` clamped at 0 when `clamp`. `pairs` must be the list the
    /// pattern was made from (same length and order).
    pub fn build(
        &self,
        pairs: &[(usize, usize, f64)],
        k: impl Fn(usize, usize) -> f64,
        clamp: bool,
        scale: f64,
        diag_add: &[f64],
    ) -> SparseMatrix {
        let mut val = vec![0.0; self.symbolic.row_idx().len()];
        for (&(i, j, w), s) in pairs.iter().zip(&self.slots) {
            let mut v = w * k(i, j);
            if clamp {
                v = v.max(0.0);
            }
            let v = scale * v;
            val[s[0]] += v;
            val[s[1]] += v;
            val[s[2]] -= v;
            val[s[3]] -= v;
        }
        for (&d, &a) in self.diag.iter().zip(diag_add) {
            val[d] += a;
        }
        SparseMatrix::new(self.symbolic.clone(), val)
    }
}
