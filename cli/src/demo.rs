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
    })?;
    eprintln!(
        "tracked; strokes, track and report in {}",
        args.out.join("replay").display()
    );
    println!("{}", serde_json::to_string(&report)?);
    Ok(())
}
