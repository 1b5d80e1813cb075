//! Operators on an [`EditProblem`]'s local vertices: cotangent stiffness, the uniform graph
//! Laplacian, per-face hat-function gradients and graph distances. Rows of ROI vertices
//! equal the rows of the whole mesh's operators (their stencils are complete).

use super::problem::EditProblem;
use crate::geometry::{cot_of_angle_between, triangle_normal, Vec3};
use crate::solve::{sparse_from_triplets, SolveError, SparseMatrix};

/// Edge cotangent weights `w_ij = ½(cot α + cot β)` summed over the local faces, as
/// `(i, j, w)` for both orders.
pub fn cotan_weights(p: &EditProblem, clamp_negative: bool) -> Vec<(usize, usize, f64)> {
    cotan_weights_at(p, &p.rest, clamp_negative)
}

/// [`cotan_weights`] of the local faces at positions `x` (one per local vertex). Clamped
/// weights are summed per edge first and come sorted by `(i, j)`.
pub fn cotan_weights_at(
    p: &EditProblem,
    x: &[Vec3],
    clamp_negative: bool,
) -> Vec<(usize, usize, f64)> {
    let mut t = Vec::with_capacity(p.faces.len() * 6);
    for f in &p.faces {
        for k in 0..3 {
            let (a, i, j) = (f[k], f[(k + 1) % 3], f[(k + 2) % 3]);
            let w = 0.5 * cot_of_angle_between(x[i] - x[a], x[j] - x[a]);
            t.push((i, j, w));
            t.push((j, i, w));
        }
    }
    if clamp_negative {
        // Grouped by row (counting sort), each row sorted, each edge's halves summed.
        let n = x.len();
        let mut start = vec![0usize; n + 1];
        for &(i, _, _) in &t {
            start[i + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut next = start.clone();
        let mut rows = vec![(0usize, 0.0f64); t.len()];
        for &(i, j, w) in &t {
            rows[next[i]] = (j, w);
            next[i] += 1;
        }
        t.clear();
        for i in 0..n {
            let row = &mut rows[start[i]..start[i + 1]];
            row.sort_unstable_by_key(|e| e.0);
            for &(j, w) in row.iter() {
                match t.last_mut() {
                    Some(last) if last.0 == i && last.1 == j => last.2 += w,
                    _ => t.push((i, j, w)),
                }
            }
        }
        for e in &mut t {
            e.2 = e.2.max(0.0);
        }
    }
    t
}

/// Symmetric positive semidefinite `K` with `K_ij = −w_ij`, `K_ii = Σ_j w_ij` from edge
/// weights given for both orders.
pub fn stiffness_from_weights(
    n: usize,
    weights: &[(usize, usize, f64)],
) -> Result<SparseMatrix, SolveError> {
    let mut t = Vec::with_capacity(weights.len() * 2);
    for &(i, j, w) in weights {
        t.push((i, j, -w));
        t.push((i, i, w));
    }
    sparse_from_triplets(n, n, &t)
}

/// The cotangent stiffness `K = −C` over the local vertices.
pub fn cotan_stiffness(p: &EditProblem) -> Result<SparseMatrix, SolveError> {
    stiffness_from_weights(p.len(), &cotan_weights(p, false))
}

/// The uniform graph Laplacian `D − A` over the local vertices.
pub fn graph_laplacian(p: &EditProblem) -> Result<SparseMatrix, SolveError> {
    let mut w = Vec::new();
    for (i, nb) in p.neighbors.iter().enumerate() {
        for &j in nb {
            w.push((i, j, 1.0));
        }
    }
    stiffness_from_weights(p.len(), &w)
}

/// Per local face: area and the area-weighted hat gradients `|T| ∇B_k = ½ n̂ × e_k`
/// (`None` for a degenerate face).
pub fn face_gradients(p: &EditProblem, x: &[Vec3]) -> Vec<Option<(f64, [Vec3; 3])>> {
    p.faces
        .iter()
        .map(|&[a, b, c]| {
            let (nh, len) = unit_normal(x[a], x[b], x[c])?;
            Some((0.5 * len, hat_gradients(nh, [x[a], x[b], x[c]])))
        })
        .collect()
}

/// A triangle's unit normal and the length of its unnormalised normal (twice its area),
/// `None` when degenerate.
#[inline]
pub fn unit_normal(a: Vec3, b: Vec3, c: Vec3) -> Option<(Vec3, f64)> {
    let n = triangle_normal(a, b, c);
    let len = n.norm();
    (len > 0.0 && len.is_finite()).then(|| (n / len, len))
}

/// The area-weighted hat gradients `|T| ∇B_k = ½ n̂ × e_k` of a triangle with unit normal
/// `nh` and corners `x` (`e_k` the edge opposite corner `k`, counter-clockwise).
#[inline(always)]
pub fn hat_gradients(nh: Vec3, x: [Vec3; 3]) -> [Vec3; 3] {
    let g = |from: usize, to: usize| nh.cross(x[to] - x[from]) * 0.5;
    [g(1, 2), g(2, 0), g(0, 1)]
}

/// Shortest edge-path distance over the local graph from `sources` (∞ if unreachable).
pub fn graph_distance(p: &EditProblem, sources: &[usize]) -> Vec<f64> {
    crate::operators::dijkstra(p.len(), sources, |i| {
        p.neighbors[i]
            .iter()
            .map(move |&j| (j, p.rest[i].distance(p.rest[j])))
    })
}

/// Shortest edge-path distance over the local graph from `sources` and, per vertex, the
/// position in `sources` of its nearest source (`usize::MAX` if unreachable).
pub fn graph_distance_nearest(p: &EditProblem, sources: &[usize]) -> (Vec<f64>, Vec<usize>) {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    #[derive(PartialEq)]
    struct Key(f64);
    impl Eq for Key {}
    impl PartialOrd for Key {
        fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
            Some(self.cmp(o))
        }
    }
    impl Ord for Key {
        fn cmp(&self, o: &Self) -> std::cmp::Ordering {
            self.0.total_cmp(&o.0)
        }
    }
    let n = p.len();
    let mut dist = vec![f64::INFINITY; n];
    let mut label = vec![usize::MAX; n];
    let mut heap = BinaryHeap::new();
    for (k, &s) in sources.iter().enumerate() {
        if s < n && dist[s] > 0.0 {
            dist[s] = 0.0;
            label[s] = k;
            heap.push(Reverse((Key(0.0), s)));
        }
    }
    while let Some(Reverse((Key(d), i))) = heap.pop() {
        if d > dist[i] {
            continue;
        }
        for &j in &p.neighbors[i] {
            let nd = d + p.rest[i].distance(p.rest[j]);
            if nd < dist[j] {
                dist[j] = nd;
                label[j] = label[i];
                heap.push(Reverse((Key(nd), j)));
            }
        }
    }
    (dist, label)
}

/// Positions as an `n × 3` faer matrix.
pub fn to_mat(x: &[Vec3]) -> faer::Mat<f64> {
    faer::Mat::from_fn(x.len(), 3, |i, c| x[i][c])
}

/// Rows of an `n × 3` matrix as positions.
pub fn from_mat(m: faer::MatRef<'_, f64>) -> Vec<Vec3> {
    (0..m.nrows())
        .map(|i| Vec3::new(m[(i, 0)], m[(i, 1)], m[(i, 2)]))
        .collect()
}

/// The rows `idx` of positions as a `k × 3` matrix.
pub fn gather(x: &[Vec3], idx: &[usize]) -> faer::Mat<f64> {
    faer::Mat::from_fn(idx.len(), 3, |r, c| x[idx[r]][c])
}
