//! An [`EditSpec`] resolved against a mesh: the region of interest (ROI), its fixed ring,
//! anchors and handles in a compact local numbering shared by every method.
//!
//! Local vertices are the ROI followed by the *ring* (vertices outside the ROI adjacent to
//! it). Ring vertices never move (they are outside the ROI) and are hard constraints for
//! every method. User anchors inside the ROI are hard for the hard-constraint methods and
//! soft (weighted) for Laplacian surface editing. Every ROI vertex has its full 1-ring in
//! the local set, so every per-vertex stencil of an ROI vertex is local.
//!
//! A handle given as explicit positions is resolved to its best-fit similarity (its entry in
//! [`EditProblem::spec_transforms`]) plus a [`HandleShape`]: the non-rigid residual and the
//! per-vertex local frame changes ([`super::frames`]). Moving such a handle by a transform
//! `S` places the residual shape by `S`; with the specification's own transform the handle
//! lands on the given positions (to round-off).

use super::frames::{handle_shape, HandleShape};
use super::similarity::Similarity;
use super::spec::{EditSpec, HandleSpec, Select};
use super::EditError;
use crate::geometry::Vec3;
use crate::mesh::{SurfaceMesh, Vertex};
use crate::operators::triangles;

/// Marks "not a local vertex" in [`EditProblem::local`].
pub const NOT_LOCAL: usize = usize::MAX;

/// What a local vertex is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// A free ROI vertex.
    Free,
    /// A user anchor inside the ROI (fixed at rest).
    Anchor,
    /// Outside the ROI, adjacent to it (fixed at rest, always hard).
    Ring,
    /// A vertex of handle `k`.
    Handle(usize),
}

/// One resolved handle.
#[derive(Debug, Clone)]
pub struct HandleSet {
    /// Local indices of its vertices.
    pub vertices: Vec<usize>,
    /// Soft-constraint weight.
    pub weight: f64,
    /// Whether its deformation gradient is constrained (implicit editing).
    pub fix_gradient: bool,
    /// Rest centroid (the default fixed point of its transform).
    pub centroid: Vec3,
    /// For a handle given as explicit positions: targets, residual and local frames.
    pub shape: Option<HandleShape>,
}

/// The ROI, ring, anchors and handles of an edit in local numbering.
#[derive(Debug, Clone)]
pub struct EditProblem {
    /// Local → global vertex index.
    pub global: Vec<usize>,
    /// Global → local index, [`NOT_LOCAL`] outside.
    pub local: Vec<usize>,
    /// Number of ROI vertices (local indices `0..n_roi`; the ring follows).
    pub n_roi: usize,
    /// Rest positions of the local vertices.
    pub rest: Vec<Vec3>,
    /// Role of each local vertex.
    pub role: Vec<Role>,
    /// Local 1-ring of each local vertex (complete for ROI vertices).
    pub neighbors: Vec<Vec<usize>>,
    /// Local triangles with at least one ROI vertex (orientation of the mesh).
    pub faces: Vec<[usize; 3]>,
    /// The handles, in specification order.
    pub handles: Vec<HandleSet>,
    /// Soft-constraint weight of anchors.
    pub anchor_weight: f64,
    /// The transforms given in the specification (one per handle; the best-fit similarity
    /// for a handle given as positions).
    pub spec_transforms: Vec<Similarity>,
    /// Per local vertex: the residual offset of a positions handle's vertex (zero elsewhere);
    /// a handle vertex's target under `S` is `S(rest + offset)`.
    pub offset: Vec<Vec3>,
}

