//! Blob detection throughput on a 640x480 frame with 4 LED spots and sensor noise
//! (issue 5 item 1 target: >= 2,000 frames/s on one core). Criterion reports elements/s = frames/s.
//!
//! With `--features opencv` the same run also measures OpenCV's baseline on the same frame (threshold +
//! `connectedComponentsWithStats`, whose output includes the centroids) and prints frames/s of both and the
//! ratio ours/OpenCV (target: >= 5x).
#![allow(missing_docs)] // criterion_group! generates an undocumented public function.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use fires_host::rng::SplitMix64;
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
    #[cfg(feature = "opencv")]
    {
        let mut cv = opencv_baseline::Baseline::new(&img, BlobConfig::default().threshold);
        assert_eq!(cv.run(), out_len(&mut det, &image), "same spots found");
        g.bench_function("opencv_threshold_ccl", |b| b.iter(|| black_box(cv.run())));
    }
    g.finish();
    #[cfg(feature = "opencv")]
    opencv_baseline::compare(&img, &image, &mut det);
}

/// Spots our detector finds on the full frame.
#[cfg(feature = "opencv")]
fn out_len(det: &mut BlobDetector, image: &GrayImage) -> usize {
    det.detect(image, None).len()
}

#[cfg(feature = "opencv")]
mod opencv_baseline {
    use super::*;
    use opencv::core::{Mat, CV_32S};
    use opencv::imgproc;
    use opencv::prelude::*;
    use std::time::{Duration, Instant};

    /// OpenCV's threshold + connected components with stats and centroids, buffers kept between frames.
    pub struct Baseline {
        src: Mat,
        bin: Mat,
        labels: Mat,
        stats: Mat,
        centroids: Mat,
        threshold: f64,
    }

    impl Baseline {
        pub fn new(img: &[u8], threshold: u8) -> Self {
            let src = Mat::new_rows_cols_with_data(480, 640, img)
                .and_then(|m| m.try_clone())
                .expect("640x480 Mat");
            Baseline {
                src,
                bin: Mat::default(),
                labels: Mat::default(),
                stats: Mat::default(),
                centroids: Mat::default(),
                threshold: f64::from(threshold),
            }
        }

        /// Components found (without the background).
        pub fn run(&mut self) -> usize {
            imgproc::threshold(
                &self.src,
                &mut self.bin,
                self.threshold,
                255.0,
                imgproc::THRESH_BINARY,
            )
            .expect("threshold");
            let n = imgproc::connected_components_with_stats(
                &self.bin,
                &mut self.labels,
                &mut self.stats,
                &mut self.centroids,
                8,
                CV_32S,
            )
            .expect("connected components");
            (n as usize).saturating_sub(1)
        }
    }

    fn rate(mut f: impl FnMut() -> usize) -> f64 {
        let budget = Duration::from_secs(2);
        let start = Instant::now();
        let mut n = 0u64;
        while start.elapsed() < budget {
            black_box(f());
            n += 1;
        }
        n as f64 / start.elapsed().as_secs_f64()
    }

    /// Measures both on the same frame, one after the other, and prints the ratio.
    pub fn compare(img: &[u8], image: &GrayImage, det: &mut BlobDetector) {
        let threads = opencv::core::get_num_threads().unwrap_or(-1);
        let mut cv = Baseline::new(img, BlobConfig::default().threshold);
        let mut out = Vec::with_capacity(16);
        let ours = rate(|| {
            det.detect_into(black_box(image), None, &mut out);
            out.len()
        });
        let theirs = rate(|| cv.run());
        println!(
            "blobs 640x480 full frame: ours {ours:.0} frames/s, OpenCV threshold+connectedComponentsWithStats \
             {theirs:.0} frames/s (OpenCV threads: {threads}); ratio ours/OpenCV = {:.2}",
            ours / theirs
        );
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
