//! Replays the inputs of the `protocol/fuzz` targets under `cargo test`, without cargo-fuzz: every file in
//! `tests/data/fuzz/<target>/` is checked with the target's own invariants. `seed-*` files are hand-made streams
//! with known contents (they also seed the fuzzer, see scripts/fuzz.sh); any other file is an input that once
//! crashed a target.

use fires_protocol::{Command, CommandParser, StreamDecoder};
use std::path::{Path, PathBuf};

fn inputs(target: &str) -> Vec<(String, Vec<u8>)> {
    let dir: PathBuf = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/fuzz")
        .join(target);
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("test data directory")
        .map(|e| e.expect("directory entry").path())
        .collect();
    files.sort();
    files
        .into_iter()
        .map(|f| {
            let name = f.file_name().and_then(|n| n.to_str()).unwrap_or_default();
            (name.to_string(), std::fs::read(&f).expect("readable input"))
        })
        .collect()
}

#[test]
fn stream_decoder_inputs_keep_the_targets_invariants() {
    let all = inputs("stream_decoder");
    assert!(!all.is_empty());
    for (name, data) in &all {
        // The target's invariants: frames are input bytes verbatim, slices equal single pushes, bytes balance.
        let mut d = StreamDecoder::new();
        let mut frames = Vec::new();
        d.feed(data, |f| frames.push(f));
        frames.extend(d.finish());
        for f in &frames {
            let end = f.end_offset as usize;
            assert!(end >= 22 && end <= data.len(), "{name}");
            assert_eq!(&data[end - 22..end], &f.frame.encode()[..], "{name}");
        }
        let mut p = StreamDecoder::new();
        let mut pushed: Vec<_> = data.iter().filter_map(|&b| p.push(b)).collect();
        pushed.extend(p.finish());
        assert_eq!(pushed, frames, "{name}");
        let s = d.stats();
        let framed = 22 * (s.sensor_frames + s.status_frames + s.duplicates);
        assert_eq!(framed + s.bytes_skipped, data.len() as u64, "{name}");
        // What the seeds hold (hardware-docs/protocol.md §1.4).
        let expected = match name.as_str() {
            // 12 sensor packets and a status; garbage (module chatter, a sync-like pair) after three of them.
            "seed-garbage-after-frames" => Some((12, 1, 0)),
            // 6 packets, the fourth lost a byte: it never comes out, and counts as lost.
            "seed-lost-byte" => Some((5, 0, 1)),
            _ => None,
        };
        if let Some((sensor, status, lost)) = expected {
            assert_eq!(
                (s.sensor_frames, s.status_frames, s.lost),
                (sensor, status, lost),
                "{name}"
            );
        }
    }
}

#[test]
fn command_parser_inputs_keep_the_targets_invariants() {
    let all = inputs("command_parser");
    assert!(!all.is_empty());
    for (name, data) in &all {
        let mut p = CommandParser::new();
        let mut n = 0;
        for (i, &b) in data.iter().enumerate() {
            if let Some(cmd) = p.push(b) {
                n += 1;
                let enc = cmd.encode();
                let bytes = enc.as_bytes();
                if matches!(cmd, Command::Start | Command::Stop) {
                    assert_eq!(bytes, &[b], "{name}");
                } else {
                    assert!(i + 1 >= bytes.len(), "{name}");
                    assert_eq!(&data[i + 1 - bytes.len()..=i], bytes, "{name}");
                }
            }
        }
        if name == "seed-commands" {
            // `=` `:`, five extended commands, `=` aborting a vibrate, `!` restarting a status request.
            assert_eq!(n, 9, "{name}");
        }
    }
}
