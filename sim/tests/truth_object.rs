//! The true object as recorded data: the description round-trips, the rebuilt object is the same, its surface
//! distance is the Euclidean one (against a brute-force dense sample), and the true drawn region.

use fires_record::{ObjectTruth, RecordingReader, TargetTruth};
use fires_sim::motion::{boundary_polyline, drawn_region, DrawnRegionOptions, RegionError, Scene};
use fires_sim::objects::{from_truth, Blob, ObjectKind, Shape, TruthError, V3};
use fires_sim::rng::SimRng;
use fires_sim::{run_scenario, SimOptions};

fn up() -> V3 {
    fires_sim::scenario::world_up()
}

fn centre() -> V3 {
    V3::new(0.03, 0.04, 0.55)
}

fn unit(rng: &mut SimRng) -> V3 {
    loop {
        let v = V3::new(rng.normal(), rng.normal(), rng.normal());
        if let Some(u) = v.try_normalize(1e-6) {
            return u;
        }
    }
}

/// The surface point in the direction `u` from the centre (every object here is star-shaped about its
/// centre): a ray cast inward from outside, independent of the distance code under test.
fn radial_point(shape: &dyn Shape, u: &V3) -> V3 {
    let c = shape.bound_centre();
    let far = 2.0 * shape.bound_radius() + 0.1;
    let start = c + u * far;
    let t = shape.ray_hit(&start, &(-u), 2.0 * far).expect("ray hits");
    start - u * t
}

/// Two JSON values equal but for numbers, which may differ by `tol` (JSON text keeps 17 digits, not always
/// the last bit).
fn assert_close(a: &serde_json::Value, b: &serde_json::Value, tol: f64) {
    use serde_json::Value;
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            assert!((x - y).abs() <= tol, "{x} vs {y}");
        }
        (Value::Array(x), Value::Array(y)) => {
            assert_eq!(x.len(), y.len());
            x.iter().zip(y).for_each(|(x, y)| assert_close(x, y, tol));
        }
        (Value::Object(x), Value::Object(y)) => {
            assert_eq!(x.keys().collect::<Vec<_>>(), y.keys().collect::<Vec<_>>());
            x.iter().for_each(|(k, v)| assert_close(v, &y[k], tol));
        }
        _ => assert_eq!(a, b),
    }
}

fn chart(u: &V3, a: f64, b: f64) -> V3 {
    let helper = if u.x.abs() < 0.9 { V3::x() } else { V3::y() };
    let t1 = u.cross(&helper).normalize();
    let t2 = u.cross(&t1);
    (u + t1 * a + t2 * b).normalize()
}

/// Brute force: distance to a dense Fibonacci sample of directions, then around the three best samples a
/// 9 x 9 grid of directions zoomed by 4 each level down to 1e-10 rad.
fn brute_distance(surf: &dyn Fn(&V3) -> V3, p: &V3) -> f64 {
    let n = 2000;
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let mut samples: Vec<(f64, V3)> = (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            let u = V3::new(r * phi.cos(), r * phi.sin(), z);
            ((surf(&u) - p).norm(), u)
        })
        .collect();
    samples.sort_by(|a, b| a.0.total_cmp(&b.0));
    let spacing = (4.0 * std::f64::consts::PI / n as f64).sqrt();
    let mut best = f64::INFINITY;
    for (_, u0) in samples.iter().take(3) {
        let (mut uc, mut s) = (*u0, 2.0 * spacing);
        while s > 1e-10 {
            let mut local = (f64::INFINITY, uc);
            for i in -4..=4 {
                for j in -4..=4 {
                    let u = chart(&uc, s * i as f64 / 4.0, s * j as f64 / 4.0);
                    let d = (surf(&u) - p).norm();
                    if d < local.0 {
                        local = (d, u);
                    }
                }
            }
            uc = local.1;
            best = best.min(local.0);
            s /= 4.0;
        }
    }
    best
}

