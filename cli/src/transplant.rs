//! `fires transplant TARGET PATCH SPEC.json -o OUT [--png P]`: replaces the region of TARGET
//! named by SPEC (`{"region": SELECT, "transition_rings": 3}`) with PATCH, zipped into the
//! hole and blended by Laplacian coordinates ([`fires_recon::edit::transplant`]); prints one
//! JSON line with the seam size, watertightness and the patch's `detail_error`.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use fires_recon::edit::detail_error;
use fires_recon::edit::transplant::{transplant, TransplantSpec};
use fires_recon::io::{write_mesh_file, PolygonSoup};
use fires_recon::render::{render, save_png, side_by_side, RenderOptions, Scene, SceneMesh};
use fires_recon::Vec3;

use super::edit::load_mesh;

/// Arguments of `fires transplant`.
#[derive(Debug, clap::Args)]
pub struct TransplantArgs {
    /// Mesh receiving the patch.
    pub target: PathBuf,
    /// Patch (one boundary loop), already placed over the region.
    pub patch: PathBuf,
    /// JSON: the region of TARGET the patch replaces.
    pub spec: PathBuf,
    /// Output mesh.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write a before/after picture (PNG: target and patch, result).
    #[arg(long)]
    pub png: Option<PathBuf>,
}

/// `fires transplant`.
pub fn run(args: &TransplantArgs) -> anyhow::Result<()> {
    let target = load_mesh(&args.target)?;
    let patch = load_mesh(&args.patch)?;
    let text = std::fs::read_to_string(&args.spec)
        .with_context(|| format!("reading {}", args.spec.display()))?;
    let spec = TransplantSpec::from_json(&text).with_context(|| args.spec.display().to_string())?;
    let t = Instant::now();
    let out = transplant(&target, &patch, &spec)?;
    let ms = t.elapsed().as_secs_f64() * 1e3;
    write_mesh_file(&args.output, &PolygonSoup::from_mesh(&out.mesh))
        .with_context(|| format!("writing {}", args.output.display()))?;
    let x: Vec<Vec3> = out
        .patch_vertices
        .iter()
        .map(|&v| out.mesh.positions()[v])
        .collect();
    let err = detail_error(&patch, &x, None)?;
    if let Some(png) = &args.png {
        let o = RenderOptions::default();
        let mut before = Scene::default();
        before
            .meshes
            .push(SceneMesh::from_mesh(&target, [170, 170, 190]));
        before
            .meshes
            .push(SceneMesh::from_mesh(&patch, [220, 120, 90]));
        let mut after = Scene::default();
        after
            .meshes
            .push(SceneMesh::from_mesh(&out.mesh, [200, 160, 110]));
        save_png(
            &side_by_side(&[render(&before, &o), render(&after, &o)]),
            png,
        )
        .with_context(|| format!("writing {}", png.display()))?;
    }
    println!(
        "{}",
        serde_json::json!({"vertices": out.mesh.n_vertices(), "seam_faces": out.seam_faces,
                           "watertight": out.mesh.is_closed() || !target.is_closed(),
                           "ms": ms, "detail_error": err})
    );
    Ok(())
}
