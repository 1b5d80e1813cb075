//! FIRESV1 (FIRES thesis §6.1–6.3): a curve network to a subdivision surface through its curves.
//!
//! [`base_mesh`] → [`triquadrify`] (§6.1) → [`refine`] by Coons patches (§6.2, 2 steps by default) →
//! K subdivision levels (§6.3): the first [`V1Options::nuliss_levels`] with the interpolatory NULISSmod step
//! ([`nuliss_mod`]), the rest with sharp Catmull-Clark ([`catmull_clark`], curves kept by snapping). This
//! is the thesis's hybrid (its telephone: 1 NULISSmod + 2 Catmull-Clark steps).

use super::catmull_clark::{catmull_clark, CatmullClarkOptions};
use super::control::ControlMesh;
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
    /// Catmull-Clark options (sharp rules, curve keeping).
    pub catmull_clark: CatmullClarkOptions,
}

impl Default for V1Options {
    fn default() -> Self {
        V1Options {
            triquad: TriquadOptions::default(),
            refine: RefineOptions::default(),
            levels: 2,
            nuliss_levels: 1,
            nuliss: NulissOptions::default(),
            catmull_clark: CatmullClarkOptions::default(),
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
            catmull_clark(&cur, &opts.catmull_clark)
                .map_err(|e| SurfaceError::BadControlMesh(format!("Catmull-Clark: {e}")))?
        };
    }
    Ok(cur)
}

/// FIRESV1: the surface of `net` as a quad control mesh at the final level (module doc).
pub fn reconstruct_v1(net: &Network, opts: &V1Options) -> Result<ControlMesh, SurfaceError> {
    subdivide_v1(&refined_v1(net, opts)?, opts)
}
