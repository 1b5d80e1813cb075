//! `fires replay REC_DIR --out OUT_DIR`: a recording through the tracker; writes strokes.json, track.csv,
//! report.json (with accuracy figures when the recording has ground truth) and then tip_error.png, the tip
//! error over time of the vision-tracked samples (its scale is in report.json's `tip_error_plot`).
//! A damaged recording replays as far as it is whole; report.json's `damaged` says what was skipped
//! (docs/recording.md, "Damaged recordings") and each kind of damage is one warning line on stderr.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::Context;
use fires_host::replay::plot::tip_error_png;
use fires_host::replay::report::{accuracy, tip_errors, world_report};
use fires_host::replay::run::world_reference;
use fires_host::replay::{replay, ReplayConfig, ReplayOutput, WorldSource};
use fires_host::track::pipeline::{TrackQuality, TrackSample};
use fires_record::RecordingReader;

/// Arguments of `fires replay`.
#[derive(Debug, clap::Args)]
pub struct ReplayArgs {
    /// Recording directory (see docs/recording.md).
    pub recording: PathBuf,
    /// Output directory (created).
    #[arg(long)]
    pub out: PathBuf,
    /// Sensor fusion: `orientation` (default: gyro/accel/mag orientation filter with vision corrections) or
    /// `thesis` (the thesis's 4-state Kalman filter, eq. 4.18-4.21).
    #[arg(long, default_value = "orientation")]
    pub fusion: String,
    /// World reference (gravity and magnetic field in the camera frame): `estimate` it from the
    /// session as a live run must (default), or take the recording's `truth` (a perfectly
    /// calibrated rig).
    #[arg(long, default_value = "estimate")]
    pub world: String,
}

/// Replays and writes the outputs; returns the report (used by `fires demo`).
pub fn replay_to_dir(args: &ReplayArgs) -> anyhow::Result<serde_json::Value> {
    let reader = RecordingReader::open_salvaging(&args.recording)
        .with_context(|| format!("cannot open recording {}", args.recording.display()))?;
    let mut config = ReplayConfig::default();
    config.tracker.fusion = match args.fusion.as_str() {
        "orientation" => fires_host::track::fusion::FusionKind::Orientation,
        "thesis" => fires_host::track::fusion::FusionKind::ThesisKalman,
        other => anyhow::bail!("unknown fusion '{other}' (orientation, thesis)"),
    };
    config.world = match args.world.as_str() {
        "estimate" => WorldSource::Estimate,
        "truth" => WorldSource::Truth,
        other => anyhow::bail!("unknown world reference '{other}' (estimate, truth)"),
    };
    if reader.meta().pen.led_positions_m.len() == 2 {
        return bar_to_dir(&reader, args);
    }
    let out = replay(&reader, &config)
        .with_context(|| format!("replay of {}", args.recording.display()))?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    write_json(
        &args.out.join("strokes.json"),
        &serde_json::json!({ "strokes": out.strokes }),
    )?;
    write_track_csv(&args.out.join("track.csv"), &out.samples, &out.display_tips)?;
    let mut report = report(&reader, &out, &args.fusion)?;
    if let Some(truth) = reader.exposure_truth()? {
        let t0 = out.samples.first().map_or(0, |s| s.t_ns);
        let points: Vec<(f64, f64)> = tip_errors(&out, &truth)
            .into_iter()
            .map(|(t, e)| (t.saturating_sub(t0) as f64 / 1e9, e * 1e3))
            .collect();
        let path = args.out.join("tip_error.png");
        let scale = tip_error_png(&path, &points)?;
        report["tip_error_plot"] = serde_json::json!({ "path": path, "scale": scale });
    }
    add_damage(&reader, &mut report)?;
    write_json(&args.out.join("report.json"), &report)?;
    Ok(report)
}

/// A two-LED recording is the bar experiment: lengths instead of a pen track.
fn bar_to_dir(reader: &RecordingReader, args: &ReplayArgs) -> anyhow::Result<serde_json::Value> {
    use fires_host::replay::bar::{bar_report, measure_bar, smooth_bar, BarSmoothing};
    use fires_host::stereo::TriangulationMethod;
    let l = &reader.meta().pen.led_positions_m;
    let nominal = (l[1] - l[0]).abs();
    let truth = reader.exposure_truth()?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let smoothing = BarSmoothing::default();
    let mut report = serde_json::json!({
        "kind": "bar",
        "recording": reader.dir(),
        "bar_smoothing": smoothing,
    });
    for (name, method) in [
        ("midpoint", TriangulationMethod::Midpoint),
        ("linear", TriangulationMethod::Linear),
        ("normal_equations", TriangulationMethod::NormalEquations),
    ] {
        let single = measure_bar(reader, method)?;
        let filtered = smooth_bar(&single, smoothing);
        let mut r = serde_json::to_value(bar_report(&filtered, nominal, truth.as_deref()))?;
        r["single_frame"] = serde_json::to_value(bar_report(&single, nominal, truth.as_deref()))?;
        if name == "midpoint" {
            write_json(
                &args.out.join("bar.json"),
                &serde_json::json!({ "samples": filtered, "single_frame_samples": single }),
            )?;
            for (k, v) in r.as_object().into_iter().flatten() {
                report[k] = v.clone();
            }
        }
        report[format!("method_{name}")] = r;
    }
    add_damage(reader, &mut report)?;
    write_json(&args.out.join("report.json"), &report)?;
    Ok(report)
}

/// Adds `damaged` (what the salvaging reader skipped) to the report and prints one warning per kind.
fn add_damage(reader: &RecordingReader, report: &mut serde_json::Value) -> anyhow::Result<()> {
    let damage = reader.damage();
    for w in &damage.warnings {
        eprintln!("warning: {}: {w}", reader.dir().display());
    }
    report["damaged"] = serde_json::to_value(&damage)?;
    Ok(())
}

