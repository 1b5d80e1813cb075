//! An [`EditSpec`] resolved against a mesh: the region of interest (ROI), its fixed ring,
//! anchors and handles in a compact local numbering shared by every method.
//!
//! Local vertices are the ROI followed by the *ring* (vertices outside the ROI adjacent to
//! it). Ring vertices never move (they are outside the ROI) and are hard constraints for
//! every method. User anchors inside the ROI are hard for the hard-constraint methods and
//! soft (weighted) for Laplacian surface editing. Every ROI vertex has its full 1-ring in
//! the local set, so every per-vertex stencil of an ROI vertex is local.

use super::similarity::Similarity;
use super::spec::EditSpec;
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
    /// The transforms given in the specification (one per handle).
    pub spec_transforms: Vec<Similarity>,
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
            spec_transforms.push(hs.transform.to_similarity(centroid, h)?);
            handles.push(HandleSet {
                vertices: lv,
                weight: hs.weight,
                fix_gradient: hs.fix_gradient,
                centroid,
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
        let neighbors = global
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
            .collect();
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
                Role::Handle(h) => transforms[h].apply(self.rest[l]),
                _ => self.rest[l],
            })
            .collect())
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
