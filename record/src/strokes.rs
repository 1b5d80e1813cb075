//! The strokes file (`strokes.json`): the curves the tracker hands to the curve network, and the one contract
//! the reconstruction reads (specified in `docs/strokes.md`).
//!
//! A stroke is one pen-down .. pen-up interval of the draw button. Its id is the number of the pen-down event in
//! the session (0, 1, ...), counted whether or not the stroke was kept, so it depends only on the button
//! stream: re-tracking a session (another tracker setting, a second pass once the world reference is known)
//! gives the same stroke the same id. Where tracking loses the pen inside a stroke the stroke keeps its id
//! and holds several [`StrokePiece`]s in time order, rather than a path invented across the gap.

use std::path::Path;

use serde::{Deserialize, Serialize};

/// The `format` value of a strokes file.
pub const STROKES_FORMAT: &str = "fires-strokes";

/// The format version this crate writes; readers accept the same major version.
pub const STROKES_VERSION: &str = "1.0";

/// Major part of [`STROKES_VERSION`].
pub const STROKES_MAJOR: u32 = 1;

/// A whole `strokes.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StrokesFile {
    /// Always [`STROKES_FORMAT`].
    pub format: String,
    /// `MAJOR.MINOR`; a reader refuses another major.
    pub version: String,
    /// Strokes in order of pen-down.
    pub strokes: Vec<Stroke>,
}

/// One drawn stroke.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stroke {
    /// Stable id: the number of this stroke's pen-down event in the session, from 0.
    pub id: u32,
    /// Pen-down host time, nanoseconds.
    pub t_start_ns: u64,
    /// Pen-up host time, nanoseconds (the session's end when the button was still held).
    pub t_end_ns: u64,
    /// Buttons held at pen-down (bit 0 = button 1, the draw button; bits 1..3 the mode buttons).
    pub buttons: u8,
    /// The stroke ends where it began (a closed loop): its end is within the closing distance of its start.
    pub closed: bool,
    /// Tracked tip samples the stroke was built from.
    pub raw_points: usize,
    /// The post-processed polyline, one piece per stretch tracked without a gap, in time order.
    pub pieces: Vec<StrokePiece>,
}

/// A stretch of a stroke tracked without a gap.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StrokePiece {
    /// Points in drawing order.
    pub points: Vec<StrokePoint>,
}

/// One point of a stroke polyline.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StrokePoint {
    /// Time at which the tip passed here, host clock, nanoseconds.
    pub t_ns: u64,
    /// Tip position in the world (left camera) frame, metres.
    pub p_m: [f64; 3],
    /// One-sigma position uncertainty, millimetres; `None` where the tracker gave none.
    pub sigma_mm: Option<f64>,
}

/// Why a strokes file cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum StrokesError {
    /// The file cannot be read or written.
    #[error("{path}: {cause}")]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// The cause.
        cause: std::io::Error,
    },
    /// The file is not JSON of the strokes schema.
    #[error("{path}: {cause}")]
    Json {
        /// The file.
        path: std::path::PathBuf,
        /// The cause.
        cause: serde_json::Error,
    },
    /// The `format` field is not [`STROKES_FORMAT`].
    #[error("format is {0:?}, expected \"fires-strokes\"")]
    NotAStrokesFile(String),
    /// The version's major is not [`STROKES_MAJOR`].
    #[error("unsupported strokes version {0:?} (this reader reads major {STROKES_MAJOR})")]
    UnsupportedVersion(String),
    /// A value the schema allows but the format forbids.
    #[error("stroke {id}: {what}")]
    Invalid {
        /// The stroke's id.
        id: u32,
        /// What is wrong.
        what: String,
    },
}

impl StrokesFile {
    /// A file of the current version holding `strokes`.
    pub fn new(strokes: Vec<Stroke>) -> Self {
        StrokesFile {
            format: STROKES_FORMAT.into(),
            version: STROKES_VERSION.into(),
            strokes,
        }
    }

    /// Parses and checks a strokes document.
    pub fn from_json(text: &[u8]) -> Result<Self, StrokesError> {
        let file: StrokesFile =
            serde_json::from_slice(text).map_err(|cause| StrokesError::Json {
                path: "strokes.json".into(),
                cause,
            })?;
        file.check()?;
        Ok(file)
    }

    /// Reads and checks `path`.
    pub fn read(path: &Path) -> Result<Self, StrokesError> {
        let text = std::fs::read(path).map_err(|cause| StrokesError::Io {
            path: path.into(),
            cause,
        })?;
        Self::from_json(&text).map_err(|e| match e {
            StrokesError::Json { cause, .. } => StrokesError::Json {
                path: path.into(),
                cause,
            },
            other => other,
        })
    }

