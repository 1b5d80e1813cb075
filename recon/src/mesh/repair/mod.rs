//! Building a [`SurfaceMesh`] from arbitrary polygons, repairing what a halfedge mesh
//! cannot hold and reporting every repair in [`Repairs`].
//!
//! Steps, in order ([`SurfaceMesh::from_polygons_repaired`]):
//! 1. an index out of range is an error (the file is broken); everything else is repaired;
//! 2. repeated consecutive corners are collapsed; faces left with fewer than three
//!    distinct vertices are dropped; exact duplicate faces (either orientation) are dropped
//!    ([`clean`]); zero-area faces are kept and counted;
//! 3. a face that would give an edge a third face is set aside ([`split`]);
//! 4. faces are oriented consistently per connected component ([`orient`]), keeping the
//!    orientation most of the component's faces had in the file; a non-orientable
//!    component is cut along the edges where orientation conflicts;
//! 5. vertices whose faces form several fans are split, copies appended ([`split`]);
//! 6. the faces set aside in step 3 are added on their own vertex copies (pmp-library,
//!    OpenMesh), also appended.
//!
//! File vertex indices stay valid: vertex `i < n` of the result is vertex `i` of the
//! input, and [`Repairs::vertex_source`] names the original of every appended copy.

mod clean;
mod orient;
mod split;

pub use clean::{is_zero_area_polygon, ZERO_AREA_RELATIVE};

use std::collections::HashMap;

use super::{MeshError, SurfaceMesh};
use crate::geometry::Vec3;

/// What [`SurfaceMesh::from_polygons_repaired`] did to the input (all zero: nothing).
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize)]
pub struct Repairs {
    /// Input vertices no face refers to (kept as isolated vertices).
    pub unreferenced_vertices: usize,
    /// Faces whose repeated consecutive corners were collapsed (`a b b c` → `a b c`).
    pub repeated_corners_collapsed: usize,
    /// Faces dropped for having fewer than three distinct vertices (or a repeated vertex).
    pub degenerate_faces_removed: usize,
    /// Faces dropped as exact duplicates of an earlier face (either orientation).
    pub duplicate_faces_removed: usize,
    /// Faces kept although their area is zero ([`ZERO_AREA_RELATIVE`]).
    pub zero_area_faces: usize,
    /// Faces whose orientation was reversed to agree with their component.
    pub flipped_faces: usize,
    /// Connected components that are not orientable (cut open to be stored).
    pub non_orientable_components: usize,
    /// Edges cut open because the faces on both sides could not be oriented alike.
    pub cut_edges: usize,
    /// Input vertices whose faces formed several fans, split into one vertex per fan.
    pub non_manifold_vertices_split: usize,
    /// Faces on a non-manifold edge (a third face) or otherwise not attachable, added on
    /// their own copies of their vertices.
    pub detached_faces: usize,
    /// Vertices appended (fan copies and copies for detached faces).
    pub vertex_copies_added: usize,
    /// For every mesh face, the index of the input face it came from.
    #[serde(skip)]
    pub face_source: Vec<usize>,
    /// For every appended vertex `n_input + k`, the input vertex it copies.
    #[serde(skip)]
    pub vertex_source: Vec<usize>,
}

impl Repairs {
    /// True when the input was already a clean, consistently oriented manifold mesh
    /// (zero-area faces and unreferenced vertices are reported but not repairs).
    pub fn is_clean(&self) -> bool {
        self.repeated_corners_collapsed == 0
            && self.degenerate_faces_removed == 0
            && self.duplicate_faces_removed == 0
            && self.flipped_faces == 0
            && self.non_orientable_components == 0
            && self.non_manifold_vertices_split == 0
            && self.detached_faces == 0
    }

    /// True when the input was manifold (no vertex split, no face detached).
    pub fn input_was_manifold(&self) -> bool {
        self.non_manifold_vertices_split == 0 && self.detached_faces == 0
    }

    /// Human-readable list of the non-zero counts, e.g. `"2 non-manifold vertices split,
    /// 3 faces flipped"`; empty when there is nothing to report.
    pub fn summary(&self) -> String {
        let items = [
            (self.unreferenced_vertices, "unreferenced vertices"),
            (
                self.repeated_corners_collapsed,
                "faces with repeated corners collapsed",
            ),
            (self.degenerate_faces_removed, "degenerate faces removed"),
            (self.duplicate_faces_removed, "duplicate faces removed"),
            (self.zero_area_faces, "zero-area faces"),
            (
                self.flipped_faces,
                "faces flipped to a consistent orientation",
            ),
            (
                self.non_orientable_components,
                "non-orientable components (cut open)",
            ),
            (
                self.non_manifold_vertices_split,
                "non-manifold vertices split",
            ),
            (self.detached_faces, "faces on non-manifold edges detached"),
            (self.vertex_copies_added, "vertex copies appended"),
        ];
        items
            .iter()
            .filter(|(n, _)| *n > 0)
            .map(|(n, what)| format!("{n} {what}"))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// Options of [`SurfaceMesh::from_polygons_repaired`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RepairOptions {
    /// Orient faces consistently per component (otherwise a face that disagrees with a
    /// neighbour is detached, as pmp-library does).
    pub orient: bool,
}

impl Default for RepairOptions {
    fn default() -> Self {
        Self { orient: true }
    }
}

/// A fast non-cryptographic hasher for the index keys of the repair maps (the
/// multiply-rotate hash of rustc's `FxHasher`); the keys are not attacker-chosen hashes
/// of secrets, and worst-case collisions only cost time.
#[derive(Default, Clone, Copy)]
pub(super) struct IndexHasher(u64);

impl std::hash::Hasher for IndexHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_usize(&mut self, i: usize) {
        self.write_u64(i as u64);
    }
}

