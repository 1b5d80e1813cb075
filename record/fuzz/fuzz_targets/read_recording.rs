//! Arbitrary bytes into every stream the recording reader parses: the first byte picks the stream (`meta.json`,
//! `link.bin`, `cam{N}/frames.jsonl`, a PGM image, each ground-truth file), the rest is the file's content. Any
//! input must give `Ok` or a `RecordError`, never a panic; what parses must re-encode to the same value.
#![no_main]

use fires_record::reader::{parse_frames, parse_json, parse_jsonl, parse_link, parse_meta};
use fires_record::{ExposureTruth, GrayImage, ImuTruth, PacketTruth, StrokeTruth, WorldTruth};
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Some((&which, bytes)) = data.split_first() else {
        return;
    };
    let path = Path::new("fuzz");
    match which % 9 {
        0 => {
            let _ = parse_meta(bytes, path);
        }
        1 => {
            if let Ok(chunks) = parse_link(bytes, path) {
                // `[u64 LE host_time_ns][u32 LE len][len bytes]` per record: the file is exactly its records.
                let mut again = Vec::new();
                for c in &chunks {
                    again.extend_from_slice(&c.host_time_ns.to_le_bytes());
                    again.extend_from_slice(&(c.bytes.len() as u32).to_le_bytes());
                    again.extend_from_slice(&c.bytes);
                }
                assert_eq!(again, bytes);
            }
        }
        2 => {
            let _ = parse_frames(bytes, path);
        }
        3 => {
            if let Ok(img) = GrayImage::from_pgm(bytes, path) {
                assert_eq!(
                    img.data.len() as u64,
                    u64::from(img.width) * u64::from(img.height)
                );
                let again =
                    GrayImage::from_pgm(&img.to_pgm(), path).expect("own encoding reads back");
                assert_eq!(again, img);
            }
        }
        4 => {
            let _ = parse_jsonl::<ImuTruth>(bytes, path);
        }
        5 => {
            let _ = parse_jsonl::<ExposureTruth>(bytes, path);
        }
        6 => {
            let _ = parse_jsonl::<PacketTruth>(bytes, path);
        }
        7 => {
            let _ = parse_json::<Vec<StrokeTruth>>(bytes, path);
        }
        _ => {
            let _ = parse_json::<WorldTruth>(bytes, path);
        }
    }
});
