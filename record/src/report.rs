//! The tracking report (`report.json`): what `fires replay`, `fires track --out` and `fires demo` say about a
//! session, with accuracy against the ground truth when the recording has one (specified in `docs/report.md`).
//!
//! One type per block, so the tools that write the report and the tests and scripts that read it share one
//! definition. Blocks that need ground truth are `None` (absent from the file) without it; a fraction over zero
//! frames is `None` (`null`), never 0.

use std::path::PathBuf;

use fires_protocol::DecoderStats;

use crate::Damage;
use serde::{Deserialize, Serialize};

/// The `format` value of a report.
pub const REPORT_FORMAT: &str = "fires-report";

/// The report version this crate writes; readers accept the same major version.
pub const REPORT_VERSION: &str = "1.0";

/// A whole `report.json`: a pen session (`kind: "replay"`) or the two-LED bar experiment (`kind: "bar"`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Report {
    /// A tracked pen session.
    Replay(Box<ReplayReport>),
    /// The bar-length accuracy experiment (FIRES thesis §7.1).
    Bar(Box<BarReport>),
}

/// The report of a tracked pen session.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReplayReport {
    /// Always [`REPORT_FORMAT`].
    pub format: String,
    /// [`REPORT_VERSION`] when written.
    pub version: String,
    /// The recording tracked (live sessions: the recording written, if any).
    pub recording: Option<PathBuf>,
    /// The direction filter: "orientation" or "thesis".
    pub fusion: String,
    /// Tracker samples (one per stereo pair, and per IMU sample while dead-reckoning).
    pub frames: usize,
    /// Samples with a tip.
    pub frames_tracked: usize,
    /// Samples with a tip from vision.
    pub frames_vision: usize,
    /// Camera frames read, per camera.
    pub camera_frames: [usize; 2],
    /// Strokes written to `strokes.json`.
    pub strokes: usize,
    /// Where the world reference came from: "truth", "configured" or "estimated".
    pub world_reference: String,
    /// The world reference estimate.
    pub world: WorldReport,
    /// The magnetometer's hard-iron calibration.
    pub magnetometer: MagReport,
    /// The pen link as decoded.
    pub link: LinkSummary,
    /// Mean processing time per tracker sample, microseconds.
    pub latency_us_per_frame: Latency,
    /// Total time per stage, milliseconds.
    pub stage_ms: StageMs,
    /// Wall time of the whole run, milliseconds.
    pub wall_ms: f64,
    /// What a damaged recording lost (empty for an intact one; docs/recording.md, "Damaged recordings").
    pub damaged: Damage,
    /// Tip accuracy against the ground truth.
    #[serde(flatten, default, skip_serializing_if = "Option::is_none")]
    pub accuracy: Option<Accuracy>,
    /// Simulated seconds per wall-clock second (with ground truth).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub realtime_factor: Option<f64>,
    /// The tip-error plot and its scale (with ground truth).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tip_error_plot: Option<TipErrorPlot>,
    // -- Display and stroke figures (issue 13, items 6 and 7). --
    /// The live display filter and, with ground truth, its lag and jitter.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub display: Option<DisplayReport>,
    /// One entry per true stroke: the tracked strokes against it (with ground truth).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strokes_vs_truth: Option<Vec<StrokeVsTruth>>,
    /// Median and worst of `strokes_vs_truth`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strokes_summary: Option<StrokesSummary>,
    /// The floor: the same figures for strokes built from the truth-labelled blobs of every frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strokes_floor: Option<Vec<StrokeVsTruth>>,
    /// Median and worst of `strokes_floor`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strokes_floor_summary: Option<StrokesSummary>,
    /// Why stereo pairs gave no vision tip, per reason.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vision_refusals: Option<VisionRefusals>,
    // -- Surface figures (issue 15, item 5). --
    /// The surface reconstructed from the tracked strokes against the true object (with ground truth).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface: Option<SurfaceReport>,
    /// The same for a surface reconstructed from the true strokes (`truth/strokes.json`): the reconstruction's
    /// own error, without the tracking's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface_from_truth: Option<SurfaceReport>,
    /// The curve network built from the tracked strokes (`network.json`), when the surface stage ran.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub network: Option<NetworkReport>,
}

/// The curve network built from a replay's strokes (docs/report.md, "Surface").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NetworkReport {
    /// Faces of the network.
    pub faces: usize,
    /// Strokes the network used.
    pub used_strokes: usize,
    /// Strokes offered (the replay's strokes with points).
    pub strokes: usize,
}