/// Hash map with [`IndexHasher`].
pub(super) type IndexMap<K, V> = HashMap<K, V, std::hash::BuildHasherDefault<IndexHasher>>;
/// Hash set with [`IndexHasher`].
pub(super) type IndexSet<K> =
    std::collections::HashSet<K, std::hash::BuildHasherDefault<IndexHasher>>;

/// Undirected edge key `(min, max)`.
pub(super) type EdgeKey = (usize, usize);

pub(super) fn edge_key(a: usize, b: usize) -> EdgeKey {
    (a.min(b), a.max(b))
}

/// The (up to two) active faces on an undirected edge and whether each traverses it
/// from the smaller to the larger index.
#[derive(Clone, Copy)]
pub(super) struct EdgeUse {
    pub(super) n: u8,
    pub(super) face: [usize; 2],
    pub(super) fwd: [bool; 2],
}

/// Faces per undirected edge (active faces only; a third face is ignored).
pub(super) fn edge_uses(faces: &[Vec<usize>], active: &[bool]) -> IndexMap<EdgeKey, EdgeUse> {
    let mut uses: IndexMap<EdgeKey, EdgeUse> = IndexMap::default();
    uses.reserve(faces.len() * 2);
    for (fi, f) in faces.iter().enumerate() {
        if !active[fi] {
            continue;
        }
        let n = f.len();
        for k in 0..n {
            let (a, b) = (f[k], f[(k + 1) % n]);
            let u = uses.entry(edge_key(a, b)).or_insert(EdgeUse {
                n: 0,
                face: [0; 2],
                fwd: [false; 2],
            });
            if (u.n as usize) < 2 {
                u.face[u.n as usize] = fi;
                u.fwd[u.n as usize] = a < b;
                u.n += 1;
            }
        }
    }
    uses
}

impl SurfaceMesh {
    /// Builds a mesh from any polygons, repairing what a manifold, oriented halfedge mesh
    /// cannot hold (module docs list the steps) and reporting it. Fails only on a vertex
    /// index out of range or a mesh too large for 32-bit handles.
    pub fn from_polygons_repaired<'a>(
        points: &[Vec3],
        faces: impl Iterator<Item = &'a [usize]>,
        options: &RepairOptions,
    ) -> Result<(SurfaceMesh, Repairs), MeshError> {
        let mut repairs = Repairs::default();
        let n = points.len();
        let mut clean = clean::clean_faces(n, faces, &mut repairs)?;
        repairs.zero_area_faces = clean
            .faces
            .iter()
            .filter(|f| is_zero_area_polygon(points, f))
            .count();
        let mut active = vec![true; clean.faces.len()];
        repairs.detached_faces += split::deactivate_complex_edge_faces(&clean.faces, &mut active);
        let cut = if options.orient {
            let o = orient::orient_faces(&mut clean.faces, &active);
            repairs.flipped_faces = o.flipped;
            repairs.non_orientable_components = o.non_orientable;
            repairs.cut_edges = o.cut.len();
            o.cut
        } else {
            Default::default()
        };
        let fans = loop {
            let fans = split::split_fans(&clean.faces, &active, n, &cut);
            let bad = split::directed_conflicts(&fans.faces, &active);
            if bad.is_empty() {
                break fans;
            }
            repairs.detached_faces += bad.len();
            for f in bad {
                active[f] = false;
            }
        };
        repairs.non_manifold_vertices_split = fans.split_vertices;
        let mut all_points = points.to_vec();
        let mut vertex_source = fans.copies;
        all_points.extend(vertex_source.iter().map(|&v| points[v]));
        let mut final_faces = fans.faces;
        for (fi, f) in clean.faces.iter().enumerate() {
            if !active[fi] {
                final_faces[fi] = f
                    .iter()
                    .map(|&v| {
                        vertex_source.push(v);
                        all_points.push(points[v]);
                        all_points.len() - 1
                    })
                    .collect();
            }
        }
        let mut used = vec![false; n];
        for f in &final_faces {
            for &v in f {
                if v < n {
                    used[v] = true;
                }
            }
        }
        for &v in &vertex_source {
            used[v] = true;
        }
        repairs.unreferenced_vertices = used.iter().filter(|&&u| !u).count();
        repairs.vertex_copies_added = vertex_source.len();
        let mesh = SurfaceMesh::from_faces(&all_points, &final_faces)?;
        repairs.face_source = clean.source;
        repairs.vertex_source = vertex_source;
        Ok((mesh, repairs))
    }
}
