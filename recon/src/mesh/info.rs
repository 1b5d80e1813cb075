//! [`mesh_info`]: counts, topology and repairs of a mesh, as one serialisable record.

use std::collections::BTreeMap;

use super::{Repairs, SurfaceMesh};

/// Most components listed one by one in [`MeshInfo::component_list`].
pub const MAX_LISTED_COMPONENTS: usize = 32;

/// Topology of one connected component (isolated vertices are not components).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct ComponentInfo {
    /// Vertices.
    pub vertices: usize,
    /// Edges.
    pub edges: usize,
    /// Faces.
    pub faces: usize,
    /// Boundary loops `b`.
    pub boundary_loops: usize,
    /// Euler characteristic χ = V − E + F.
    pub euler_characteristic: i64,
    /// Genus `g = (2 − χ − b)/2` of the (oriented, manifold) component.
    pub genus: i64,
    /// No boundary.
    pub closed: bool,
}

/// What `fires mesh info` prints.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MeshInfo {
    /// Live vertices (appended copies included).
    pub vertices: usize,
    /// Live edges.
    pub edges: usize,
    /// Live faces.
    pub faces: usize,
    /// Vertices without an edge.
    pub isolated_vertices: usize,
    /// Faces with three vertices.
    pub triangles: usize,
    /// Faces with four vertices.
    pub quads: usize,
    /// Faces with five or more vertices.
    pub polygons: usize,
    /// Largest face degree (0 without faces).
    pub max_face_degree: usize,
    /// Number of faces of each degree.
    pub face_degrees: BTreeMap<usize, usize>,
    /// Edges with a single face.
    pub boundary_edges: usize,
    /// Boundary loops.
    pub boundary_loops: usize,
    /// Connected components (through edges; isolated vertices excluded).
    pub components: usize,
    /// χ = V − E + F over the non-isolated vertices.
    pub euler_characteristic: i64,
    /// Sum over components of `(2 − χ_c − b_c)/2`.
    pub genus: i64,
    /// No boundary edge.
    pub closed: bool,
    /// The input was manifold (no vertex split, no face detached on reading).
    pub manifold: bool,
    /// The input was orientable (every component could be oriented consistently).
    pub orientable: bool,
    /// The first [`MAX_LISTED_COMPONENTS`] components, largest first.
    pub component_list: Vec<ComponentInfo>,
    /// What was repaired on reading.
    pub repairs: Repairs,
}

/// Counts and topology of `mesh`; `repairs` is what reading it changed (default: none).
/// The genus of a component with boundary is the standard `(2 − χ − b)/2`, summed over
/// components for [`MeshInfo::genus`].
pub fn mesh_info(mesh: &SurfaceMesh, repairs: &Repairs) -> MeshInfo {
    let nv = mesh.vertices_size();
    let mut parent: Vec<usize> = (0..nv).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for e in mesh.edges() {
        let (a, b) = mesh.edge_vertices(e);
        let (ra, rb) = (find(&mut parent, a.idx()), find(&mut parent, b.idx()));
        if ra != rb {
            parent[ra.max(rb)] = ra.min(rb);
        }
    }
    let mut comp_of_root: BTreeMap<usize, usize> = BTreeMap::new();
    let mut comps: Vec<ComponentInfo> = Vec::new();
    let mut comp = vec![usize::MAX; nv];
    let mut isolated = 0;
    for v in mesh.vertices() {
        if mesh.is_isolated(v) {
            isolated += 1;
            continue;
        }
        let r = find(&mut parent, v.idx());
        let c = *comp_of_root.entry(r).or_insert_with(|| {
            comps.push(ComponentInfo {
                vertices: 0,
                edges: 0,
                faces: 0,
                boundary_loops: 0,
                euler_characteristic: 0,
                genus: 0,
                closed: true,
            });
            comps.len() - 1
        });
        comp[v.idx()] = c;
        comps[c].vertices += 1;
    }
    let mut boundary_edges = 0;
    for e in mesh.edges() {
        let c = comp[mesh.edge_vertices(e).0.idx()];
        comps[c].edges += 1;
        if mesh.is_boundary_edge(e) {
            boundary_edges += 1;
            comps[c].closed = false;
        }
    }
    let mut face_degrees = BTreeMap::new();
    for f in mesh.faces() {
        *face_degrees.entry(mesh.face_valence(f)).or_insert(0) += 1;
        comps[comp[mesh.face_vertices(f).next().map_or(0, |v| v.idx())]].faces += 1;
    }
    let loops = mesh.boundary_loops();
    for l in &loops {
        comps[comp[mesh.from_vertex(l[0]).idx()]].boundary_loops += 1;
    }
    for c in &mut comps {
        c.euler_characteristic = c.vertices as i64 - c.edges as i64 + c.faces as i64;
        c.genus = (2 - c.euler_characteristic - c.boundary_loops as i64).div_euclid(2);
    }
    let genus = comps.iter().map(|c| c.genus).sum();
    let n_components = comps.len();
    comps.sort_by(|a, b| b.faces.cmp(&a.faces).then(b.vertices.cmp(&a.vertices)));
    comps.truncate(MAX_LISTED_COMPONENTS);
    let count = |pred: &dyn Fn(usize) -> bool| {
        face_degrees
            .iter()
            .filter(|(&d, _)| pred(d))
            .map(|(_, &n)| n)
            .sum()
    };
    MeshInfo {
        vertices: mesh.n_vertices(),
        edges: mesh.n_edges(),
        faces: mesh.n_faces(),
        isolated_vertices: isolated,
        triangles: count(&|d| d == 3),
        quads: count(&|d| d == 4),
        polygons: count(&|d| d >= 5),
        max_face_degree: face_degrees.keys().next_back().copied().unwrap_or(0),
        face_degrees,
        boundary_edges,
        boundary_loops: loops.len(),
        components: n_components,
        euler_characteristic: (mesh.n_vertices() - isolated) as i64 - mesh.n_edges() as i64
            + mesh.n_faces() as i64,
        genus,
        closed: boundary_edges == 0,
        manifold: repairs.input_was_manifold(),
        orientable: repairs.non_orientable_components == 0,
        component_list: comps,
        repairs: repairs.clone(),
    }
}
