//! `fires network STROKES.json [--journal J] -o network.json [--png P]`: the curve network from strokes
//! (the tracker's `strokes.json`, or a simulated recording's `truth/strokes.json`), built by the
//! insertion rules (docs/network.md) or replayed from a sketch journal; one JSON summary line on
//! standard output.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use fires_recon::network::{
    build_network, replay, BuildOptions, BuildReport, Journal, Network, NetworkFile, StrokeInput,
    Topology,
};
use fires_recon::render::{render, save_png, Camera, Polyline, RenderOptions, Scene, SceneMesh};
use fires_recon::Vec3;
use fires_record::{StrokeTruth, StrokesFile};
use serde::Serialize;

use crate::output::write_json;

/// Arguments of `fires network`.
#[derive(Debug, clap::Args)]
pub struct NetworkArgs {
    /// Strokes: a `strokes.json` from `fires replay`, or a recording's `truth/strokes.json`.
    pub strokes: PathBuf,
    /// Replay this sketch journal over the strokes instead of building by the insertion rules.
    #[arg(long)]
    pub journal: Option<PathBuf>,
    /// Output `network.json`.
    #[arg(short, long)]
    pub out: PathBuf,
    /// Also write the journal of the build (the steps taken), to replay or edit later.
    #[arg(long)]
    pub journal_out: Option<PathBuf>,
    /// Write a picture of the network (curves over its faces).
    #[arg(long)]
    pub png: Option<PathBuf>,
}

/// The summary line of `fires network`.
#[derive(Debug, Serialize)]
pub struct NetworkSummary {
    /// Counts and Euler characteristic.
    #[serde(flatten)]
    pub topology: Topology,
    /// Strokes read.
    pub strokes: usize,
    /// Strokes used by the network.
    pub used_strokes: usize,
    /// Strokes not used, with the rule that failed.
    pub rejected: Vec<RejectedLine>,
    /// Wall time of the build, milliseconds.
    pub ms: f64,
}

/// One rejected stroke in the summary.
#[derive(Debug, Serialize)]
pub struct RejectedLine {
    /// Stroke id.
    pub stroke: u32,
    /// The rule that failed.
    pub rule: String,
    /// What failed, with the distance where one applies.
    pub detail: String,
}

/// Reads strokes for the network builder from either strokes format.
pub fn load_stroke_inputs(path: &Path) -> anyhow::Result<Vec<StrokeInput>> {
    let text = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    let value: serde_json::Value =
        serde_json::from_slice(&text).with_context(|| format!("{} is not JSON", path.display()))?;
    if value.is_array() {
        let truth: Vec<StrokeTruth> = serde_json::from_value(value)
            .with_context(|| format!("{} is not a truth strokes list", path.display()))?;
        return Ok(truth_inputs(&truth));
    }
    let file =
        StrokesFile::from_json(&text).with_context(|| format!("reading {}", path.display()))?;
    Ok(tracked_inputs(&file))
}

/// The tracker's strokes as builder input (the pen mode is `buttons >> 1`; sigma the largest of its points).
pub fn tracked_inputs(file: &StrokesFile) -> Vec<StrokeInput> {
    file.strokes
        .iter()
        .filter(|s| !s.is_empty())
        .map(|s| StrokeInput {
            id: s.id,
            points: s.polyline_m(),
            closed: s.closed,
            sigma_mm: s
                .points()
                .filter_map(|p| p.sigma_mm)
                .fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.max(v)))),
            mode: s.buttons >> 1,
            untracked_mm: s.untracked_mm(),
        })
        .collect()
}

/// The simulator's true strokes as builder input (the boundary is closed; no uncertainty).
pub fn truth_inputs(truth: &[StrokeTruth]) -> Vec<StrokeInput> {
    truth
        .iter()
        .filter(|s| s.tip_polyline_m.len() >= 2)
        .map(|s| StrokeInput {
            id: s.id,
            points: s.tip_polyline_m.clone(),
            closed: matches!(s.kind, fires_record::StrokeKind::Boundary),
            sigma_mm: None,
            mode: s.mode,
            untracked_mm: [0.0; 2],
        })
        .collect()
}

/// Builds (or replays) the network of `strokes`.
pub fn network_of(
    strokes: &[StrokeInput],
    journal: Option<&Path>,
) -> anyhow::Result<(Network, Option<BuildReport>)> {
    match journal {
        Some(j) => {
            let text = std::fs::read(j).with_context(|| format!("cannot read {}", j.display()))?;
            let journal: Journal = serde_json::from_slice(&text)
                .with_context(|| format!("{} is not a sketch journal", j.display()))?;
            let net =
                replay(&journal, strokes).with_context(|| format!("replaying {}", j.display()))?;
            Ok((net, None))
        }
        None => {
            let (net, report) = build_network(strokes, &BuildOptions::default());
            Ok((net, Some(report)))
        }
    }
}

