//! Stable element handles of the curve network.
//!
//! A handle is the index of its element's slot. Slots are never reused while the element's transaction
//! stands: removing an element leaves an empty slot, so a handle held by a caller names the same element
//! or nothing. (Rolling back or undoing a transaction frees the slots it created, and a later transaction
//! may fill them again.)

use crate::handle::handle;

handle!(
    /// A vertex of the network (a curve end or a crossing).
    VertexId, "v"
);
handle!(
    /// An edge: a vertex pair and one polyline.
    EdgeId, "e"
);
handle!(
    /// A face: a closed ordered loop of edges.
    FaceId, "f"
);
handle!(
    /// A polyline (the geometry of one edge).
    PolylineId, "p"
);
