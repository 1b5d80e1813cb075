//! The Python example writer in docs/examples produces a recording this crate reads (skipped without python3).

use fires_protocol::{Frame, StreamDecoder};
use fires_record::{FrameContent, RecordingReader};
use std::path::Path;
use std::process::Command;

#[test]
fn the_documented_python_writer_produces_a_readable_recording() {
    if Command::new("python3").arg("--version").output().is_err() {
        eprintln!("python3 not available: skipped");
        return;
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/examples/write_recording.py");
    let dir = tempfile::tempdir().unwrap();
    let status = Command::new("python3")
        .arg(&script)
        .arg(dir.path())
        .status()
        .unwrap();
    assert!(status.success());
    let r = RecordingReader::open(dir.path()).unwrap();
    assert!(!r.has_truth());
    assert_eq!(r.meta().cameras[1].provides, FrameContent::Images);
    let chunks = r.link_chunks().unwrap();
    assert_eq!(chunks.len(), 10);
    let mut dec = StreamDecoder::new();
    let mut frames = Vec::new();
    for c in &chunks {
        dec.feed(&c.bytes, |d| frames.push(d.frame));
    }
    frames.extend(dec.finish().map(|d| d.frame));
    assert_eq!(frames.len(), 10);
    assert!(matches!(frames[3], Frame::Sensor(s) if s.counter == 3 && s.accel == [0, 1024, 0]));
    let f0 = r.frames(0).unwrap();
    assert_eq!(f0[0].blobs.as_ref().unwrap()[0].x, 300.25);
    let f1 = r.frames(1).unwrap();
    let img = r.image(&f1[0]).unwrap().unwrap();
    assert_eq!(img.data[200 * 640 + 300], 255);
    let px = r.meta().rig.cameras[0]
        .project_world([0.0, 0.0, 1.0])
        .unwrap();
    assert_eq!(px, [319.5, 239.5]);
}
