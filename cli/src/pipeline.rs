//! The stages after tracking that `fires replay` (and so `fires demo`) runs: strokes → curve network →
//! surface (FIRESV2), and, for a simulated recording, the comparison of that surface with the true object
//! (`truth/world.json` → `target`) and of a surface built the same way from the true strokes, so tracking and
//! reconstruction errors can be told apart (docs/report.md, "Surface").

use std::path::Path;

use anyhow::Context;
use fires_recon::network::{build_network, BuildOptions, Network, NetworkFile, StrokeInput};
use fires_recon::render::{
    render, save_png, side_by_side, Polyline, RenderOptions, Scene, SceneMesh,
};
use fires_recon::surface::{compare_surface, CompareOptions, ControlMesh};
use fires_recon::Vec3;
use fires_record::report::{NetworkReport, SurfaceReport};
use fires_record::{RecordingReader, StrokeTruth, StrokesFile};
use fires_sim::motion::region::{boundary_polyline, drawn_region, DrawnRegionOptions};
use fires_sim::motion::Scene as TrueScene;

use crate::network::{drawn_side_view, truth_inputs};
use crate::recon::{reconstruct, surface_scene, write_surface, Method};

/// The true object of a simulated recording: its scene (object and drawing plane) and the sample of its
/// drawn region.
pub struct TrueObject {
    /// The object and the plane the strokes were planned in.
    pub scene: TrueScene,
    /// Points of the object inside the true boundary stroke, on the side facing the cameras (1 mm grid).
    pub region: Vec<Vec3>,
    /// The true strokes.
    pub strokes: Vec<StrokeTruth>,
}

/// What the surface stage made.
pub struct SurfaceOutputs {
    /// From the tracked strokes (None when they make no network face).
    pub surface: Option<SurfaceReport>,
    /// From the true strokes (simulated recordings only).
    pub surface_from_truth: Option<SurfaceReport>,
    /// The tracked strokes' network.
    pub network: NetworkReport,
}

fn v3(p: &nalgebra::Vector3<f64>) -> Vec3 {
    Vec3::new(p.x, p.y, p.z)
}

/// The true object of `reader`'s recording, when it has one (older recordings and real ones do not).
pub fn true_object(reader: &RecordingReader) -> anyhow::Result<Option<TrueObject>> {
    let (Some(world), Some(strokes)) = (reader.world_truth()?, reader.strokes()?) else {
        return Ok(None);
    };
    let Some(target) = world.target else {
        return Ok(None);
    };
    let scene = TrueScene::from_truth(&target).context("truth/world.json target")?;
    let Some(boundary) = boundary_polyline(&strokes) else {
        return Ok(None);
    };
    let region = drawn_region(&scene, &boundary, &DrawnRegionOptions::default())
        .context("sampling the true drawn region")?;
    if region.len() < 3 {
        // A boundary cut off before it enclosed anything (a short or damaged session).
        return Ok(None);
    }
    Ok(Some(TrueObject {
        scene,
        region: region.iter().map(v3).collect(),
        strokes,
    }))
}

/// The network of `strokes` (the builder's rules) and its surface, when the network has a face.
/// A network, the number of strokes it used, and its surface with the method that made it.
type Built = (Network, usize, Option<(ControlMesh, Method)>);

fn network_and_surface(strokes: &[StrokeInput]) -> anyhow::Result<Built> {
    let (net, report) = build_network(strokes, &BuildOptions::default());
    if net.n_faces() == 0 {
        return Ok((net, report.used.len(), None));
    }
    // FIRESV2 by default; where its flow cannot be solved (degenerate faces from noisy strokes), FIRESV1,
    // which needs no solve, and the report names the method used.
    let surface = match reconstruct(&net, Method::V2, None) {
        Ok(s) => (s, Method::V2),
        Err(e) => {
            eprintln!("warning: FIRESV2 failed ({e:#}); the surface is FIRESV1's");
            (reconstruct(&net, Method::V1, None)?, Method::V1)
        }
    };
    Ok((net, report.used.len(), Some(surface)))
}

