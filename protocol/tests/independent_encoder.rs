//! A user's experiment (issue #12): 3,000 sensor packets from an encoder written independently of this crate
//! (the logic of `samples/make_pen_stream.py`, ported byte by byte from hardware-docs/protocol.md §1.1), with 60
//! packets dropped, 15 corrupted and 40 bursts of garbage (never `0x20`) between packets. Every one of the 2,925
//! intact packets must come out, and `lost` must be exactly the 75 missing counters.

use fires_protocol::{Frame, StreamDecoder};

const PACKETS: usize = 3000;
const DROPPED: usize = 60;
const CORRUPTED: usize = 15;
const GARBAGE_BURSTS: usize = 40;

/// SplitMix64: a tiny deterministic generator, so the experiment is the same on every machine.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// The Python encoder's `sensor()`: sync `20 0A`, counter, nine little-endian i16, XOR of the 21 bytes before.
fn sensor(counter: usize, values: [i16; 9]) -> Vec<u8> {
    let mut out = vec![0x20, 0x0A, (counter & 0xFF) as u8];
    for v in values {
        out.push((v as u16 & 0xFF) as u8);
        out.push((v as u16 >> 8) as u8);
    }
    let x = out.iter().fold(0u8, |a, b| a ^ b);
    out.push(x);
    out
}

/// The Python encoder's motion: a pen at rest rocked slowly about its y axis (raw counts at the board's scales).
fn sample(i: usize) -> [i16; 9] {
    let t = i as f64 / 100.0;
    let tilt = 0.3 * (2.0 * std::f64::consts::PI * 0.2 * t).sin();
    let g = 1024.0;
    let rate =
        0.3 * 2.0 * std::f64::consts::PI * 0.2 * (2.0 * std::f64::consts::PI * 0.2 * t).cos();
    let r = |x: f64| x.round() as i16;
    [
        r(-g * tilt.sin()),
        0,
        r(g * tilt.cos()),
        0,
        r(rate.to_degrees() / 0.070),
        0,
        r(200.0 * tilt.cos()),
        0,
        r(-430.0 + 200.0 * tilt.sin()),
    ]
}

#[derive(Clone, Copy, PartialEq)]
enum Fault {
    None,
    Dropped,
    Corrupted,
    GarbageAfter,
}

/// The stream: the intact packets' bytes in order, the wire, the total garbage length, and the byte ranges of the
/// wire that belong to no intact packet.
struct Experiment {
    intact: Vec<Vec<u8>>,
    wire: Vec<u8>,
    garbage_bytes: usize,
    faulty_ranges: Vec<(usize, usize)>,
    /// Intact packets directly followed by garbage.
    followed_by_garbage: usize,
}

fn experiment(seed: u64) -> Experiment {
    let mut rng = Rng(seed);
    // Fault sites: distinct packets at least three apart, so that after every fault two intact packets in a row
    // give the decoder back its lock (protocol.md §1.4, rule 2); never the first two or the last packet.
    let mut faults = vec![Fault::None; PACKETS];
    let kinds = std::iter::repeat_n(Fault::Dropped, DROPPED)
        .chain(std::iter::repeat_n(Fault::Corrupted, CORRUPTED))
        .chain(std::iter::repeat_n(Fault::GarbageAfter, GARBAGE_BURSTS));
    for kind in kinds {
        loop {
            let i = 2 + rng.below(PACKETS - 3);
            let lo = i.saturating_sub(2);
            let hi = (i + 2).min(PACKETS - 1);
            if faults[lo..=hi].iter().all(|&f| f == Fault::None) {
                faults[i] = kind;
                break;
            }
        }
    }
    let mut e = Experiment {
        intact: Vec::new(),
        wire: Vec::new(),
        garbage_bytes: 0,
        faulty_ranges: Vec::new(),
        followed_by_garbage: 0,
    };
    for (i, &fault) in faults.iter().enumerate() {
        let mut p = sensor(i, sample(i));
        match fault {
            Fault::Dropped => continue,
            Fault::Corrupted => {
                let at = rng.below(p.len());
                p[at] ^= 1 + rng.below(255) as u8;
                let start = e.wire.len();
                e.wire.extend_from_slice(&p);
                e.faulty_ranges.push((start, e.wire.len()));
            }
            Fault::None | Fault::GarbageAfter => {
                e.wire.extend_from_slice(&p);
                e.intact.push(p);
            }
        }
        if fault == Fault::GarbageAfter {
            // Module chatter and line noise: 1 to 40 bytes of any value but 0x20.
            let n = 1 + rng.below(40);
            let start = e.wire.len();
            for _ in 0..n {
                let b = loop {
                    let b = rng.next() as u8;
                    if b != 0x20 {
                        break b;
                    }
                };
                e.wire.push(b);
            }
            e.garbage_bytes += n;
            e.faulty_ranges.push((start, e.wire.len()));
            e.followed_by_garbage += 1;
        }
    }
    e
}

