//! Strokes in, network out, without a journal: the first closed stroke is the boundary and every other
//! stroke a curve insertion (or the tool its pen mode selects, [`PenMode`]). The thesis needs the strokes in a strict order; we do not: a stroke that
//! breaks a rule now is retried after the strokes that follow it, pass after pass, until a pass uses no
//! stroke. Each stroke that is never used is reported with the rule and the distance that failed.
//!
//! Input is plain polylines ([`StrokeInput`]), so this crate knows nothing of the tracker; a
//! `fires_record::StrokesFile` maps onto it one stroke at a time (id, `polyline_m()`, `closed`, the
//! largest `sigma_mm`).

use serde::{Deserialize, Serialize};

use super::journal::{Journal, Step};
use super::mesh::Network;
use super::tools::{
    create_hole, glue_borders, insert_boundary, insert_curve, mirror_curve, skin_profiles,
    tag_sharp, Adjustment, BoundaryOptions, CurveInput, GlueOptions, HoleOptions, InsertOptions,
    SkinOptions, ToolError,
};
use super::topology::Topology;

/// One stroke as the network builder reads it.
#[derive(Clone, Debug, PartialEq)]
pub struct StrokeInput {
    /// The stroke's id (kept on its polylines).
    pub id: u32,
    /// Points in drawing order, metres.
    pub points: Vec<[f64; 3]>,
    /// The stroke ends where it began.
    pub closed: bool,
    /// Largest one-sigma position uncertainty of its points, millimetres.
    pub sigma_mm: Option<f64>,
    /// The pen mode held at pen-down: the strokes file's `buttons >> 1` (see [`PenMode`]).
    pub mode: u8,
    /// How far the pen may have drawn before the first and after the last point without being
    /// tracked, millimetres (`fires_record::Stroke::untracked_mm`; 0 for complete strokes). Curve
    /// insertion looks that much further along the stroke's end for the curve it started or ended on
    /// ([`CurveInput::untracked_mm`]).
    pub untracked_mm: [f64; 2],
}

/// The tool a pen mode selects (the mode buttons are bits 1–3 of the strokes file's `buttons`; the
/// value is `buttons >> 1`). Documented in docs/network.md.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PenMode {
    /// 0: curve insertion (the first closed stroke is the boundary).
    Insert,
    /// 1: curve insertion, then the stroke's curves are tagged sharp (sharpness 1).
    Sharp,
    /// 2: mirroring; the mirrored closed curve is the boundary (or, after it, an insertion).
    Mirror,
    /// 3: hole creation (`create_hole`): the closed stroke bounds a hole (never the boundary).
    Hole,
    /// 4: border gluing (`glue_borders`) after every insertion and hole: a glue-mode stroke is a
    /// marker from one border to the other; when the tool needs a second marker, the next
    /// glue-mode stroke is it.
    Glue,
    /// 5: skinning (`skin_profiles`) before the gluing: the session's closed skin-mode strokes
    /// are the profiles in drawing order, its two open ones the spines.
    Skin,
    /// 6, 7: no tool.
    Other(u8),
}

impl PenMode {
    /// The names of modes 0–5, in mode order (`fires sim --mode ID=NAME`, docs/network.md).
    pub const NAMES: [&'static str; 6] = ["insert", "sharp", "mirror", "hole", "glue", "skin"];

    /// The mode of a stroke's mode value (`buttons >> 1`).
    pub fn from_mode(mode: u8) -> Self {
        match mode & 0b111 {
            0 => PenMode::Insert,
            1 => PenMode::Sharp,
            2 => PenMode::Mirror,
            3 => PenMode::Hole,
            4 => PenMode::Glue,
            5 => PenMode::Skin,
            m => PenMode::Other(m),
        }
    }
}

/// Options of [`build_network`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct BuildOptions {
    /// Curve insertion thresholds.
    pub insert: InsertOptions,
    /// Closing distance of the boundary, mm.
    pub close_mm: Option<f64>,
}

/// A stroke that was not used.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Rejected {
    /// Its id.
    pub stroke: u32,
    /// The rule it broke on its last try.
    pub rule: String,
    /// The full message, with the distance that failed.
    pub detail: String,
    /// That distance, mm, where there is one.
    pub distance_mm: Option<f64>,
}

