//! FIRESV1 (FIRES thesis §6.1–6.3): a curve network to a subdivision surface through its curves.
//!
//! [`base_mesh`] → [`triquadrify`] (§6.1) → [`refine`] by Coons patches (§6.2, 2 steps by default) →
//! K subdivision levels (§6.3): the first [`V1Options::nuliss_levels`] with the interpolatory NULISSmod step
//! ([`nuliss_mod`]), the rest with sharp Catmull-Clark ([`catmull_clark`]). This is the thesis's hybrid
//! (its telephone: 1 NULISSmod + 2 Catmull-Clark steps).
//!
//! **Curve keeping in the Catmull-Clark levels.** The default is [`CurveKeeping::Limit`] followed by a
//! projection of every vertex to its limit position: the bilinear Coons patches of neighbouring faces meet
//! at an angle along the drawn curves, and snapping the curve vertices back onto the curves at every level
//! ([`CurveKeeping::Snap`]) keeps that kink (measured on a torus network: about 20° across the curves at
//! every level, against 4° between neighbouring faces elsewhere), while the limit fit lets the surface
//! become tangent-continuous across them (under 6° at level 3 and 3° at level 4, like the faces
//! elsewhere) and keeps the curve vertices within about 0.05 mm of the curves there. `Snap` keeps them
//! exactly, kink included.

use super::catmull_clark::{catmull_clark, limit_positions, CatmullClarkOptions, CurveKeeping};
use super::control::{ControlMesh, VertexTag};
use super::error::SurfaceError;
use super::from_network::base_mesh;
use super::nuliss::{nuliss_mod, NulissOptions};
use super::refine::{refine, RefineOptions};
use super::triquad::{triquadrify, TriquadOptions};
use crate::network::Network;

/// Options of [`reconstruct_v1`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V1Options {
    /// Triquadrification options.
    pub triquad: TriquadOptions,
    /// Basic refinement options (default 2 steps).
    pub refine: RefineOptions,
    /// Subdivision levels K after the basic refinement (default 2).
    pub levels: usize,
    /// How many of the K levels use NULISSmod (the first ones; default 1); the others use Catmull-Clark.
    pub nuliss_levels: usize,
    /// NULISSmod options.
    pub nuliss: NulissOptions,
    /// Catmull-Clark options (sharp rules, curve keeping; default keeping [`CurveKeeping::Limit`], module
    /// doc). With `Limit`, the result's vertices are projected to their limit positions.
    pub catmull_clark: CatmullClarkOptions,
    /// Keep the generated polylines (triquadrification cuts, refinement centre lines) as constraints in the
    /// Catmull-Clark levels too (default false: only the network's own polylines are kept there, so the
    /// approximating levels smooth the patch interiors; NULISSmod always snaps to all of them, §6.3).
    pub keep_generated: bool,
}

impl Default for V1Options {
    fn default() -> Self {
        V1Options {
            triquad: TriquadOptions::default(),
            refine: RefineOptions::default(),
            levels: 2,
            nuliss_levels: 1,
            nuliss: NulissOptions::default(),
            catmull_clark: CatmullClarkOptions {
                keep: CurveKeeping::Limit,
                ..CatmullClarkOptions::default()
            },
            keep_generated: false,
        }
    }
}

/// The refined mesh of FIRESV1 (base mesh, triquadrification, basic refinement), before subdivision.
pub fn refined_v1(net: &Network, opts: &V1Options) -> Result<ControlMesh, SurfaceError> {
    let base = base_mesh(net)?;
    let tq = triquadrify(&base, &opts.triquad)?;
    refine(&tq, &opts.refine)
}

/// Subdivides a refined mesh `levels` times with the V1 schedule (NULISSmod first, then Catmull-Clark).
pub fn subdivide_v1(cm: &ControlMesh, opts: &V1Options) -> Result<ControlMesh, SurfaceError> {
    let mut cur = cm.clone();
    for level in 0..opts.levels {
        cur = if level < opts.nuliss_levels {
            nuliss_mod(&cur, &opts.nuliss)?
        } else {
            if level == opts.nuliss_levels && !opts.keep_generated {
                cur = without_generated(&cur);
            }
            catmull_clark(&cur, &opts.catmull_clark)
                .map_err(|e| SurfaceError::BadControlMesh(format!("Catmull-Clark: {e}")))?
        };
    }
    if opts.levels > opts.nuliss_levels && opts.catmull_clark.keep == CurveKeeping::Limit {
        let p = limit_positions(&cur, &opts.catmull_clark);
        for (q, l) in cur.mesh.positions_mut().iter_mut().zip(p) {
            *q = l;
        }
    }
    Ok(cur)
}

/// FIRESV1: the surface of `net` as a quad control mesh at the final level (module doc).
pub fn reconstruct_v1(net: &Network, opts: &V1Options) -> Result<ControlMesh, SurfaceError> {
    subdivide_v1(&refined_v1(net, opts)?, opts)
}

/// `cm` with the spans and curve tags of generated curves removed (the curves themselves stay, so curve
/// indices do not change).
pub fn without_generated(cm: &ControlMesh) -> ControlMesh {
    let generated = |c: usize| cm.curves.get(c).is_some_and(|c| c.generated);
    let mut out = cm.clone();
    for s in &mut out.edge_curve {
        if s.is_some_and(|x| generated(x.curve)) {
            *s = None;
        }
    }
    for t in &mut out.vertex_tag {
        if let VertexTag::OnCurve(p) = *t {
            if generated(p.curve) {
                *t = VertexTag::Free;
            }
        }
    }
    out
}
