//! Tests of the orientation filter (`orientation.rs`) on synthetic pen motion.

use super::imu::{ImuSample, WorldReference};
use super::orientation::*;
use super::DirectionFilter;
use crate::track::fusion::{ThesisKalman, ThesisKalmanConfig};
use crate::track::synth::{imu_sample, ImuNoise, PenMotion, SplitMix64};
use nalgebra::{UnitQuaternion, Vector3};
use std::collections::VecDeque;

/// Runs a filter on `seconds` of synthetic data: IMU at 200 Hz, vision at 30 Hz with
/// `vision_sigma` rad of direction noise, delivered `latency_ns` late. Returns the RMS axis
/// error (rad) over the second half.
fn run(
    filter: &mut dyn DirectionFilter,
    seconds: f64,
    vision_sigma: f64,
    latency_ns: u64,
    seed: u64,
) -> f64 {
    run_motion(
        filter,
        &PenMotion::drawing(),
        seconds,
        vision_sigma,
        latency_ns,
        seed,
    )
}

/// [`run`] for a given motion.
fn run_motion(
    filter: &mut dyn DirectionFilter,
    motion: &PenMotion,
    seconds: f64,
    vision_sigma: f64,
    latency_ns: u64,
    seed: u64,
) -> f64 {
    let world = WorldReference::default();
    let noise = ImuNoise::default();
    let mut rng = SplitMix64::new(seed);
    let imu_dt = 5_000_000u64;
    let cam_dt = 33_333_333u64;
    let mut next_frame = cam_dt;
    let mut pending: VecDeque<(u64, Vector3<f64>)> = VecDeque::new();
    let (mut sum, mut n) = (0.0, 0);
    let steps = (seconds / 0.005) as u64;
    for k in 1..=steps {
        let t = k * imu_dt;
        while next_frame <= t {
            let truth = motion.pose(next_frame as f64 * 1e-9).direction();
            let noisy = (truth
                + Vector3::new(rng.gaussian(), rng.gaussian(), rng.gaussian()) * vision_sigma)
                .normalize();
            pending.push_back((next_frame, noisy));
            next_frame += cam_dt;
        }
        filter.imu(&imu_sample(motion, t, &world, &noise, &mut rng));
        while pending.front().is_some_and(|(tf, _)| tf + latency_ns <= t) {
            if let Some((tf, v)) = pending.pop_front() {
                filter.vision(tf, &v, Some(vision_sigma * vision_sigma));
            }
        }
        if k > steps / 2 {
            let est = filter.direction_at(t).expect("initialised");
            let truth = motion.pose(t as f64 * 1e-9).direction();
            sum += est.angle(&truth).powi(2);
            n += 1;
        }
    }
    (sum / f64::from(n)).sqrt()
}

/// A pen held still, vision axes with 0.6 degrees of noise: the axis variance grows at the
/// gyro's rest rate, so the fused axis averages many more frames than with the rate of a turning
/// pen, and its error is well under that of the constant growth (measured 0.11 against 0.28
/// degrees); while the pen draws it is the same (0.32 degrees both: the drawing motion turns
/// faster than `walk_rate` most of the time).
#[test]
fn a_still_pen_averages_its_vision_axes_over_longer() {
    let still = PenMotion {
        radius: 0.0,
        amplitude: [0.0; 3],
        ..PenMotion::drawing()
    };
    let sigma = 0.6f64.to_radians();
    let constant = OrientationConfig {
        rest_walk_fraction: 1.0,
        ..OrientationConfig::default()
    };
    let mut scaled =
        OrientationFilter::new(OrientationConfig::default(), WorldReference::default());
    let mut fixed = OrientationFilter::new(constant, WorldReference::default());
    let e_scaled = run_motion(&mut scaled, &still, 20.0, sigma, 0, 3);
    let e_fixed = run_motion(&mut fixed, &still, 20.0, sigma, 0, 3);
    assert!(
        e_scaled < 0.5 * e_fixed,
        "{} vs {} degrees",
        e_scaled.to_degrees(),
        e_fixed.to_degrees()
    );
    let mut scaled =
        OrientationFilter::new(OrientationConfig::default(), WorldReference::default());
    let mut fixed = OrientationFilter::new(constant, WorldReference::default());
    let d_scaled = run(&mut scaled, 20.0, sigma, 0, 3);
    let d_fixed = run(&mut fixed, 20.0, sigma, 0, 3);
    assert!(
        d_scaled < 1.1 * d_fixed,
        "drawing: {} vs {} degrees",
        d_scaled.to_degrees(),
        d_fixed.to_degrees()
    );
}