    /// Writes `path` as pretty-printed JSON.
    pub fn write(&self, path: &Path) -> Result<(), StrokesError> {
        let text = serde_json::to_string_pretty(self).map_err(|cause| StrokesError::Json {
            path: path.into(),
            cause,
        })?;
        std::fs::write(path, text + "\n").map_err(|cause| StrokesError::Io {
            path: path.into(),
            cause,
        })
    }

    /// The stroke with id `id`.
    pub fn stroke(&self, id: u32) -> Option<&Stroke> {
        self.strokes.iter().find(|s| s.id == id)
    }

    fn check(&self) -> Result<(), StrokesError> {
        if self.format != STROKES_FORMAT {
            return Err(StrokesError::NotAStrokesFile(self.format.clone()));
        }
        let major = self.version.split('.').next().and_then(|m| m.parse().ok());
        if major != Some(STROKES_MAJOR) {
            return Err(StrokesError::UnsupportedVersion(self.version.clone()));
        }
        let mut ids = std::collections::HashSet::new();
        for s in &self.strokes {
            let invalid = |what: &str| StrokesError::Invalid {
                id: s.id,
                what: what.into(),
            };
            if !ids.insert(s.id) {
                return Err(invalid("id used twice"));
            }
            if s.t_end_ns < s.t_start_ns {
                return Err(invalid("ends before it starts"));
            }
            let points = s.pieces.iter().flat_map(|p| &p.points);
            for p in points {
                if !p.p_m.iter().all(|c| c.is_finite()) {
                    return Err(invalid("a point is not finite"));
                }
                if p.sigma_mm.is_some_and(|v| !(v.is_finite() && v >= 0.0)) {
                    return Err(invalid("an uncertainty is negative or not finite"));
                }
            }
        }
        Ok(())
    }
}

impl Stroke {
    /// All points of all pieces, in order.
    pub fn points(&self) -> impl Iterator<Item = &StrokePoint> {
        self.pieces.iter().flat_map(|p| &p.points)
    }

    /// All positions of all pieces, in order, metres.
    pub fn polyline_m(&self) -> Vec<[f64; 3]> {
        self.points().map(|p| p.p_m).collect()
    }

    /// Number of points over all pieces.
    pub fn len(&self) -> usize {
        self.pieces.iter().map(|p| p.points.len()).sum()
    }

    /// No points at all.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// How far the pen may have drawn, millimetres, before its first tracked point and after its
    /// last (the button was down, the tracker had no tip): the untracked time at that end times the
    /// speed of the [`SPEED_POINTS`] tracked points next to it (an upper bound while the pen speeds up
    /// from rest, as a stroke does). 0 when the gap is under [`UNTRACKED_GAP_NS`] (ordinary latency).
    /// The curve network widens its search for that end's curve by it (docs/network.md).
    pub fn untracked_mm(&self) -> [f64; 2] {
        let pts: Vec<&StrokePoint> = self.points().collect();
        let (Some(first), Some(last)) = (pts.first(), pts.last()) else {
            return [0.0; 2];
        };
        let speed = |ps: &[&StrokePoint]| {
            let (Some(a), Some(b)) = (ps.first(), ps.last()) else {
                return 0.0;
            };
            let len: f64 = ps
                .windows(2)
                .map(|w| {
                    let d = [0, 1, 2].map(|k| w[1].p_m[k] - w[0].p_m[k]);
                    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
                })
                .sum();
            let dt = b.t_ns.saturating_sub(a.t_ns) as f64 * 1e-9;
            if dt > 0.0 {
                len / dt
            } else {
                0.0
            }
        };
        let k = SPEED_POINTS.min(pts.len());
        let gap = |dt_ns: u64, v: f64| {
            if dt_ns < UNTRACKED_GAP_NS {
                0.0
            } else {
                dt_ns as f64 * 1e-9 * v * 1e3
            }
        };
        [
            gap(first.t_ns.saturating_sub(self.t_start_ns), speed(&pts[..k])),
            gap(
                self.t_end_ns.saturating_sub(last.t_ns),
                speed(&pts[pts.len() - k..]),
            ),
        ]
    }
}

/// Tracked points next to an end whose mean speed [`Stroke::untracked_mm`] takes.
pub const SPEED_POINTS: usize = 5;

/// A gap between the button and the first (last) tracked point shorter than this is latency, not an
/// untracked part of the stroke: three frames of a 60 Hz camera.
pub const UNTRACKED_GAP_NS: u64 = 50_000_000;
