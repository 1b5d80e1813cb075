//! `fires recon IN -o OUT.obj [--method v1|v2] [--levels K] [--png OUT.png]`: a surface from a curve
//! network (FIRES thesis ch. 6). IN is a `network.json`, a sketch journal (with `--strokes`), or strokes
//! (`strokes.json` or a recording's `truth/strokes.json`, built as `fires network` does). Writes the
//! quad mesh (OBJ or PLY by extension), the curves as OBJ lines next to it (`OUT.curves.obj`), and
//! one JSON summary line on standard output.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use fires_recon::io::{write_mesh_file, PolygonSoup};
use fires_recon::network::{Network, NetworkFile, JOURNAL_FORMAT, NETWORK_FORMAT};
use fires_recon::render::{render, save_png, Polyline, Scene, SceneMesh};
use fires_recon::surface::{reconstruct_v1, reconstruct_v2, ControlMesh, V1Options, V2Options};
use fires_recon::Vec3;
use serde::Serialize;

use crate::network::{drawn_side_view, load_stroke_inputs, network_of};

/// Which surface method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// FIRESV1 (thesis §6.1–6.3): triquadrification, Coons refinement, interpolatory subdivision.
    V1,
    /// FIRESV2 (thesis §6.4): tessellation, surface-diffusion flow, Catmull-Clark.
    V2,
}

impl Method {
    /// The method's name in reports (`v1`, `v2`).
    pub fn name(self) -> &'static str {
        match self {
            Method::V1 => "v1",
            Method::V2 => "v2",
        }
    }
}

/// Arguments of `fires recon`.
#[derive(Debug, clap::Args)]
pub struct ReconArgs {
    /// A `network.json`, a sketch journal (give `--strokes`), or a strokes file.
    pub input: PathBuf,
    /// The strokes a journal refers to.
    #[arg(long)]
    pub strokes: Option<PathBuf>,
    /// Output mesh (`.obj` or `.ply`; quads).
    #[arg(short, long)]
    pub out: PathBuf,
    /// Surface method.
    #[arg(long, value_enum, default_value_t = Method::V2)]
    pub method: Method,
    /// Subdivision levels after the refinement (the method's default when omitted).
    #[arg(long)]
    pub levels: Option<usize>,
    /// Write a shaded picture of the surface with the curves over it.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// A simulated recording whose true object the surface is compared with (`truth` in the summary).
    #[arg(long)]
    pub truth: Option<PathBuf>,
}

/// The summary line of `fires recon`.
#[derive(Debug, Serialize)]
pub struct ReconSummary {
    /// The method used.
    pub method: Method,
    /// Faces of the output mesh.
    pub faces: usize,
    /// Vertices of the output mesh.
    pub vertices: usize,
    /// Faces of the curve network.
    pub network_faces: usize,
    /// Wall time of the reconstruction, milliseconds.
    pub ms: f64,
    /// RMS distance from the drawn curves' points to the surface, mm.
    pub curve_rms_mm: f64,
    /// Largest distance from a drawn curve's point to the surface, mm.
    pub curve_max_mm: f64,
    /// The surface against the true object of `--truth` (docs/report.md, "Surface").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub truth: Option<fires_record::SurfaceReport>,
}

/// Reads IN as a network (see the module docs).
pub fn read_network(input: &Path, strokes: Option<&Path>) -> anyhow::Result<Network> {
    let text = std::fs::read_to_string(input)
        .with_context(|| format!("cannot read {}", input.display()))?;
    let format = serde_json::from_str::<serde_json::Value>(&text)
        .ok()
        .and_then(|v| v.get("format").and_then(|f| f.as_str()).map(str::to_owned));
    match format.as_deref() {
        Some(NETWORK_FORMAT) => {
            NetworkFile::parse(&text).with_context(|| format!("reading {}", input.display()))
        }
        Some(JOURNAL_FORMAT) => {
            let strokes = strokes.ok_or_else(|| {
                anyhow::anyhow!(
                    "{} is a sketch journal: give its strokes with --strokes",
                    input.display()
                )
            })?;
            let inputs = load_stroke_inputs(strokes)?;
            Ok(network_of(&inputs, Some(input))?.0)
        }
        _ => Ok(network_of(&load_stroke_inputs(input)?, None)?.0),
    }
}

/// Reconstructs `net` with `method`.
pub fn reconstruct(
    net: &Network,
    method: Method,
    levels: Option<usize>,
) -> anyhow::Result<ControlMesh> {
    Ok(match method {
        Method::V1 => {
            let mut o = V1Options::default();
            if let Some(k) = levels {
                o.levels = k;
            }
            reconstruct_v1(net, &o)?
        }
        Method::V2 => {
            let mut o = V2Options::default();
            if levels.is_some() {
                o.levels = levels;
            }
            reconstruct_v2(net, &o)?
        }
    })
}

