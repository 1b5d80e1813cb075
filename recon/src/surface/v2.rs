//! FIRESV2 (FIRES thesis §6.4, Fig. 3.2b): the network's faces as polygons ([`base_mesh`]), the
//! Catmull-Clark-topology tessellation with the curve vertices on the polylines ([`tessellate`]), the
//! two-step surface-diffusion flow under the curve constraints ([`surface_diffusion`]), then Catmull-Clark
//! with sharp rules, keeping the curves, to the final resolution ([`catmull_clark`]).
//!
//! New polylines are never generated (§6.4.2: the flow moves the interior points; the tessellation's
//! flat averages are its start). The number of Catmull-Clark levels is chosen, unless given, as the
//! largest (at most [`V2Options::max_levels`]) that keeps the result under [`V2Options::max_vertices`].

use super::catmull_clark::{
    catmull_clark_n, interpolating_control, limit_positions, CatmullClarkOptions, CurveKeeping,
};
use super::control::ControlMesh;
use super::diffusion::{surface_diffusion, DiffusionOptions};
use super::error::SurfaceError;
use super::from_network::base_mesh;
use super::tessellate::{tessellate, TessellateOptions};
use crate::network::Network;

/// Options of [`reconstruct_v2`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V2Options {
    /// The basic refinement (default 3 levels: 16n quads per n-gon).
    pub tessellate: TessellateOptions,
    /// The surface-diffusion flow: the thesis's defaults (λ = 1, σ = 0.2, τ = 0.5 in the network's grid
    /// units, 10 outer iterations of 5 inner steps; [`diffusion_options`] sets the grid) but with hard
    /// curve constraints, the digest's recommendation for a surface that interpolates the network (soft
    /// λ = 1 lets the curve vertices drift: when this was chosen, on a bumpy 5 × 5 grid 0.62 mm
    /// Hausdorff error and 0.79° across the curves, against 0.45 mm and 0.13° with hard constraints).
    pub diffusion: DiffusionOptions,
    /// The final subdivision's rules and curve keeping (default [`CurveKeeping::Limit`]: tangent-continuous
    /// across the smooth curves, and through them after the final limit projection).
    pub subdivision: CatmullClarkOptions,
    /// Catmull-Clark levels after the flow; `None` chooses them from [`Self::max_vertices`].
    pub levels: Option<usize>,
    /// Vertex budget of the automatic level choice (default 60 000).
    pub max_vertices: usize,
    /// Most levels the automatic choice takes (default 3).
    pub max_levels: usize,
    /// Gauss-Seidel sweeps making the final surface's limit interpolate the flow's Refined Mesh before the
    /// subdivision ([`interpolating_control`]; default 24, 0 = subdivide the Refined Mesh as it is, which
    /// shrinks it by the usual Catmull-Clark amount).
    pub interpolate_sweeps: usize,
}

impl Default for V2Options {
    fn default() -> Self {
        Self {
            tessellate: TessellateOptions::default(),
            diffusion: DiffusionOptions {
                hard: true,
                ..DiffusionOptions::default()
            },
            subdivision: CatmullClarkOptions {
                keep: CurveKeeping::Limit,
                ..CatmullClarkOptions::default()
            },
            levels: None,
            max_vertices: 60_000,
            max_levels: 3,
            interpolate_sweeps: 24,
        }
    }
}

/// FIRESV2 from a curve network (module docs).
pub fn reconstruct_v2(net: &Network, opts: &V2Options) -> Result<ControlMesh, SurfaceError> {
    reconstruct_v2_from_base(&base_mesh(net)?, opts)
}

/// FIRESV2 from a base control mesh (the network's faces as polygons, curve edges tagged).
pub fn reconstruct_v2_from_base(
    base: &ControlMesh,
    opts: &V2Options,
) -> Result<ControlMesh, SurfaceError> {
    let refined = v2_refined(base, opts)?;
    let levels = opts
        .levels
        .unwrap_or_else(|| auto_levels(&refined, opts.max_vertices, opts.max_levels));
    let control = if opts.interpolate_sweeps > 0 && levels > 0 {
        interpolating_control(&refined, &opts.subdivision, opts.interpolate_sweeps)
    } else {
        refined
    };
    subdivide(&control, levels, &opts.subdivision)
}

/// The Refined Mesh of V2: tessellation and flow, before the final subdivision.
pub fn v2_refined(base: &ControlMesh, opts: &V2Options) -> Result<ControlMesh, SurfaceError> {
    let t = tessellate(base, &opts.tessellate)?;
    surface_diffusion(&t, &diffusion_options(base, opts))
}

/// The flow's options with its grid length set to the base mesh's mean edge length (the network's grid;
/// [`DiffusionOptions::grid`]) unless `opts` gives one.
pub fn diffusion_options(base: &ControlMesh, opts: &V2Options) -> DiffusionOptions {
    let m = &base.mesh;
    let mean_edge = m.edges().map(|e| m.edge_length(e)).sum::<f64>() / m.n_edges().max(1) as f64;
    DiffusionOptions {
        grid: opts.diffusion.grid.or(Some(mean_edge).filter(|l| *l > 0.0)),
        ..opts.diffusion
    }
}

/// `levels` Catmull-Clark steps; with [`CurveKeeping::Limit`] the result is moved to its limit positions
/// (so its curve vertices lie on the curves).
pub fn subdivide(
    c: &ControlMesh,
    levels: usize,
    opts: &CatmullClarkOptions,
) -> Result<ControlMesh, SurfaceError> {
    let mut m = catmull_clark_n(c, levels, opts)?;
    if opts.keep == CurveKeeping::Limit && levels > 0 {
        let lim = limit_positions(&m, opts);
        m.mesh.positions_mut().copy_from_slice(&lim);
    }
    Ok(m)
}

/// The most Catmull-Clark levels (≤ `max_levels`) keeping `V + E + F`-style growth under `max_vertices`.
fn auto_levels(c: &ControlMesh, max_vertices: usize, max_levels: usize) -> usize {
    let (mut v, mut e, mut f) = (c.mesh.n_vertices(), c.mesh.n_edges(), c.mesh.n_faces());
    let mut k = 0;
    while k < max_levels {
        let (v2, e2, f2) = (v + e + f, 2 * e + 4 * f, 4 * f);
        if v2 > max_vertices {
            break;
        }
        (v, e, f) = (v2, e2, f2);
        k += 1;
    }
    k
}
