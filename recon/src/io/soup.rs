//! [`PolygonSoup`]: positions plus flat polygon index lists, what every reader produces.

use std::io::Write;

use super::IoError;
use crate::geometry::Vec3;
use crate::mesh::{RepairOptions, Repairs, SurfaceMesh, Vertex};

/// Vertex positions and polygons (as index lists stored back to back).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PolygonSoup {
    /// Vertex positions.
    pub points: Vec<Vec3>,
    /// Start of each face in `indices`, plus a final end marker (`n_faces + 1` entries).
    pub face_starts: Vec<usize>,
    /// Vertex indices of all faces, concatenated.
    pub indices: Vec<usize>,
}

impl PolygonSoup {
    /// An empty soup.
    pub fn new() -> Self {
        Self {
            points: Vec::new(),
            face_starts: vec![0],
            indices: Vec::new(),
        }
    }
    /// Number of faces.
    pub fn n_faces(&self) -> usize {
        self.face_starts.len().saturating_sub(1)
    }
    /// The vertex indices of face `i`.
    pub fn face(&self, i: usize) -> &[usize] {
        &self.indices[self.face_starts[i]..self.face_starts[i + 1]]
    }
    /// All faces in order.
    pub fn faces(&self) -> impl Iterator<Item = &[usize]> + Clone + '_ {
        (0..self.n_faces()).map(|i| self.face(i))
    }
    /// Appends a face.
    pub fn push_face(&mut self, face: &[usize]) {
        if self.face_starts.is_empty() {
            self.face_starts.push(0);
        }
        self.indices.extend_from_slice(face);
        self.face_starts.push(self.indices.len());
    }
    /// Checks every index is below the number of points.
    pub fn check_indices(&self) -> Result<(), IoError> {
        let n = self.points.len();
        match self.indices.iter().position(|&i| i >= n) {
            Some(k) => {
                let face = self
                    .face_starts
                    .partition_point(|&s| s <= k)
                    .saturating_sub(1);
                Err(IoError::Mesh(
                    crate::mesh::MeshError::VertexIndexOutOfRange {
                        face,
                        index: self.indices[k],
                        n_vertices: n,
                    },
                ))
            }
            None => Ok(()),
        }
    }
    /// Builds a halfedge mesh (fails on non-manifold input).
    pub fn to_mesh(&self) -> Result<SurfaceMesh, IoError> {
        Ok(SurfaceMesh::from_face_slices(&self.points, self.faces())?)
    }
    /// Builds a halfedge mesh from any polygons, repairing orientation, non-manifold
    /// vertices and edges, degenerate and duplicate faces (see
    /// [`SurfaceMesh::from_polygons_repaired`]); fails only on broken indices.
    pub fn to_mesh_repaired(&self) -> Result<(SurfaceMesh, Repairs), IoError> {
        Ok(SurfaceMesh::from_polygons_repaired(
            &self.points,
            self.faces(),
            &RepairOptions::default(),
        )?)
    }
    /// The live vertices and faces of a mesh, renumbered densely.
    pub fn from_mesh(mesh: &SurfaceMesh) -> Self {
        let mut map = vec![usize::MAX; mesh.vertices_size()];
        let mut soup = Self::new();
        for v in mesh.vertices() {
            map[v.idx()] = soup.points.len();
            soup.points.push(mesh.position(v));
        }
        for f in mesh.faces() {
            let idx: Vec<usize> = mesh
                .face_vertices(f)
                .map(|v: Vertex| map[v.idx()])
                .collect();
            soup.push_face(&idx);
        }
        soup
    }
}

/// Writes every face as a text line `k i₁ … i_k` (the face lists of OFF and ASCII PLY).
pub(crate) fn write_counted_face_lines<W: Write>(
    w: &mut W,
    soup: &PolygonSoup,
) -> Result<(), IoError> {
    for f in soup.faces() {
        write!(w, "{}", f.len())?;
        for i in f {
            write!(w, " {i}")?;
        }
        writeln!(w)?;
    }
    Ok(())
}