/// A reconstructed surface against the true object (docs/report.md, "Surface").
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SurfaceReport {
    /// Reconstruction method: "v1" or "v2".
    pub method: String,
    /// Vertices of the final surface mesh.
    pub vertices: usize,
    /// RMS distance of area-uniform surface samples from the true object's surface, millimetres.
    pub rms_mm: f64,
    /// 95th percentile of the same distances, millimetres.
    pub p95_mm: f64,
    /// Symmetric Hausdorff distance: the larger of the farthest surface sample from the object and the farthest
    /// sample of the true drawn region from the surface, millimetres.
    pub hausdorff_mm: f64,
    /// Diagonal of the bounding box of the true drawn region, millimetres.
    pub diag_mm: f64,
    /// `rms_mm` as a percentage of `diag_mm`.
    pub rms_pct_diag: f64,
    /// Fraction of the true drawn region's samples within 3 mm of the surface.
    pub completeness_3mm: f64,
    /// RMS distance of the network's curve points from the surface, millimetres (`null` without curve points).
    pub curve_rms_mm: Option<f64>,
}

/// The live display of the tip: its filter and, with ground truth, how well it follows the pen.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DisplayReport {
    /// "one-euro" or "thesis".
    pub filter: String,
    /// The time shift (0..600 ms, 5 ms steps) that best aligns the display with the true tip, milliseconds.
    pub lag_ms: Option<f64>,
    /// RMS distance of the display from the true tip shifted by `lag_ms`, millimetres.
    pub rms_at_lag_mm: Option<f64>,
    /// RMS distance of the display from its mean over the windows in which the true tip rests, millimetres.
    pub jitter_at_rest_mm: Option<f64>,
    /// Display samples inside those rest windows.
    pub rest_samples: usize,
    /// The same jitter of the tracker's tip before the display filter, millimetres.
    pub raw_jitter_at_rest_mm: Option<f64>,
}

/// The tracked strokes against one true stroke.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StrokeVsTruth {
    /// Id of the true stroke (`truth/strokes.json`).
    pub truth_id: u32,
    /// Ids of the tracked strokes matched to it by time overlap (empty if it was lost).
    pub tracked_ids: Vec<u32>,
    /// RMS distance of the tracked points from the true tip polyline, millimetres (`null` if lost).
    pub rms_mm: Option<f64>,
    /// Largest distance of a tracked point from the true tip polyline, millimetres (`null` if lost).
    pub max_mm: Option<f64>,
    /// Fraction of the true path's length within 3 mm of the tracked pieces (`null` for a path of no length).
    pub coverage_3mm: Option<f64>,
    /// Tracked length over true length (`null` if lost or for a true path of no length).
    pub length_ratio: Option<f64>,
}

/// The median and the worst of one stroke figure (`null` when no stroke has it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MedianWorst {
    /// Median over the strokes that have the figure.
    pub median: Option<f64>,
    /// Worst over those strokes (largest distance, smallest coverage, ratio farthest from 1).
    pub worst: Option<f64>,
}

/// Summary of a `strokes_vs_truth` list.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StrokesSummary {
    /// True strokes.
    pub true_strokes: usize,
    /// True strokes with at least one tracked stroke.
    pub kept: usize,
    /// RMS distance to the true path, millimetres.
    pub rms_mm: MedianWorst,
    /// Largest distance to the true path, millimetres.
    pub max_mm: MedianWorst,
    /// Fraction of the true path within 3 mm.
    pub coverage_3mm: MedianWorst,
    /// Tracked over true length.
    pub length_ratio: MedianWorst,
}

/// Stereo pairs and why those without a vision tip were refused (`vision_refusals`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct VisionRefusals {
    /// Camera frames not paired with the other camera (no other frame yet, or too far apart in time).
    pub unpaired_frames: usize,
    /// All stereo pairs.
    pub all: PairRefusals,
    /// The pairs in which both cameras truly see at least three LEDs (with ground truth).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub truly_visible: Option<PairRefusals>,
    /// The truly visible pairs whose left exposure falls inside a true stroke (with stroke truth).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub truly_visible_in_strokes: Option<PairRefusals>,
}

/// A set of stereo pairs: how many gave a vision tip, and what each refusal reason cost.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PairRefusals {
    /// Stereo pairs.
    pub pairs: usize,
    /// Pairs with a vision tip.
    pub vision: usize,
    /// `vision / pairs` (`null` over zero pairs).
    pub vision_fraction: Option<f64>,
    /// Pairs refused, per reason.
    pub refused: RefusalCounts,
}

