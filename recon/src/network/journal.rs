//! The sketch journal: the tool applications of a session in order (tool, the stroke it uses by id, its
//! options), so a session can be saved, replayed, edited and shared. Replaying a journal over the same
//! strokes gives the same network bit for bit (the tools are deterministic and the handles are slot
//! indices). [`build_network`](super::build_network) returns the journal of what it applied.

use serde::{Deserialize, Serialize};

use super::build::StrokeInput;
use super::mesh::Network;
use super::tools::{
    align_curves, close_boundary, create_hole, delete_stroke, glue_borders, glue_tube,
    insert_boundary, insert_curve, mirror_curve, skin_profiles, tag_sharp, transform_network,
    AlignOptions, BoundaryOptions, CloseOptions, CurveInput, GlueOptions, HoleOptions,
    InsertOptions, SkinOptions, ToolError, TubeOptions,
};

/// The `format` value of a journal.
pub const JOURNAL_FORMAT: &str = "fires-sketch-journal";
/// The version this crate writes.
pub const JOURNAL_VERSION: &str = "1.0";

/// One tool application.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "tool", rename_all = "snake_case")]
pub enum Step {
    /// The initial boundary from a closed stroke.
    Boundary {
        /// The stroke.
        stroke: u32,
        /// Closing distance, mm.
        close_mm: f64,
        /// The stroke is mirrored first (pen mode mirror).
        #[serde(default)]
        mirror: bool,
    },
    /// Curve insertion.
    Insert {
        /// The stroke.
        stroke: u32,
        /// Thresholds.
        options: InsertOptions,
        /// The stroke is mirrored first (pen mode mirror).
        #[serde(default)]
        mirror: bool,
    },
    /// Curve delete of a whole stroke.
    Delete {
        /// The stroke.
        stroke: u32,
    },
    /// Tag a stroke's curves with a sharpness.
    Sharp {
        /// The stroke.
        stroke: u32,
        /// 0 (smooth) .. 1 (sharp).
        sharpness: f64,
    },
    /// Hole creation from a closed stroke (with or without crossings).
    Hole {
        /// The stroke.
        stroke: u32,
        /// Thresholds and solver settings.
        #[serde(default)]
        options: HoleOptions,
    },
    /// Mesh closure: a face on the boundary loop both ends of the stroke lie on.
    Close {
        /// The locating stroke (not inserted by this step).
        stroke: u32,
        /// Snapping distance.
        #[serde(default)]
        options: CloseOptions,
    },
    /// Border gluing: the marker strokes a₁ → b₁ and optionally a₂ → b₂ (not inserted).
    Glue {
        /// One or two stroke ids.
        strokes: Vec<u32>,
        /// Survivor, halves and distances.
        #[serde(default)]
        options: GlueOptions,
    },
    /// Border gluing by a tube of two faces (the thesis's construction): two strokes a₁ → b₁, a₂ → b₂,
    /// both inserted.
    Tube {
        /// The two strokes.
        strokes: [u32; 2],
        /// Half pairing and distances.
        #[serde(default)]
        options: TubeOptions,
    },
    /// Alignment of a moved object (thesis §5.3): the network's curves of stroke `reference` are
    /// matched to stroke `object`, the same curve drawn again on the moved object (not inserted), and
    /// the whole network is moved onto it.
    Align {
        /// The stroke whose curves in the network are the reference.
        reference: u32,
        /// The redrawn stroke.
        object: u32,
        /// ICP iterations after the PCA guess (0: PCA only, as in the thesis).
        #[serde(default = "default_icp_iterations")]
        icp_iterations: usize,
    },
    /// Skinning: closed profile strokes in order and two spine strokes.
    Skin {
        /// The profiles, in order along the spines.
        profiles: Vec<u32>,
        /// The two spines.
        spines: [u32; 2],
        /// Thresholds and caps.
        #[serde(default)]
        options: SkinOptions,
    },
}

fn default_icp_iterations() -> usize {
    AlignOptions::default().icp_iterations
}

/// A whole journal document.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Journal {
    /// Always [`JOURNAL_FORMAT`].
    pub format: String,
    /// `MAJOR.MINOR`.
    pub version: String,
    /// The steps in order.
    pub steps: Vec<Step>,
}

impl Default for Journal {
    fn default() -> Self {
        Journal {
            format: JOURNAL_FORMAT.into(),
            version: JOURNAL_VERSION.into(),
            steps: Vec::new(),
        }
    }
}

/// Why a journal cannot be replayed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum JournalError {
    /// Wrong format or major version.
    #[error("not a version-1 sketch journal ({0:?})")]
    NotAJournal(String),
    /// A step names a stroke that is not in the strokes.
    #[error("step {step}: stroke {stroke} is not in the strokes")]
    MissingStroke {
        /// Step number.
        step: usize,
        /// The stroke id.
        stroke: u32,
    },
    /// A step's tool refused its stroke.
    #[error("step {step}: {error}")]
    Refused {
        /// Step number.
        step: usize,
        /// The tool's error.
        error: ToolError,
    },
}

