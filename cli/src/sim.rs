//! `fires sim`: writes a simulated pen session (a recording with ground truth) with the deterministic simulator.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use fires_recon::network::PenMode;
use fires_sim::motion::MAX_PLANNED_STROKES;
use fires_sim::objects::ObjectKind;
use fires_sim::{run_scenario, SimOptions, SimSummary, SCENARIOS};

/// What to simulate: shared by `fires sim` and `fires demo`.
#[derive(Debug, Clone, clap::Args)]
pub struct SessionArgs {
    /// Named scenario (see `fires sim --help` for the list); `webcam`, two 60 Hz IR webcams, by default.
    #[arg(long, default_value = "webcam")]
    pub scenario: String,
    /// Random seed; the same seed gives a byte-identical recording.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Simulated duration, seconds.
    #[arg(long, default_value_t = 60.0)]
    pub duration: f64,
}

/// Arguments of `fires sim`.
#[derive(Debug, clap::Args)]
#[command(after_help = scenario_help())]
pub struct SimArgs {
    /// Scenario, seed and duration.
    #[command(flatten)]
    pub session: SessionArgs,
    /// Output directory of the recording (created; must not hold another recording).
    #[arg(long)]
    pub out: PathBuf,
    /// Write blob lists instead of 8-bit images for image cameras.
    #[arg(long)]
    pub no_images: bool,
    /// Leave out the ground truth (as a recording of real hardware).
    #[arg(long)]
    pub no_truth: bool,
    /// Object the pen draws on: sphere, cylinder, box or blob (drawing scenarios only).
    #[arg(long, value_parser = parse_object)]
    pub object: Option<ObjectKind>,
    /// Hold a mode button while drawing planned stroke ID: `ID=MODE`, MODE one of insert, sharp,
    /// mirror, hole, glue, skin or 0–7 (the curve network's pen modes, docs/network.md); repeatable.
    #[arg(long = "mode", value_parser = parse_stroke_mode)]
    pub modes: Vec<(u32, u8)>,
}

fn parse_stroke_mode(s: &str) -> Result<(u32, u8), String> {
    let (id, mode) = s
        .split_once('=')
        .ok_or_else(|| format!("'{s}': expected ID=MODE, e.g. 3=sharp"))?;
    let id: u32 = id
        .trim()
        .parse()
        .map_err(|_| format!("'{s}': the stroke id '{id}' is not a number"))?;
    if id as usize >= MAX_PLANNED_STROKES {
        return Err(format!(
            "'{s}': the plan has strokes 0 to {}",
            MAX_PLANNED_STROKES - 1
        ));
    }
    let mode = mode.trim();
    let m = match PenMode::NAMES.iter().position(|&n| n == mode) {
        Some(m) => m as u8,
        None => mode.parse::<u8>().ok().filter(|&m| m < 8).ok_or_else(|| {
            format!(
                "'{s}': unknown mode '{mode}' ({} or 0-7)",
                PenMode::NAMES.join(", ")
            )
        })?,
    };
    Ok((id, m))
}

fn parse_object(s: &str) -> Result<ObjectKind, String> {
    ObjectKind::parse(s)
        .ok_or_else(|| format!("unknown object '{s}' (sphere, cylinder, box, blob)"))
}

fn scenario_help() -> String {
    let mut s = String::from("Scenarios:\n");
    for (name, desc) in SCENARIOS {
        s.push_str(&format!("  {name:10} {desc}\n"));
    }
    s
}

/// Runs the simulator and returns its summary (used by `fires demo` too).
pub fn simulate(args: &SimArgs) -> anyhow::Result<SimSummary> {
    let opts = SimOptions {
        images: !args.no_images,
        object: args.object,
        truth: !args.no_truth,
        stroke_modes: {
            let mut m = [0; MAX_PLANNED_STROKES];
            for &(id, mode) in &args.modes {
                m[id as usize] = mode;
            }
            m
        },
    };
    let session = &args.session;
    run_scenario(
        &session.scenario,
        session.seed,
        session.duration,
        &args.out,
        opts,
    )
    .with_context(|| {
        format!(
            "simulation of '{}' into {}",
            session.scenario,
            args.out.display()
        )
    })
}

/// The line `fires sim` prints: the simulator's summary and the wall time.
#[derive(serde::Serialize)]
struct SimLine<'a> {
    kind: &'static str,
    #[serde(flatten)]
    summary: &'a SimSummary,
    wall_s: f64,
}

/// `fires sim`: simulate and print a one-line JSON summary.
pub fn run(args: &SimArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    let s = simulate(args)?;
    let line = SimLine {
        kind: "sim",
        summary: &s,
        wall_s: start.elapsed().as_secs_f64(),
    };
    println!("{}", serde_json::to_string(&line)?);
    Ok(())
}
