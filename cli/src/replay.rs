//! `fires replay REC_DIR --out OUT_DIR`: a recording through the tracker; writes strokes.json, track.csv,
//! report.json (with accuracy figures when the recording has ground truth) and then tip_error.png, the tip
//! error over time of the vision-tracked samples (its scale is in report.json's `tip_error_plot`).
//! A damaged recording replays as far as it is whole; report.json's `damaged` says what was skipped
//! (docs/recording.md, "Damaged recordings") and each kind of damage is one warning line on stderr.

use std::path::PathBuf;

use anyhow::Context;
use fires_host::replay::bar::bar_experiment;
use fires_host::replay::floor::floor_figures;
use fires_host::replay::plot::tip_error_png;
use fires_host::replay::report::{replay_report, tip_errors};
use fires_host::replay::{replay, ReplayConfig, WorldSource};
use fires_host::session::DisplayFilter;
use fires_host::track::fusion::FusionKind;
use fires_record::report::TipErrorPlot;
use fires_record::{RecordingReader, Report};

use crate::output::{write_json, write_strokes, write_track_csv};
use crate::pipeline::surface_stage;

/// Arguments of `fires replay`.
#[derive(Debug, clap::Args)]
pub struct ReplayArgs {
    /// Recording directory (see docs/recording.md).
    pub recording: PathBuf,
    /// Output directory (created).
    #[arg(long)]
    pub out: PathBuf,
    /// Sensor fusion of the pen direction.
    #[arg(long, value_enum, default_value_t = Fusion::Orientation)]
    pub fusion: Fusion,
    /// World reference (gravity and magnetic field in the camera frame).
    #[arg(long, value_enum, default_value_t = World::Estimate)]
    pub world: World,
    /// Filter of the live display tip (`display_*` in track.csv).
    #[arg(long, value_enum, default_value_t = Display::OneEuro)]
    pub display: Display,
    /// One Euro display filter: cutoff at rest, Hz (default 0.5).
    #[arg(long)]
    pub min_cutoff: Option<f64>,
    /// One Euro display filter: cutoff increase per m/s of tip speed, Hz·s/m (default 20).
    #[arg(long)]
    pub beta: Option<f64>,
    /// One Euro display filter: cutoff of the speed estimate, Hz (default 1.5).
    #[arg(long)]
    pub d_cutoff: Option<f64>,
    /// Stop after the strokes: no curve network, surface or surface comparison.
    #[arg(long)]
    pub no_surface: bool,
}

/// `--display`: the filter behind the live display of the tip.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Display {
    /// The One Euro filter (Casiez et al., CHI 2012) tuned for a pen (the default): a few ms of lag.
    OneEuro,
    /// The thesis's causal Gaussian (300 taps, 3 passes): steady, but trails the pen by about 0.5 s.
    Thesis,
}

impl Display {
    /// The session's display filter for this choice (default parameters).
    pub fn filter(self) -> DisplayFilter {
        match self {
            Display::OneEuro => DisplayFilter::OneEuro(Default::default()),
            Display::Thesis => DisplayFilter::Thesis(Default::default()),
        }
    }
}

/// `--fusion`: which filter fuses the IMU with the vision axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Fusion {
    /// Gyro/accelerometer/magnetometer orientation filter with vision corrections (the default).
    Orientation,
    /// The thesis's 4-state Kalman filter (FIRES thesis, eqs. 4.18-4.21).
    Thesis,
}

impl Fusion {
    /// The tracker's filter for this choice.
    pub fn kind(self) -> FusionKind {
        match self {
            Fusion::Orientation => FusionKind::Orientation,
            Fusion::Thesis => FusionKind::ThesisKalman,
        }
    }

    /// The name used on the command line and in `report.json`.
    pub fn name(self) -> &'static str {
        match self {
            Fusion::Orientation => "orientation",
            Fusion::Thesis => "thesis",
        }
    }
}

/// `--world`: where the world reference comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum World {
    /// Estimated from the session, as a live run must (the default).
    Estimate,
    /// The recording's ground truth (a perfectly calibrated rig; simulated recordings only).
    Truth,
}

