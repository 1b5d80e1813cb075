//! Replays the inputs of the `read_recording` fuzz target (`record/fuzz`) under `cargo test`, without cargo-fuzz:
//! every file in `tests/data/fuzz/read_recording/` goes through the same parser as in the target (its first byte
//! picks the stream). `seed-*` files are excerpts of a simulated recording and must parse; any other file is an
//! input that once crashed a parser and must now give `Ok` or a typed error.

use fires_record::reader::{parse_frames, parse_json, parse_jsonl, parse_link, parse_meta};
use fires_record::{
    ExposureTruth, GrayImage, ImuTruth, PacketTruth, RecordError, StrokeTruth, WorldTruth,
};
use std::path::Path;

/// The fuzz target's dispatch: which stream, and whether it parsed (`Err` carries the message).
fn parse(data: &[u8]) -> (&'static str, Result<(), RecordError>) {
    let Some((&which, bytes)) = data.split_first() else {
        return ("empty", Ok(()));
    };
    let path = Path::new("fuzz");
    match which % 9 {
        0 => ("meta.json", parse_meta(bytes, path).map(drop)),
        1 => ("link.bin", parse_link(bytes, path).map(drop)),
        2 => ("frames.jsonl", parse_frames(bytes, path).map(drop)),
        3 => ("pgm", GrayImage::from_pgm(bytes, path).map(drop)),
        4 => ("imu.jsonl", parse_jsonl::<ImuTruth>(bytes, path).map(drop)),
        5 => (
            "exposures.jsonl",
            parse_jsonl::<ExposureTruth>(bytes, path).map(drop),
        ),
        6 => (
            "packets.jsonl",
            parse_jsonl::<PacketTruth>(bytes, path).map(drop),
        ),
        7 => (
            "strokes.json",
            parse_json::<Vec<StrokeTruth>>(bytes, path).map(drop),
        ),
        _ => (
            "world.json",
            parse_json::<WorldTruth>(bytes, path).map(drop),
        ),
    }
}

#[test]
fn fuzz_inputs_parse_or_fail_with_a_typed_error() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz/read_recording");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("test data directory")
        .map(|e| e.expect("directory entry").path())
        .collect();
    files.sort();
    let mut seeds = std::collections::BTreeSet::new();
    for f in &files {
        let data = std::fs::read(f).expect("readable test input");
        let name = f.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        let (stream, result) = parse(&data);
        if name.starts_with("seed-") {
            assert!(result.is_ok(), "{name} ({stream}): {result:?}");
            seeds.insert(stream);
        }
    }
    // One seed per stream the reader parses.
    assert_eq!(seeds.len(), 9, "seeds cover {seeds:?}");
}

/// The `read_strokes` target's inputs: an even first byte is a strokes file, an odd one a report; `seed-*`
/// files must read, any other file is an input that once crashed a reader and must now give a typed error.
#[test]
fn strokes_and_report_fuzz_inputs_read_or_fail_with_a_typed_error() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz/read_strokes");
    let mut seeds = 0;
    for entry in std::fs::read_dir(&dir).expect("test data directory") {
        let f = entry.expect("directory entry").path();
        let data = std::fs::read(&f).expect("readable test input");
        let Some((&which, bytes)) = data.split_first() else {
            continue;
        };
        let ok = if which % 2 == 0 {
            fires_record::StrokesFile::from_json(bytes).is_ok()
        } else {
            fires_record::Report::from_json(bytes).is_ok()
        };
        let name = f.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        if name.starts_with("seed-") {
            assert!(ok, "{name} must read");
            seeds += 1;
        }
    }
    assert!(seeds >= 1, "a seed strokes file");
}
