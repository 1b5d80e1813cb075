//! Stable element handles of the curve network.
//!
//! A handle is the index of its element's slot. Slots are never reused while the element's transaction
//! stands: removing an element leaves an empty slot, so a handle held by a caller names the same element
//! or nothing. (Rolling back or undoing a transaction frees the slots it created, and a later transaction
//! may fill them again.)

use std::fmt;

macro_rules! handle {
    ($(#[$doc:meta])* $name:ident, $prefix:literal) => {
        $(#[$doc])*
        #[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize)]
        #[serde(transparent)]
        pub struct $name(pub u32);

        impl $name {
            /// The slot index of this element.
            pub const fn idx(self) -> usize {
                self.0 as usize
            }
        }

        impl fmt::Debug for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, concat!($prefix, "{}"), self.0)
            }
        }

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                fmt::Debug::fmt(self, f)
            }
        }
    };
}

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