/// The surface against the true object.
pub fn surface_report(
    surface: &ControlMesh,
    method: Method,
    truth: &TrueObject,
) -> anyhow::Result<SurfaceReport> {
    let curves: Vec<Vec3> = surface
        .curves
        .iter()
        .filter(|c| !c.generated)
        .flat_map(|c| c.points.iter().copied())
        .collect();
    let shape = &truth.scene.shape;
    let c = compare_surface(
        &surface.mesh,
        &curves,
        |p| shape.distance(&nalgebra::Vector3::new(p.x, p.y, p.z)),
        &truth.region,
        &CompareOptions::default(),
    )?;
    Ok(SurfaceReport {
        method: method.name().into(),
        vertices: surface.mesh.n_vertices(),
        rms_mm: c.rms_mm,
        p95_mm: c.p95_mm,
        hausdorff_mm: c.hausdorff_mm,
        diag_mm: c.diag_mm,
        rms_pct_diag: c.rms_pct_diag,
        completeness_3mm: c.completeness_3mm,
        curve_rms_mm: c.curve_rms_mm,
    })
}

/// Runs the surface stage on a replay's strokes into `out` (see the module docs).
pub fn surface_stage(
    reader: &RecordingReader,
    strokes: &StrokesFile,
    out: &Path,
) -> anyhow::Result<SurfaceOutputs> {
    let tracked = crate::network::tracked_inputs(strokes);
    let (net, used, surface) = network_and_surface(&tracked)?;
    let net_path = out.join("network.json");
    std::fs::write(&net_path, NetworkFile::to_json(&net) + "\n")
        .with_context(|| format!("cannot write {}", net_path.display()))?;
    let truth = true_object(reader)?;
    let view = truth.as_ref().map(|t| v3(&t.scene.view));
    let mut outputs = SurfaceOutputs {
        surface: None,
        surface_from_truth: None,
        network: NetworkReport {
            faces: net.n_faces(),
            used_strokes: used,
            strokes: tracked.len(),
        },
    };
    if let Some((surface, _)) = &surface {
        let path = out.join("surface.obj");
        write_surface(surface, &path)?;
        let png = out.join("surface.png");
        save_png(
            &two_views(&surface_scene(surface, [205, 190, 160]), view),
            &png,
        )
        .with_context(|| format!("cannot write {}", png.display()))?;
    }
    if let Some(truth) = &truth {
        let object = true_object_mesh(&truth.scene);
        let png = out.join("strokes_on_truth.png");
        let mut scene = Scene::default();
        scene.meshes.push(object.clone());
        for s in &strokes.strokes {
            for piece in &s.pieces {
                scene.polylines.push(Polyline {
                    points: piece
                        .points
                        .iter()
                        .map(|p| Vec3::new(p.p_m[0], p.p_m[1], p.p_m[2]))
                        .collect(),
                    color: [200, 40, 30],
                    width: 2,
                    closed: false,
                });
            }
        }
        save_png(&two_views(&scene, view), &png)
            .with_context(|| format!("cannot write {}", png.display()))?;
        if let Some((surface, method)) = &surface {
            outputs.surface = Some(surface_report(surface, *method, truth)?);
            let png = out.join("surface_error.png");
            save_png(&two_views(&error_scene(surface, truth), view), &png)
                .with_context(|| format!("cannot write {}", png.display()))?;
        }
        let (tnet, _, tsurface) = network_and_surface(&truth_inputs(&truth.strokes))?;
        let path = out.join("network_truth.json");
        std::fs::write(&path, NetworkFile::to_json(&tnet) + "\n")
            .with_context(|| format!("cannot write {}", path.display()))?;
        if let Some((ts, method)) = &tsurface {
            outputs.surface_from_truth = Some(surface_report(ts, *method, truth)?);
            let path = out.join("surface_truth.obj");
            write_surface(ts, &path)?;
            let png = out.join("surface_truth_error.png");
            save_png(&two_views(&error_scene(ts, truth), view), &png)
                .with_context(|| format!("cannot write {}", png.display()))?;
        }
    }
    Ok(outputs)
}