#[test]
fn tracks_imu_only_and_estimates_gyro_bias() {
    let mut f = OrientationFilter::new(OrientationConfig::default(), WorldReference::default());
    let rms = run(&mut f, 30.0, 0.0, 0, 1);
    // IMU only (no vision frames are delivered: latency beyond the run).
    let mut g = OrientationFilter::new(OrientationConfig::default(), WorldReference::default());
    let rms_imu = run(&mut g, 30.0, 0.01, u64::MAX / 2, 2);
    assert!(rms < 0.01, "with perfect vision {rms}");
    assert!(rms_imu < 0.06, "imu only {rms_imu}");
    let bias_err = (g.gyro_bias() - ImuNoise::default().gyro_bias).norm();
    assert!(bias_err < 0.01, "bias error {bias_err}");
}

/// The filter's magnetic reference 10 degrees off in heading (soft iron, a misjudged field):
/// with vision owning the axis, the heading pull no longer tilts the fused axis away.
#[test]
fn vision_owns_the_axis_against_a_biased_heading() {
    let d = WorldReference::default();
    let yaw =
        UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(d.up()), 10f64.to_radians());
    let biased = WorldReference {
        magnetic: (yaw * d.magnetic()).into(),
        ..d
    };
    // The axis variance kept at the gyro's (no relaxing to the heading reference's, which
    // the fighting filter would do between every frame): ownership alone is compared.
    let owns_cfg = OrientationConfig {
        reference_var: 0.0,
        ..OrientationConfig::default()
    };
    let fights_cfg = OrientationConfig {
        vision_owns_axis_ns: 0,
        ..owns_cfg
    };
    let mut owns = OrientationFilter::new(owns_cfg, biased);
    let mut fights = OrientationFilter::new(fights_cfg, biased);
    let (e_owns, e_fights) = (
        run(&mut owns, 20.0, 0.003, 0, 3),
        run(&mut fights, 20.0, 0.003, 0, 3),
    );
    eprintln!(
        "axis RMS error: {:.2} deg owning, {:.2} deg fighting",
        e_owns.to_degrees(),
        e_fights.to_degrees()
    );
    // Measured 0.37 against 0.56 degrees.
    assert!(e_owns < 0.75 * e_fights, "{e_owns} vs {e_fights}");
}

/// Between IMU samples (and after the last one, where camera frames usually fall) the
/// orientation follows the last rate: exact for a constant rotation, where holding the last
/// sample's orientation would lag by the rate times the time since it.
#[test]
fn orientation_between_and_after_samples_follows_the_rate() {
    let config = OrientationConfig {
        k_accel: 0.0,
        k_mag: 0.0,
        k_bias: 0.0,
        ..OrientationConfig::default()
    };
    let mut f = OrientationFilter::new(config, WorldReference::default());
    let w = Vector3::new(0.3, -1.0, 3.0);
    let sample = |t_ns: u64| ImuSample {
        t_ns,
        accel: [0.0, 0.0, 9.81],
        gyro: w.into(),
        mag: [20.0, 0.0, -40.0],
    };
    for k in 0..=10u64 {
        f.imu(&sample(k * 10_000_000));
    }
    let q0 = *f.orientation();
    let after = f.orientation_at(107_000_000).unwrap();
    let expected = q0 * UnitQuaternion::from_scaled_axis(w * 0.007);
    assert!(
        after.angle_to(&expected) < 1e-9,
        "{}",
        after.angle_to(&expected)
    );
    assert!(q0.angle_to(&expected) > 0.02);
    let between = f.orientation_at(95_000_000).unwrap();
    let mid = q0 * UnitQuaternion::from_scaled_axis(w * -0.005);
    assert!(between.angle_to(&mid) < 1e-9, "{}", between.angle_to(&mid));
}

