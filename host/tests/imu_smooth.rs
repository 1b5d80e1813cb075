//! IMU-aided smoothing of a stroke's tips (`fires_host::stroke::imu_smooth`): exact on a path whose
//! acceleration the IMU measures exactly, blind to a slowly varying acceleration error, less than half
//! the tips' error when they are noisier than the tracker said, unmoved by a flick the IMU
//! got wrong, covariant under translation, and declined where it has too little to work with;
//! `stroke_record` smooths the runs of a stroke on their own.

use fires_host::rng::SplitMix64;
use fires_host::stroke::{
    imu_smooth, stroke_record, ImuSmoothOptions, Stroke, StrokeRecordConfig, TimedAccel, TimedPoint,
};

const MS: u64 = 1_000_000;
const T0: u64 = 7_000 * MS;

/// A quadratic path: its acceleration is constant, and the grid's second difference is exact.
fn quadratic(t_ns: u64) -> [f64; 3] {
    let t = (t_ns as f64 - T0 as f64) * 1e-9;
    [
        0.02 + 0.15 * t - 0.4 * t * t,
        -0.01 + 0.05 * t + 0.7 * t * t,
        0.6 - 0.08 * t + 0.2 * t * t,
    ]
}

fn quadratic_accel(_t_ns: u64) -> [f64; 3] {
    [-0.8, 1.4, 0.4]
}

/// A drawn curve: a circle of 3 cm at 1.5 turns per second, and its acceleration.
fn circle(t_ns: u64) -> [f64; 3] {
    let w = 1.5 * std::f64::consts::TAU;
    let t = (t_ns as f64 - T0 as f64) * 1e-9;
    [0.03 * (w * t).cos(), 0.03 * (w * t).sin(), 0.55 + 0.01 * t]
}

fn circle_accel(t_ns: u64) -> [f64; 3] {
    let w = 1.5 * std::f64::consts::TAU;
    let t = (t_ns as f64 - T0 as f64) * 1e-9;
    [
        -0.03 * w * w * (w * t).cos(),
        -0.03 * w * w * (w * t).sin(),
        0.0,
    ]
}

/// Tips every `period_ms` (with a few ms of jitter) over `ms` milliseconds, with σ `sigma_m`, and the
/// IMU at 100 Hz offset by 3 ms from the tips' grid, `accel(t) + error(t)`.
fn session(
    period_ms: u64,
    ms: u64,
    sigma_m: f64,
    path: fn(u64) -> [f64; 3],
    accel: fn(u64) -> [f64; 3],
    error: impl Fn(u64) -> [f64; 3],
) -> (Vec<TimedPoint>, Vec<TimedAccel>) {
    let mut rng = SplitMix64::new(11);
    let tips = (0..=ms / period_ms)
        .map(|k| {
            let t_ns = T0 + k * period_ms * MS + (rng.unit() * 3.0 * MS as f64) as u64;
            TimedPoint {
                t_ns,
                p: path(t_ns),
                sigma_m: Some(sigma_m),
            }
        })
        .collect();
    let samples = (0..=ms / 10 + 1)
        .map(|k| {
            let t_ns = (T0 + k * 10 * MS).saturating_sub(3 * MS);
            let (a, e) = (accel(t_ns), error(t_ns));
            TimedAccel {
                t_ns,
                a: std::array::from_fn(|i| a[i] + e[i]),
            }
        })
        .collect();
    (tips, samples)
}

/// Gaussian noise of `sigma_m` per axis on every tip (seeded).
fn add_noise(tips: &mut [TimedPoint], sigma_m: f64, seed: u64) {
    let mut rng = SplitMix64::new(seed);
    for t in tips {
        for v in &mut t.p {
            *v += sigma_m * rng.gaussian();
        }
    }
}

fn largest_error(tips: &[TimedPoint], path: fn(u64) -> [f64; 3], out: &[[f64; 3]]) -> f64 {
    tips.iter()
        .zip(out)
        .map(|(t, p)| dist(&path(t.t_ns), p))
        .fold(0.0, f64::max)
}

fn rms(v: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x * x, n + 1));
    (s / n as f64).sqrt()
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

#[test]
fn exact_tips_and_exact_acceleration_come_back_unchanged() {
    let (tips, accel) = session(33, 900, 3e-4, quadratic, quadratic_accel, |_| [0.0; 3]);
    let out = imu_smooth(&tips, &accel, &ImuSmoothOptions::default()).expect("smoothed");
    let e = largest_error(&tips, quadratic, &out);
    assert!(e < 1e-9, "{e}");
}

#[test]
fn a_slowly_varying_acceleration_error_is_taken_up() {
    // A degree of orientation error leaks 0.17 m/s² of gravity, drifting as the pen turns.
    let error = |t: u64| {
        let s = (t as f64 - T0 as f64) * 1e-9;
        [0.17, -0.1 + 0.1 * s, 0.05]
    };
    let (tips, accel) = session(33, 1200, 3e-4, quadratic, quadratic_accel, error);
    let out = imu_smooth(&tips, &accel, &ImuSmoothOptions::default()).expect("smoothed");
    let e = largest_error(&tips, quadratic, &out);
    assert!(e < 2e-5, "{e}");
}