#[test]
fn the_object_description_round_trips_and_rebuilds_the_same_object() {
    let mut rng = SimRng::stream(7, 0);
    for kind in ObjectKind::ALL {
        let shape = kind.build(centre(), 0.08, up());
        let t = shape.to_truth();
        let json = serde_json::to_string(&t).unwrap();
        let back: ObjectTruth = serde_json::from_str(&json).unwrap();
        assert_close(
            &serde_json::to_value(&back).unwrap(),
            &serde_json::to_value(&t).unwrap(),
            1e-15,
        );
        let rebuilt = from_truth(&back).unwrap();
        for _ in 0..200 {
            let p = centre() + unit(&mut rng) * rng.range(0.0, 0.15);
            assert!(
                (rebuilt.sdf(&p) - shape.sdf(&p)).abs() < 1e-12,
                "{kind:?} at {p:?}"
            );
        }
        // The recovered description is the one the object was built from (box: up and yaw recovered).
        let again = rebuilt.to_truth();
        assert_close(
            &serde_json::to_value(&t).unwrap(),
            &serde_json::to_value(&again).unwrap(),
            1e-12,
        );
        if let ObjectTruth::RoundedBox { up: u, yaw_rad, .. } = t {
            assert!((V3::from(u) - up()).norm() < 1e-12, "{u:?}");
            assert!((yaw_rad - 30f64.to_radians()).abs() < 1e-12, "{yaw_rad}");
        }
    }
}

#[test]
fn bad_object_descriptions_are_typed_errors() {
    let bad = [
        ObjectTruth::Sphere {
            centre_m: [0.0, f64::NAN, 0.0],
            radius_m: 0.1,
        },
        ObjectTruth::Sphere {
            centre_m: [0.0; 3],
            radius_m: -0.1,
        },
        ObjectTruth::Cylinder {
            centre_m: [0.0; 3],
            axis: [0.0; 3],
            radius_m: 0.1,
            half_length_m: 0.1,
        },
        ObjectTruth::RoundedBox {
            centre_m: [0.0; 3],
            half_extents_m: [0.1, 0.1, 0.01],
            rounding_m: 0.02,
            up: [0.0, -1.0, 0.0],
            yaw_rad: 0.0,
        },
        ObjectTruth::RoundedBox {
            centre_m: [0.0; 3],
            half_extents_m: [0.1, 0.1, 0.1],
            rounding_m: 0.02,
            up: [0.0, 0.0, 1.0],
            yaw_rad: 0.0,
        },
        ObjectTruth::Blob {
            centre_m: [0.0; 3],
            mean_radius_m: f64::INFINITY,
        },
    ];
    for t in &bad {
        let e = from_truth(t).expect_err("refused");
        assert!(matches!(
            e,
            TruthError::NotFinite(_) | TruthError::OutOfRange(_) | TruthError::NotADirection(_)
        ));
    }
}

#[test]
fn surface_distance_is_euclidean_to_a_micrometre_near_the_surface() {
    let mut rng = SimRng::stream(11, 0);
    for kind in ObjectKind::ALL {
        let shape = kind.build(centre(), 0.08, up());
        let blob = Blob {
            centre: centre(),
            radius: 0.08,
        };
        let surf = |u: &V3| {
            if kind == ObjectKind::Blob {
                blob.surface_point(u)
            } else {
                radial_point(shape.as_ref(), u)
            }
        };
        let points = if kind == ObjectKind::Blob { 60 } else { 10 };
        let mut worst: f64 = 0.0;
        for i in 0..points {
            let on = surf(&unit(&mut rng));
            // Within 20 mm of the surface, inside and outside (the first few very close to it).
            let reach = if i < 3 { 1e-5 } else { 0.02 };
            let p = on + unit(&mut rng) * rng.range(0.0, reach);
            let d = shape.distance(&p);
            let q = shape.closest_point(&p);
            let want = brute_distance(&surf, &p);
            worst = worst.max((d - want).abs());
            assert!(
                (d - want).abs() <= 1e-6,
                "{kind:?} point {i}: distance {d} vs brute force {want}"
            );
            assert!(
                shape.sdf(&q).abs() < 1e-9,
                "{kind:?}: closest point off the surface"
            );
            assert!(((q - p).norm() - d).abs() < 1e-6, "{kind:?}");
        }
        eprintln!("{kind:?}: worst |distance - brute force| = {worst:.2e} m");
    }
}