/// What [`build_network`] did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BuildReport {
    /// The stroke used as the boundary.
    pub boundary: Option<u32>,
    /// Strokes used, in the order they were applied.
    pub used: Vec<u32>,
    /// Strokes not used.
    pub rejected: Vec<Rejected>,
    /// Trims and extensions, by stroke.
    pub adjustments: Vec<(u32, Adjustment)>,
    /// Passes over the pending strokes.
    pub passes: usize,
    /// The result's topology.
    pub topology: Topology,
    /// The tool applications made, in order; replaying it over the same strokes gives the same network.
    pub journal: Journal,
}

fn curve(s: &StrokeInput) -> CurveInput<'_> {
    CurveInput {
        points: &s.points,
        stroke: Some(s.id),
        sigma_mm: s.sigma_mm,
        untracked_mm: s.untracked_mm,
    }
}

fn rejected(stroke: u32, e: &ToolError) -> Rejected {
    Rejected {
        stroke,
        rule: e.rule().into(),
        detail: e.to_string(),
        distance_mm: e.distance_mm(),
    }
}

/// Builds the network of a drawing session.
pub fn build_network(strokes: &[StrokeInput], options: &BuildOptions) -> (Network, BuildReport) {
    let mut net = Network::new();
    let mut report = BuildReport {
        boundary: None,
        used: Vec::new(),
        rejected: Vec::new(),
        adjustments: Vec::new(),
        passes: 0,
        topology: net.topology(),
        journal: Journal::default(),
    };
    let boundary_options = BoundaryOptions {
        close_mm: options
            .close_mm
            .unwrap_or(BoundaryOptions::default().close_mm),
    };
    // Pen modes: mirrored strokes become their closed mirrored curve; modes without a tool are reported.
    let mut prepared: Vec<StrokeInput> = Vec::with_capacity(strokes.len());
    let (mut glue, mut skin): (Vec<&StrokeInput>, Vec<&StrokeInput>) = (Vec::new(), Vec::new());
    for s in strokes {
        match PenMode::from_mode(s.mode) {
            PenMode::Insert | PenMode::Sharp | PenMode::Hole => prepared.push(s.clone()),
            PenMode::Glue => glue.push(s),
            PenMode::Skin => skin.push(s),
            PenMode::Mirror => match mirror_curve(&s.points) {
                Ok(m) => prepared.push(StrokeInput {
                    points: m.points,
                    closed: true,
                    untracked_mm: [0.0; 2],
                    ..s.clone()
                }),
                Err(e) => report.rejected.push(rejected(s.id, &e)),
            },
            _ => report
                .rejected
                .push(rejected(s.id, &ToolError::NoToolForMode { mode: s.mode })),
        }
    }
    let strokes = &prepared[..];
    let mirror = |s: &StrokeInput| PenMode::from_mode(s.mode) == PenMode::Mirror;
    let hole = |s: &StrokeInput| PenMode::from_mode(s.mode) == PenMode::Hole;
    // Holes take the insertion thresholds; their other settings are the defaults.
    let hole_options = HoleOptions {
        insert: options.insert.clone(),
        ..HoleOptions::default()
    };
    let mut pending: Vec<(usize, Option<ToolError>)> = Vec::new();
    for (k, s) in strokes.iter().enumerate() {
        if report.boundary.is_none() && s.closed && !hole(s) {
            match insert_boundary(&mut net, curve(s), &boundary_options) {
                Ok(_) => {
                    report.journal.steps.push(Step::Boundary {
                        stroke: s.id,
                        close_mm: boundary_options.close_mm,
                        mirror: mirror(s),
                    });
                    report.boundary = Some(s.id);
                    report.used.push(s.id);
                    continue;
                }
                Err(e) => {
                    report.rejected.push(rejected(s.id, &e));
                    continue;
                }
            }
        }
        pending.push((k, None));
    }
    if report.boundary.is_some() {
        loop {
            report.passes += 1;
            let mut progress = false;
            pending.retain_mut(|(k, last)| {
                let s = &strokes[*k];
                if hole(s) {
                    return match create_hole(&mut net, curve(s), &hole_options) {
                        Ok(_) => {
                            report.journal.steps.push(Step::Hole {
                                stroke: s.id,
                                options: hole_options.clone(),
                            });
                            report.used.push(s.id);
                            progress = true;
                            false
                        }
                        Err(e) => {
                            *last = Some(e);
                            true
                        }
                    };
                }
                match insert_curve(&mut net, curve(s), &options.insert) {
                    Ok((r, _)) => {
                        report.journal.steps.push(Step::Insert {
                            stroke: s.id,
                            options: options.insert.clone(),
                            mirror: mirror(s),
                        });
                        if PenMode::from_mode(s.mode) == PenMode::Sharp
                            && tag_sharp(&mut net, s.id, 1.0).is_ok()
                        {
                            report.journal.steps.push(Step::Sharp {
                                stroke: s.id,
                                sharpness: 1.0,
                            });
                        }
                        report.used.push(s.id);
                        report
                            .adjustments
                            .extend(r.adjustments.iter().map(|a| (s.id, *a)));
                        progress = true;
                        false
                    }
                    Err(e) => {
                        *last = Some(e);
                        true
                    }
                }
            });
            if !progress || pending.is_empty() {
                break;
            }
        }
    }
    for (k, last) in pending {
        let e = last.unwrap_or(ToolError::BadCurve(
            "no closed stroke to bound the network".into(),
        ));
        report.rejected.push(rejected(strokes[k].id, &e));
    }
    apply_skinning(&mut net, &skin, &mut report);
    apply_gluing(&mut net, &glue, &mut report);
    report.rejected.sort_by_key(|r| r.stroke);
    report.topology = net.topology();
    (net, report)
}

