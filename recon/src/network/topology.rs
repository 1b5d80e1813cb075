//! Euler bookkeeping of a network: V, E, F, boundary loops, components, χ and genus.

use serde::{Deserialize, Serialize};

use super::mesh::Network;

/// Counts that describe a network's topology.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Topology {
    /// Vertices.
    pub vertices: usize,
    /// Edges.
    pub edges: usize,
    /// Faces.
    pub faces: usize,
    /// Boundary loops: connected components of the edges used by exactly one face.
    pub boundaries: usize,
    /// Connected components (vertices joined by edges).
    pub components: usize,
    /// Euler characteristic V − E + F.
    pub euler: i64,
    /// Total genus `(2·components − boundaries − χ) / 2` (orientable surfaces).
    pub genus: i64,
}

struct UnionFind(Vec<usize>);

impl UnionFind {
    fn find(&mut self, mut i: usize) -> usize {
        while self.0[i] != i {
            self.0[i] = self.0[self.0[i]];
            i = self.0[i];
        }
        i
    }
    fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.0[ra] = rb;
        }
    }
}

impl Network {
    /// V, E, F, boundaries, components, Euler characteristic and genus.
    pub fn topology(&self) -> Topology {
        let n = self.vertices.len();
        let mut all = UnionFind((0..n).collect());
        let mut border = UnionFind((0..n).collect());
        let mut on_border = vec![false; n];
        for (_, e) in self.edges() {
            all.union(e.from.idx(), e.to.idx());
            if e.faces.len() == 1 {
                border.union(e.from.idx(), e.to.idx());
                on_border[e.from.idx()] = true;
                on_border[e.to.idx()] = true;
            }
        }
        let live: Vec<usize> = self.vertices().map(|(v, _)| v.idx()).collect();
        let components = live.iter().filter(|&&i| all.find(i) == i).count();
        let boundaries = live
            .iter()
            .filter(|&&i| on_border[i] && border.find(i) == i)
            .count();
        let (v, e, f) = (self.n_vertices(), self.n_edges(), self.n_faces());
        let euler = v as i64 - e as i64 + f as i64;
        Topology {
            vertices: v,
            edges: e,
            faces: f,
            boundaries,
            components,
            euler,
            genus: (2 * components as i64 - boundaries as i64 - euler) / 2,
        }
    }
}
