//! `fires track --left DEV --right DEV --serial PATH --rig rig.json [--record DIR] [--out OUT_DIR]`: live
//! tracking from two cameras (the `camera` feature) and the pen's serial link until Ctrl-C, with the IMU fusion
//! and button-delimited strokes as in `fires replay`; with `--record` the session is also written as a
//! recording, and with `--out` its strokes.json, track.csv and report.json (the session summary) are written.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use anyhow::Context;
use fires_host::capture::SourceOpener;
use fires_host::clock::HostClock;
use fires_host::link::SerialConfig;
use fires_host::live::{run_live, LiveConfig, LiveOutput, DEFAULT_REORDER_NS};
use fires_host::replay::run::tip_axis_for;
use fires_host::replay::ReplayConfig;
use fires_record::{FrameContent, RigCalibration};

use crate::output::{write_json, write_strokes, write_track_csv};

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
    /// Write strokes.json, track.csv and report.json into this directory when the session ends.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Nominal camera frame rate for the recording's metadata, hertz.
    #[arg(long, default_value_t = 30.0)]
    pub fps: f64,
    /// Stop by itself after this many seconds.
    #[arg(long)]
    pub seconds: Option<f64>,
    /// World reference (gravity and magnetic field in the camera frame) of this rig: the
    /// report.json of an earlier `fires track --out` (its `world`) or a `{up, magnetic, gravity}`
    /// object. Without it the first seconds of the session estimate it.
    #[arg(long)]
    pub world: Option<PathBuf>,
}

/// Reads a world reference from `path`: a report with a `world` field, or the reference itself.
fn read_world_reference(
    path: &std::path::Path,
) -> anyhow::Result<fires_host::track::fusion::WorldReference> {
    let text = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    let value: serde_json::Value =
        serde_json::from_slice(&text).with_context(|| format!("{} is not JSON", path.display()))?;
    let world = match value.get("world") {
        Some(w) if w.is_object() => w.clone(),
        _ => value,
    };
    let world: fires_host::track::fusion::WorldReference = serde_json::from_value(world)
        .with_context(|| {
            format!(
                "{} holds no world reference (up, magnetic, gravity)",
                path.display()
            )
        })?;
    let finite = world
        .up
        .iter()
        .chain(&world.magnetic)
        .chain(std::iter::once(&world.gravity))
        .all(|v| v.is_finite());
    let up_norm = world.up.iter().map(|v| v * v).sum::<f64>().sqrt();
    if !finite || up_norm < 0.5 || world.gravity <= 0.0 {
        anyhow::bail!("{}: the world reference is degenerate", path.display());
    }
    Ok(world)
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
        "fires track needs the `camera` feature: build with `cargo build --release -p fires-cli --features camera` (needs libv4l-dev and clang)"
    )
}

/// `fires track`: prints a JSON summary line at the end.
pub fn run(args: &TrackArgs) -> anyhow::Result<()> {
    let sources = [camera(&args.left)?, camera(&args.right)?];
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
    let mut replay = ReplayConfig::default();
    // Live cameras are webcams: the tip's axis as for a recording of image cameras.
    replay.tracker.direction_source = tip_axis_for(FrameContent::Images);
    replay.tracker.world = args
        .world
        .as_deref()
        .map(read_world_reference)
        .transpose()?;
    let cfg = LiveConfig {
        rig,
        serial: SerialConfig::pen(&args.serial),
        record: args.record.clone(),
        nominal_rate_hz: args.fps,
        blobs: replay.blobs,
        tracker: replay.tracker,
        max_duration: args.seconds.map(Duration::from_secs_f64),
        strokes: replay.strokes,
        reorder_ns: DEFAULT_REORDER_NS,
    };
    eprintln!("tracking; Ctrl-C ends");
    let out = run_live(sources, &cfg, HostClock::new(), stop)?;
    println!("{}", serde_json::to_string(&out.summary)?);
    if let Some(dir) = &args.out {
        write_live_outputs(dir, &out)?;
    }
    Ok(())
}

/// strokes.json, track.csv and report.json of a live session, as `fires replay` writes them.
pub fn write_live_outputs(dir: &std::path::Path, out: &LiveOutput) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    write_strokes(&dir.join("strokes.json"), &out.strokes)?;
    let samples: Vec<_> = out.samples.iter().map(|s| s.track).collect();
    let display: Vec<_> = out.samples.iter().map(|s| s.display_tip).collect();
    write_track_csv(&dir.join("track.csv"), &samples, &display)?;
    let mut report = serde_json::to_value(&out.summary)?;
    report["kind"] = "live".into();
    write_json(&dir.join("report.json"), &report)
}

#[cfg(test)]
mod tests {
    use super::read_world_reference;

    #[test]
    fn world_reference_from_a_report_or_bare_and_errors_otherwise() {
        let dir = std::env::temp_dir().join(format!("fires-world-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bare = r#"{"up":[0.0,-0.9,0.3],"magnetic":[0.1,0.5,0.8],"gravity":9.81}"#;
        let report = format!(r#"{{"kind":"live","world":{bare}}}"#);
        for (name, text) in [("bare.json", bare.to_string()), ("report.json", report)] {
            let p = dir.join(name);
            std::fs::write(&p, text).unwrap();
            let w = read_world_reference(&p).unwrap();
            assert_eq!(w.up, [0.0, -0.9, 0.3]);
            assert_eq!(w.gravity, 9.81);
        }
        for (name, text) in [
            ("none.json", r#"{"kind":"live","world":null}"#),
            (
                "zero.json",
                r#"{"up":[0,0,0],"magnetic":[0,1,0],"gravity":9.8}"#,
            ),
            ("junk.json", "not json"),
        ] {
            let p = dir.join(name);
            std::fs::write(&p, text).unwrap();
            assert!(read_world_reference(&p).is_err(), "{name}");
        }
        assert!(read_world_reference(&dir.join("missing.json")).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
