//! `fires denoise MESH -o OUT [--png P]`: denoising by gradient-field filtering (Yu et al.
//! 2004 §4.3, [`fires_recon::edit::denoise`]); prints one JSON line.

use std::path::PathBuf;
use std::time::Instant;

use fires_recon::edit::denoise::{denoise, DenoiseOptions};

use super::edit::{load_mesh, save_before_after, save_mesh};

/// Arguments of `fires denoise`.
#[derive(Debug, clap::Args)]
pub struct DenoiseArgs {
    /// Triangle mesh (OBJ, OFF, PLY, STL).
    pub mesh: PathBuf,
    /// Output mesh.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Filter-and-solve passes.
    #[arg(long, default_value_t = 3)]
    pub iterations: usize,
    /// Spatial width of the normal filter, in mean edge lengths.
    #[arg(long, default_value_t = 2.0)]
    pub sigma_f: f64,
    /// Normal-difference width in degrees.
    #[arg(long, default_value_t = 36.0)]
    pub sigma_g_deg: f64,
    /// Keep the enclosed volume of a closed mesh.
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    pub preserve_volume: bool,
    /// Also write a before/after picture (PNG).
    #[arg(long)]
    pub png: Option<PathBuf>,
}

/// `fires denoise`.
pub fn run(args: &DenoiseArgs) -> anyhow::Result<()> {
    let mesh = load_mesh(&args.mesh)?;
    let t = Instant::now();
    let x = denoise(
        &mesh,
        &DenoiseOptions {
            iterations: args.iterations,
            sigma_f: args.sigma_f,
            sigma_g: args.sigma_g_deg.to_radians(),
            preserve_volume: args.preserve_volume,
        },
    )?;
    let ms = t.elapsed().as_secs_f64() * 1e3;
    save_mesh(&args.output, &mesh, &x)?;
    if let Some(png) = &args.png {
        save_before_after(png, &mesh, mesh.positions(), &x)?;
    }
    let moved = mesh
        .positions()
        .iter()
        .zip(&x)
        .map(|(a, b)| a.distance(*b))
        .fold(0.0, f64::max);
    println!(
        "{}",
        serde_json::json!({"vertices": mesh.n_vertices(), "iterations": args.iterations,
                           "ms": ms, "max_displacement": moved})
    );
    Ok(())
}
