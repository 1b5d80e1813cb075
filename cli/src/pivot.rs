//! `fires pivot REC_DIR [--out FILE]`: the pen-tip offset from a recording of the pivot gesture (tip held on one
//! point, pen turned about it), by tracking the recording and fitting the tip along the LED axis
//! ([`fires_host::calibrate::pivot`]). Prints one JSON line with the offset and the residual in millimetres.

use std::path::PathBuf;

use anyhow::Context;
use fires_host::calibrate::pivot::{axis_poses, pivot_axis};
use fires_host::replay::{replay, ReplayConfig};
use fires_record::RecordingReader;

use crate::output::write_json;

/// Largest RMS scatter of the per-frame tips around the pivot, millimetres: a tip that stayed on one point
/// scatters about the tracking noise (about 1 mm at 0.7 m); more means the gesture was not a pivot.
const MAX_RMS_MM: f64 = 5.0;

/// Arguments of `fires pivot`.
#[derive(Debug, clap::Args)]
pub struct PivotArgs {
    /// Recording of the pivot gesture (e.g. `fires track --record DIR`, or `fires sim --scenario pivot`).
    pub recording: PathBuf,
    /// Also write the result as JSON to this file.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Tracks the recording and fits the tip offset; returns the result as JSON.
pub fn pivot_to_json(args: &PivotArgs) -> anyhow::Result<serde_json::Value> {
    let reader = RecordingReader::open(&args.recording)
        .with_context(|| format!("cannot open recording {}", args.recording.display()))?;
    let out = replay(&reader, &ReplayConfig::default())
        .with_context(|| format!("tracking {}", args.recording.display()))?;
    let pen = fires_host::meta::pen_geometry(reader.meta())?;
    let poses = axis_poses(&out.samples, &pen);
    let fit = pivot_axis(&poses).with_context(|| {
        format!(
            "pivot fit from {} tracked frames (hold the tip on one point and turn the pen through at least 20 degrees)",
            poses.len()
        )
    })?;
    if fit.rms_mm > MAX_RMS_MM {
        anyhow::bail!(
            "the tip did not stay on one point: the fitted tips scatter {:.1} mm RMS (at most {MAX_RMS_MM} mm); \
             hold the tip in a small dent and only turn the pen",
            fit.rms_mm
        );
    }
    Ok(serde_json::json!({
        "kind": "pivot",
        "recording": args.recording,
        "tip_offset_mm": fit.tip_offset * 1e3,
        "configured_tip_offset_mm": pen.tip_offset * 1e3,
        "pivot_m": [fit.pivot.x, fit.pivot.y, fit.pivot.z],
        "rms_mm": fit.rms_mm,
        "max_mm": fit.max_mm,
        "spread_deg": fit.spread_rad.to_degrees(),
        "poses": poses.len(),
    }))
}

/// `fires pivot`: prints the fit as one JSON line.
pub fn run(args: &PivotArgs) -> anyhow::Result<()> {
    let result = pivot_to_json(args)?;
    if let Some(path) = &args.out {
        write_json(path, &result)?;
    }
    println!("{result}");
    Ok(())
}
