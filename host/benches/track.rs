//! "Stereo to fused tip" per camera frame (issue 5 target: median <= 50 us): undistortion,
//! correspondence, triangulation, identification, tip and the fusion update, on a synthetic
//! asynchronous recording (60 Hz per camera, IMU at 200 Hz, 4 LEDs + 0.5 px noise at 1024x768).
//! Only `Tracker::push_frame` is timed; IMU samples are fed between frames untimed.
#![allow(missing_docs)] // criterion_group! generates an undocumented public function.

use criterion::{criterion_group, criterion_main, Criterion};
use fires_host::stereo::{CameraId, StereoRig};
use fires_host::track::fusion::{FusionKind, ImuSample, WorldReference};
use fires_host::track::pipeline::{CameraFrame, Tracker, TrackerConfig};
use fires_host::track::synth::{imu_sample, project_leds, ImuNoise, PenMotion, SplitMix64};
use fires_host::track::PenGeometry;
use std::hint::black_box;
use std::time::{Duration, Instant};

enum Event {
    Imu(ImuSample),
    Frame(CameraFrame),
}

fn recording(rig: &StereoRig, seconds: f64) -> Vec<Event> {
    let motion = PenMotion::drawing();
    let pen = PenGeometry::thesis();
    let world = WorldReference::default();
    let mut rng = SplitMix64::new(42);
    let end = (seconds * 1e9) as u64;
    let mut times: Vec<(u64, u8)> = (1..end / 5_000_000).map(|k| (k * 5_000_000, 0)).collect();
    times.extend((1..end / 16_666_667).map(|k| (k * 16_666_667, 1)));
    times.extend((1..end / 16_666_667).map(|k| (k * 16_666_667 + 7_000_000, 2)));
    times.sort();
    times
        .into_iter()
        .map(|(t, kind)| {
            if kind == 0 {
                Event::Imu(imu_sample(
                    &motion,
                    t,
                    &world,
                    &ImuNoise::default(),
                    &mut rng,
                ))
            } else {
                let proj = project_leds(rig, &pen, &motion.pose(t as f64 * 1e-9), 0.5, &mut rng);
                let camera = if kind == 1 {
                    CameraId::Left
                } else {
                    CameraId::Right
                };
                let blobs = proj[usize::from(kind - 1)]
                    .iter()
                    .flatten()
                    .copied()
                    .collect();
                Event::Frame(CameraFrame::new(camera, t, blobs))
            }
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let rig = StereoRig::parallel(1024, 768, 45f64.to_radians(), 0.25);
    let events = recording(&rig, 20.0);
    let mut g = c.benchmark_group("stereo_to_fused_tip");
    for (name, fusion) in [
        ("orientation_filter", FusionKind::Orientation),
        ("thesis_kalman", FusionKind::ThesisKalman),
    ] {
        let config = TrackerConfig {
            fusion,
            ..TrackerConfig::default()
        };
        let new_tracker = || Tracker::new(rig.clone(), config.clone()).expect("valid pen");
        let mut tracker = new_tracker();
        let mut cursor = 0usize;
        g.bench_function(name, |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                let mut done = 0;
                while done < iters {
                    if cursor >= events.len() {
                        cursor = 0;
                        tracker = new_tracker();
                    }
                    match &events[cursor] {
                        Event::Imu(s) => {
                            black_box(tracker.push_imu(s));
                        }
                        Event::Frame(f) => {
                            let f = f.clone();
                            let start = Instant::now();
                            black_box(tracker.push_frame(f));
                            total += start.elapsed();
                            done += 1;
                        }
                    }
                    cursor += 1;
                }
                total
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
