//! `fires edit lse|poisson|implicit|naive MESH SPEC.json -o OUT [--png P]`: differential mesh
//! editing ([`fires_recon::edit`]) by a JSON edit specification; prints one JSON line
//! `{"method","roi_vertices","build_ms","factor_ms","solve_ms","detail_error"}`.

use std::path::{Path, PathBuf};

use anyhow::Context;
use fires_recon::edit::{edit_mesh, EditSpec, Method};
use fires_recon::io::{read_mesh_file, write_mesh_file, PolygonSoup};
use fires_recon::render::{render, save_png, side_by_side, RenderOptions, Scene, SceneMesh};
use fires_recon::{SurfaceMesh, Vec3};

/// The editing method.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum MethodArg {
    /// Laplacian surface editing (Sorkine et al. 2004), two re-fitting iterations.
    Lse,
    /// Poisson gradient-field editing (Yu et al. 2004).
    Poisson,
    /// Implicit Laplacian editing (Fu, ch. 2), both solves.
    Implicit,
    /// Naive Laplacian editing, the baseline.
    Naive,
}

impl MethodArg {
    /// The library's method.
    pub fn method(self) -> Method {
        match self {
            MethodArg::Lse => Method::Lse,
            MethodArg::Poisson => Method::Poisson,
            MethodArg::Implicit => Method::Implicit,
            MethodArg::Naive => Method::Naive,
        }
    }
}

/// Arguments of `fires edit`.
#[derive(Debug, clap::Args)]
pub struct EditArgs {
    /// Editing method.
    #[arg(value_enum)]
    pub method: MethodArg,
    /// Triangle mesh (OBJ, OFF, PLY, STL).
    pub mesh: PathBuf,
    /// Edit specification (JSON: roi, anchors, handles with transforms).
    pub spec: PathBuf,
    /// Output mesh (format from the extension).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write a before/after picture (PNG).
    #[arg(long)]
    pub png: Option<PathBuf>,
}

/// Reads a mesh file into a halfedge mesh.
pub fn load_mesh(path: &Path) -> anyhow::Result<SurfaceMesh> {
    read_mesh_file(path)
        .and_then(|s| s.to_mesh())
        .with_context(|| format!("reading mesh {}", path.display()))
}

/// Writes `mesh` with new positions.
pub fn save_mesh(path: &Path, mesh: &SurfaceMesh, positions: &[Vec3]) -> anyhow::Result<()> {
    let mut m = mesh.clone();
    m.positions_mut().copy_from_slice(positions);
    write_mesh_file(path, &PolygonSoup::from_mesh(&m))
        .with_context(|| format!("writing mesh {}", path.display()))
}

/// Writes a before/after picture: the input left, the result right.
pub fn save_before_after(
    path: &Path,
    mesh: &SurfaceMesh,
    before: &[Vec3],
    after: &[Vec3],
) -> anyhow::Result<()> {
    let o = RenderOptions::default();
    let pic = |x: &[Vec3], color| {
        let mut s = Scene::default();
        s.meshes.push(SceneMesh::from_positions(mesh, x, color));
        render(&s, &o)
    };
    let img = side_by_side(&[pic(before, [170, 170, 190]), pic(after, [200, 160, 110])]);
    save_png(&img, path).with_context(|| format!("writing {}", path.display()))
}

/// `fires edit`.
pub fn run(args: &EditArgs) -> anyhow::Result<()> {
    let mesh = load_mesh(&args.mesh)?;
    let text = std::fs::read_to_string(&args.spec)
        .with_context(|| format!("reading {}", args.spec.display()))?;
    let spec = EditSpec::from_json(&text).with_context(|| args.spec.display().to_string())?;
    let (x, report) = edit_mesh(&mesh, &spec, args.method.method())?;
    save_mesh(&args.output, &mesh, &x)?;
    if let Some(png) = &args.png {
        save_before_after(png, &mesh, mesh.positions(), &x)?;
    }
    println!("{}", serde_json::to_string(&report)?);
    Ok(())
}