/// Refused stereo pairs per reason, attributed in pipeline order (docs/report.md, "Vision refusals").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RefusalCounts {
    /// Blob detection: a camera has fewer than three blobs.
    pub blobs: usize,
    /// Correspondence: fewer than three stereo candidates.
    pub correspondence: usize,
    /// Identification: fewer than two candidates used.
    pub too_few_candidates: usize,
    /// Identification: no labelling fits the distances, the line and the cross ratio.
    pub distances: usize,
    /// Identification: every fitting labelling disagrees with the fused direction.
    pub direction_prior: usize,
    /// Identification: a mirror-symmetric labelling that no prior resolves.
    pub mirror: usize,
    /// Identification: several labellings and no prior.
    pub no_prior: usize,
    /// Identification: several labellings agree with the priors.
    pub several_agree: usize,
    /// Identification: several labellings, none agrees with the priors.
    pub none_agrees: usize,
    /// Identification: a three-LED labelling with a scaled twin, unconfirmed by continuity.
    pub twin: usize,
    /// Identification: a conflicting rival labelling.
    pub rival: usize,
    /// Identification: LEDs would trade places with the previous frame's.
    pub trading_places: usize,
    /// Identification: the labelled pen does not explain the image blobs.
    pub image_evidence: usize,
    /// The tip could not be computed.
    pub tip: usize,
    /// Fewer than four LEDs labelled before the world reference is accepted.
    pub world_not_accepted: usize,
    /// Safety: two LEDs not confirmed by a fresh prior and the predicted motion.
    pub safety_two_leds: usize,
    /// Safety: the pen's LED images overlap.
    pub safety_pen_images: usize,
    /// Safety: a blob next to a labelled blob.
    pub safety_crowded: usize,
    /// The other camera's labelled blobs could not be moved to the pair's time (no image velocity
    /// yet) and its frame was exposed too long before: labels kept, no tip.
    #[serde(default)]
    pub unaligned: usize,
}

/// The decoder's counters and the bytes read: the `link` block, and the last line of `fires decode`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct LinkSummary {
    /// Bytes read.
    pub bytes: u64,
    /// The decoder's counters.
    #[serde(flatten)]
    pub stats: DecoderStats,
}

/// Mean processing time per tracker sample, microseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Latency {
    /// Blob detection.
    pub blobs: f64,
    /// Stereo, identification, tip and fusion.
    pub track: f64,
}

/// Total time per stage, milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StageMs {
    /// Link decode and IMU timing.
    pub link: f64,
    /// Blob detection on images.
    pub blobs: f64,
    /// Stereo, identification, tip and fusion.
    pub track: f64,
    /// Stroke post-processing.
    pub strokes: f64,
}

/// Tip accuracy against the ground truth.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Accuracy {
    /// Root mean square tip error, millimetres.
    pub tip_rmse_mm: f64,
    /// 95th percentile tip error, millimetres.
    pub tip_p95_mm: f64,
    /// Fraction of tracked frames with the tip within 2 mm (`null` over no frame).
    pub frac_within_2mm: Option<f64>,
    /// The same over frames whose tip is at most 1 m from the left camera (`null` over no frame).
    pub frac_within_2mm_le_1m: Option<f64>,
    /// Frames (tracked, with truth) at most 1 m from the left camera.
    pub frames_le_1m: usize,
    /// Accepted LED labels that name the wrong LED.
    pub mislabels: usize,
    /// Accepted LED labels checked.
    pub labels_checked: usize,
}

/// Where the world reference came from and, when it was estimated and the recording has ground truth, how
/// far the estimate is from the truth.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct WorldReport {
    /// "truth", "configured" or "estimated".
    pub source: String,
    /// Seconds from the first IMU sample to the first accepted estimate.
    pub accepted_after_s: Option<f64>,
    /// Axis pairs behind the final estimate (inliers / all).
    pub pairs: Option<[usize; 2]>,
    /// RMS residual of the final fit, degrees.
    pub residual_rms_deg: Option<f64>,
    /// Standard deviation of the worst-determined axis of the final fit, degrees.
    pub worst_axis_sigma_deg: Option<f64>,
    /// Angle between the estimated and the true "up", degrees.
    pub up_error_deg: Option<f64>,
    /// Angle between the estimated and the true magnetic north (horizontal), degrees.
    pub heading_error_deg: Option<f64>,
}

