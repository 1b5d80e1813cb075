//! FIRESV2's basic refinement: the generalised Catmull-Clark splitting topology without smoothing (FIRES
//! thesis §6.4, "basic refinement"): every n-gon gets a vertex at its centroid joined to the midpoints of
//! its edges, repeated [`TessellateOptions::levels`] times (3 by default: an n-gon becomes 16n quads and
//! each base edge 8 segments).
//!
//! Choices (the thesis leaves them open): the midpoint of a curve edge is its curve's point at the span's
//! mid-parameter (so after three levels a base edge's vertices sit at arc fractions k/8 of its curve, on
//! the polyline); every other new point is a flat average: an edge's midpoint, a face's vertex average.
//! Old vertices do not move. The curves are taken as drawn: the diffusion flow (diffusion.rs) moves the
//! interior to a fair surface afterwards.

use super::catmull_clark::build_child;
use super::control::ControlMesh;
use super::error::SurfaceError;
use crate::geometry::Vec3;

/// Options of [`tessellate`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TessellateOptions {
    /// Splitting levels (default 3: each n-gon becomes 4ⁱ⁻¹·4n = 16n quads).
    pub levels: usize,
}

impl Default for TessellateOptions {
    fn default() -> Self {
        Self { levels: 3 }
    }
}

/// One split: centroids, midpoints (on the curve for curve edges), old vertices kept.
pub fn tessellate_step(c: &ControlMesh) -> Result<ControlMesh, SurfaceError> {
    if c.mesh.has_garbage() {
        return Err(SurfaceError::BadControlMesh(
            "the mesh has deleted elements".into(),
        ));
    }
    let m = &c.mesh;
    let p = m.positions();
    let fp: Vec<Vec3> = m
        .faces()
        .map(|f| {
            let (s, k) = m
                .face_vertices(f)
                .fold((Vec3::ZERO, 0usize), |(s, k), v| (s + p[v.idx()], k + 1));
            s / k.max(1) as f64
        })
        .collect();
    let mut ep = Vec::with_capacity(m.edges_size());
    for e in m.edges() {
        let on_curve = c.span(e).map(|s| {
            c.curves
                .get(s.curve)
                .map(|cv| cv.point_at(0.5 * (s.t0 + s.t1)))
                .ok_or_else(|| {
                    SurfaceError::BadControlMesh(format!(
                        "edge tag names curve {}, which does not exist",
                        s.curve
                    ))
                })
        });
        ep.push(match on_curve {
            Some(q) => q?,
            None => {
                let (a, b) = m.edge_vertices(e);
                (p[a.idx()] + p[b.idx()]) * 0.5
            }
        });
    }
    build_child(c, p.to_vec(), ep, fp)
}

/// The V2 basic refinement: [`tessellate_step`] `opts.levels` times.
pub fn tessellate(c: &ControlMesh, opts: &TessellateOptions) -> Result<ControlMesh, SurfaceError> {
    let mut m = c.clone();
    for _ in 0..opts.levels {
        m = tessellate_step(&m)?;
    }
    Ok(m)
}
