//! Write/read round trip and malformed-input handling of the recording format.

mod common;
use common::test_meta;
use fires_protocol::{Frame, SensorPacket};
use fires_record::*;
use std::fs;
use std::path::Path;

fn meta(has_truth: bool) -> Meta {
    test_meta(
        (8, 6),
        0.1,
        &[FrameContent::Images, FrameContent::Blobs],
        Some(7),
        has_truth,
    )
}

fn pose() -> PoseTruth {
    PoseTruth {
        tip_m: [0.1, 0.2, 0.3],
        orientation_xyzw: [0.0, 0.0, 0.0, 1.0],
        leds_m: vec![[0.0, 0.0, 0.5]],
    }
}

fn write_sample(dir: &Path) -> (Vec<LinkChunk>, Vec<CameraFrame>, GrayImage) {
    let m = meta(true);
    let mut w = RecordingWriter::create(dir, &m).unwrap();
    let chunks = vec![
        LinkChunk {
            host_time_ns: 5,
            bytes: vec![1, 2, 3],
        },
        LinkChunk {
            host_time_ns: 9,
            bytes: vec![],
        },
        LinkChunk {
            host_time_ns: u64::MAX,
            bytes: (0..=255).collect(),
        },
    ];
    for c in &chunks {
        w.write_link_chunk(c).unwrap();
    }
    let mut img = GrayImage::new(8, 6);
    img.data[13] = 200;
    let f0 = CameraFrame {
        camera: 0,
        index: 3,
        exposure_time_ns: 1234,
        blobs: None,
        image: None,
    };
    w.write_frame(&f0, Some(&img)).unwrap();
    let f1 = CameraFrame {
        camera: 1,
        index: 0,
        exposure_time_ns: 1300,
        blobs: Some(vec![Blob {
            x: 1.25,
            y: 2.5,
            area: 3.0,
            intensity: 255.0,
        }]),
        image: None,
    };
    w.write_frame(&f1, None).unwrap();
    w.write_imu_truth(&ImuTruth {
        sample_index: 0,
        counter: 0,
        device_time_us: 10,
        time_ns: 20,
        pose: pose(),
        specific_force_mps2: [0.0, 9.8, 0.0],
        angular_velocity_radps: [0.0; 3],
        earth_field_t: [1e-5, 2e-5, 3e-5],
        gyro_bias_radps: [0.0; 3],
        buttons: 1,
    })
    .unwrap();
    w.write_packet_truth(&PacketTruth {
        send_time_ns: 1,
        frame: Frame::Sensor(SensorPacket {
            counter: 4,
            accel: [1, -2, 3],
            gyro: [4, 5, -6],
            mag: [7, 8, 9],
        }),
        fate: PacketFate::Damaged,
    })
    .unwrap();
    w.write_exposure_truth(&ExposureTruth {
        camera: 0,
        index: 3,
        exposure_time_ns: 1233,
        pose: pose(),
        leds: vec![LedTruth {
            pixel: Some([3.5, 2.5]),
            visibility: Visibility::OccludedByHand,
            brightness: 0.5,
        }],
        spurious: vec![[1.0, 1.0]],
    })
    .unwrap();
    w.write_strokes(&[StrokeTruth {
        id: 0,
        kind: StrokeKind::Boundary,
        start_time_ns: 1,
        end_time_ns: 2,
        complete: true,
        starts_on: None,
        ends_on: None,
        crosses: vec![],
        tip_polyline_m: vec![[0.0; 3], [1.0, 0.0, 0.0]],
        mode: 1,
    }])
    .unwrap();
    w.finish().unwrap();
    let mut f0 = f0;
    f0.image = Some("000003.pgm".into());
    (chunks, vec![f0, f1], img)
}