/// Runs `fires network`.
pub fn run(args: &NetworkArgs) -> anyhow::Result<()> {
    let strokes = load_stroke_inputs(&args.strokes)?;
    let t0 = Instant::now();
    let (net, report) = network_of(&strokes, args.journal.as_deref())?;
    let ms = t0.elapsed().as_secs_f64() * 1e3;
    std::fs::write(&args.out, NetworkFile::to_json(&net) + "\n")
        .with_context(|| format!("cannot write {}", args.out.display()))?;
    if let (Some(path), Some(r)) = (&args.journal_out, &report) {
        write_json(path, &r.journal)?;
    }
    if let Some(png) = &args.png {
        save_png(&render(&network_scene(&net), &network_view(&net)), png)
            .with_context(|| format!("cannot write {}", png.display()))?;
    }
    let summary = NetworkSummary {
        strokes: strokes.len(),
        used_strokes: report.as_ref().map_or(strokes.len(), |r| r.used.len()),
        rejected: report
            .as_ref()
            .map(|r| {
                r.rejected
                    .iter()
                    .map(|x| RejectedLine {
                        stroke: x.stroke,
                        rule: x.rule.clone(),
                        detail: x.detail.clone(),
                    })
                    .collect()
            })
            .unwrap_or_default(),
        topology: net.topology(),
        ms,
    };
    println!("{}", serde_json::to_string(&summary)?);
    Ok(())
}

/// The network's faces (fan-filled, pale) with its curves drawn over them.
pub fn network_scene(net: &Network) -> Scene {
    let mut scene = Scene::default();
    for (k, (f, _)) in net.faces().enumerate() {
        let pts = net.face_points(f);
        scene.meshes.push(SceneMesh {
            positions: pts.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect(),
            faces: vec![(0..pts.len()).collect()],
            color: face_colour(k),
        });
    }
    for (_, p) in net.polylines() {
        scene.polylines.push(Polyline {
            points: p
                .points
                .iter()
                .map(|q| Vec3::new(q[0], q[1], q[2]))
                .collect(),
            color: if p.attrs.sharpness >= 0.5 {
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

/// A pale colour per face, neighbours in handle order told apart (golden-angle hues).
fn face_colour(k: usize) -> [u8; 3] {
    let h = (k as f64 * 0.618_033_988_75).fract() * 6.0;
    let x = 1.0 - (h % 2.0 - 1.0).abs();
    let (r, g, b) = match h as usize {
        0 => (1.0, x, 0.0),
        1 => (x, 1.0, 0.0),
        2 => (0.0, 1.0, x),
        3 => (0.0, x, 1.0),
        4 => (x, 0.0, 1.0),
        _ => (1.0, 0.0, x),
    };
    let pale = |c: f64| (150.0 + 90.0 * c) as u8;
    [pale(r), pale(g), pale(b)]
}

/// A view onto the drawn side of a set of points: along the normal of their best-fit plane, pointing
/// away from the world origin (the rig's cameras sit near it).
pub fn drawn_side_view(points: &[Vec3]) -> RenderOptions {
    let mut o = RenderOptions::default();
    if points.len() < 3 {
        return o;
    }
    let c = points.iter().fold(Vec3::ZERO, |s, p| s + *p) * (1.0 / points.len() as f64);
    let mut m = [[0.0f64; 3]; 3];
    for p in points {
        let d = *p - c;
        let d = [d.x, d.y, d.z];
        for (i, row) in m.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v += d[i] * d[j];
            }
        }
    }
    let n = smallest_eigenvector(m);
    let mut dir = Vec3::new(n[0], n[1], n[2]);
    if dir.dot(c) < 0.0 {
        dir = -dir;
    }
    // Tilt a little so relief shows in the shading.
    let side = if dir.z.abs() < 0.9 {
        Vec3::new(0.0, 0.0, 1.0)
    } else {
        Vec3::new(0.0, 1.0, 0.0)
    };
    let up = (side - dir * side.dot(dir)).normalize_or_zero();
    o.camera = Camera {
        direction: (dir + up * -0.25).normalize_or_zero(),
        up,
    };
    o.light = dir + up * -0.5 + dir.cross(up) * 0.3;
    o
}

fn network_view(net: &Network) -> RenderOptions {
    let pts: Vec<Vec3> = net
        .polylines()
        .flat_map(|(_, p)| p.points.iter().map(|q| Vec3::new(q[0], q[1], q[2])))
        .collect();
    drawn_side_view(&pts)
}

/// The unit eigenvector of the smallest eigenvalue of a symmetric 3×3 matrix (by inverse power
/// iteration on a shifted matrix; exact enough for picking a view).
fn smallest_eigenvector(m: [[f64; 3]; 3]) -> [f64; 3] {
    let na = nalgebra::Matrix3::from_fn(|i, j| m[i][j]);
    let eig = na.symmetric_eigen();
    let mut k = 0;
    for i in 1..3 {
        if eig.eigenvalues[i] < eig.eigenvalues[k] {
            k = i;
        }
    }
    let v = eig.eigenvectors.column(k);
    [v[0], v[1], v[2]]
}
