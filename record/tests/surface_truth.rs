//! The true object in `truth/world.json` and the surface blocks of `report.json`: written, they read back
//! equal; files written before these fields existed still read.

mod common;
use common::test_meta;
use fires_record::report::{Latency, LinkSummary, MagReport, StageMs, WorldReport};
use fires_record::*;

fn world(target: Option<TargetTruth>) -> WorldTruth {
    WorldTruth {
        gravity_world_mps2: [0.0, 9.81, 0.0],
        earth_field_world_t: [2e-5, 0.0, 4e-5],
        hard_iron_t: [1e-6, 0.0, 0.0],
        soft_iron: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        accel_bias_mps2: [0.01, 0.0, 0.0],
        pen_clock_drift_ppm: 12.5,
        pen_clock_origin_ns: 5,
        disconnects: vec![],
        object: "blob".into(),
        target,
    }
}

fn target(object: ObjectTruth) -> TargetTruth {
    TargetTruth {
        object,
        scene: SceneTruth {
            view: [0.0, 0.0, 1.0],
            e1: [1.0, 0.0, 0.0],
            e2: [0.0, 1.0, 0.0],
            origin_m: [0.03125, 0.0625, 0.5],
            rho_m: 0.044,
            eye_m: [0.0, 0.0, 0.0],
            up: [0.0, -1.0, 0.0],
        },
    }
}

fn objects() -> Vec<ObjectTruth> {
    vec![
        ObjectTruth::Sphere {
            centre_m: [0.0, 0.0, 0.5],
            radius_m: 0.1,
        },
        ObjectTruth::Cylinder {
            centre_m: [0.0, 0.0, 0.5],
            axis: [0.0, -1.0, 0.0],
            radius_m: 0.064,
            half_length_m: 0.096,
        },
        ObjectTruth::RoundedBox {
            centre_m: [0.0, 0.0, 0.5],
            half_extents_m: [0.072, 0.06, 0.064],
            rounding_m: 0.02,
            up: [0.0, -1.0, 0.0],
            yaw_rad: 0.5,
        },
        ObjectTruth::Blob {
            centre_m: [0.03, 0.04, 0.55],
            mean_radius_m: 0.08,
        },
    ]
}

#[test]
fn the_target_is_written_and_read_back_and_an_older_world_file_still_reads() {
    for object in objects() {
        let dir = tempfile::tempdir().unwrap();
        let meta = test_meta(
            (8, 6),
            0.1,
            &[FrameContent::Blobs, FrameContent::Blobs],
            None,
            true,
        );
        let mut w = RecordingWriter::create(dir.path(), &meta).unwrap();
        let written = world(Some(target(object.clone())));
        w.write_world_truth(&written).unwrap();
        w.finish().unwrap();
        let r = RecordingReader::open(dir.path()).unwrap();
        assert_eq!(r.world_truth().unwrap(), Some(written.clone()));
        // Tagged by kind, every length named in metres.
        let text = std::fs::read_to_string(dir.path().join("truth/world.json")).unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        let kind = v["target"]["object"]["kind"].as_str().unwrap().to_string();
        assert!(
            ["sphere", "cylinder", "rounded_box", "blob"].contains(&kind.as_str()),
            "{kind}"
        );
        assert_eq!(v["target"]["scene"]["rho_m"], 0.044);
    }
    // A world.json of a recording written before `target` existed: no field, reads as None, and is not
    // written back with one.
    let old = world(None);
    let mut v = serde_json::to_value(&old).unwrap();
    assert!(v.get("target").is_none());
    v.as_object_mut().unwrap().remove("target");
    let back: WorldTruth = serde_json::from_value(v).unwrap();
    assert_eq!(back, old);
    // An unknown object kind is an error, not a silent None.
    let mut bad = serde_json::to_value(world(Some(target(objects()[0].clone())))).unwrap();
    bad["target"]["object"]["kind"] = "torus".into();
    assert!(serde_json::from_value::<WorldTruth>(bad).is_err());
}

fn replay_report() -> ReplayReport {
    ReplayReport {
        format: REPORT_FORMAT.into(),
        version: REPORT_VERSION.into(),
        recording: Some("rec".into()),
        fusion: "orientation".into(),
        frames: 10,
        frames_tracked: 9,
        frames_vision: 8,
        camera_frames: [5, 5],
        strokes: 3,
        world_reference: "truth".into(),
        world: WorldReport::default(),
        magnetometer: MagReport::default(),
        link: LinkSummary::default(),
        latency_us_per_frame: Latency::default(),
        stage_ms: StageMs::default(),
        wall_ms: 1.5,
        damaged: Damage::default(),
        accuracy: None,
        realtime_factor: None,
        tip_error_plot: None,
        display: None,
        strokes_vs_truth: None,
        strokes_summary: None,
        strokes_floor: None,
        strokes_floor_summary: None,
        vision_refusals: None,
        surface: None,
        surface_from_truth: None,
        network: None,
    }
}

#[test]
fn the_surface_blocks_read_back_and_a_report_without_them_still_reads() {
    let old = replay_report();
    let text = serde_json::to_vec(&Report::Replay(Box::new(old.clone()))).unwrap();
    let v: serde_json::Value = serde_json::from_slice(&text).unwrap();
    assert!(v.get("surface").is_none() && v.get("surface_from_truth").is_none());
    assert_eq!(
        Report::from_json(&text).unwrap(),
        Report::Replay(Box::new(old.clone()))
    );

    let block = |method: &str, rms: f64| SurfaceReport {
        method: method.into(),
        vertices: 3120,
        rms_mm: rms,
        p95_mm: 2.0 * rms,
        hausdorff_mm: 4.0 * rms,
        diag_mm: 130.0,
        rms_pct_diag: 100.0 * rms / 130.0,
        completeness_3mm: 0.98,
        curve_rms_mm: Some(0.05),
    };
    let mut new = old;
    new.surface = Some(block("v2", 0.5));
    new.surface_from_truth = Some(SurfaceReport {
        curve_rms_mm: None,
        ..block("v2", 0.25)
    });
    let report = Report::Replay(Box::new(new));
    let text = serde_json::to_vec(&report).unwrap();
    let v: serde_json::Value = serde_json::from_slice(&text).unwrap();
    // The fields the issue names, in the block.
    for key in [
        "method",
        "vertices",
        "rms_mm",
        "p95_mm",
        "hausdorff_mm",
        "diag_mm",
        "rms_pct_diag",
        "completeness_3mm",
        "curve_rms_mm",
    ] {
        assert!(v["surface"].get(key).is_some(), "{key}");
    }
    assert_eq!(
        v["surface_from_truth"]["curve_rms_mm"],
        serde_json::Value::Null
    );
    assert_eq!(Report::from_json(&text).unwrap(), report);
}