impl World {
    /// The replay's world source for this choice.
    pub fn source(self) -> WorldSource {
        match self {
            World::Estimate => WorldSource::Estimate,
            World::Truth => WorldSource::Truth,
        }
    }
}

/// Replays and writes the outputs; returns the report (used by `fires demo`).
pub fn replay_to_dir(args: &ReplayArgs) -> anyhow::Result<Report> {
    let reader = RecordingReader::open_salvaging(&args.recording)
        .with_context(|| format!("cannot open recording {}", args.recording.display()))?;
    let mut config = ReplayConfig::default();
    config.tracker.fusion = args.fusion.kind();
    config.world = args.world.source();
    config.strokes.display = args.display.filter();
    if let DisplayFilter::OneEuro(c) = &mut config.strokes.display {
        c.min_cutoff_hz = args.min_cutoff.unwrap_or(c.min_cutoff_hz);
        c.beta = args.beta.unwrap_or(c.beta);
        c.d_cutoff_hz = args.d_cutoff.unwrap_or(c.d_cutoff_hz);
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    if reader.meta().pen.led_positions_m.len() == 2 {
        let bar = bar_experiment(&reader)
            .with_context(|| format!("bar experiment of {}", args.recording.display()))?;
        write_json(
            &args.out.join("bar.json"),
            &serde_json::json!({
                "samples": bar.samples,
                "single_frame_samples": bar.single_frame_samples,
            }),
        )?;
        warn_damage(&reader, &bar.report.damaged);
        let report = Report::Bar(Box::new(bar.report));
        write_json(&args.out.join("report.json"), &report)?;
        return Ok(report);
    }
    let out = replay(&reader, &config)
        .with_context(|| format!("replay of {}", args.recording.display()))?;
    write_strokes(&args.out.join("strokes.json"), &out.strokes)?;
    write_track_csv(&args.out.join("track.csv"), &out.samples, &out.display_tips)?;
    let mut report = replay_report(&reader, &out, args.fusion.name())
        .with_context(|| format!("report of {}", args.recording.display()))?;
    if let Some((floor, summary)) = floor_figures(&reader, &config, &out.imu.buttons)
        .with_context(|| format!("stroke floor of {}", args.recording.display()))?
    {
        report.strokes_floor = Some(floor);
        report.strokes_floor_summary = Some(summary);
    }
    if let Some(truth) = reader.exposure_truth()? {
        let t0 = out.samples.first().map_or(0, |s| s.t_ns);
        let points: Vec<(f64, f64)> = tip_errors(&out, &truth)
            .into_iter()
            .map(|(t, e)| (t.saturating_sub(t0) as f64 / 1e9, e * 1e3))
            .collect();
        let path = args.out.join("tip_error.png");
        let scale = tip_error_png(&path, &points)?;
        report.tip_error_plot = Some(TipErrorPlot { path, scale });
    }
    if !args.no_surface {
        // The tracking's outputs are written; a surface that cannot be made is said, not fatal.
        match surface_stage(
            &reader,
            &fires_record::StrokesFile::new(out.strokes.clone()),
            &args.out,
        ) {
            Ok(stage) => {
                report.surface = stage.surface;
                report.surface_from_truth = stage.surface_from_truth;
                report.network = Some(stage.network);
            }
            Err(e) => eprintln!("warning: {}: no surface: {e:#}", args.recording.display()),
        }
    }
    warn_damage(&reader, &report.damaged);
    let report = Report::Replay(Box::new(report));
    write_json(&args.out.join("report.json"), &report)?;
    Ok(report)
}

/// One warning line on standard error per kind of damage the salvaging reader skipped.
fn warn_damage(reader: &RecordingReader, damage: &fires_record::Damage) {
    for w in &damage.warnings {
        eprintln!("warning: {}: {w}", reader.dir().display());
    }
}

/// `fires replay`: prints the report as one JSON line.
pub fn run(args: &ReplayArgs) -> anyhow::Result<()> {
    let report = replay_to_dir(args)?;
    println!("{}", serde_json::to_string(&report)?);
    Ok(())
}
