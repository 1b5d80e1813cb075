//! `network.json`: the polyline mesh on disk (specified in docs/network.md).
//!
//! Every element keeps its handle (`id`), and the vertex→edge and edge→face lists are stored in their
//! in-memory order, so writing and reading a network gives it back bit for bit. Reading checks the format,
//! the version and [`Network::validate`].

use serde::{Deserialize, Serialize};

use super::handles::{EdgeId, FaceId, PolylineId, VertexId};
use super::mesh::{Edge, EdgeUse, Face, Network, Polyline, PolylineAttrs, Vertex};
use super::topology::Topology;
use super::validate::InvariantError;

/// The `format` value of a network file.
pub const NETWORK_FORMAT: &str = "fires-network";
/// The version this crate writes; readers accept the same major.
pub const NETWORK_VERSION: &str = "1.0";

/// A whole `network.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NetworkFile {
    /// Always [`NETWORK_FORMAT`].
    pub format: String,
    /// `MAJOR.MINOR`.
    pub version: String,
    /// Always `"m"`: positions are metres.
    pub units: String,
    /// Number of slots of each kind (live elements plus removed ones), `[vertices, edges, faces, polylines]`.
    pub slots: [usize; 4],
    /// V, E, F, boundaries, χ, genus (informative; recomputed on read).
    pub topology: Topology,
    /// Live vertices.
    pub vertices: Vec<VertexRecord>,
    /// Live polylines.
    pub polylines: Vec<PolylineRecord>,
    /// Live edges.
    pub edges: Vec<EdgeRecord>,
    /// Live faces.
    pub faces: Vec<FaceRecord>,
}

/// A vertex in the file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VertexRecord {
    /// Handle.
    pub id: VertexId,
    /// Position, metres.
    pub p: [f64; 3],
    /// Its edges.
    pub edges: Vec<EdgeId>,
}

/// A polyline in the file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PolylineRecord {
    /// Handle.
    pub id: PolylineId,
    /// Points, metres.
    pub points: Vec<[f64; 3]>,
    /// Attributes.
    #[serde(flatten)]
    pub attrs: PolylineAttrs,
}

/// An edge in the file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EdgeRecord {
    /// Handle.
    pub id: EdgeId,
    /// Start vertex.
    pub from: VertexId,
    /// End vertex.
    pub to: VertexId,
    /// Its polyline.
    pub polyline: PolylineId,
    /// Faces using it.
    pub faces: Vec<FaceId>,
}

/// A face in the file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FaceRecord {
    /// Handle.
    pub id: FaceId,
    /// Its loop.
    pub edges: Vec<EdgeUse>,
}

/// Why a network file cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum NetworkFileError {
    /// Not JSON of the schema.
    #[error("network.json: {0}")]
    Json(#[from] serde_json::Error),
    /// Wrong `format`.
    #[error("format is {0:?}, expected \"fires-network\"")]
    NotANetworkFile(String),
    /// Another major version.
    #[error("unsupported network version {0:?}")]
    UnsupportedVersion(String),
    /// An id outside its slot count or used twice.
    #[error("{0}")]
    BadId(String),
    /// The network breaks an invariant.
    #[error(transparent)]
    Invalid(#[from] InvariantError),
}

impl NetworkFile {
    /// The file of `net`.
    pub fn from_network(net: &Network) -> Self {
        NetworkFile {
            format: NETWORK_FORMAT.into(),
            version: NETWORK_VERSION.into(),
            units: "m".into(),
            slots: [
                net.vertices.len(),
                net.edges.len(),
                net.faces.len(),
                net.polylines.len(),
            ],
            topology: net.topology(),
            vertices: net
                .vertices()
                .map(|(id, v)| VertexRecord {
                    id,
                    p: v.position,
                    edges: v.edges.clone(),
                })
                .collect(),
            polylines: net
                .polylines()
                .map(|(id, p)| PolylineRecord {
                    id,
                    points: p.points.clone(),
                    attrs: p.attrs,
                })
                .collect(),
            edges: net
                .edges()
                .map(|(id, e)| EdgeRecord {
                    id,
                    from: e.from,
                    to: e.to,
                    polyline: e.polyline,
                    faces: e.faces.clone(),
                })
                .collect(),
            faces: net
                .faces()
                .map(|(id, f)| FaceRecord {
                    id,
                    edges: f.uses.clone(),
                })
                .collect(),
        }
    }

    /// The network of this file, checked.
    pub fn to_network(&self) -> Result<Network, NetworkFileError> {
        if self.format != NETWORK_FORMAT {
            return Err(NetworkFileError::NotANetworkFile(self.format.clone()));
        }
        if self.version.split('.').next() != Some("1") {
            return Err(NetworkFileError::UnsupportedVersion(self.version.clone()));
        }
        fn place<T>(
            slots: &mut [Option<T>],
            id: usize,
            value: T,
            kind: &str,
        ) -> Result<(), NetworkFileError> {
            match slots.get_mut(id) {
                Some(s @ None) => {
                    *s = Some(value);
                    Ok(())
                }
                _ => Err(NetworkFileError::BadId(format!(
                    "{kind} id {id} is out of range or repeated"
                ))),
            }
        }
        let mut net = Network::new();
        net.vertices = vec![None; self.slots[0]];
        net.edges = vec![None; self.slots[1]];
        net.faces = vec![None; self.slots[2]];
        net.polylines = vec![None; self.slots[3]];
        for v in &self.vertices {
            let value = Vertex {
                position: v.p,
                edges: v.edges.clone(),
            };
            place(&mut net.vertices, v.id.idx(), value, "vertex")?;
        }
        for p in &self.polylines {
            let value = Polyline {
                points: p.points.clone(),
                attrs: p.attrs,
            };
            place(&mut net.polylines, p.id.idx(), value, "polyline")?;
        }
        for e in &self.edges {
            let value = Edge {
                from: e.from,
                to: e.to,
                polyline: e.polyline,
                faces: e.faces.clone(),
            };
            place(&mut net.edges, e.id.idx(), value, "edge")?;
        }
        for f in &self.faces {
            let value = Face {
                uses: f.edges.clone(),
            };
            place(&mut net.faces, f.id.idx(), value, "face")?;
        }
        let in_range = |id: usize, n: usize| id < n;
        let ok = net
            .vertices()
            .all(|(_, v)| v.edges.iter().all(|e| in_range(e.idx(), self.slots[1])))
            && net.edges().all(|(_, e)| {
                in_range(e.from.idx(), self.slots[0])
                    && in_range(e.to.idx(), self.slots[0])
                    && in_range(e.polyline.idx(), self.slots[3])
                    && e.faces.iter().all(|f| in_range(f.idx(), self.slots[2]))
            })
            && net
                .faces()
                .all(|(_, f)| f.uses.iter().all(|u| in_range(u.edge.idx(), self.slots[1])));
        if !ok {
            return Err(NetworkFileError::BadId(
                "a reference is out of range".into(),
            ));
        }
        net.rebuild_boxes();
        net.validate()?;
        Ok(net)
    }

    /// Parses and checks a `network.json` document.
    pub fn parse(text: &str) -> Result<Network, NetworkFileError> {
        let file: NetworkFile = serde_json::from_str(text)?;
        file.to_network()
    }

    /// The document text of `net` (pretty-printed JSON).
    pub fn to_json(net: &Network) -> String {
        serde_json::to_string_pretty(&Self::from_network(net)).unwrap_or_default()
    }
}
