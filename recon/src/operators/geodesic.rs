//! Geodesic distance: the heat method (Crane, Weischedel, Wardetzky 2013) with both
//! factorisations precomputed, and Dijkstra on the edge graph as a fallback.
//!
//! Heat method: `(M − tC) u = δ_S` with `t = h²` (h = mean edge length), per-face
//! `X = −∇u/|∇u|`, then `(−C + εM) φ = Gᵀ|T|X` and `φ` is shifted so its minimum over
//! the sources is 0. `ε = 1e-10` (relative to the stiffness scale) only removes the
//! constant null space; the right-hand side is orthogonal to it. Boundaries get natural
//! (Neumann) conditions. Distances are only meaningful on the sources' components.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use faer::Mat;

use super::cotan::cotan_matrix;
use super::gradient::hat_gradients;
use super::mass::{vertex_areas, MassKind};
use super::{mean_edge_length, triangles_for, OperatorError};
use crate::geometry::Vec3;
use crate::mesh::{SurfaceMesh, Vertex};
use crate::solve::{sparse_from_triplets, sparse_triplets, CholeskyOptions, CholeskySolver};

/// Precomputed heat-method geodesics for one mesh: query with many source sets.
#[derive(Debug, Clone)]
pub struct HeatGeodesic {
    heat: CholeskySolver,
    poisson: CholeskySolver,
    tris: Vec<[usize; 3]>,
    grads: Vec<Option<(f64, [Vec3; 3])>>,
    n: usize,
}

impl HeatGeodesic {
    /// Factorises the heat and Poisson systems of a triangle mesh.
    pub fn new(mesh: &SurfaceMesh) -> Result<Self, OperatorError> {
        let tris = triangles_for(mesh, "heat geodesics")?;
        let n = mesh.vertices_size();
        let c = sparse_triplets(cotan_matrix(mesh)?.as_ref());
        let m = vertex_areas(mesh, MassKind::MixedVoronoi)?;
        let h = mean_edge_length(mesh);
        let t = h * h;
        let scale = c
            .iter()
            .filter(|e| e.0 == e.1)
            .map(|e| -e.2)
            .fold(0.0, f64::max)
            .max(1e-300);
        let mean_m = m.iter().sum::<f64>() / n.max(1) as f64;
        let eps = 1e-10 * scale / mean_m.max(1e-300);
        let heat_t: Vec<_> = c
            .iter()
            .map(|&(i, j, v)| (i, j, -t * v))
            .chain(m.iter().enumerate().map(|(i, &a)| (i, i, a.max(1e-300))))
            .collect();
        let poisson_t: Vec<_> = c
            .iter()
            .map(|&(i, j, v)| (i, j, -v))
            .chain(m.iter().enumerate().map(|(i, &a)| (i, i, eps * a + 1e-300)))
            .collect();
        let opts = CholeskyOptions::default();
        let heat = CholeskySolver::new(sparse_from_triplets(n, n, &heat_t)?.as_ref(), opts)?;
        let poisson = CholeskySolver::new(sparse_from_triplets(n, n, &poisson_t)?.as_ref(), opts)?;
        let grads = hat_gradients(mesh, &tris);
        Ok(Self {
            heat,
            poisson,
            tris,
            grads,
            n,
        })
    }

    /// Approximate geodesic distance from the `sources` to every vertex.
    pub fn distance(&self, sources: &[Vertex]) -> Result<Vec<f64>, OperatorError> {
        let mut u = Mat::zeros(self.n, 1);
        for &s in sources {
            if s.idx() >= self.n {
                return Err(OperatorError::InvalidVertex(s));
            }
            u[(s.idx(), 0)] = 1.0;
        }
        self.heat.solve_in_place(u.as_mut())?;
        let mut b = Mat::zeros(self.n, 1);
        for (tri, g) in self.tris.iter().zip(&self.grads) {
            let Some((area, w)) = g else { continue };
            let grad_u = w[0] * u[(tri[0], 0)] + w[1] * u[(tri[1], 0)] + w[2] * u[(tri[2], 0)];
            let x = -grad_u.normalize_or_zero();
            for k in 0..3 {
                b[(tri[k], 0)] += area * w[k].dot(x);
            }
        }
        self.poisson.solve_in_place(b.as_mut())?;
        let shift = sources
            .iter()
            .map(|s| b[(s.idx(), 0)])
            .fold(f64::INFINITY, f64::min);
        let shift = if shift.is_finite() { shift } else { 0.0 };
        Ok((0..self.n).map(|i| b[(i, 0)] - shift).collect())
    }
}

/// One-shot heat-method distance (see [`HeatGeodesic`] to reuse the factorisations).
pub fn geodesic_heat(mesh: &SurfaceMesh, sources: &[Vertex]) -> Result<Vec<f64>, OperatorError> {
    HeatGeodesic::new(mesh)?.distance(sources)
}

#[derive(PartialEq)]
struct Item(f64, usize);
impl Eq for Item {}
impl PartialOrd for Item {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Item {
    fn cmp(&self, o: &Self) -> Ordering {
        o.0.total_cmp(&self.0)
    }
}

/// Shortest-path distance along edges from the `sources` (∞ where unreachable). Works on
/// any polygon mesh; an upper bound of the geodesic distance.
pub fn geodesic_dijkstra(
    mesh: &SurfaceMesh,
    sources: &[Vertex],
) -> Result<Vec<f64>, OperatorError> {
    for &s in sources {
        if s.idx() >= mesh.vertices_size() || mesh.is_deleted_vertex(s) {
            return Err(OperatorError::InvalidVertex(s));
        }
    }
    let starts: Vec<usize> = sources.iter().map(|s| s.idx()).collect();
    Ok(dijkstra(mesh.vertices_size(), &starts, |i| {
        let v = Vertex::new(i);
        mesh.vertex_vertices(v)
            .map(move |w| (w.idx(), mesh.position(v).distance(mesh.position(w))))
    }))
}

/// Shortest-path distances over a graph of `n` nodes from `sources` (∞ where unreachable): `edges(i)` lists the
/// neighbours of node `i` with the edge lengths (non-negative). Dijkstra's algorithm with a binary heap.
pub(crate) fn dijkstra<I: IntoIterator<Item = (usize, f64)>>(
    n: usize,
    sources: &[usize],
    mut edges: impl FnMut(usize) -> I,
) -> Vec<f64> {
    let mut dist = vec![f64::INFINITY; n];
    let mut heap = BinaryHeap::new();
    for &s in sources {
        dist[s] = 0.0;
        heap.push(Item(0.0, s));
    }
    while let Some(Item(d, i)) = heap.pop() {
        if d > dist[i] {
            continue;
        }
        for (j, len) in edges(i) {
            let nd = d + len;
            if nd < dist[j] {
                dist[j] = nd;
                heap.push(Item(nd, j));
            }
        }
    }
    dist
}