#[test]
fn write_then_read_gives_the_same_data() {
    let dir = tempfile::tempdir().unwrap();
    let (chunks, frames, img) = write_sample(dir.path());
    let r = RecordingReader::open(dir.path()).unwrap();
    assert_eq!(r.meta(), &meta(true));
    assert_eq!(r.link_chunks().unwrap(), chunks);
    assert_eq!(r.frames(0).unwrap(), vec![frames[0].clone()]);
    assert_eq!(r.frames(1).unwrap(), vec![frames[1].clone()]);
    assert_eq!(r.image(&frames[0]).unwrap(), Some(img));
    assert_eq!(r.image(&frames[1]).unwrap(), None);
    assert_eq!(r.imu_truth().unwrap().unwrap()[0].buttons, 1);
    let p = &r.packet_truth().unwrap().unwrap()[0];
    assert_eq!(p.fate, PacketFate::Damaged);
    assert!(matches!(p.frame, Frame::Sensor(s) if s.gyro == [4, 5, -6]));
    assert_eq!(
        r.exposure_truth().unwrap().unwrap()[0].leds[0].visibility,
        Visibility::OccludedByHand
    );
    assert_eq!(r.strokes().unwrap().unwrap()[0].tip_polyline_m.len(), 2);
    assert!(matches!(
        r.frames(2),
        Err(RecordError::UnknownCamera { camera: 2 })
    ));
}

#[test]
fn a_recording_without_truth_has_none() {
    let dir = tempfile::tempdir().unwrap();
    let mut w = RecordingWriter::create(dir.path(), &meta(false)).unwrap();
    assert!(w.write_strokes(&[]).is_err());
    w.finish().unwrap();
    let r = RecordingReader::open(dir.path()).unwrap();
    assert!(r.imu_truth().unwrap().is_none());
    assert!(r.strokes().unwrap().is_none());
    assert!(r.link_chunks().unwrap().is_empty());
    assert!(!dir.path().join("truth").exists());
}

#[test]
fn unknown_major_version_is_rejected_and_minor_is_accepted() {
    let dir = tempfile::tempdir().unwrap();
    write_sample(dir.path());
    let path = dir.path().join("meta.json");
    let text = fs::read_to_string(&path).unwrap();
    let current = format!("\"{}\"", fires_record::FORMAT_VERSION);
    fs::write(&path, text.replace(&current, "\"1.7\"")).unwrap();
    RecordingReader::open(dir.path()).unwrap();
    for bad in ["\"2.0\"", "\"1\"", "\"x.y\"", "\"1.\""] {
        fs::write(&path, text.replace(&current, bad)).unwrap();
        let e = RecordingReader::open(dir.path()).unwrap_err();
        assert!(
            matches!(e, RecordError::UnsupportedVersion { .. }),
            "{bad}: {e}"
        );
    }
    fs::write(&path, text.replace("fires-recording", "other")).unwrap();
    assert!(matches!(
        RecordingReader::open(dir.path()),
        Err(RecordError::NotARecording { .. })
    ));
}

