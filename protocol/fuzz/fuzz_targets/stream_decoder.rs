//! Arbitrary bytes into the stream decoder: it must not panic, every frame it emits must be 22 input bytes
//! verbatim, its byte accounting must balance, and the slice fast path must equal byte-by-byte pushing.
#![no_main]

use fires_protocol::StreamDecoder;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut d = StreamDecoder::new();
    let mut frames = Vec::new();
    d.feed(data, |f| frames.push(f));
    frames.extend(d.finish());
    for f in &frames {
        let end = f.end_offset as usize;
        assert!(end >= 22 && end <= data.len());
        assert_eq!(&data[end - 22..end], &f.frame.encode()[..]);
    }
    let mut p = StreamDecoder::new();
    let mut pushed: Vec<_> = data.iter().filter_map(|&b| p.push(b)).collect();
    pushed.extend(p.finish());
    assert_eq!(pushed, frames);
    let s = d.stats();
    assert_eq!(22 * (s.sensor_frames + s.status_frames + s.duplicates) + s.bytes_skipped, data.len() as u64);
});
