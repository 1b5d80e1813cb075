//! Typed element handles. Each is a `u32` index into the mesh's arrays; a halfedge's
//! twin is `h ^ 1` and its edge is `h / 2` (implicit twins, as in pmp-library).

use crate::handle::handle;

handle!(
    /// A vertex.
    Vertex, "v"
);
handle!(
    /// A directed halfedge.
    Halfedge, "h"
);
handle!(
    /// An undirected edge (a pair of halfedges `2e`, `2e + 1`).
    Edge, "e"
);
handle!(
    /// A face (polygon).
    Face, "f"
);

impl Halfedge {
    /// The opposite (twin) halfedge.
    pub const fn opposite(self) -> Halfedge {
        Halfedge(self.0 ^ 1)
    }
    /// The edge this halfedge belongs to.
    pub const fn edge(self) -> Edge {
        Edge(self.0 >> 1)
    }
}

impl Edge {
    /// One of the two halfedges of this edge (`i` is 0 or 1).
    pub const fn halfedge(self, i: u32) -> Halfedge {
        Halfedge((self.0 << 1) | (i & 1))
    }
}

/// Internal marker for "no element".
pub(crate) const INVALID: u32 = u32::MAX;
