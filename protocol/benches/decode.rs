//! Decoder throughput in MB/s on a clean stream and on a stream with 1% corrupted bytes (issue target: 200 MB/s).
#![allow(missing_docs)] // criterion's macros generate undocumented items

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use fires_protocol::{SensorPacket, StreamDecoder};

/// `n` consecutive sensor packets with varied field values.
fn clean_stream(n: usize) -> Vec<u8> {
    (0..n)
        .flat_map(|i| {
            let v = (i as i16).wrapping_mul(31);
            SensorPacket {
                counter: i as u8,
                accel: [v, v ^ 0x55, -v],
                gyro: [v.wrapping_add(7), 3, -3],
                mag: [100, v, 0x2020],
            }
            .encode()
        })
        .collect()
}

/// Flips one byte in every hundred (deterministically).
fn corrupted(mut s: Vec<u8>) -> Vec<u8> {
    for i in (37..s.len()).step_by(100) {
        s[i] ^= 0x5A;
    }
    s
}

fn decode_all(bytes: &[u8]) -> u64 {
    let mut d = StreamDecoder::new();
    let mut n = 0u64;
    d.feed(bytes, |_| n += 1);
    n + u64::from(d.finish().is_some())
}

/// The least any decoder must do: XOR every 22-byte chunk. The baseline the decoder is compared with, so the
/// ratio means something on a loaded machine.
fn xor_chunks(bytes: &[u8]) -> u8 {
    bytes
        .chunks_exact(22)
        .fold(0, |acc, c| acc ^ c.iter().fold(0, |a, b| a ^ b))
}

fn bench(c: &mut Criterion) {
    let clean = clean_stream(50_000);
    let noisy = corrupted(clean.clone());
    let mut g = c.benchmark_group("decoder");
    g.throughput(Throughput::Bytes(clean.len() as u64));
    g.bench_function("baseline_xor_only", |b| {
        b.iter(|| xor_chunks(std::hint::black_box(&clean)))
    });
    g.bench_function("clean", |b| {
        b.iter(|| decode_all(std::hint::black_box(&clean)))
    });
    g.bench_function("corrupt_1pct", |b| {
        b.iter(|| decode_all(std::hint::black_box(&noisy)))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