/// A front view onto the drawn side (along `view`, the cameras' viewing direction, when known) and an
/// oblique one, side by side.
fn two_views(scene: &Scene, view: Option<Vec3>) -> fires_recon::render::RgbImage {
    let pts: Vec<Vec3> = scene
        .meshes
        .iter()
        .flat_map(|m| m.positions.iter().copied())
        .chain(
            scene
                .polylines
                .iter()
                .flat_map(|l| l.points.iter().copied()),
        )
        .collect();
    let mut front = drawn_side_view(&pts);
    if let Some(v) = view.and_then(Vec3::try_normalize) {
        let up = front.camera.up;
        let up = (up - v * up.dot(v)).normalize_or_zero();
        front.camera.direction = (v + up * -0.25).normalize_or_zero();
        front.camera.up = up;
        front.light = v + up * -0.5 + v.cross(up) * 0.3;
    }
    let mut oblique: RenderOptions = front;
    let d = front.camera.direction;
    let side = d.cross(front.camera.up).normalize_or_zero();
    oblique.camera.direction = (d + side * 0.9).normalize_or_zero();
    side_by_side(&[render(scene, &front), render(scene, &oblique)])
}

/// The true object's camera-facing side over the planning disc (1.3 ρ), lifted from a square grid.
fn true_object_mesh(scene: &TrueScene) -> SceneMesh {
    let n = 80usize;
    let r = 1.3 * scene.rho;
    let mut idx = vec![None; (n + 1) * (n + 1)];
    let mut mesh = SceneMesh {
        color: [190, 200, 215],
        ..SceneMesh::default()
    };
    for i in 0..=n {
        for j in 0..=n {
            let uv = [
                -r + 2.0 * r * i as f64 / n as f64,
                -r + 2.0 * r * j as f64 / n as f64,
            ];
            if let Some((p, _)) = scene.lift(uv) {
                idx[i * (n + 1) + j] = Some(mesh.positions.len());
                mesh.positions.push(v3(&p));
            }
        }
    }
    for i in 0..n {
        for j in 0..n {
            let q = [
                idx[i * (n + 1) + j],
                idx[(i + 1) * (n + 1) + j],
                idx[(i + 1) * (n + 1) + j + 1],
                idx[i * (n + 1) + j + 1],
            ];
            if let [Some(a), Some(b), Some(c), Some(d)] = q {
                mesh.faces.push(vec![a, b, c, d]);
            }
        }
    }
    mesh
}

/// The surface's faces coloured by their centre's distance to the true object: green up to 0.25 mm,
/// through yellow (0.5 mm) and orange (1 mm) to red from 2 mm.
fn error_scene(surface: &ControlMesh, truth: &TrueObject) -> Scene {
    const BINS: [(f64, [u8; 3]); 5] = [
        (0.25e-3, [90, 180, 90]),
        (0.5e-3, [200, 210, 80]),
        (1e-3, [235, 170, 60]),
        (2e-3, [230, 110, 50]),
        (f64::INFINITY, [200, 40, 40]),
    ];
    let positions = surface.mesh.positions().to_vec();
    let mut meshes: Vec<SceneMesh> = BINS
        .iter()
        .map(|&(_, color)| SceneMesh {
            positions: positions.clone(),
            faces: Vec::new(),
            color,
        })
        .collect();
    for f in surface.mesh.face_index_lists() {
        let c = f.iter().fold(Vec3::ZERO, |s, &i| s + positions[i]) * (1.0 / f.len().max(1) as f64);
        let d = truth
            .scene
            .shape
            .distance(&nalgebra::Vector3::new(c.x, c.y, c.z));
        let bin = BINS
            .iter()
            .position(|&(limit, _)| d <= limit)
            .unwrap_or(BINS.len() - 1);
        meshes[bin].faces.push(f);
    }
    Scene {
        meshes: meshes.into_iter().filter(|m| !m.faces.is_empty()).collect(),
        polylines: Vec::new(),
    }
}