/// Runs `fires recon`.
pub fn run(args: &ReconArgs) -> anyhow::Result<()> {
    let net = read_network(&args.input, args.strokes.as_deref())?;
    let t0 = Instant::now();
    let surface = reconstruct(&net, args.method, args.levels)?;
    let ms = t0.elapsed().as_secs_f64() * 1e3;
    let curve = curve_distance(&surface)?;
    write_surface(&surface, &args.out)?;
    if let Some(png) = &args.png {
        save_png(
            &render(
                &surface_scene(&surface, [205, 190, 160]),
                &drawn_side_view(surface.mesh.positions()),
            ),
            png,
        )
        .with_context(|| format!("cannot write {}", png.display()))?;
    }
    let summary = ReconSummary {
        method: args.method,
        faces: surface.mesh.n_faces(),
        vertices: surface.mesh.n_vertices(),
        network_faces: net.n_faces(),
        ms,
        curve_rms_mm: curve.rms_mm,
        curve_max_mm: curve.max_mm,
        truth: match &args.truth {
            Some(rec) => Some(compare_with_recording(&surface, args.method, rec)?),
            None => None,
        },
    };
    println!("{}", serde_json::to_string(&summary)?);
    Ok(())
}

/// The surface against the true object of the simulated recording `rec`.
pub fn compare_with_recording(
    surface: &ControlMesh,
    method: Method,
    rec: &Path,
) -> anyhow::Result<fires_record::SurfaceReport> {
    let reader = fires_record::RecordingReader::open(rec)
        .with_context(|| format!("cannot open recording {}", rec.display()))?;
    let truth = crate::pipeline::true_object(&reader)?.ok_or_else(|| {
        anyhow::anyhow!(
            "{} has no true object (truth/world.json target)",
            rec.display()
        )
    })?;
    crate::pipeline::surface_report(surface, method, &truth)
}

/// Writes the mesh to `out` and its curves as OBJ lines to `out` with the extension `.curves.obj`.
pub fn write_surface(surface: &ControlMesh, out: &Path) -> anyhow::Result<PathBuf> {
    let mut soup = PolygonSoup::new();
    soup.points = surface.mesh.positions().to_vec();
    for f in surface.mesh.face_index_lists() {
        soup.push_face(&f);
    }
    write_mesh_file(out, &soup).with_context(|| format!("cannot write {}", out.display()))?;
    let curves = out.with_extension("curves.obj");
    let mut text = String::from("# FIRES curve network: one OBJ line element per curve, metres\n");
    let mut base = 1;
    for c in &surface.curves {
        for p in &c.points {
            text.push_str(&format!("v {:.9} {:.9} {:.9}\n", p.x, p.y, p.z));
        }
        text.push('l');
        for k in 0..c.points.len() {
            text.push_str(&format!(" {}", base + k));
        }
        text.push('\n');
        base += c.points.len();
    }
    std::fs::write(&curves, text).with_context(|| format!("cannot write {}", curves.display()))?;
    Ok(curves)
}

/// The surface shaded in `color` with its drawn curves over it (sharp ones red).
pub fn surface_scene(surface: &ControlMesh, color: [u8; 3]) -> Scene {
    let mut scene = Scene::default();
    scene
        .meshes
        .push(SceneMesh::from_mesh(&surface.mesh, color));
    for c in surface.curves.iter().filter(|c| !c.generated) {
        scene.polylines.push(Polyline {
            points: c.points.clone(),
            color: if c.sharp {
                [200, 30, 30]
            } else {
                [30, 60, 160]
            },
            width: 2,
            closed: false,
        });
    }
    scene
}

/// Distances from the drawn curves' points to a surface, mm.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct CurveDistance {
    /// RMS over the points.
    pub rms_mm: f64,
    /// Largest.
    pub max_mm: f64,
}

/// How far the surface lies from the user's curves (their points against its triangles): the drawn
/// curves are the only measurement, so a surface must not leave them (thesis §6.3).
pub fn curve_distance(surface: &ControlMesh) -> anyhow::Result<CurveDistance> {
    let points: Vec<Vec3> = surface
        .curves
        .iter()
        .filter(|c| !c.generated)
        .flat_map(|c| c.points.iter().copied())
        .collect();
    let d = fires_recon::surface::point_distances(&surface.mesh, &points)?;
    let n = d.len().max(1) as f64;
    Ok(CurveDistance {
        rms_mm: (d.iter().map(|x| x * x).sum::<f64>() / n).sqrt() * 1e3,
        max_mm: d.iter().copied().fold(0.0, f64::max) * 1e3,
    })
}
