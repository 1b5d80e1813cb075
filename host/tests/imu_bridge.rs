//! The IMU bridge across a gap between vision tips (`fires_host::stroke::imu_bridge`): exact on a path
//! whose acceleration it integrates exactly, blind to a constant acceleration error when it can fit one,
//! within `b T² / 8` of the pen when it can only pin the ends, and refused where the samples do not cover
//! the gap or the tips around it disagree with the IMU; `stroke_record` keeps a stroke whole across a gap it bridges and splits it where it cannot.

use fires_host::stroke::{
    imu_bridge, stroke_record, ImuBridgeOptions, Stroke, StrokeRecordConfig, TimedAccel, TimedPoint,
};

const MS: u64 = 1_000_000;
const T0: u64 = 5_000 * MS;

/// A cubic path: acceleration linear in time, so the bridge's piecewise-linear integration is exact.
fn cubic(t_ns: u64) -> [f64; 3] {
    let t = (t_ns - T0) as f64 * 1e-9;
    [
        0.02 + 0.15 * t - 0.4 * t * t + 0.9 * t * t * t,
        -0.01 + 0.05 * t + 0.7 * t * t - 0.3 * t * t * t,
        0.6 - 0.08 * t + 0.2 * t * t,
    ]
}

fn cubic_accel(t_ns: u64) -> [f64; 3] {
    let t = (t_ns - T0) as f64 * 1e-9;
    [-0.8 + 5.4 * t, 1.4 - 1.8 * t, 0.4]
}

/// Vision tips every `period` ms over 0.6 s except inside `gap` (ms from T0), and 100 Hz acceleration
/// plus `bias`.
fn session(
    period: u64,
    gap: (u64, u64),
    bias: [f64; 3],
    path: fn(u64) -> [f64; 3],
) -> (Vec<TimedPoint>, Vec<TimedAccel>) {
    let tips = (0..=600 / period)
        .map(|k| k * period)
        .filter(|&ms| ms <= gap.0 || ms >= gap.1)
        .map(|ms| TimedPoint {
            t_ns: T0 + ms * MS,
            p: path(T0 + ms * MS),
            sigma_m: Some(3e-4),
        })
        .collect();
    let accel = (0..=60)
        .map(|k| {
            let t_ns = T0 + k * 10 * MS + 3 * MS;
            let a = cubic_accel(t_ns);
            TimedAccel {
                t_ns,
                a: std::array::from_fn(|i| a[i] + bias[i]),
            }
        })
        .collect();
    (tips, accel)
}

fn gap_index(tips: &[TimedPoint]) -> usize {
    (0..tips.len() - 1)
        .max_by_key(|&i| tips[i + 1].t_ns - tips[i].t_ns)
        .unwrap()
}

