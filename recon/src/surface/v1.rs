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
//! ([`CurveKeeping::Snap`]) keeps that kink (measured on a torus network: about 20° between the faces
//! across the curves at every level, against 4° elsewhere), while the limit fit lets the surface become
//! tangent-continuous across them (2.9° across the curves and 2.7° elsewhere at K = 3, halving per level)
//! and keeps the curve vertices within about 0.05 mm of the curves there. `Snap` keeps them exactly, kink
//! included. At the first Catmull-Clark level the fit's correction is spread over the free vertices
//! ([`CatmullClarkOptions::limit_fit_spread`], below).
//!
//! **Tangent continuity across the curves** (issue #15; recon/tests/surface_v1_continuity.rs). V1's
//! surface is the Catmull-Clark limit surface of its final control mesh ([`subdivide_v1_control`]; the
//! output's vertices are its limit points). The smooth rules apply across every curve not tagged sharp, so
//! the surface is C1 there; a sharp curve gets the crease rules and keeps its crease. The measure is the
//! one-sided normal jump: each side's face normal extrapolated to the curve from the two faces of the quad
//! strip across it, O(h²) on a smooth surface, the crease angle on a crease. The dihedral angles measured
//! before (5.7° across the curves against 4.6° elsewhere, torus, K = 3) were not a crease: across the curves
//! as elsewhere they halve per level and the one-sided jump falls by a quarter. They were larger across
//! the curves because of a narrow band of higher curvature along them, from two causes:
//! 1. The limit fit moved only the curve vertices. After the interpolatory NULISSmod level the whole net
//!    lies on the surface, and lifting the curve rows alone (by 9/4 of the Catmull-Clark shrinkage at a
//!    valence-4 vertex) left a ridge along every curve. The first Catmull-Clark level now also moves the
//!    free vertices along their normals by the harmonic extension of the curve vertices' normal corrections.
//!    One-sided jump at K = 2, across the curves / elsewhere, before → after: sphere of three great circles
//!    8.35° / 5.94° → 3.19° / 2.20°; bumpy 5 × 5 grid 2.21° / 1.49° → 0.53° / 0.34°; torus 8 × 6 4.22° /
//!    2.58° → 0.93° / 0.49°. The validation's Hausdorff errors fall too (torus 0.69 → 0.34 mm, torus of
//!    hexagons 1.78 → 1.49 mm).
//! 2. The Coons patches of the basic refinement meet at an angle along the curves and the interpolatory
//!    NULISSmod level keeps their points; the Catmull-Clark levels round this within a few faces (without
//!    the NULISSmod level, the sphere reads about 1° across the curves at K = 2). This is the thesis's
//!    scheme and stays.
//!
//! At K = 2 the final faces of the coarsest networks are too coarse for the measure even away
//! from the curves (8-face sphere: 2.2° between ordinary faces), so continuity is also judged on V1's limit
//! surface itself, sampled two levels finer by plain Catmull-Clark (which leaves the limit surface as it
//! is; on the sphere that is 24 578 vertices, the resolution of FIRESV2's final level whose 0.04° the
//! same measure gives): at most 0.2° across the curves on the sphere, 0.03° on the bump grid, 0.06° on
//! the torus, against 53.13° across a sharp fold of 53.13° and 2.00° across a 2° fold put into the bump
//! grid's surface.
//! At the default K = 3 (the thesis's telephone schedule) the final level itself reads 0.79° / 0.15° /
//! 0.24° across the curves on the sphere / bump grid / torus, so the "≤ 1° at the final level"
//! holds on the output as written (K = 2 has a quarter of the vertices; the sphere's final level reads
//! 3.19° there, its limit surface the same 0.2°).

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
    /// Subdivision levels K after the basic refinement (default 3: the thesis's telephone, 1 NULISSmod
    /// and 2 Catmull-Clark levels; the final level's normals agree within 1° across the curves).
    pub levels: usize,
    /// How many of the K levels use NULISSmod (the first ones; default 1); the others use Catmull-Clark.
    pub nuliss_levels: usize,
    /// NULISSmod options.
    pub nuliss: NulissOptions,
    /// Catmull-Clark options (sharp rules, curve keeping; default keeping [`CurveKeeping::Limit`] with the
    /// fit spread over the free vertices at the first Catmull-Clark level, module doc). With `Limit`, the
    /// result's vertices are projected to their limit positions.
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
            levels: 3,
            nuliss_levels: 1,
            nuliss: NulissOptions::default(),
            catmull_clark: CatmullClarkOptions {
                keep: CurveKeeping::Limit,
                limit_fit_spread: 16,
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

/// Subdivides a refined mesh `levels` times with the V1 schedule (NULISSmod first, then Catmull-Clark),
/// and with [`CurveKeeping::Limit`] projects the vertices to their limit positions (module doc).
pub fn subdivide_v1(cm: &ControlMesh, opts: &V1Options) -> Result<ControlMesh, SurfaceError> {
    let mut cur = subdivide_v1_control(cm, opts)?;
    if opts.levels > opts.nuliss_levels && opts.catmull_clark.keep == CurveKeeping::Limit {
        let p = limit_positions(&cur, &opts.catmull_clark);
        cur.mesh.positions_mut().copy_from_slice(&p);
    }
    Ok(cur)
}

/// [`subdivide_v1`] without the final limit projection: with [`CurveKeeping::Limit`] and at least one
/// Catmull-Clark level, the control mesh whose Catmull-Clark limit surface is V1's surface (to evaluate
/// it more finely, e.g. its normals across the curves; module doc).
pub fn subdivide_v1_control(
    cm: &ControlMesh,
    opts: &V1Options,
) -> Result<ControlMesh, SurfaceError> {
    let mut cur = cm.clone();
    for level in 0..opts.levels {
        cur = if level < opts.nuliss_levels {
            nuliss_mod(&cur, &opts.nuliss)?
        } else {
            let mut cc = opts.catmull_clark;
            if level == opts.nuliss_levels {
                if !opts.keep_generated {
                    cur = without_generated(&cur);
                }
            } else {
                // The spread matters where the whole net lies on the surface (module doc); later levels
                // only fit their new curve edge points, a few hundredths of a millimetre.
                cc.limit_fit_spread = 0;
            }
            catmull_clark(&cur, &cc)
                .map_err(|e| SurfaceError::BadControlMesh(format!("Catmull-Clark: {e}")))?
        };
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