#[test]
fn the_drawn_region_is_the_lifted_grid_inside_the_boundary() {
    // A sphere seen along +z: a circular boundary of plane radius r lifts to a cap; the grid inside it has
    // about pi r^2 / h^2 points, all on the sphere's camera-facing side.
    let radius = 0.1;
    let shape = ObjectKind::Sphere.build(centre(), radius, up());
    let scene = Scene::new(shape, V3::z(), up(), V3::zeros(), 0.05);
    let r = 0.04;
    let boundary: Vec<V3> = (0..400)
        .map(|k| {
            let th = std::f64::consts::TAU * k as f64 / 400.0;
            scene
                .lift([r * th.cos(), r * th.sin()])
                .expect("on the sphere")
                .0
        })
        .collect();
    let h = 1e-3;
    let opts = DrawnRegionOptions {
        spacing_m: h,
        ..Default::default()
    };
    let region = drawn_region(&scene, &boundary, &opts).unwrap();
    let expect = std::f64::consts::PI * r * r / (h * h);
    assert!(
        (region.len() as f64 - expect).abs() < 2.0 * std::f64::consts::TAU * r / h,
        "{} vs {expect}",
        region.len()
    );
    for p in &region {
        assert!(scene.shape.distance(p) < 1e-9);
        assert!(
            scene.shape.normal(p).dot(&scene.view) < 0.0,
            "facing the cameras"
        );
        let uv = scene.project(p);
        assert!(uv[0].hypot(uv[1]) <= r + 1e-12);
        // On the plane grid.
        for x in uv {
            assert!(((x / h) - (x / h).round()).abs() < 1e-6);
        }
    }
    // Halving the spacing quadruples the count.
    let fine = drawn_region(
        &scene,
        &boundary,
        &DrawnRegionOptions {
            spacing_m: h / 2.0,
            ..Default::default()
        },
    )
    .unwrap();
    let ratio = fine.len() as f64 / region.len() as f64;
    assert!((ratio - 4.0).abs() < 0.1, "{ratio}");
    // Bad input is refused.
    assert_eq!(
        drawn_region(&scene, &boundary[..2], &opts),
        Err(RegionError::BadBoundary)
    );
    assert!(matches!(
        drawn_region(
            &scene,
            &boundary,
            &DrawnRegionOptions {
                spacing_m: 0.0,
                ..Default::default()
            }
        ),
        Err(RegionError::BadSpacing(_))
    ));
    assert!(matches!(
        drawn_region(
            &scene,
            &boundary,
            &DrawnRegionOptions {
                spacing_m: 1e-7,
                ..Default::default()
            }
        ),
        Err(RegionError::TooManyPoints(..))
    ));
}

#[test]
fn a_simulated_recording_describes_its_object_and_scene() {
    let dir = tempfile::tempdir().unwrap();
    let opts = SimOptions {
        images: false,
        truth: true,
        object: None,
        ..SimOptions::default()
    };
    run_scenario("fires-v2", 3, 12.0, dir.path(), opts).unwrap();
    let r = RecordingReader::open(dir.path()).unwrap();
    let world = r.world_truth().unwrap().expect("world truth");
    let target: TargetTruth = world.target.clone().expect("target in world.json");
    assert!(matches!(target.object, ObjectTruth::Blob { .. }));
    let scene = Scene::from_truth(&target).unwrap();
    assert_close(
        &serde_json::to_value(scene.to_truth()).unwrap(),
        &serde_json::to_value(&target).unwrap(),
        1e-15,
    );
    // The true strokes were drawn on the object: the tip touches it.
    let strokes = r.strokes().unwrap().expect("strokes");
    let boundary = boundary_polyline(&strokes).expect("a boundary stroke");
    let worst = boundary
        .iter()
        .map(|p| scene.shape.distance(p))
        .fold(0.0, f64::max);
    assert!(worst < 1e-6, "boundary {worst} m off the object");
    let region = drawn_region(&scene, &boundary, &DrawnRegionOptions::default()).unwrap();
    assert!(region.len() > 1000, "{}", region.len());
    // An older world.json without `target` still reads.
    let mut v = serde_json::to_value(&world).unwrap();
    v.as_object_mut().unwrap().remove("target");
    let old: fires_record::WorldTruth = serde_json::from_value(v).unwrap();
    assert_eq!(old.target, None);
}