#[test]
fn malformed_files_give_typed_errors_with_location() {
    let dir = tempfile::tempdir().unwrap();
    write_sample(dir.path());
    let r = RecordingReader::open(dir.path()).unwrap();

    // A broken JSON line reports its line number.
    let frames = dir.path().join("cam1").join("frames.jsonl");
    let good = fs::read_to_string(&frames).unwrap();
    fs::write(&frames, format!("{good}{{\"camera\": 1, \"index\": \n")).unwrap();
    match r.frames(1) {
        Err(RecordError::Json { line, path, .. }) => {
            assert_eq!(line, 2);
            assert!(path.ends_with("frames.jsonl"));
        }
        other => panic!("{other:?}"),
    }
    // A path-traversing image name is refused.
    fs::write(
        &frames,
        "{\"camera\":1,\"index\":0,\"exposure_time_ns\":1,\"image\":\"../meta.json\"}\n",
    )
    .unwrap();
    assert!(matches!(
        r.frames(1),
        Err(RecordError::BadImageName { line: 1, .. })
    ));

    // Truncated link.bin names the offset of the broken record.
    let link = dir.path().join("link.bin");
    let bytes = fs::read(&link).unwrap();
    fs::write(&link, &bytes[..bytes.len() - 1]).unwrap();
    match r.link_chunks() {
        Err(RecordError::LinkTruncated { offset, .. }) => assert_eq!(offset, 12 + 3 + 12),
        other => panic!("{other:?}"),
    }
    // An absurd length is refused before allocating.
    let mut huge = 0u64.to_le_bytes().to_vec();
    huge.extend_from_slice(&u32::MAX.to_le_bytes());
    fs::write(&link, &huge).unwrap();
    assert!(matches!(
        r.link_chunks(),
        Err(RecordError::LinkRecordTooLong { offset: 0, .. })
    ));
    // Header shorter than 12 bytes.
    fs::write(&link, [1, 2, 3]).unwrap();
    assert!(matches!(
        r.link_chunks(),
        Err(RecordError::LinkTruncated { offset: 0, .. })
    ));

    // Bad images.
    let img_path = dir.path().join("cam0").join("000003.pgm");
    let frame = r.frames(0).unwrap().remove(0);
    for bad in [
        &b"P2\n8 6\n255\n"[..],
        b"P5\n8 6\n65535\n",
        b"P5\n8 6\n255\n\x01\x02",
        b"P5\n8",
        b"P5\n4 12\n255\n000000000000000000000000000000000000000000000000",
        b"P5 99999999999 2 255\n",
    ] {
        fs::write(&img_path, bad).unwrap();
        assert!(
            matches!(r.image(&frame), Err(RecordError::BadImage { .. })),
            "{:?}",
            String::from_utf8_lossy(bad)
        );
    }
    // A comment in the header is fine.
    let mut ok = b"P5\n# made by hand\n8 6\n255\n".to_vec();
    ok.extend_from_slice(&[7u8; 48]);
    fs::write(&img_path, &ok).unwrap();
    assert_eq!(r.image(&frame).unwrap().unwrap().data, vec![7u8; 48]);

    // Missing files are I/O errors naming the file.
    fs::remove_file(&img_path).unwrap();
    match r.image(&frame) {
        Err(RecordError::Io { path, .. }) => assert_eq!(path, img_path),
        other => panic!("{other:?}"),
    }
    fs::write(dir.path().join("meta.json"), "{not json").unwrap();
    assert!(matches!(
        RecordingReader::open(dir.path()),
        Err(RecordError::Json { line: 1, .. })
    ));
}

#[test]
fn projection_applies_opencv_distortion() {
    // Hand-computed: fx = fy = 500, (cx, cy) = (320, 240), k1 = 0.1, p1 = 0.01, point (0.1, 0.05, 1).
    // r2 = 0.0125; radial = 1.00125; xd = 0.100125 + 2 p1 x y = 0.100225; yd = 0.0500625 + p1 (r2 + 2 y^2) =
    // 0.0502375; u = 370.1125, v = 265.11875.
    let mut m = CameraModel::from_hfov(640, 480, 1.0);
    (m.fx, m.fy, m.cx, m.cy, m.k1, m.p1) = (500.0, 500.0, 320.0, 240.0, 0.1, 0.01);
    let px = m.project([0.1, 0.05, 1.0]).unwrap();
    assert!(
        (px[0] - 370.1125).abs() < 1e-9 && (px[1] - 265.11875).abs() < 1e-9,
        "{px:?}"
    );
    assert!(m.project([0.0, 0.0, -1.0]).is_none());
    let e = Extrinsics {
        rotation: [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        translation_m: [0.5, 0.0, 0.0],
    };
    let c = e.centre_world();
    let back = e.world_to_camera(c);
    assert!(back.iter().all(|v| v.abs() < 1e-15));
}