#[test]
fn tips_noisier_than_their_sigma_are_smoothed_to_less_than_half() {
    // Tips 2 mm off per axis, the tracker claiming 0.1 mm: the residuals tell the smoother. With
    // the IMU's assumed white error of 0.02 m/s²/√Hz, the path may leave the integrated acceleration
    // by a random walk that matches the tips' averaged noise over about 0.18 s, five tips at 30 Hz:
    // a gain of about √5.
    let (mut tips, accel) = session(33, 2000, 1e-4, circle, circle_accel, |_| [0.0; 3]);
    add_noise(&mut tips, 0.002, 5);
    let out = imu_smooth(&tips, &accel, &ImuSmoothOptions::default()).expect("smoothed");
    let raw = rms(tips.iter().map(|t| dist(&t.p, &circle(t.t_ns))));
    let smooth = rms(tips.iter().zip(&out).map(|(t, p)| dist(p, &circle(t.t_ns))));
    assert!(smooth < raw / 2.0, "{smooth} vs {raw}");
}

#[test]
fn a_flick_the_imu_got_wrong_does_not_move_good_tips() {
    // 30 m/s² of error for 30 ms (the lever term of a differentiated gyro in a flick).
    let error = |t: u64| {
        let ms = t.saturating_sub(T0) / MS;
        if (400..430).contains(&ms) {
            [30.0, -20.0, 10.0]
        } else {
            [0.0; 3]
        }
    };
    let (tips, accel) = session(8, 900, 5e-5, circle, circle_accel, error);
    let out = imu_smooth(&tips, &accel, &ImuSmoothOptions::default()).expect("smoothed");
    let e = largest_error(&tips, circle, &out);
    assert!(e < 2e-4, "{e}");
}

#[test]
fn a_translated_stroke_smooths_to_the_translated_path() {
    let (mut tips, accel) = session(33, 1500, 1e-4, circle, circle_accel, |_| [0.0; 3]);
    add_noise(&mut tips, 0.001, 8);
    let options = ImuSmoothOptions::default();
    let out = imu_smooth(&tips, &accel, &options).expect("smoothed");
    let shift = [0.3, -0.2, 0.1];
    let moved: Vec<TimedPoint> = tips
        .iter()
        .map(|t| TimedPoint {
            p: std::array::from_fn(|k| t.p[k] + shift[k]),
            ..*t
        })
        .collect();
    let out_moved = imu_smooth(&moved, &accel, &options).expect("smoothed");
    for (a, b) in out.iter().zip(&out_moved) {
        let back: [f64; 3] = std::array::from_fn(|k| b[k] - shift[k]);
        assert!(dist(a, &back) < 1e-9, "{a:?} {back:?}");
    }
}

#[test]
fn too_little_to_work_with_is_declined() {
    let options = ImuSmoothOptions::default();
    let (tips, accel) = session(33, 900, 1e-4, circle, circle_accel, |_| [0.0; 3]);
    // Too few tips.
    assert!(imu_smooth(&tips[..options.min_tips - 1], &accel, &options).is_none());
    // The IMU silent for 60 ms inside the stroke.
    let holed: Vec<TimedAccel> = accel
        .iter()
        .copied()
        .filter(|s| !(T0 + 300 * MS..T0 + 360 * MS).contains(&s.t_ns))
        .collect();
    assert!(imu_smooth(&tips, &holed, &options).is_none());
    // No IMU at all.
    assert!(imu_smooth(&tips, &[], &options).is_none());
    // A 40-minute stroke (no pen-down lasts that long): more nodes than a path may have, declined.
    let long: Vec<TimedPoint> = (0..16_000u64)
        .map(|k| TimedPoint {
            t_ns: T0 + k * 150 * MS,
            ..tips[0]
        })
        .collect();
    let steady: Vec<TimedAccel> = (0..240_100u64)
        .map(|k| TimedAccel {
            t_ns: T0 + k * 10 * MS,
            a: [0.0; 3],
        })
        .collect();
    assert!(imu_smooth(&long, &steady, &options).is_none());
    // Times out of order.
    let mut swapped = tips.clone();
    swapped.swap(3, 4);
    assert!(imu_smooth(&swapped, &accel, &options).is_none());
}

#[test]
fn stroke_record_smooths_each_run_and_keeps_a_run_it_cannot_smooth() {
    // Noisy tips over 2 s, with a 400 ms gap (longer than the IMU bridges) after 1 s, and a short
    // run of 3 tips at the end, too few to smooth.
    let (tips, accel) = session(33, 2000, 1e-4, circle, circle_accel, |_| [0.0; 3]);
    let mut tips: Vec<TimedPoint> = tips
        .into_iter()
        .filter(|t| !(T0 + 1000 * MS..T0 + 1400 * MS).contains(&t.t_ns))
        .filter(|t| !(T0 + 1700 * MS..T0 + 1900 * MS).contains(&t.t_ns))
        .collect();
    add_noise(&mut tips, 0.0015, 21);
    let stroke = Stroke {
        t_start_ns: T0,
        t_end_ns: T0 + 2100 * MS,
        points: tips.clone(),
        accel,
    };
    let smoothed = stroke_record(0, 1, &stroke, &StrokeRecordConfig::default());
    let plain = stroke_record(
        0,
        1,
        &stroke,
        &StrokeRecordConfig {
            imu_smooth: None,
            ..StrokeRecordConfig::default()
        },
    );
    assert_eq!(smoothed.pieces.len(), plain.pieces.len());
    assert_eq!(smoothed.pieces.len(), 3);
    let error = |r: &fires_record::Stroke, piece: usize| {
        rms(r.pieces[piece]
            .points
            .iter()
            .map(|q| dist(&q.p_m, &circle(q.t_ns))))
    };
    for piece in 0..2 {
        let (s, p) = (error(&smoothed, piece), error(&plain, piece));
        assert!(s < 0.75 * p, "piece {piece}: {s} vs {p}");
    }
    // The last run was left as tracked: the same polyline with and without smoothing.
    assert_eq!(smoothed.pieces[2], plain.pieces[2]);
}
