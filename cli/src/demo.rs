//! `fires demo`: the main job without hardware: a simulated pen session, then its replay through the tracker.

use std::path::PathBuf;

use crate::replay::{replay_to_dir, Display, Fusion, ReplayArgs, World};
use crate::sim::{simulate, SessionArgs, SimArgs};

/// Arguments of `fires demo`.
#[derive(Debug, clap::Args)]
pub struct DemoArgs {
    /// Output folder: the recording goes to OUT/recording, the tracker's outputs to OUT/replay.
    #[arg(long, default_value = "fires-demo")]
    pub out: PathBuf,
    /// Scenario, seed and duration of the simulated session.
    #[command(flatten)]
    pub session: SessionArgs,
}

/// Simulates, replays and prints a summary line.
pub fn run(args: &DemoArgs) -> anyhow::Result<()> {
    let rec = args.out.join("recording");
    if rec.exists() {
        std::fs::remove_dir_all(&rec)
            .map_err(|e| anyhow::anyhow!("cannot clear {}: {e}", rec.display()))?;
    }
    let sim = simulate(&SimArgs {
        session: args.session.clone(),
        out: rec.clone(),
        no_images: false,
        no_truth: false,
        object: None,
        modes: Vec::new(),
    })?;
    eprintln!(
        "simulated {} s of '{}': {} IMU samples, {} camera frames, {} strokes -> {}",
        sim.duration_s,
        sim.scenario,
        sim.imu_samples,
        sim.frames.iter().sum::<u64>(),
        sim.strokes,
        rec.display()
    );
    let report = replay_to_dir(&ReplayArgs {
        recording: rec,
        out: args.out.join("replay"),
        fusion: Fusion::Orientation,
        world: World::Estimate,
        display: Display::OneEuro,
        min_cutoff: None,
        beta: None,
        d_cutoff: None,
        no_surface: false,
    })?;
    let out = args.out.join("replay");
    if let fires_record::Report::Replay(r) = &report {
        for line in summary_lines(r, &out) {
            println!("{line}");
        }
    }
    Ok(())
}

/// The few lines a person reads after a demo: what was made, its errors in mm, where the files are.
fn summary_lines(r: &fires_record::ReplayReport, out: &std::path::Path) -> Vec<String> {
    let mut lines = Vec::new();
    match &r.strokes_summary {
        Some(s) => lines.push(format!(
            "tracked {} of {} drawn strokes, off the true pen path by RMS {} (median stroke), {} (worst)",
            s.kept,
            s.true_strokes,
            mm(s.rms_mm.median),
            mm(s.rms_mm.worst)
        )),
        None => lines.push(format!("tracked {} strokes", r.strokes)),
    }
    if let Some(s) = &r.strokes_summary {
        lines.push(format!(
            "worst stroke: {} of its true path within 3 mm of the tracked one, length ratio {} (tracked over true)",
            percent(s.coverage_3mm.worst),
            s.length_ratio.worst.map_or("-".into(), |x| format!("{x:.3}"))
        ));
    }
    let pairs = r.vision_refusals.as_ref().and_then(|v| {
        Some((
            v.truly_visible.as_ref()?.vision_fraction,
            v.truly_visible_in_strokes.as_ref()?.vision_fraction,
        ))
    });
    if let (Some((all, drawing)), Some(d)) = (pairs, &r.display) {
        lines.push(format!(
            "vision tips from {} of the stereo pairs in which both cameras see the pen ({} while drawing); display ({}) lag {}, jitter at rest {}",
            percent(all),
            percent(drawing),
            d.filter,
            d.lag_ms.map_or("-".into(), |x| format!("{x:.0} ms")),
            mm(d.jitter_at_rest_mm)
        ));
    }
    if let Some(n) = &r.network {
        lines.push(format!(
            "curve network: {} faces from {} of {} strokes -> {}",
            n.faces,
            n.used_strokes,
            n.strokes,
            out.join("network.json").display()
        ));
    }
    let surface = |name: &str, s: &fires_record::SurfaceReport| {
        format!(
            "{name}: {} vertices, RMS {} ({:.2}% of the {:.0} mm drawn region), p95 {}, Hausdorff {}, {:.0}% of the region within 3 mm, curves {} off",
            s.vertices,
            mm(Some(s.rms_mm)),
            s.rms_pct_diag,
            s.diag_mm,
            mm(Some(s.p95_mm)),
            mm(Some(s.hausdorff_mm)),
            100.0 * s.completeness_3mm,
            mm(s.curve_rms_mm)
        )
    };
    match &r.surface {
        Some(s) => lines.push(surface(
            &format!(
                "surface (FIRES{}) from the tracked strokes",
                s.method.to_uppercase()
            ),
            s,
        )),
        None => lines.push("no surface: the tracked strokes make no closed network face".into()),
    }
    if let Some(s) = &r.surface_from_truth {
        lines.push(surface(
            &format!(
                "the same (FIRES{}) from the true strokes",
                s.method.to_uppercase()
            ),
            s,
        ));
    }
    lines.push(format!(
        "files in {}: strokes.json, network.json, surface.obj (+ .curves.obj), report.json; pictures surface.png, surface_error.png, surface_truth_error.png, strokes_on_truth.png, tip_error.png",
        out.display()
    ));
    lines
}

fn mm(v: Option<f64>) -> String {
    v.map_or("-".into(), |x| format!("{x:.2} mm"))
}

fn percent(v: Option<f64>) -> String {
    v.map_or("-".into(), |x| format!("{:.1}%", 100.0 * x))
}
