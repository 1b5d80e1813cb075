//! A salvaging reader keeps what is whole of a damaged recording and says what it skipped; a strict reader
//! refuses the same damage.

mod common;
use common::test_meta;
use fires_record::salvage::scan_link;
use fires_record::*;
use std::fs;
use std::path::Path;

fn meta() -> Meta {
    test_meta(
        (8, 6),
        0.1,
        &[FrameContent::Images, FrameContent::Blobs],
        None,
        true,
    )
}

/// Chunk `i`: time `1000 + 10 i`, `i % 7 + 1` bytes of value `i`.
fn chunk(i: u64) -> LinkChunk {
    LinkChunk {
        host_time_ns: 1000 + 10 * i,
        bytes: vec![i as u8; (i % 7 + 1) as usize],
    }
}

fn record_len(i: u64) -> usize {
    12 + chunk(i).bytes.len()
}

/// Writes 20 link chunks, 5 image frames on camera 0, 5 blob frames on camera 1 and 5 IMU truth lines.
fn write(dir: &Path) {
    let mut w = RecordingWriter::create(dir, &meta()).unwrap();
    for i in 0..20 {
        w.write_link_chunk(&chunk(i)).unwrap();
    }
    for i in 0..5u64 {
        let mut img = GrayImage::new(8, 6);
        img.data[0] = i as u8;
        let f = CameraFrame {
            camera: 0,
            index: i,
            exposure_time_ns: 2000 + i,
            blobs: None,
            image: None,
        };
        w.write_frame(&f, Some(&img)).unwrap();
        let b = CameraFrame {
            camera: 1,
            index: i,
            exposure_time_ns: 2000 + i,
            blobs: Some(vec![]),
            image: None,
        };
        w.write_frame(&b, None).unwrap();
        w.write_imu_truth(&imu(i)).unwrap();
    }
    w.finish().unwrap();
}

fn imu(i: u64) -> ImuTruth {
    ImuTruth {
        sample_index: i,
        counter: i as u8,
        device_time_us: i,
        time_ns: i,
        pose: PoseTruth {
            tip_m: [0.0; 3],
            orientation_xyzw: [0.0, 0.0, 0.0, 1.0],
            leds_m: vec![],
        },
        specific_force_mps2: [0.0; 3],
        angular_velocity_radps: [0.0; 3],
        earth_field_t: [0.0; 3],
        gyro_bias_radps: [0.0; 3],
        buttons: 0,
    }
}

fn cut(path: &Path, by: usize) {
    let b = fs::read(path).unwrap();
    fs::write(path, &b[..b.len() - by]).unwrap();
}

#[test]
fn intact_recording_reads_the_same_salvaged_and_strict() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path());
    let strict = RecordingReader::open(dir.path()).unwrap();
    let salv = RecordingReader::open_salvaging(dir.path()).unwrap();
    assert_eq!(strict.link_chunks().unwrap(), salv.link_chunks().unwrap());
    assert_eq!(strict.frames(0).unwrap(), salv.frames(0).unwrap());
    assert_eq!(strict.imu_truth().unwrap(), salv.imu_truth().unwrap());
    for f in salv.frames(0).unwrap() {
        assert!(matches!(
            salv.frame_image(&f).unwrap(),
            FrameImage::Image(_)
        ));
    }
    // world.json was never written: lost, but only when asked for.
    assert!(salv.damage().is_clean(), "{:?}", salv.damage());
    assert_eq!(salv.world_truth().unwrap(), None);
    assert!(salv.damage().lost_files.contains_key("truth/world.json"));
    assert!(strict.world_truth().is_err());
}

#[test]
fn torn_last_records_are_dropped_and_counted_per_stream() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path());
    let d = dir.path();
    // The last link record (12 + 19 % 7 + 1 = 18 bytes) cut 5 bytes short: 13 of its bytes remain.
    cut(&d.join("link.bin"), 5);
    cut(&d.join("cam1").join("frames.jsonl"), 4);
    cut(&d.join("truth").join("imu.jsonl"), 30);
    let strict = RecordingReader::open(d).unwrap();
    let whole: usize = (0..19).map(record_len).sum();
    match strict.link_chunks() {
        Err(RecordError::LinkTruncated { offset, .. }) => assert_eq!(offset as usize, whole),
        other => panic!("{other:?}"),
    }
    assert!(strict.frames(1).is_err());

    let r = RecordingReader::open_salvaging(d).unwrap();
    let chunks = r.link_chunks().unwrap();
    assert_eq!(chunks, (0..19).map(chunk).collect::<Vec<_>>());
    assert_eq!(r.frames(1).unwrap().len(), 4);
    assert_eq!(r.frames(0).unwrap().len(), 5);
    assert_eq!(
        r.imu_truth().unwrap().unwrap(),
        (0..4).map(imu).collect::<Vec<_>>()
    );
    // Reading again does not count twice.
    r.link_chunks().unwrap();
    let dmg = r.damage();
    assert_eq!(dmg.torn_bytes["link.bin"], (record_len(19) - 5) as u64);
    let line_len = |rel: &str| {
        let b = fs::read(d.join(rel)).unwrap();
        (b.len() - b[..b.len() - 1].iter().rposition(|&c| c == b'\n').unwrap() - 1) as u64
    };
    assert_eq!(
        dmg.torn_bytes["cam1/frames.jsonl"],
        line_len("cam1/frames.jsonl")
    );
    assert_eq!(
        dmg.torn_bytes["truth/imu.jsonl"],
        line_len("truth/imu.jsonl")
    );
    assert_eq!(dmg.torn_bytes.len(), 3);
    assert_eq!(
        dmg.warnings.len(),
        1,
        "one line per kind: {:?}",
        dmg.warnings
    );
    assert!(dmg.warnings[0].contains("link.bin") && dmg.warnings[0].contains("13 bytes"));
}