/// `fires replay`: prints the report as one JSON line.
pub fn run(args: &ReplayArgs) -> anyhow::Result<()> {
    let report = replay_to_dir(args)?;
    println!("{report}");
    Ok(())
}

fn report(
    reader: &RecordingReader,
    out: &ReplayOutput,
    fusion: &str,
) -> anyhow::Result<serde_json::Value> {
    let tracked = out.samples.iter().filter(|s| s.tip.is_some()).count();
    let vision = out
        .samples
        .iter()
        .filter(|s| matches!(s.quality, TrackQuality::Vision { .. }))
        .count();
    let link = out.imu.stats;
    let frames = out.samples.len().max(1) as f64;
    let mut report = serde_json::json!({
        "kind": "replay",
        "recording": reader.dir(),
        "fusion": fusion,
        "frames": out.samples.len(),
        "frames_tracked": tracked,
        "frames_vision": vision,
        "camera_frames": out.frames,
        "strokes": out.strokes.len(),
        "world_reference": out.world_reference,
        "world": world_report(out, reader.world_truth()?.map(|w| world_reference(&w)).as_ref()),
        "magnetometer": mag_report(out, reader.world_truth()?.as_ref()),
        "link": {
            "bytes": out.imu.bytes,
            "sensor_frames": link.sensor_frames,
            "status_frames": link.status_frames,
            "checksum_errors": link.checksum_errors,
            "bytes_skipped": link.bytes_skipped,
            "lost": link.lost,
            "duplicates": link.duplicates,
        },
        "latency_us_per_frame": {
            "blobs": out.times.blobs_ns as f64 / 1e3 / frames,
            "track": out.times.track_ns as f64 / 1e3 / frames,
        },
        "stage_ms": {
            "link": out.times.link_ns as f64 / 1e6,
            "blobs": out.times.blobs_ns as f64 / 1e6,
            "track": out.times.track_ns as f64 / 1e6,
            "strokes": out.times.strokes_ns as f64 / 1e6,
        },
        "wall_ms": out.wall_ns as f64 / 1e6,
    });
    if let Some(truth) = reader.exposure_truth()? {
        let acc = accuracy(out, &truth);
        let t0 = truth.iter().map(|e| e.exposure_time_ns).min().unwrap_or(0);
        let t1 = truth.iter().map(|e| e.exposure_time_ns).max().unwrap_or(0);
        let duration_s = (t1 - t0) as f64 / 1e9;
        if let Some(map) = report.as_object_mut() {
            for (k, v) in serde_json::to_value(&acc)?
                .as_object()
                .into_iter()
                .flatten()
            {
                map.insert(k.clone(), v.clone());
            }
            map.insert(
                "realtime_factor".into(),
                (duration_s / (out.wall_ns as f64 / 1e9)).into(),
            );
        }
    }
    Ok(report)
}

/// The hard-iron offset found in the session and, with ground truth, its error (microtesla).
fn mag_report(out: &ReplayOutput, truth: Option<&fires_record::WorldTruth>) -> serde_json::Value {
    let Some(o) = &out.mag_offset else {
        return serde_json::json!({ "calibrated": false });
    };
    let mut r = serde_json::json!({
        "calibrated": true,
        "hard_iron": o.hard_iron,
        "field": o.field,
        "sigma_of_field": o.sigma,
        "samples": o.samples,
    });
    if let Some(t) = truth {
        // Readings are in microtesla (the recording's scale factors), the truth in tesla.
        let err: f64 = (0..3)
            .map(|k| (o.hard_iron[k] - t.hard_iron_t[k] * 1e6).powi(2))
            .sum::<f64>()
            .sqrt();
        r["hard_iron_error"] = err.into();
    }
    r
}

pub(crate) fn write_json(path: &Path, value: &serde_json::Value) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    std::fs::write(path, text + "\n").with_context(|| format!("cannot write {}", path.display()))
}

/// Writes one CSV row per tracker sample (with the display-smoothed tip in the last columns).
pub(crate) fn write_track_csv(
    path: &Path,
    samples: &[TrackSample],
    display_tips: &[Option<[f64; 3]>],
) -> anyhow::Result<()> {
    let file =
        std::fs::File::create(path).with_context(|| format!("cannot write {}", path.display()))?;
    let mut w = std::io::BufWriter::new(file);
    writeln!(w, "t_ns,quality,leds,tip_x_m,tip_y_m,tip_z_m,dir_x,dir_y,dir_z,labels,confidence,interference,display_x_m,display_y_m,display_z_m")?;
    for (i, s) in samples.iter().enumerate() {
        let (q, n) = match s.quality {
            TrackQuality::Vision { leds } => ("vision", leds),
            TrackQuality::DeadReckoned => ("dead_reckoned", 0),
            TrackQuality::Lost => ("lost", 0),
        };
        let v3 = |v: Option<[f64; 3]>| {
            v.map_or(",,".to_string(), |p| {
                format!("{:.6},{:.6},{:.6}", p[0], p[1], p[2])
            })
        };
        let labels: String = s
            .labels
            .iter()
            .map(|l| l.map_or("-".into(), |(a, b)| format!("{a}:{b}")))
            .collect::<Vec<_>>()
            .join(" ");
        writeln!(
            w,
            "{},{q},{n},{},{},{labels},{:.3},{},{}",
            s.t_ns,
            v3(s.tip),
            v3(s.direction),
            s.confidence,
            s.interference,
            v3(display_tips.get(i).copied().flatten())
        )?;
    }
    w.flush()
        .with_context(|| format!("cannot write {}", path.display()))
}
