//! Blob detection throughput on a 640x480 frame with 4 LED spots and sensor noise
//! (issue 5 item 1 target: >= 2,000 frames/s on one core). Criterion reports elements/s = frames/s.
#![allow(missing_docs)] // criterion_group! generates an undocumented public function.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use fires_host::track::synth::SplitMix64;
use fires_host::vision::blobs::render_spots;
use fires_host::vision::{BlobConfig, BlobDetector, GrayImage, Rect};
use std::hint::black_box;

fn frame() -> Vec<u8> {
    let spots = [
        (200.3, 180.6, 1.6, 190.0),
        (260.7, 201.2, 1.6, 190.0),
        (295.1, 213.9, 1.6, 190.0),
        (340.4, 229.5, 1.6, 190.0),
    ];
    let mut img = render_spots(640, 480, 18, &spots);
    let mut rng = SplitMix64::new(9);
    for p in &mut img {
        let n = (rng.gaussian() * 4.0).round() as i32;
        *p = (i32::from(*p) + n).clamp(0, 255) as u8;
    }
    img
}

fn bench(c: &mut Criterion) {
    let img = frame();
    let image = GrayImage::new(640, 480, &img).expect("valid frame");
    let mut det = BlobDetector::new(BlobConfig::default());
    let mut out = Vec::with_capacity(16);
    let mut g = c.benchmark_group("blobs_640x480");
    g.throughput(Throughput::Elements(1));
    g.bench_function("full_frame", |b| {
        b.iter(|| {
            det.detect_into(black_box(&image), None, &mut out);
            black_box(out.len())
        })
    });
    let window = Rect::around(&[[200.3, 180.6], [340.4, 229.5]], 24.0, 640, 480);
    g.bench_function("window", |b| {
        b.iter(|| {
            det.detect_into(black_box(&image), window, &mut out);
            black_box(out.len())
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