fn worst_error(bridge: &[(u64, [f64; 3])], path: fn(u64) -> [f64; 3]) -> f64 {
    bridge
        .iter()
        .map(|(t, p)| {
            let q = path(*t);
            (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt()
        })
        .fold(0.0, f64::max)
}

#[test]
fn a_path_with_linear_acceleration_is_reproduced_exactly() {
    let (tips, accel) = session(17, (204, 408), [0.0; 3], cubic);
    let i = gap_index(&tips);
    let bridge = imu_bridge(&tips, i, &accel, &ImuBridgeOptions::default()).unwrap();
    assert!(bridge.len() >= 18, "{} points", bridge.len());
    assert!(bridge
        .iter()
        .all(|(t, _)| *t > tips[i].t_ns && *t < tips[i + 1].t_ns));
    let worst = worst_error(&bridge, cubic);
    assert!(worst < 1e-12, "{worst}");
}

#[test]
fn a_constant_acceleration_error_is_fitted_away() {
    // 0.5 m/s^2 (a 3 degree orientation error's gravity) would put a pinned bridge b T^2 / 8 = 2.6 mm off
    // over these 204 ms; the fit to the tips around the gap takes it out.
    let (tips, accel) = session(17, (204, 408), [0.3, -0.4, 0.0], cubic);
    let bridge = imu_bridge(
        &tips,
        gap_index(&tips),
        &accel,
        &ImuBridgeOptions::default(),
    )
    .unwrap();
    let worst = worst_error(&bridge, cubic);
    assert!(worst < 1e-9, "{worst}");
}

#[test]
fn with_only_the_two_ends_the_bridge_is_pinned_and_within_b_t_squared_over_8() {
    let (tips, accel) = session(17, (204, 408), [0.3, -0.4, 0.0], cubic);
    let i = gap_index(&tips);
    let ends = [tips[i], tips[i + 1]];
    let bridge = imu_bridge(&ends, 0, &accel, &ImuBridgeOptions::default()).unwrap();
    let span = (ends[1].t_ns - ends[0].t_ns) as f64 * 1e-9;
    let bound = 0.5 * span * span / 8.0;
    let worst = worst_error(&bridge, cubic);
    // The bound is reached mid-gap, where the samples (every 10 ms) nearly are.
    assert!(worst <= bound * (1.0 + 1e-9), "{worst} vs {bound}");
    assert!(worst > 0.9 * bound, "{worst} vs {bound}");
    let (a, b) = (bridge.first().unwrap().1, bridge.last().unwrap().1);
    let (qa, qb) = (cubic(bridge[0].0), cubic(bridge.last().unwrap().0));
    // Pinned: at the gap's ends the error goes to zero with the distance from them.
    assert!(
        (0..3).all(|k| (a[k] - qa[k]).abs() < bound * 0.3 && (b[k] - qb[k]).abs() < bound * 0.3)
    );
}

#[test]
fn tips_around_the_gap_that_disagree_with_the_imu_bridge_nothing() {
    // The two tips before the gap hooked 2.5 mm sideways (the pen turning into a view the cameras
    // could not resolve): the fit's acceleration would carry that across the gap.
    let (mut tips, accel) = session(17, (204, 408), [0.0; 3], cubic);
    let i = gap_index(&tips);
    for tip in &mut tips[i - 1..=i] {
        tip.p[1] += 2.5e-3;
        tip.sigma_m = Some(1e-4);
    }
    let options = ImuBridgeOptions::default();
    assert!(imu_bridge(&tips, i, &accel, &options).is_none());
    // The same miss from tips whose noise explains it (1 mm per axis) is bridged.
    for tip in &mut tips[i - 1..=i] {
        tip.sigma_m = Some(1e-3);
    }
    assert!(imu_bridge(&tips, i, &accel, &options).is_some());
}

#[test]
fn a_gap_the_samples_do_not_cover_is_not_bridged() {
    let (tips, mut accel) = session(17, (204, 408), [0.0; 3], cubic);
    let i = gap_index(&tips);
    let options = ImuBridgeOptions::default();
    // A link outage of 50 ms inside the gap.
    accel.retain(|a| !(T0 + 280 * MS..T0 + 330 * MS).contains(&a.t_ns));
    assert!(imu_bridge(&tips, i, &accel, &options).is_none());
    // No samples at all, or none inside the gap.
    assert!(imu_bridge(&tips, i, &[], &options).is_none());
    // Not a gap: the last tip has no successor.
    assert!(imu_bridge(&tips, tips.len() - 1, &accel, &options).is_none());
}

/// The largest distance of a stroke's points from the cubic path.
fn off_path(stroke: &fires_record::Stroke) -> f64 {
    let dist = |p: &[f64; 3], t: u64| {
        let q = cubic(t);
        (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt()
    };
    stroke
        .points()
        .map(|p| {
            (T0..=T0 + 600 * MS)
                .step_by(MS as usize / 4)
                .map(|t| dist(&p.p_m, t))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}

#[test]
fn a_stroke_stays_whole_across_a_gap_the_imu_bridges_and_splits_where_it_cannot() {
    let config = StrokeRecordConfig::default();
    // 150 ms: beyond the chord's 89 ms, within the IMU's 200 ms.
    let (points, accel) = session(17, (204, 357), [0.1, 0.0, -0.1], cubic);
    assert!(config.max_gap_ns() < 150 * MS && config.max_imu_gap_ns() > 150 * MS);
    let stroke = |accel: Vec<TimedAccel>| Stroke {
        t_start_ns: T0,
        t_end_ns: T0 + 600 * MS,
        points: points.clone(),
        accel,
    };
    let whole = stroke_record(3, 1, &stroke(accel), &config);
    assert_eq!(whole.pieces.len(), 1);
    assert_eq!(whole.raw_points, points.len());
    // The spline through the bridge stays on the path; through the chord (a config that allows it) it
    // does not: the cubic bends away from its chord over the gap.
    let chord_config = StrokeRecordConfig {
        drawing_accel_mps2: 0.2,
        ..config
    };
    let chord = stroke_record(3, 1, &stroke(Vec::new()), &chord_config);
    assert_eq!(chord.pieces.len(), 1);
    let (imu_off, chord_off) = (off_path(&whole), off_path(&chord));
    // 0.10 mm against 1.38 mm when written.
    assert!(
        imu_off < 2e-4 && chord_off > 1e-3,
        "{imu_off} vs {chord_off}"
    );
    let split = stroke_record(3, 1, &stroke(Vec::new()), &config);
    assert_eq!(split.pieces.len(), 2);
}
