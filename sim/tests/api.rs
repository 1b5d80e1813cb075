//! The public entry point: errors, options, and what the metadata says each camera provides.

use fires_record::{FrameContent, RecordingReader};
use fires_sim::{run_scenario, SimError, SimOptions, SCENARIOS};

#[test]
fn bad_arguments_are_typed_errors() {
    let dir = tempfile::tempdir().unwrap();
    assert!(matches!(
        run_scenario("nope", 1, 1.0, dir.path(), SimOptions::default()),
        Err(SimError::UnknownScenario(_))
    ));
    for d in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            run_scenario("bar", 1, d, dir.path(), SimOptions::default()),
            Err(SimError::BadDuration(_))
        ));
    }
    // An output path that cannot be a directory.
    let file = dir.path().join("file");
    std::fs::write(&file, b"x").unwrap();
    assert!(matches!(
        run_scenario("bar", 1, 0.2, &file, SimOptions::default()),
        Err(SimError::Record(_))
    ));
}

#[test]
fn unknown_scenario_error_lists_every_scenario() {
    let dir = tempfile::tempdir().unwrap();
    let err =
        run_scenario("nope", 1, 1.0, dir.path(), SimOptions::default()).expect_err("unknown name");
    let msg = err.to_string();
    assert!(msg.contains("\"nope\""), "{msg}");
    let listed = msg
        .split_once("(known: ")
        .and_then(|(_, rest)| rest.strip_suffix(')'))
        .unwrap_or_else(|| panic!("no list in {msg}"));
    let names: Vec<&str> = SCENARIOS.iter().map(|(n, _)| *n).collect();
    assert_eq!(listed.split(", ").collect::<Vec<_>>(), names);
    assert!(names.contains(&"pivot"), "{names:?}");
}

#[test]
fn every_scenario_runs_and_says_what_its_cameras_provide() {
    for (name, _) in SCENARIOS {
        for images in [true, false] {
            let dir = tempfile::tempdir().unwrap();
            let opts = SimOptions {
                images,
                truth: false,
                object: None,
                ..SimOptions::default()
            };
            let s = run_scenario(name, 2, 0.3, dir.path(), opts).unwrap();
            assert!(s.imu_samples >= 28 && s.frames.len() == 2, "{name}: {s:?}");
            let r = RecordingReader::open(dir.path()).unwrap();
            assert!(!r.has_truth() && !dir.path().join("truth").exists());
            for cam in &r.meta().cameras {
                let frames = r.frames(cam.id).unwrap();
                assert!(!frames.is_empty());
                match cam.provides {
                    FrameContent::Images => {
                        assert!(
                            images
                                && frames
                                    .iter()
                                    .all(|f| f.image.is_some() && f.blobs.is_none())
                        )
                    }
                    FrameContent::Blobs => {
                        assert!(frames
                            .iter()
                            .all(|f| f.blobs.is_some() && f.image.is_none()))
                    }
                }
            }
            let wii = name.starts_with("fires-v1") || ["bar", "tip", "pivot"].contains(name);
            assert_eq!(
                r.meta().cameras[0].provides,
                if images && !wii {
                    FrameContent::Images
                } else {
                    FrameContent::Blobs
                },
                "{name}"
            );
        }
    }
}
