//! `fires track --left DEV --right DEV --serial PATH --rig rig.json [--record DIR] [--out OUT_DIR]`: live
//! tracking from two cameras (the `camera` feature) and the pen's serial link until Ctrl-C; with `--record`
//! the session is written as a recording, and with `--out` (needs `--record`) it is then replayed like
//! `fires replay` (strokes, track, report with the IMU fusion).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use anyhow::Context;
use fires_host::capture::SourceOpener;
use fires_host::clock::HostClock;
use fires_host::link::SerialConfig;
use fires_host::live::{run_live, LiveConfig};
use fires_host::replay::ReplayConfig;
use fires_record::RigCalibration;

use super::replay::{replay_to_dir, ReplayArgs};

/// Arguments of `fires track`.
#[derive(Debug, clap::Args)]
pub struct TrackArgs {
    /// Left camera (camera 0, defines the world frame): /dev/videoN or N.
    #[arg(long)]
    pub left: String,
    /// Right camera: /dev/videoN or N.
    #[arg(long)]
    pub right: String,
    /// The pen's serial port (e.g. /dev/rfcomm0).
    #[arg(long)]
    pub serial: PathBuf,
    /// Rig calibration JSON as `fires calibrate` writes it.
    #[arg(long, default_value = "rig.json")]
    pub rig: PathBuf,
    /// Write the session as a recording into this directory (replayable with `fires replay`).
    #[arg(long)]
    pub record: Option<PathBuf>,
    /// After Ctrl-C, replay the recording into this directory (needs --record).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Nominal camera frame rate for the recording's metadata, hertz.
    #[arg(long, default_value_t = 30.0)]
    pub fps: f64,
    /// Stop by itself after this many seconds.
    #[arg(long)]
    pub seconds: Option<f64>,
}

#[cfg(feature = "camera")]
fn camera(device: &str) -> anyhow::Result<SourceOpener> {
    use fires_host::capture::camera::NokhwaCamera;
    use fires_host::capture::FrameSource;
    if device.starts_with('/') && !std::path::Path::new(device).exists() {
        anyhow::bail!("camera {device}: no such device");
    }
    let device = device.to_string();
    Ok(Box::new(move || {
        NokhwaCamera::open(&device).map(|c| Box::new(c) as Box<dyn FrameSource>)
    }))
}

#[cfg(not(feature = "camera"))]
fn camera(_device: &str) -> anyhow::Result<SourceOpener> {
    anyhow::bail!(
        "fires track needs the `camera` feature: build with `cargo build --release -p fires-host --features camera` (needs libv4l-dev and clang)"
    )
}

/// `fires track`: prints a JSON summary line at the end.
pub fn run(args: &TrackArgs) -> anyhow::Result<()> {
    let sources = [camera(&args.left)?, camera(&args.right)?];
    if args.out.is_some() && args.record.is_none() {
        anyhow::bail!("--out replays the recording: give --record DIR too");
    }
    let rig: RigCalibration = serde_json::from_slice(
        &std::fs::read(&args.rig)
            .with_context(|| format!("cannot read rig {}", args.rig.display()))?,
    )
    .with_context(|| format!("rig {} is not a rig calibration", args.rig.display()))?;
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = stop.clone();
        ctrlc::set_handler(move || stop.store(true, Ordering::Relaxed))
            .context("cannot install the Ctrl-C handler")?;
    }
    let replay = ReplayConfig::default();
    let cfg = LiveConfig {
        rig,
        serial: SerialConfig::pen(&args.serial),
        record: args.record.clone(),
        nominal_rate_hz: args.fps,
        blobs: replay.blobs,
        tracker: replay.tracker,
        max_duration: args.seconds.map(Duration::from_secs_f64),
    };
    eprintln!("tracking; Ctrl-C ends");
    let summary = run_live(sources, &cfg, HostClock::new(), stop)?;
    println!("{}", serde_json::to_string(&summary)?);
    if let (Some(rec), Some(out)) = (&args.record, &args.out) {
        let report = replay_to_dir(&ReplayArgs {
            recording: rec.clone(),
            out: out.clone(),
            fusion: "orientation".into(),
        })?;
        println!("{report}");
    }
    Ok(())
}