impl EditProblem {
    /// Resolves `spec` on a triangle mesh without garbage.
    pub fn new(mesh: &SurfaceMesh, spec: &EditSpec) -> Result<Self, EditError> {
        let tris = triangles(mesh)?;
        let n = mesh.vertices_size();
        let roi = spec.roi.resolve(mesh)?;
        if roi.is_empty() {
            return Err(EditError::EmptySelection("roi".into()));
        }
        let mut in_roi = vec![false; n];
        for &i in &roi {
            in_roi[i] = true;
        }
        let mut local = vec![NOT_LOCAL; n];
        let mut global = roi.clone();
        for (k, &g) in roi.iter().enumerate() {
            local[g] = k;
        }
        let n_roi = roi.len();
        for &g in &roi {
            for w in mesh.vertex_vertices(Vertex::new(g)) {
                if local[w.idx()] == NOT_LOCAL {
                    local[w.idx()] = global.len();
                    global.push(w.idx());
                }
            }
        }
        let mut role: Vec<Role> = (0..global.len())
            .map(|k| if k < n_roi { Role::Free } else { Role::Ring })
            .collect();
        if let Some(sel) = &spec.anchors {
            let anchors = sel.resolve(mesh)?;
            if anchors.is_empty() {
                return Err(EditError::EmptySelection("anchors".into()));
            }
            for g in anchors {
                let l = local[g];
                if l != NOT_LOCAL && l < n_roi {
                    role[l] = Role::Anchor;
                }
            }
        }
        let mut handles = Vec::with_capacity(spec.handles.len());
        let mut spec_transforms = Vec::with_capacity(spec.handles.len());
        let mut pending = Vec::new();
        for (h, hs) in spec.handles.iter().enumerate() {
            let verts = hs.select.resolve(mesh)?;
            if verts.is_empty() {
                return Err(EditError::EmptySelection(format!("handle {h}")));
            }
            if !(hs.weight.is_finite() && hs.weight > 0.0) {
                return Err(EditError::BadTransform {
                    handle: h,
                    reason: "weight must be a finite number > 0".into(),
                });
            }
            let mut lv = Vec::with_capacity(verts.len());
            let mut centroid = Vec3::ZERO;
            for &g in &verts {
                let l = local[g];
                if l == NOT_LOCAL || l >= n_roi {
                    return Err(EditError::HandleOutsideRoi {
                        handle: h,
                        vertex: g,
                    });
                }
                match role[l] {
                    Role::Anchor => {
                        return Err(EditError::HandleIsAnchor {
                            handle: h,
                            vertex: g,
                        })
                    }
                    Role::Handle(o) => {
                        return Err(EditError::HandlesOverlap {
                            first: o,
                            second: h,
                            vertex: g,
                        })
                    }
                    _ => {}
                }
                role[l] = Role::Handle(h);
                lv.push(l);
                centroid += mesh.position(Vertex::new(g));
            }
            centroid = centroid / verts.len() as f64;
            match ordered_positions(hs, &verts, h)? {
                Some(pos) => {
                    pending.push((h, pos));
                    spec_transforms.push(Similarity::identity());
                }
                None => spec_transforms.push(hs.transform.to_similarity(centroid, h)?),
            }
            handles.push(HandleSet {
                vertices: lv,
                weight: hs.weight,
                fix_gradient: hs.fix_gradient,
                centroid,
                shape: None,
            });
        }
        if !(spec.anchor_weight.is_finite() && spec.anchor_weight > 0.0) {
            return Err(EditError::Spec(
                "anchor_weight must be a finite number > 0".into(),
            ));
        }
        if !role.iter().any(|r| matches!(r, Role::Ring | Role::Anchor)) {
            return Err(EditError::NothingFixed);
        }
        let rest: Vec<Vec3> = global.iter().map(|&g| mesh.positions()[g]).collect();
        let neighbors: Vec<Vec<usize>> = global
            .iter()
            .map(|&g| {
                mesh.vertex_vertices(Vertex::new(g))
                    .map(|w| local[w.idx()])
                    .filter(|&l| l != NOT_LOCAL)
                    .collect()
            })
            .collect();
        let faces = tris
            .iter()
            .filter(|t| t.iter().any(|&g| in_roi[g]))
            .map(|t| t.map(|g| local[g]))
            .collect::<Vec<_>>();
        let mut offset = vec![Vec3::ZERO; global.len()];
        for (h, pos) in pending {
            let hs = &mut handles[h];
            let (fit, shape) = handle_shape(&hs.vertices, pos, &rest, &neighbors, &faces, h)?;
            for (&l, &o) in hs.vertices.iter().zip(&shape.offset) {
                offset[l] = o;
            }
            spec_transforms[h] = fit;
            hs.shape = Some(shape);
        }
        Ok(Self {
            global,
            local,
            n_roi,
            rest,
            role,
            neighbors,
            faces,
            handles,
            anchor_weight: spec.anchor_weight,
            spec_transforms,
            offset,
        })
    }

    /// Number of local vertices (ROI + ring).
    pub fn len(&self) -> usize {
        self.global.len()
    }

