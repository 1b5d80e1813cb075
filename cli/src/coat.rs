//! `fires coat DETAILED BASE -o OUT [--png P]`: coating transfer (Sorkine et al. 2004 §5.1,
//! [`fires_recon::edit::coating`]): the detail of DETAILED over its smoothed base, put onto
//! BASE (same connectivity); prints one JSON line.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::bail;
use fires_recon::edit::coating::{coat, CoatingOptions};

use super::edit::{load_mesh, save_before_after, save_mesh};

/// Arguments of `fires coat`.
#[derive(Debug, clap::Args)]
pub struct CoatArgs {
    /// Mesh whose detail is transferred.
    pub detailed: PathBuf,
    /// Mesh receiving the detail (same connectivity as DETAILED).
    pub base: PathBuf,
    /// Output mesh.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Smoothing steps that define the detail band.
    #[arg(long, default_value_t = 10)]
    pub smoothing_steps: usize,
    /// Fairing strength of one smoothing step.
    #[arg(long, default_value_t = 1.0)]
    pub smoothing: f64,
    /// Also write a before/after picture (PNG: BASE, result).
    #[arg(long)]
    pub png: Option<PathBuf>,
}

/// `fires coat`.
pub fn run(args: &CoatArgs) -> anyhow::Result<()> {
    let detailed = load_mesh(&args.detailed)?;
    let base = load_mesh(&args.base)?;
    if detailed.face_index_lists() != base.face_index_lists() {
        bail!(
            "{} and {} do not have the same connectivity",
            args.detailed.display(),
            args.base.display()
        );
    }
    let t = Instant::now();
    let x = coat(
        &detailed,
        base.positions(),
        &CoatingOptions {
            smoothing: args.smoothing,
            smoothing_steps: args.smoothing_steps,
        },
    )?;
    let ms = t.elapsed().as_secs_f64() * 1e3;
    save_mesh(&args.output, &base, &x)?;
    if let Some(png) = &args.png {
        save_before_after(png, &base, base.positions(), &x)?;
    }
    println!(
        "{}",
        serde_json::json!({"vertices": base.n_vertices(), "ms": ms})
    );
    Ok(())
}