/// Replays `journal` over `strokes` from an empty network.
pub fn replay(journal: &Journal, strokes: &[StrokeInput]) -> Result<Network, JournalError> {
    if journal.format != JOURNAL_FORMAT || journal.version.split('.').next() != Some("1") {
        return Err(JournalError::NotAJournal(format!(
            "{} {}",
            journal.format, journal.version
        )));
    }
    let mut net = Network::new();
    for (step, s) in journal.steps.iter().enumerate() {
        let id = match s {
            Step::Boundary { stroke, .. }
            | Step::Insert { stroke, .. }
            | Step::Hole { stroke, .. }
            | Step::Close { stroke, .. } => *stroke,
            Step::Delete { stroke } => {
                delete_stroke(&mut net, *stroke)
                    .map_err(|error| JournalError::Refused { step, error })?;
                continue;
            }
            Step::Skin {
                profiles,
                spines,
                options,
            } => {
                let ps = profiles
                    .iter()
                    .map(|id| find(strokes, step, *id).map(curve))
                    .collect::<Result<Vec<_>, _>>()?;
                let sp = [
                    curve(find(strokes, step, spines[0])?),
                    curve(find(strokes, step, spines[1])?),
                ];
                skin_profiles(&mut net, &ps, sp, options)
                    .map_err(|error| JournalError::Refused { step, error })?;
                continue;
            }
            Step::Tube {
                strokes: ids,
                options,
            } => {
                let c1 = curve(find(strokes, step, ids[0])?);
                let c2 = curve(find(strokes, step, ids[1])?);
                glue_tube(&mut net, c1, c2, options)
                    .map_err(|error| JournalError::Refused { step, error })?;
                continue;
            }
            Step::Glue {
                strokes: ids,
                options,
            } => {
                let (Some(first), second) = (ids.first(), ids.get(1)) else {
                    return Err(JournalError::Refused {
                        step,
                        error: ToolError::BadCurve("a glue step names no stroke".into()),
                    });
                };
                let first = curve(find(strokes, step, *first)?);
                let second = second
                    .map(|id| find(strokes, step, *id))
                    .transpose()?
                    .map(curve);
                glue_borders(&mut net, first, second, options)
                    .map_err(|error| JournalError::Refused { step, error })?;
                continue;
            }
            Step::Sharp { stroke, sharpness } => {
                tag_sharp(&mut net, *stroke, *sharpness)
                    .map_err(|error| JournalError::Refused { step, error })?;
                continue;
            }
            Step::Align {
                reference,
                object,
                icp_iterations,
            } => {
                let object = find(strokes, step, *object)?;
                let reference_points: Vec<[f64; 3]> = net
                    .polylines()
                    .filter(|(_, p)| p.attrs.stroke == Some(*reference))
                    .flat_map(|(_, p)| p.points.iter().copied())
                    .collect();
                if reference_points.is_empty() {
                    return Err(JournalError::Refused {
                        step,
                        error: ToolError::BadCurve(format!(
                            "stroke {reference} has no curve in the network to align"
                        )),
                    });
                }
                let options = AlignOptions {
                    icp_iterations: *icp_iterations,
                };
                let a = align_curves(&reference_points, &object.points, &options)
                    .map_err(|error| JournalError::Refused { step, error })?;
                transform_network(&mut net, &a);
                continue;
            }
        };
        let st = strokes
            .iter()
            .find(|x| x.id == id)
            .ok_or(JournalError::MissingStroke { step, stroke: id })?;
        let mirrored = match s {
            Step::Boundary { mirror: true, .. } | Step::Insert { mirror: true, .. } => Some(
                mirror_curve(&st.points)
                    .map_err(|error| JournalError::Refused { step, error })?
                    .points,
            ),
            _ => None,
        };
        let curve = CurveInput {
            points: mirrored.as_deref().unwrap_or(&st.points),
            stroke: Some(st.id),
            sigma_mm: st.sigma_mm,
            // A mirrored curve's ends are not where the pen was.
            untracked_mm: if mirrored.is_some() {
                [0.0; 2]
            } else {
                st.untracked_mm
            },
        };
        let r = match s {
            Step::Boundary { close_mm, .. } => insert_boundary(
                &mut net,
                curve,
                &BoundaryOptions {
                    close_mm: *close_mm,
                },
            )
            .map(|_| ()),
            Step::Insert { options, .. } => insert_curve(&mut net, curve, options).map(|_| ()),
            Step::Hole { options, .. } => create_hole(&mut net, curve, options).map(|_| ()),
            Step::Close { options, .. } => close_boundary(&mut net, curve, options).map(|_| ()),
            Step::Delete { .. }
            | Step::Sharp { .. }
            | Step::Glue { .. }
            | Step::Skin { .. }
            | Step::Align { .. }
            | Step::Tube { .. } => Ok(()),
        };
        r.map_err(|error| JournalError::Refused { step, error })?;
    }
    Ok(net)
}

fn find(strokes: &[StrokeInput], step: usize, id: u32) -> Result<&StrokeInput, JournalError> {
    strokes
        .iter()
        .find(|x| x.id == id)
        .ok_or(JournalError::MissingStroke { step, stroke: id })
}

fn curve(s: &StrokeInput) -> CurveInput<'_> {
    CurveInput {
        points: &s.points,
        stroke: Some(s.id),
        sigma_mm: s.sigma_mm,
        untracked_mm: s.untracked_mm,
    }
}