    /// True when there are no local vertices (never, for a resolved problem).
    pub fn is_empty(&self) -> bool {
        self.global.is_empty()
    }

    /// True for a local vertex inside the ROI.
    pub fn in_roi(&self, l: usize) -> bool {
        l < self.n_roi
    }

    /// True for a vertex with a hard position constraint in the hard-constraint methods
    /// (ring, anchors, handles).
    pub fn is_constrained(&self, l: usize) -> bool {
        !matches!(self.role[l], Role::Free)
    }

    /// Local indices of all hard-constrained vertices (ring, anchors, handles), ascending.
    pub fn constrained(&self) -> Vec<usize> {
        (0..self.len())
            .filter(|&l| self.is_constrained(l))
            .collect()
    }

    /// Target position of every local vertex under the handle transforms (rest elsewhere).
    pub fn targets(&self, transforms: &[Similarity]) -> Result<Vec<Vec3>, EditError> {
        self.check_transforms(transforms)?;
        Ok((0..self.len())
            .map(|l| match self.role[l] {
                Role::Handle(h) => self.handle_target(l, h, self.rest[l], transforms),
                _ => self.rest[l],
            })
            .collect())
    }

    /// Target of handle `h`'s local vertex `l` placed at `x` (its rest position, or a
    /// displaced one) under the handle transforms: `S_h(x + offset_l)`.
    pub fn handle_target(&self, l: usize, h: usize, x: Vec3, transforms: &[Similarity]) -> Vec3 {
        transforms[h].apply(x + self.offset[l])
    }

    /// Fails unless there is one transform per handle.
    pub fn check_transforms(&self, transforms: &[Similarity]) -> Result<(), EditError> {
        if transforms.len() != self.handles.len() {
            return Err(EditError::TransformCount {
                expected: self.handles.len(),
                got: transforms.len(),
            });
        }
        Ok(())
    }

    /// Writes local positions into a copy of the full mesh positions.
    pub fn scatter(&self, mesh_positions: &[Vec3], local_positions: &[Vec3]) -> Vec<Vec3> {
        let mut out = mesh_positions.to_vec();
        for (l, &g) in self.global.iter().enumerate() {
            out[g] = local_positions[l];
        }
        out
    }

    /// Mean length of the edges between local vertices with an ROI end.
    pub fn mean_edge_length(&self) -> f64 {
        let (mut s, mut c) = (0.0, 0usize);
        for i in 0..self.n_roi {
            for &j in &self.neighbors[i] {
                s += self.rest[i].distance(self.rest[j]);
                c += 1;
            }
        }
        if c == 0 {
            1.0
        } else {
            s / c as f64
        }
    }
}

/// A handle's explicit positions in the order of its resolved (ascending) vertices, or
/// `None` for a transform handle. With `{"vertices": [...]}` the positions follow the listed
/// order; otherwise ascending vertex index.
fn ordered_positions(
    hs: &HandleSpec,
    verts: &[usize],
    h: usize,
) -> Result<Option<Vec<Vec3>>, EditError> {
    let Some(pos) = &hs.positions else {
        return Ok(None);
    };
    let bad = |reason: String| EditError::BadPositions { handle: h, reason };
    if !hs.transform.is_identity() {
        return Err(bad("give either a transform or positions, not both".into()));
    }
    if let Some(k) = pos.iter().position(|p| p.iter().any(|x| !x.is_finite())) {
        return Err(bad(format!("positions[{k}] is not finite")));
    }
    let listed: &[usize] = match &hs.select {
        Select::Vertices(list) => list,
        _ => verts,
    };
    if pos.len() != listed.len() {
        return Err(bad(format!(
            "{} positions for {} selected vertices",
            pos.len(),
            listed.len()
        )));
    }
    let mut by_vertex = std::collections::HashMap::with_capacity(listed.len());
    for (&g, p) in listed.iter().zip(pos) {
        if by_vertex.insert(g, Vec3::from_array(*p)).is_some() {
            return Err(bad(format!("vertex {g} is listed twice")));
        }
    }
    verts
        .iter()
        .map(|g| {
            by_vertex
                .get(g)
                .copied()
                .ok_or_else(|| bad(format!("vertex {g} has no position")))
        })
        .collect::<Result<Vec<_>, _>>()
        .map(Some)
}