/// Vision lost for 1.5 s while the magnetic reference is 10 degrees off in heading (an
/// uncalibrated magnetometer): the heading pull moves the axis off, and the filter's variance
/// must grow with it, so that the first vision axis after the loss, even a weak one (two LEDs,
/// (1.8 degrees)^2), removes most of the error. With the gyro's random walk alone it kept a
/// small variance and took under a quarter of the correction (webcam seed 11: 10 degrees left, and the
/// next frames refused by the direction prior).
#[test]
fn the_first_vision_after_a_loss_corrects_the_heading_drift() {
    let truth = WorldReference::default();
    let yaw = UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(truth.up()), 0.17);
    let biased = WorldReference {
        magnetic: (yaw * truth.magnetic()).into(),
        ..truth
    };
    // The pen level and still along the world's x axis (the body x axis).
    let axis = Vector3::x();
    let sample = |t_ns: u64| ImuSample {
        t_ns,
        accel: (truth.up() * truth.gravity).into(),
        gyro: [0.0; 3],
        mag: truth.magnetic().into(),
    };
    let run = |config: OrientationConfig| {
        let mut f = OrientationFilter::new(config, biased);
        let step = 5_000_000u64;
        let mut t = 0;
        // Tracked for 2 s: vision every 16.7 ms (about 0.2 degrees).
        let mut next_frame = 0;
        while t < 2_000_000_000 {
            f.imu(&sample(t));
            if t >= next_frame {
                f.vision(t, &axis, Some(1e-5));
                next_frame += 16_666_667;
            }
            t += step;
        }
        // Lost for 1.5 s.
        while t < 3_500_000_000 {
            f.imu(&sample(t));
            t += step;
        }
        let before = f.direction_at(t).unwrap().angle(&axis);
        f.vision(t, &axis, Some(1e-3));
        (before, f.direction_at(t).unwrap().angle(&axis))
    };
    let (before, after) = run(OrientationConfig::default());
    let (old_before, old_after) = run(OrientationConfig {
        reference_var: 0.0,
        ..OrientationConfig::default()
    });
    eprintln!(
        "axis error before/after the first vision: {:.2}/{:.2} deg, without the reference \
         variance {:.2}/{:.2} deg",
        before.to_degrees(),
        after.to_degrees(),
        old_before.to_degrees(),
        old_after.to_degrees()
    );
    assert!(
        before > 2f64.to_radians(),
        "the heading pull moved the axis: {before}"
    );
    assert!(after < 0.3 * before, "{after} of {before}");
    assert!(old_after > 0.7 * old_before, "{old_after} of {old_before}");
}

#[test]
fn vision_pulls_the_axis() {
    let world = WorldReference::default();
    let mut f = OrientationFilter::new(
        OrientationConfig {
            startup_s: 0.0,
            ..Default::default()
        },
        world,
    );
    let q = UnitQuaternion::from_euler_angles(0.1, 0.2, 0.3);
    let s = ImuSample {
        t_ns: 0,
        accel: (q.inverse() * world.up() * world.gravity).into(),
        gyro: [0.0; 3],
        mag: (q.inverse() * world.magnetic()).into(),
    };
    f.imu(&s);
    let target = UnitQuaternion::from_euler_angles(0.0, 0.0, 0.3) * (q * Vector3::x());
    let before = f.direction_at(0).unwrap().angle(&target);
    for _ in 0..10 {
        f.vision(0, &target, None);
    }
    let after = f.direction_at(0).unwrap().angle(&target);
    assert!(after < 0.25 * before, "{before} -> {after}");
}

#[test]
fn default_beats_the_thesis_kalman_on_the_same_data() {
    let world = WorldReference::default();
    for (seed, sigma, latency) in [(3, 0.01, 0), (4, 0.02, 20_000_000), (5, 0.005, 40_000_000)] {
        let mut ours = OrientationFilter::new(OrientationConfig::default(), world);
        let a = run(&mut ours, 20.0, sigma, latency, seed);
        // The thesis gives no Q/R: give it its best process noise over a grid (no strawman).
        let b = [0.5, 2.0, 8.0, 32.0]
            .iter()
            .map(|&q_rate| {
                let cfg = ThesisKalmanConfig {
                    q_rate,
                    r_vision: 2.0 * sigma * sigma,
                    ..Default::default()
                };
                run(
                    &mut ThesisKalman::new(cfg, world),
                    20.0,
                    sigma,
                    latency,
                    seed,
                )
            })
            .fold(f64::INFINITY, f64::min);
        eprintln!("sigma {sigma} latency {latency}: orientation {a:.4} rad, thesis {b:.4} rad");
        assert!(a < 0.7 * b, "orientation {a} vs thesis {b}");
    }
}