#[test]
fn a_corrupt_link_record_inside_the_file_is_skipped_by_resyncing() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path());
    let link = dir.path().join("link.bin");
    let mut b = fs::read(&link).unwrap();
    // Record 8's length field: absurd.
    let at: usize = (0..8).map(record_len).sum();
    b[at + 8..at + 12].copy_from_slice(&u32::MAX.to_le_bytes());
    // Record 14's time: before record 13's.
    let at14: usize = (0..14).map(record_len).sum();
    b[at14..at14 + 8].copy_from_slice(&3u64.to_le_bytes());
    fs::write(&link, &b).unwrap();
    let r = RecordingReader::open_salvaging(dir.path()).unwrap();
    let expect: Vec<LinkChunk> = (0..20).filter(|&i| i != 8 && i != 14).map(chunk).collect();
    assert_eq!(r.link_chunks().unwrap(), expect);
    let dmg = r.damage();
    assert_eq!(dmg.skipped_records["link.bin"], 2);
    assert!(dmg.torn_bytes.is_empty() && dmg.unread_bytes.is_empty());
    assert!(matches!(
        RecordingReader::open(dir.path()).unwrap().link_chunks(),
        Err(RecordError::LinkRecordTooLong { .. })
    ));
}

#[test]
fn reading_stops_where_no_resync_is_possible_and_keeps_what_came_before() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path());
    let link = dir.path().join("link.bin");
    let mut b = fs::read(&link).unwrap();
    // Everything from record 17 on overwritten with 0xFF: no offset starts plausible records.
    let at: usize = (0..17).map(record_len).sum();
    b[at..].fill(0xFF);
    fs::write(&link, &b).unwrap();
    let scan = scan_link(&b);
    assert_eq!(scan.chunks, (0..17).map(chunk).collect::<Vec<_>>());
    let r = RecordingReader::open_salvaging(dir.path()).unwrap();
    assert_eq!(r.link_chunks().unwrap().len(), 17);
    let dmg = r.damage();
    assert_eq!(dmg.unread_bytes["link.bin"], (b.len() - at) as u64);
    assert!(dmg.warnings[0].contains("reading stopped"), "{dmg:?}");
}

#[test]
fn corrupt_lines_are_skipped_and_the_rest_read() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path());
    let frames = dir.path().join("cam0").join("frames.jsonl");
    let text = fs::read_to_string(&frames).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines[1] = "{\"camera\":0,\"ind".into();
    lines[3] = lines[3].replace("000003.pgm", "../000003.pgm");
    fs::write(&frames, lines.join("\n") + "\n").unwrap();
    let r = RecordingReader::open_salvaging(dir.path()).unwrap();
    let idx: Vec<u64> = r.frames(0).unwrap().iter().map(|f| f.index).collect();
    assert_eq!(idx, vec![0, 2, 4]);
    let dmg = r.damage();
    assert_eq!(dmg.skipped_records["cam0/frames.jsonl"], 2);
    assert!(dmg.torn_bytes.is_empty());
    assert!(RecordingReader::open(dir.path())
        .unwrap()
        .frames(0)
        .is_err());
}

#[test]
fn missing_and_unreadable_frame_images_are_lost_not_fatal() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path());
    let cam0 = dir.path().join("cam0");
    fs::remove_file(cam0.join("000001.pgm")).unwrap();
    cut(&cam0.join("000003.pgm"), 10);
    let r = RecordingReader::open_salvaging(dir.path()).unwrap();
    let got: Vec<bool> = r
        .frames(0)
        .unwrap()
        .iter()
        .map(|f| matches!(r.frame_image(f).unwrap(), FrameImage::Image(_)))
        .collect();
    assert_eq!(got, vec![true, false, true, false, true]);
    for f in r.frames(0).unwrap() {
        r.frame_image(&f).unwrap();
    }
    let dmg = r.damage();
    assert_eq!((dmg.frames_missing, dmg.frames_unreadable), (1, 1));
    assert_eq!(dmg.warnings.len(), 2, "{:?}", dmg.warnings);
    assert!(dmg.warnings.iter().any(|w| w.contains("cam0/000001.pgm")));
    assert!(dmg.warnings.iter().any(|w| w.contains("cam0/000003.pgm")));
    let strict = RecordingReader::open(dir.path()).unwrap();
    let f1 = strict.frames(0).unwrap().remove(1);
    assert!(strict.frame_image(&f1).is_err());
    // The damage summary serialises as documented.
    let v = serde_json::to_value(&dmg).unwrap();
    for key in [
        "torn_bytes",
        "skipped_records",
        "unread_bytes",
        "lost_files",
        "frames_missing",
        "frames_unreadable",
        "warnings",
    ] {
        assert!(v.get(key).is_some(), "{key} in {v}");
    }
}

#[test]
fn lost_stream_files_read_as_empty_or_absent() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path());
    fs::remove_file(dir.path().join("link.bin")).unwrap();
    fs::remove_file(dir.path().join("cam1").join("frames.jsonl")).unwrap();
    let r = RecordingReader::open_salvaging(dir.path()).unwrap();
    assert!(r.link_chunks().unwrap().is_empty());
    assert!(r.frames(1).unwrap().is_empty());
    assert_eq!(r.frames(0).unwrap().len(), 5);
    let dmg = r.damage();
    assert_eq!(
        dmg.lost_files.keys().collect::<Vec<_>>(),
        vec!["cam1/frames.jsonl", "link.bin"]
    );
}