/// Mode 5: the closed strokes are the profiles, the two open ones the spines (thesis §5.1.4).
fn apply_skinning(net: &mut Network, skin: &[&StrokeInput], report: &mut BuildReport) {
    if skin.is_empty() {
        return;
    }
    let (profiles, spines): (Vec<&StrokeInput>, Vec<&StrokeInput>) =
        skin.iter().partition(|s| s.closed);
    let result = match spines.as_slice() {
        [a, b] if profiles.len() >= 2 => {
            let curves: Vec<CurveInput<'_>> = profiles.iter().map(|s| curve(s)).collect();
            let options = SkinOptions::default();
            skin_profiles(net, &curves, [curve(a), curve(b)], &options).map(|_| {
                report.journal.steps.push(Step::Skin {
                    profiles: profiles.iter().map(|s| s.id).collect(),
                    spines: [a.id, b.id],
                    options,
                });
            })
        }
        _ => Err(ToolError::BadCurve(format!(
            "skinning needs at least 2 closed profile strokes and exactly 2 open spine strokes; \
             the skin-mode strokes are {} closed and {} open",
            profiles.len(),
            spines.len()
        ))),
    };
    match result {
        Ok(()) => report.used.extend(skin.iter().map(|s| s.id)),
        Err(e) => report
            .rejected
            .extend(skin.iter().map(|s| rejected(s.id, &e))),
    }
}

/// Mode 4: each marker alone, or with the next one when the tool needs a second (thesis §5.1.3).
fn apply_gluing(net: &mut Network, glue: &[&StrokeInput], report: &mut BuildReport) {
    let options = GlueOptions::default();
    let mut k = 0;
    while k < glue.len() {
        let first = glue[k];
        let mut r = glue_borders(net, curve(first), None, &options).map(|_| vec![first.id]);
        if matches!(r, Err(ToolError::NeedsSecondCurve)) {
            if let Some(second) = glue.get(k + 1) {
                r = glue_borders(net, curve(first), Some(curve(second)), &options)
                    .map(|_| vec![first.id, second.id]);
            }
        }
        match r {
            Ok(ids) => {
                k += ids.len();
                report.used.extend(&ids);
                report.journal.steps.push(Step::Glue {
                    strokes: ids,
                    options: options.clone(),
                });
            }
            Err(e) => {
                report.rejected.push(rejected(first.id, &e));
                k += 1;
            }
        }
    }
}
