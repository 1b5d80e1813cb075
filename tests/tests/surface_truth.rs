//! Any replay can measure a surface against the true object: a simulated recording's `truth/world.json`
//! rebuilds the object and the drawn region, and `compare_surface` measures a surface made of the true
//! object itself (a mesh through the lifted region grid) as exact to within its chordal error.

use std::collections::HashMap;

use fires_recon::surface::{compare_surface, CompareOptions};
use fires_recon::{SurfaceMesh, Vec3};
use fires_record::RecordingReader;
use fires_sim::motion::{boundary_polyline, drawn_region, DrawnRegionOptions, Scene};
use fires_sim::objects::V3;
use fires_sim::{run_scenario, SimOptions};

#[test]
fn a_mesh_of_the_true_drawn_region_measures_as_the_true_object() {
    let dir = tempfile::tempdir().unwrap();
    let opts = SimOptions {
        images: false,
        ..SimOptions::default()
    };
    run_scenario("fires-v2", 1, 12.0, dir.path(), opts).unwrap();
    let r = RecordingReader::open(dir.path()).unwrap();
    let target = r.world_truth().unwrap().unwrap().target.expect("target");
    let scene = Scene::from_truth(&target).unwrap();
    let strokes = r.strokes().unwrap().unwrap();
    let boundary = boundary_polyline(&strokes).unwrap();
    let h = 1e-3;
    let region = drawn_region(
        &scene,
        &boundary,
        &DrawnRegionOptions {
            spacing_m: h,
            ..Default::default()
        },
    )
    .unwrap();
    // The region's points sit on the plane grid: index them, and join every grid cell with four corners in
    // the region into a quad.
    let to_v = |p: &V3| Vec3::new(p.x, p.y, p.z);
    let key = |p: &V3| {
        let uv = scene.project(p);
        ((uv[0] / h).round() as i64, (uv[1] / h).round() as i64)
    };
    let index: HashMap<(i64, i64), usize> = region
        .iter()
        .enumerate()
        .map(|(i, p)| (key(p), i))
        .collect();
    let mut faces = Vec::new();
    let mut cells = std::collections::HashSet::new();
    let mut keys: Vec<_> = index.iter().collect();
    keys.sort();
    for (&(i, j), &a) in keys {
        let corners = [(i + 1, j), (i + 1, j + 1), (i, j + 1)].map(|k| index.get(&k).copied());
        if let [Some(b), Some(c), Some(d)] = corners {
            faces.push(vec![a, b, c, d]);
            cells.insert((i, j));
        }
    }
    let cell = |p: &V3| {
        let uv = scene.project(p);
        ((uv[0] / h).floor() as i64, (uv[1] / h).floor() as i64)
    };
    let points: Vec<Vec3> = region.iter().map(to_v).collect();
    let mesh = SurfaceMesh::from_faces(&points, &faces).unwrap();
    // Curve points: the true crossing strokes over the mesh (their points are on the object).
    let curve: Vec<Vec3> = strokes
        .iter()
        .skip(1)
        .flat_map(|s| s.tip_polyline_m.iter())
        .map(|&p| V3::from(p))
        .filter(|p| cells.contains(&cell(p)))
        .map(|p| to_v(&p))
        .collect();
    let c = compare_surface(
        &mesh,
        &curve,
        |p| scene.shape.distance(&V3::new(p.x, p.y, p.z)),
        &points,
        &CompareOptions::default(),
    )
    .unwrap();
    eprintln!("{c:?}");
    // A 1 mm mesh of the true object: its chords stay within a few micrometres of the surface.
    assert!(c.rms_mm < 0.01 && c.hausdorff_mm < 0.05, "{c:?}");
    assert_eq!(c.completeness_3mm, 1.0);
    assert!(c.curve_rms_mm.is_some_and(|d| d < 0.01), "{c:?}");
    // The default scenario's drawn region spans about 130 mm (issue 15).
    assert!((90.0..170.0).contains(&c.diag_mm), "{}", c.diag_mm);
}