/// The magnetometer's hard-iron calibration (in the readings' unit, microtesla).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MagReport {
    /// The session turned the pen enough to calibrate the offset.
    pub calibrated: bool,
    /// The offset found.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hard_iron: Option<[f64; 3]>,
    /// Field magnitude after removing the offset.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub field: Option<f64>,
    /// Standard deviation of the offset along its worst direction, as a fraction of the field.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma_of_field: Option<f64>,
    /// Readings behind the fit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub samples: Option<usize>,
    /// Distance of the offset from the true one (with ground truth).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hard_iron_error: Option<f64>,
}

/// A written plot of the tip error over time.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TipErrorPlot {
    /// The PNG file.
    pub path: PathBuf,
    /// Its axes.
    pub scale: PlotScale,
}

/// The scale of a written plot.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PlotScale {
    /// The x axis spans 0..x_max_s seconds.
    pub x_max_s: f64,
    /// One vertical grid line every x_tick_s seconds.
    pub x_tick_s: f64,
    /// The y axis spans 0..y_max_mm millimetres (larger errors are drawn orange, on the top edge).
    pub y_max_mm: f64,
    /// One horizontal grid line every y_tick_mm millimetres.
    pub y_tick_mm: f64,
    /// Points drawn.
    pub points: usize,
}

/// The report of the bar experiment: the length between two LEDs, measured per frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BarReport {
    /// Always [`REPORT_FORMAT`].
    pub format: String,
    /// [`REPORT_VERSION`] when written.
    pub version: String,
    /// The recording measured.
    pub recording: PathBuf,
    /// The temporal filter behind the headline figures.
    pub bar_smoothing: BarSmoothing,
    /// What a damaged recording lost (empty for an intact one).
    pub damaged: Damage,
    /// The headline figures: midpoint triangulation.
    #[serde(flatten)]
    pub headline: BarMethod,
    /// Midpoint triangulation (FIRES thesis eqs. 4.1-4.4).
    pub method_midpoint: BarMethod,
    /// Linear (DLT) triangulation.
    pub method_linear: BarMethod,
    /// The normal-equations triangulation.
    pub method_normal_equations: BarMethod,
}

/// Bar figures of one triangulation method: filtered, and per frame.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BarMethod {
    /// From the filtered LED positions.
    #[serde(flatten)]
    pub filtered: BarFigures,
    /// From each frame alone.
    pub single_frame: BarFigures,
}

/// Bar accuracy figures.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BarFigures {
    /// Nominal bar length from the recording's pen geometry, millimetres.
    pub bar_nominal_mm: f64,
    /// Frames measured.
    pub bar_frames: usize,
    /// Frames measured at most 1 m from the left camera.
    pub bar_frames_le_1m: usize,
    /// Fraction of those within ±2 mm of the nominal length (`null` over no frame).
    pub bar_frac_within_2mm_le_1m: Option<f64>,
    /// Fraction of all measured frames within ±2 mm (`null` over no frame).
    pub bar_frac_within_2mm: Option<f64>,
    /// RMS length error over frames at most 1 m away, millimetres.
    pub bar_rmse_mm_le_1m: f64,
}

/// Temporal filter of the LED positions used for the headline bar figure.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct BarSmoothing {
    /// Half width of the window around each frame, nanoseconds.
    pub half_window_ns: u64,
    /// Fewest frames in the window for a fit (else the frame keeps its single-frame length).
    pub min_frames: usize,
}

impl Default for BarSmoothing {
    fn default() -> Self {
        // ±40 ms: 9 frames at 100 Hz; a minimum-jerk hand move changes curvature far more slowly.
        BarSmoothing {
            half_window_ns: 40_000_000,
            min_frames: 5,
        }
    }
}

/// Why a report cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// Not JSON of the report schema.
    #[error("report: {0}")]
    Json(#[from] serde_json::Error),
    /// Another format or major version.
    #[error("report: format {format:?} version {version:?}, expected \"fires-report\" major 1")]
    Unsupported {
        /// The `format` found.
        format: String,
        /// The `version` found.
        version: String,
    },
}

impl Report {
    /// Parses and checks a report.
    pub fn from_json(text: &[u8]) -> Result<Self, ReportError> {
        let report: Report = serde_json::from_slice(text)?;
        let (format, version) = match &report {
            Report::Replay(r) => (&r.format, &r.version),
            Report::Bar(r) => (&r.format, &r.version),
        };
        if format != REPORT_FORMAT || version.split('.').next() != Some("1") {
            return Err(ReportError::Unsupported {
                format: format.clone(),
                version: version.clone(),
            });
        }
        Ok(report)
    }
}
