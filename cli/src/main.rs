//! `fires`: the FIRES command-line tool.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use fires_cli as cli;

/// FIRES: track a smart-pen with two cameras, turn the drawn curves into surfaces.
#[derive(Debug, Parser)]
#[command(
    name = "fires",
    version,
    about = "FIRES: track a smart-pen with two cameras and turn the curves it draws into surfaces",
    after_help = "Examples:\n  fires decode samples/pen-stream.bin      decode a captured pen stream\n  \
                  cat /dev/rfcomm0 | fires decode -        decode a live Bluetooth serial port\n\n\
                  Errors go to standard error as one line; the exit code is 2."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Simulate a pen session and track it: the whole pipeline without hardware.
    Demo(cli::demo::DemoArgs),
    /// Track a recording: strokes.json, track.csv and report.json (accuracy when it has ground truth).
    Replay(cli::replay::ReplayArgs),
    /// Decode raw pen link bytes into one JSON line per packet, then a summary line.
    Decode(cli::decode::DecodeArgs),
    /// Benchmark the sparse solvers of the geometry core (JSON line of median timings).
    Bench(cli::bench::BenchArgs),
    /// Simulate a pen session (pen, IMU, link, cameras) into a recording with ground truth.
    Sim(cli::sim::SimArgs),
    /// Track live: two cameras and the pen's serial port until Ctrl-C (needs the `camera` feature).
    Track(cli::track::TrackArgs),
    /// Calibrate the stereo rig from chessboard image pairs (needs the `opencv` feature).
    Calibrate(cli::calibrate::CalibrateArgs),
    /// Edit a mesh by a JSON specification: Laplacian surface, Poisson, implicit or naive Laplacian editing.
    Edit(cli::edit::EditArgs),
    /// Transfer the detail of one mesh onto another of the same connectivity (coating transfer).
    Coat(cli::coat::CoatArgs),
    /// Replace a region of a mesh by a patch, blended with Laplacian coordinates.
    Transplant(cli::transplant::TransplantArgs),
    /// Denoise a mesh by filtering its gradient field (bilateral normal filter + Poisson solve).
    Denoise(cli::denoise::DenoiseArgs),
    /// Fit the pen-tip offset from a recording of the pivot gesture (tip held still, pen turned).
    Pivot(cli::pivot::PivotArgs),
    /// Inspect a mesh file: counts, topology and what reading it repaired (one JSON line).
    Mesh(cli::mesh::MeshArgs),
    /// Build the curve network from strokes (or replay a sketch journal): network.json and a summary line.
    Network(cli::network::NetworkArgs),
    /// Reconstruct a surface from a curve network (FIRESV1 or FIRESV2): quad mesh, curves, summary line.
    Recon(cli::recon::ReconArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Decode(args) => cli::decode::run(args),
        Command::Demo(args) => cli::demo::run(args),
        Command::Replay(args) => cli::replay::run(args),
        Command::Bench(args) => cli::bench::run(args),
        Command::Sim(args) => cli::sim::run(args),
        Command::Calibrate(args) => cli::calibrate::run(args),
        Command::Track(args) => cli::track::run(args),
        Command::Pivot(args) => cli::pivot::run(args),
        Command::Mesh(args) => cli::mesh::run(args),
        Command::Network(args) => cli::network::run(args),
        Command::Recon(args) => cli::recon::run(args),
        Command::Edit(args) => cli::edit::run(args),
        Command::Coat(args) => cli::coat::run(args),
        Command::Transplant(args) => cli::transplant::run(args),
        Command::Denoise(args) => cli::denoise::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("fires: error: {e:#}");
            ExitCode::from(2)
        }
    }
}

/// A closed standard output (`fires decode x | head`) ends the program quietly.
fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