#[test]
fn every_intact_packet_of_an_independent_encoder_comes_out_and_lost_counts_only_the_missing() {
    let e = experiment(12);
    assert_eq!(e.intact.len(), PACKETS - DROPPED - CORRUPTED);
    assert_eq!(e.followed_by_garbage, GARBAGE_BURSTS);
    // Preconditions of the exact count, checked on the bytes, not through the decoder:
    // (a) no window that starts in a corrupted packet or in garbage looks like a frame (sync pair and right
    //     checksum): such a window would swallow the start of the real packet after it;
    for &(a, b) in &e.faulty_ranges {
        for s in a..b {
            let w = &e.wire[s..(s + 22).min(e.wire.len())];
            let looks_like_frame = w.len() == 22
                && w[0] == 0x20
                && matches!(w[1], 0x0A | 0x0B)
                && w.iter().fold(0u8, |x, y| x ^ y) == 0;
            assert!(!looks_like_frame, "window at {s} passes the checksum");
        }
    }
    // (b) no intact packet followed by garbage ends in 0x20 with the garbage starting like a sync pair's second
    //     byte (the "lost byte" sign of rule 3, which would hold that packet back).
    for &(a, _) in &e.faulty_ranges {
        assert!(!(a > 0 && e.wire[a - 1] == 0x20 && matches!(e.wire[a], 0x0A | 0x0B)));
    }

    let mut d = StreamDecoder::new();
    let mut got = Vec::new();
    d.feed(&e.wire, |f| got.push(f));
    got.extend(d.finish());
    let s = d.stats();

    let got_bytes: Vec<Vec<u8>> = got.iter().map(|g| g.frame.encode().to_vec()).collect();
    eprintln!(
        "decoded {} of {} intact packets; {s:?}",
        got_bytes.len(),
        e.intact.len()
    );
    assert_eq!(got_bytes.len(), 2925);
    assert!(
        got_bytes == e.intact,
        "the decoded packets are exactly the intact ones, in order"
    );
    assert_eq!(s.sensor_frames, 2925);
    assert_eq!(s.status_frames, 0);
    assert_eq!(s.duplicates, 0);
    assert_eq!(s.lost, 75, "60 dropped + 15 corrupted");
    assert_eq!(
        s.bytes_skipped,
        (e.garbage_bytes + CORRUPTED * 22) as u64,
        "skipped = the garbage and the corrupted packets, nothing else"
    );
    // Each packet's own gap: counters are consecutive modulo 256, so the gap is the number of packets missing.
    let mut prev: Option<u8> = None;
    for g in &got {
        let Frame::Sensor(p) = g.frame else {
            panic!("only sensor packets were sent")
        };
        if let Some(c) = prev {
            assert_eq!(g.lost_before, p.counter.wrapping_sub(c).wrapping_sub(1));
        }
        prev = Some(p.counter);
    }

    // Byte-at-a-time decoding gives the same.
    let mut d2 = StreamDecoder::new();
    let mut pushed: Vec<_> = e.wire.iter().filter_map(|&b| d2.push(b)).collect();
    pushed.extend(d2.finish());
    assert_eq!(pushed, got);
    assert_eq!(d2.stats(), s);
}
