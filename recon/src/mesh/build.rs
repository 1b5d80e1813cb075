//! Building a [`SurfaceMesh`] from indexed polygons, with manifoldness checks.

use std::collections::HashMap;

use super::error::MeshError;
use super::handles::{Halfedge, Vertex, INVALID};
use super::SurfaceMesh;
use crate::geometry::Vec3;

impl SurfaceMesh {
    /// Builds a mesh from vertex positions and polygons given as vertex-index lists.
    ///
    /// Rejects, with an error naming the element: indices out of range, faces with fewer
    /// than three distinct vertices, a directed edge used twice (a non-manifold edge or
    /// inconsistent orientation), and vertices whose faces do not form one fan.
    pub fn from_faces<F: AsRef<[usize]>>(points: &[Vec3], faces: &[F]) -> Result<Self, MeshError> {
        Self::from_face_slices(points, faces.iter().map(|f| f.as_ref()))
    }

    /// [`Self::from_faces`] for any source of index slices (e.g. a flat polygon soup).
    pub fn from_face_slices<'a>(
        points: &[Vec3],
        faces: impl Iterator<Item = &'a [usize]> + Clone,
    ) -> Result<Self, MeshError> {
        let n_he: usize = faces.clone().map(|f| f.len()).sum();
        if points.len() >= INVALID as usize || n_he.saturating_mul(2) >= INVALID as usize {
            return Err(MeshError::TooLarge);
        }
        let mut mesh = SurfaceMesh::new();
        for &p in points {
            mesh.add_vertex(p);
        }
        let mut directed: HashMap<(u32, u32), Halfedge> = HashMap::with_capacity(n_he);
        for (fi, face) in faces.enumerate() {
            mesh.add_indexed_face(fi, face, &mut directed)?;
        }
        mesh.link_boundary_halfedges()?;
        mesh.check_vertex_fans()?;
        Ok(mesh)
    }

    fn add_indexed_face(
        &mut self,
        fi: usize,
        face: &[usize],
        directed: &mut HashMap<(u32, u32), Halfedge>,
    ) -> Result<(), MeshError> {
        let nv = self.vertices_size();
        for &i in face {
            if i >= nv {
                return Err(MeshError::VertexIndexOutOfRange {
                    face: fi,
                    index: i,
                    n_vertices: nv,
                });
            }
        }
        let distinct = if face.len() <= 8 {
            (1..face.len()).all(|k| !face[..k].contains(&face[k]))
        } else {
            let mut sorted = face.to_vec();
            sorted.sort_unstable();
            sorted.windows(2).all(|w| w[0] != w[1])
        };
        if face.len() < 3 || !distinct {
            return Err(MeshError::DegenerateFace { face: fi });
        }
        let n = face.len();
        let mut hs = Vec::with_capacity(n);
        for k in 0..n {
            let (a, b) = (face[k] as u32, face[(k + 1) % n] as u32);
            if directed.contains_key(&(a, b)) {
                return Err(MeshError::NonManifoldEdge {
                    from: Vertex(a),
                    to: Vertex(b),
                    face: fi,
                });
            }
            let h = match directed.get(&(b, a)) {
                Some(&o) => o.opposite(),
                None => self.new_edge(Vertex(a), Vertex(b)),
            };
            directed.insert((a, b), h);
            hs.push(h);
        }
        let f = self.new_face();
        self.set_face_halfedge(f, hs[0]);
        for k in 0..n {
            self.set_face(hs[k], Some(f));
            self.set_next(hs[k], hs[(k + 1) % n]);
            self.set_vertex_halfedge(self.from_vertex(hs[k]), Some(hs[k]));
        }
        Ok(())
    }

    /// Links the face-less halfedges into boundary loops; a vertex with two outgoing
    /// boundary halfedges is non-manifold.
    fn link_boundary_halfedges(&mut self) -> Result<(), MeshError> {
        let mut boundary_out = vec![INVALID; self.vertices_size()];
        for h in 0..self.halfedges_size() {
            let h = Halfedge::new(h);
            if self.is_boundary_halfedge(h) {
                let v = self.from_vertex(h);
                if boundary_out[v.idx()] != INVALID {
                    return Err(MeshError::NonManifoldVertex(v));
                }
                boundary_out[v.idx()] = h.0;
            }
        }
        for h in 0..self.halfedges_size() {
            let h = Halfedge::new(h);
            if self.is_boundary_halfedge(h) {
                let next = Halfedge(boundary_out[self.to_vertex(h).idx()]);
                self.set_next(h, next);
                self.set_vertex_halfedge(self.from_vertex(h), Some(h));
            }
        }
        Ok(())
    }

    /// Every vertex's outgoing halfedges must all be reached by one rotation.
    fn check_vertex_fans(&self) -> Result<(), MeshError> {
        let mut outgoing = vec![0usize; self.vertices_size()];
        for h in self.halfedges() {
            outgoing[self.from_vertex(h).idx()] += 1;
        }
        for v in self.vertices() {
            if self.vertex_halfedges(v).count() != outgoing[v.idx()] {
                return Err(MeshError::NonManifoldVertex(v));
            }
        }
        Ok(())
    }

    /// Builds a triangle mesh from positions and index triples.
    pub fn from_triangles(points: &[Vec3], triangles: &[[usize; 3]]) -> Result<Self, MeshError> {
        Self::from_faces(points, triangles)
    }
}
