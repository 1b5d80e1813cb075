//! The curve network: the FIRES thesis's polyline mesh (§3.3) and the sketching tools that build it
//! (ch. 5), each a transaction.
//!
//! * [`Network`]: vertices, polylines, edges, faces with stable handles, [`Network::validate`] and
//!   [`Network::topology`] (Euler bookkeeping);
//! * [`tools`]: initial boundary and curve insertion (with vertex snapping, overshoot trimming and
//!   short-stop extension);
//! * [`build_network`]: strokes in, network out;
//! * [`NetworkFile`]: `network.json`; [`Journal`]: the sketch journal and [`replay`] (docs/network.md).

mod build;
mod file;
pub(crate) mod geom;
mod handles;
mod journal;
mod mesh;
mod ops;
pub mod tools;
mod topology;
mod txn;
mod validate;

pub use build::{build_network, BuildOptions, BuildReport, PenMode, Rejected, StrokeInput};
pub use file::{NetworkFile, NetworkFileError, NETWORK_FORMAT, NETWORK_VERSION};
pub use handles::{EdgeId, FaceId, PolylineId, VertexId};
pub use journal::{replay, Journal, JournalError, Step, JOURNAL_FORMAT, JOURNAL_VERSION};
pub use mesh::{Edge, EdgeUse, Face, Fit, Network, Origin, Polyline, PolylineAttrs, Vertex};
pub use topology::Topology;
pub use txn::Transaction;
pub use validate::{InvariantError, ENDPOINT_TOLERANCE_M};
