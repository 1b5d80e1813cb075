//! Tests of the time alignment (`pipeline/align.rs`).

use super::*;
use crate::track::pen::PenGeometry;
use nalgebra::UnitQuaternion;
use std::f64::consts::PI;

/// The alignment options of the tests: time alignment on, a global shutter, no centre noise,
/// the thesis pen.
pub(in crate::track::pipeline) const OPTIONS: AlignOptions = AlignOptions {
    time_align: true,
    continuity_ns: 100_000_000,
    max_blob_motion_px: 40.0,
    row_time_ns: [0.0; 2],
    pixel_sigma: 0.0,
    pen: PenGeometry {
        led_offsets: [0.0, 0.070, 0.110, 0.160],
        tip_offset: 0.0,
    },
    pattern: PatternOptions::DEFAULT,
};

fn rig() -> StereoRig {
    StereoRig::parallel(1024, 768, 45f64.to_radians(), 0.25)
}

/// The thesis pen with LED 1 at `led1`, lying along x (tip towards +x).
fn pen_at(led1: Vector3<f64>) -> [Vector3<f64>; LED_COUNT] {
    PenGeometry::thesis()
        .led_offsets
        .map(|l| led1 - Vector3::x() * l)
}

#[test]
fn a_camera_keeps_its_last_two_frames_and_labels_the_newest() {
    let mut h = CameraHistory::default();
    h.push(1, vec![[1.0, 2.0]], Vec::new(), Vec::new());
    h.label_current([Some(0), None, None, None]);
    h.push(2, vec![[3.0, 4.0]], Vec::new(), Vec::new());
    let (cur, prev) = (h.current.as_ref().unwrap(), h.previous.as_ref().unwrap());
    assert_eq!((cur.t_ns, prev.t_ns), (2, 1));
    assert_eq!(prev.labels[0], Some(0));
    assert_eq!(cur.labels, [None; LED_COUNT]);
}

/// Two poses 10 ms apart moving at 0.5 m/s: the prediction extrapolates linearly, and is
/// refused beyond the continuity time.
#[test]
fn predicted_leds_extrapolate_at_constant_velocity() {
    let mut a = TimeAlignment::new(OPTIONS);
    assert!(a.predicted_leds(0).is_none());
    let v = Vector3::new(0.5, -0.2, 0.1);
    let p0 = Vector3::new(0.0, 0.0, 0.8);
    a.remember_pose(100_000_000, pen_at(p0));
    // One pose: no velocity yet, the pen stands still.
    assert!((a.predicted_leds(120_000_000).unwrap()[0] - p0).norm() < 1e-15);
    a.remember_pose(110_000_000, pen_at(p0 + v * 0.01));
    let p = a.predicted_leds(130_000_000).unwrap();
    for (k, q) in pen_at(p0 + v * 0.03).iter().enumerate() {
        assert!((p[k] - q).norm() < 1e-12, "{k}");
    }
    assert!(a
        .predicted_leds(110_000_000 + OPTIONS.continuity_ns + 1)
        .is_none());
}

/// Two poses from nearly simultaneous frames (free-running cameras drift into phase) do not
/// make the velocity: the pose before them does, so a millimetre of noise between them
/// predicts nothing absurd.
#[test]
fn poses_microseconds_apart_keep_the_older_velocity_baseline() {
    let mut a = TimeAlignment::new(OPTIONS);
    let v = Vector3::new(0.1, 0.0, 0.0);
    let p0 = Vector3::new(0.0, 0.0, 0.8);
    a.remember_pose(100_000_000, pen_at(p0));
    a.remember_pose(116_000_000, pen_at(p0 + v * 0.016));
    // 20 us later, 1 mm off by noise: as a velocity baseline this would be 50 m/s.
    let noisy = p0 + v * 0.01602 + Vector3::new(0.0, 0.001, 0.0);
    a.remember_pose(116_020_000, pen_at(noisy));
    let p = a.predicted_leds(132_000_000).unwrap();
    // The velocity comes from the pose 16 ms older: 1 mm over 16 ms, 1 mm more in 16 ms.
    let want = noisy + (noisy - p0) / 0.01602 * 0.01598;
    assert!((p[0] - want).norm() < 1e-9, "{:?} vs {want:?}", p[0]);
    assert!((p[0] - (p0 + v * 0.032)).norm() < 0.0025);
}

/// A labelled frame keeps its labels; an unlabelled one takes the blob at each predicted LED
/// image, except where two blobs are equally close candidates.
#[test]
fn frame_identities_come_from_labels_or_unambiguous_predictions() {
    let rig = rig();
    let mut a = TimeAlignment::new(OPTIONS);
    let leds = pen_at(Vector3::new(0.05, 0.0, 0.8));
    a.remember_pose(0, leds);
    let px: Vec<[f64; 2]> = leds
        .iter()
        .map(|p| rig.project(CameraId::Left, p).unwrap())
        .collect();
    // Reversed order, slightly off the prediction.
    let blobs: Vec<[f64; 2]> = px.iter().rev().map(|p| [p[0] + 0.3, p[1] - 0.2]).collect();
    let frame = KeptFrame {
        t_ns: 0,
        blobs: blobs.clone(),
        labels: [None; LED_COUNT],
        radii: Vec::new(),
        shapes: Vec::new(),
        blob_delay_ns: Vec::new(),
        guess: None,
    };
    assert_eq!(
        a.frame_identities(&rig, CameraId::Left, &frame),
        [Some(3), Some(2), Some(1), Some(0)]
    );
    let labelled = KeptFrame {
        labels: [Some(1), None, None, None],
        ..frame.clone()
    };
    assert_eq!(
        a.frame_identities(&rig, CameraId::Left, &labelled),
        labelled.labels
    );
    // A second blob next to LED 1's image: LED 1 is no longer identified.
    let mut crowded = frame;
    crowded.blobs.push([px[0][0] - 0.3, px[0][1]]);
    let ids = a.frame_identities(&rig, CameraId::Left, &crowded);
    assert_eq!(ids, [None, Some(2), Some(1), Some(0)]);
}

/// After a loss no vision pose predicts a frame: its blobs are labelled by the pattern of the
/// pen placed where it was last seen along the inertial direction, though it has moved 30 mm
/// since and turned by 3 degrees; without that guess, or with the pen turned end for end,
/// nothing is labelled.
#[test]
fn frames_after_a_loss_are_labelled_by_the_pens_pattern() {
    let rig = rig();
    let a = TimeAlignment::new(OPTIONS);
    let (turn_s, turn_c) = 3f64.to_radians().sin_cos();
    let dir = Vector3::new(turn_c, turn_s, 0.0);
    let tip = Vector3::new(0.08, 0.02, 0.82);
    let seen: Vec<[f64; 2]> = [0.0, 0.070, 0.110, 0.160]
        .iter()
        .map(|l| rig.project(CameraId::Left, &(tip - dir * *l)).unwrap())
        .collect();
    // LED 1 hidden by the hand, a reflection, the order shuffled.
    let blobs = vec![seen[3], [100.0, 700.0], seen[1], seen[2]];
    let guess = PenGuess {
        tip: Vector3::new(0.05, 0.0, 0.8),
        orientation: UnitQuaternion::identity(),
    };
    let frame = KeptFrame {
        blobs,
        guess: Some(guess),
        ..KeptFrame::default()
    };
    assert_eq!(
        a.frame_identities(&rig, CameraId::Left, &frame),
        [None, Some(2), Some(3), Some(0)]
    );
    let unguessed = KeptFrame {
        guess: None,
        ..frame.clone()
    };
    assert_eq!(
        a.frame_identities(&rig, CameraId::Left, &unguessed),
        [None; LED_COUNT]
    );
    let reversed = KeptFrame {
        guess: Some(PenGuess {
            orientation: UnitQuaternion::from_axis_angle(&Vector3::z_axis(), PI),
            ..guess
        }),
        ..frame
    };
    assert_eq!(
        a.frame_identities(&rig, CameraId::Left, &reversed),
        [None; LED_COUNT]
    );
}

/// A pen at rest that sets off at 2 m/s² just before a 15 Hz camera's last frame: its three
/// frames show it nearly still, and moving its blobs to a pair 30 ms later from them misses
/// by pixels; the tip's measured acceleration (less what the frames already show, and with an
/// offset of 0.2 m/s² that the IMU adds throughout) moves them exactly.
#[test]
fn a_pen_setting_off_is_moved_with_its_measured_acceleration() {
    let rig = rig();
    let start = 120_000_000u64;
    let accel = Vector3::new(2.0, -1.0, 0.0);
    let tip_at = |t: u64| {
        let s = (t.saturating_sub(start)) as f64 * 1e-9;
        Vector3::new(0.05, 0.02, 0.8) + accel * (0.5 * s * s)
    };
    let dir = Vector3::new(0.6, 0.0, -0.8);
    let offsets = OPTIONS.pen.led_offsets;
    let images = |t: u64| -> Vec<[f64; 2]> {
        offsets
            .iter()
            .map(|l| {
                rig.project(CameraId::Right, &(tip_at(t) - dir * *l))
                    .unwrap()
            })
            .collect()
    };
    let labels = [Some(0), Some(1), Some(2), Some(3)];
    let bias = Vector3::new(0.0, 0.2, 0.0);
    let run = |imu: bool| {
        let mut a = TimeAlignment::new(OPTIONS);
        for k in 0..=40u64 {
            let t = k * 5_000_000;
            let true_accel = if t >= start { accel } else { Vector3::zeros() };
            if imu {
                a.push_accel(t, true_accel + bias);
            }
            a.push_gyro(t, Vector3::zeros());
        }
        for t in [0u64, 66_000_000, 132_000_000] {
            a.push(1, t, images(t), Vec::new());
            a.label(1, labels, [None; LED_COUNT]);
            a.set_guess(
                1,
                Some(PenGuess {
                    tip: tip_at(0),
                    orientation: UnitQuaternion::rotation_between(&Vector3::x(), &dir)
                        .unwrap_or_else(UnitQuaternion::identity),
                }),
            );
        }
        let target = 162_000_000;
        let want = images(target);
        a.alignment(&rig, 1, target)
            .iter()
            .map(|m| (m.moved[0] - want[m.blob][0]).hypot(m.moved[1] - want[m.blob][1]))
            .fold(0.0, f64::max)
    };
    assert!(run(true) < 1e-6, "{}", run(true));
    assert!(run(false) > 1.0, "{}", run(false));
}

/// A pen turning about its resting tip, at 1 rad/s and from 50 ms on at 4 rad/s, seen at
/// 30 Hz: its blobs' image motion is no constant velocity or acceleration, but the gyro says
/// how it turned, and with the frame's guess of the pen the blobs are moved to the pair's
/// time exactly; without the guess they miss by pixels.
#[test]
fn a_turning_pens_blobs_are_moved_with_the_gyro() {
    let rig = rig();
    let rate = |t: u64| if t < 50_000_000 { 1.0 } else { 4.0 };
    let tip = Vector3::new(0.05, 0.02, 0.8);
    let offsets = OPTIONS.pen.led_offsets;
    let orientation = |t: u64| {
        let s = t as f64 * 1e-9;
        let angle = 0.4 + s.min(0.05) + 4.0 * (s - 0.05).max(0.0);
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), angle)
    };
    let images = |t: u64| -> Vec<[f64; 2]> {
        let d = orientation(t) * Vector3::x();
        offsets
            .iter()
            .map(|l| rig.project(CameraId::Right, &(tip - d * *l)).unwrap())
            .collect()
    };
    let labels = [Some(0), Some(1), Some(2), Some(3)];
    let run = |guessed: bool| {
        let mut a = TimeAlignment::new(OPTIONS);
        for k in 0..=24 {
            a.push_gyro(k * 5_000_000, Vector3::new(0.0, 0.0, rate(k * 5_000_000)));
        }
        for t in [10_000_000u64, 43_000_000, 76_000_000] {
            a.push(1, t, images(t), Vec::new());
            a.label(1, labels, [None; LED_COUNT]);
            let guess = PenGuess {
                tip,
                orientation: orientation(t),
            };
            a.set_guess(1, guessed.then_some(guess));
        }
        let want = images(100_000_000);
        a.alignment(&rig, 1, 100_000_000)
            .iter()
            .map(|m| (m.moved[0] - want[m.blob][0]).hypot(m.moved[1] - want[m.blob][1]))
            .fold(0.0, f64::max)
    };
    assert!(run(true) < 1e-6, "{}", run(true));
    assert!(run(false) > 1.0, "{}", run(false));
}

/// A pen drawing at 0.1 m/s while it turns at 3 rad/s, seen at 15 Hz, whose LED 1 had no
/// identity in the frame before (a reflection beside it): the other three LEDs' blobs measure
/// the translation, the gyro the turn, and LED 1's blob is moved with both to within what the
/// measured LEDs themselves reach, where before it was not moved at all (and the pair was
/// refused as unaligned).
#[test]
fn a_blob_without_a_measured_velocity_moves_with_the_rigid_pen() {
    let rig = rig();
    let rate = 3.0;
    let velocity = Vector3::new(0.0, 0.1, 0.0);
    let tip_at = |t: u64| Vector3::new(0.05, 0.02, 0.8) + velocity * (t as f64 * 1e-9);
    let orientation = |t: u64| {
        let angle = 0.4 + rate * t as f64 * 1e-9;
        UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 0.5)
            * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), angle)
    };
    // The gyro measures the rate in the pen's frame: the pen turns about its own z axis.
    let offsets = OPTIONS.pen.led_offsets;
    let images = |t: u64| -> Vec<[f64; 2]> {
        let d = orientation(t) * Vector3::x();
        offsets
            .iter()
            .map(|l| rig.project(CameraId::Right, &(tip_at(t) - d * *l)).unwrap())
            .collect()
    };
    let run = |gyro: bool| {
        let mut a = TimeAlignment::new(OPTIONS);
        for k in 0..=30 {
            if gyro {
                a.push_gyro(k * 5_000_000, Vector3::new(0.0, 0.0, rate));
            }
        }
        for (t, labels) in [
            (10_000_000u64, [None, Some(1), Some(2), Some(3)]),
            (76_000_000, [Some(0), Some(1), Some(2), Some(3)]),
        ] {
            a.push(1, t, images(t), Vec::new());
            a.label(1, labels, [None; LED_COUNT]);
            let guess = PenGuess {
                tip: tip_at(t),
                orientation: orientation(t),
            };
            a.set_guess(1, Some(guess));
        }
        let target = 106_000_000;
        let want = images(target);
        let error =
            |m: &MovedBlob| (m.moved[0] - want[m.blob][0]).hypot(m.moved[1] - want[m.blob][1]);
        let moved = a.alignment(&rig, 1, target);
        let led1 = moved.iter().find(|m| m.blob == 0).map(error);
        let others = moved
            .iter()
            .filter(|m| m.blob != 0)
            .map(error)
            .fold(0.0, f64::max);
        (led1, others)
    };
    let now = images(76_000_000);
    let later = images(106_000_000);
    let motion = (later[0][0] - now[0][0]).hypot(later[0][1] - now[0][1]);
    let (led1, others) = run(true);
    let led1 = led1.expect("LED 1 is moved");
    assert!(motion > 3.0, "LED 1 moves {motion} px");
    assert!(
        led1 <= others + 0.05 && led1 < 0.2,
        "LED 1 {led1} px, the others {others} px"
    );
    // Without the gyro nothing tells LED 1's own motion: it is not moved.
    assert_eq!(run(false).0, None);
}

/// Blobs moving at constant image velocity are moved exactly to the target time, using the
/// velocity between the labelled previous and current frame.
#[test]
fn labelled_blobs_move_with_their_measured_velocity() {
    let rig = rig();
    let mut a = TimeAlignment::new(OPTIONS);
    let v = [2.0e-7, -1.0e-7]; // pixels per nanosecond (200 and -100 px/s)
    let start = [[400.0, 300.0], [430.0, 310.0], [450.0, 315.0]];
    let at = |t: u64| -> Vec<[f64; 2]> {
        start
            .iter()
            .map(|b| [b[0] + v[0] * t as f64, b[1] + v[1] * t as f64])
            .collect()
    };
    a.push(1, 10_000_000, at(10_000_000), Vec::new());
    a.label(1, [Some(0), Some(1), None, Some(2)], [None; LED_COUNT]);
    a.push(1, 26_000_000, at(26_000_000), Vec::new());
    a.label(1, [Some(0), Some(1), None, Some(2)], [None; LED_COUNT]);
    let moved = a.alignment(&rig, 1, 33_000_000);
    assert_eq!(moved.len(), 3);
    let want = at(33_000_000);
    for MovedBlob {
        blob: i,
        moved: p,
        velocity: vel,
        ..
    } in moved
    {
        assert!((p[0] - want[i][0]).abs() < 1e-9 && (p[1] - want[i][1]).abs() < 1e-9);
        assert!((vel[0] - v[0]).abs() < 1e-15 && (vel[1] - v[1]).abs() < 1e-15);
    }
    // Filling a pair: the left frame's own blobs stay, the right ones are the moved ones.
    a.push(0, 33_000_000, vec![[500.0, 300.0]], Vec::new());
    let mut points = PairPoints::default();
    a.prepare(&rig, 0, 33_000_000, &mut points);
    assert_eq!(points.pixels(CameraId::Left), &[[500.0, 300.0]]);
    assert_eq!(points.pixels(CameraId::Right).len(), 3);
    assert!((points.pixels(CameraId::Right)[2][0] - want[2][0]).abs() < 1e-9);
    assert_eq!((points.left_norm.len(), points.right_norm.len()), (1, 3));
    // Without time alignment the blobs stay where they were imaged.
    let still = TimeAlignment {
        options: AlignOptions {
            time_align: false,
            ..OPTIONS
        },
        ..a.clone()
    };
    still.prepare(&rig, 0, 33_000_000, &mut points);
    assert_eq!(points.aligned, at(26_000_000));
    assert!(points.aligned_velocity.iter().all(Option::is_none));
}

/// Blobs accelerating uniformly: the move at the velocity measured over the last frame
/// interval misses the true position by exactly the predicted `a s (dt + s) / 2`, for a move
/// forwards in time and for one backwards into that interval; at constant velocity the
/// predicted error is zero, and stays zero when the centres' noise fakes an acceleration.
#[test]
fn an_accelerating_blob_is_moved_exactly_and_its_error_predicted() {
    let rig = rig();
    let acc = [3.0e-14, -2.0e-14]; // pixels per ns² (30 000 and -20 000 px/s²: a flick)
    let v0 = [1.0e-7, 5.0e-8];
    let start = [[400.0, 300.0], [430.0, 310.0], [450.0, 315.0]];
    let at = |t: u64| -> Vec<[f64; 2]> {
        let t = t as f64 - 26e6;
        start
            .iter()
            .map(|b| {
                [
                    b[0] + v0[0] * t + 0.5 * acc[0] * t * t,
                    b[1] + v0[1] * t + 0.5 * acc[1] * t * t,
                ]
            })
            .collect()
    };
    let labels = [Some(0), Some(1), None, Some(2)];
    let mut a = TimeAlignment::new(OPTIONS);
    for t in [10_000_000, 26_000_000, 43_000_000] {
        a.push(1, t, at(t), Vec::new());
        a.label(1, labels, [None; LED_COUNT]);
    }
    for target in [55_000_000u64, 35_000_000] {
        let moved = a.alignment(&rig, 1, target);
        assert_eq!(moved.len(), 3);
        let want = at(target);
        for m in moved {
            let miss = (m.moved[0] - want[m.blob][0]).hypot(m.moved[1] - want[m.blob][1]);
            let shift = target as f64 - 43e6;
            let predicted = extrapolation_error(acc[0].hypot(acc[1]), 17e6, shift);
            assert!(predicted > 0.01, "{predicted}");
            assert!(
                (m.error_px - predicted).abs() < 1e-6 * predicted,
                "{} vs {predicted}",
                m.error_px
            );
            // A constant acceleration is followed exactly: the error bound is what moving
            // at the measured velocity alone would have missed by.
            assert!(miss < 1e-6 * predicted, "{miss} vs {predicted}");
        }
    }
    let uniform = |t: u64| -> Vec<[f64; 2]> {
        start
            .iter()
            .map(|b| [b[0] + v0[0] * t as f64, b[1] + v0[1] * t as f64])
            .collect()
    };
    let mut b = TimeAlignment::new(OPTIONS);
    for t in [10_000_000, 26_000_000, 43_000_000] {
        b.push(1, t, uniform(t), Vec::new());
        b.label(1, labels, [None; LED_COUNT]);
    }
    assert!(b
        .alignment(&rig, 1, 55_000_000)
        .iter()
        .all(|m| m.error_px < 1e-9));
    // Centres jittered by half the pixel noise at constant velocity: an acceleration below
    // the noise floor predicts no error.
    let sigma = 0.5;
    let mut c = TimeAlignment::new(AlignOptions {
        pixel_sigma: sigma,
        ..OPTIONS
    });
    for (k, t) in [10_000_000u64, 26_000_000, 43_000_000]
        .into_iter()
        .enumerate()
    {
        let jitter = if k == 1 { -0.5 * sigma } else { 0.5 * sigma };
        let blobs = uniform(t)
            .iter()
            .map(|p| [p[0] + jitter, p[1] - jitter])
            .collect();
        c.push(1, t, blobs, Vec::new());
        c.label(1, labels, [None; LED_COUNT]);
    }
    let moved = c.alignment(&rig, 1, 55_000_000);
    assert_eq!(moved.len(), 3);
    assert!(moved.iter().all(|m| m.error_px == 0.0));
    // The same centres on a rig whose measured noise is a tenth of the configured: the floor
    // falls with it, and the jitter (five times that noise) reads as motion.
    c.set_noise_scale(0.1);
    let moved = c.alignment(&rig, 1, 55_000_000);
    assert!(moved.iter().all(|m| m.error_px > 0.0));
}

/// With a rolling shutter every blob was exposed at its own row's time: the frame's time is its
/// blobs' median row's, and every blob, the pair's own camera's too, is moved to the pair's time
/// with the velocity measured between its own exposure times, exactly for a constant velocity.
#[test]
fn rolling_shutter_blobs_move_from_their_rows_times() {
    let rig = rig();
    let row = 20_000.0; // ns per row: a 15 ms readout over 750 rows
    let mut a = TimeAlignment::new(AlignOptions {
        row_time_ns: [row, row],
        ..OPTIONS
    });
    let v = [2.0e-7, 1.5e-7]; // pixels per nanosecond
    let start = [[400.0, 100.0], [430.0, 300.0], [450.0, 500.0]];
    let at = |s: f64| -> Vec<[f64; 2]> {
        start
            .iter()
            .map(|b| [b[0] + v[0] * s, b[1] + v[1] * s])
            .collect()
    };
    // The blobs of a frame whose first row is exposed at `t0`: each where it is when its row
    // is exposed (y = y0 + v_y (t0 + row y)).
    let frame = |t0: f64| -> Vec<[f64; 2]> {
        start
            .iter()
            .map(|b| {
                let y = (b[1] + v[1] * t0) / (1.0 - v[1] * row);
                [b[0] + v[0] * (t0 + row * y), y]
            })
            .collect()
    };
    let t1 = a.push(1, 10_000_000, frame(10e6), Vec::new());
    let median = frame(10e6)[1][1];
    assert_eq!(t1, 10_000_000 + (row * median).round() as u64);
    a.label(1, [Some(0), Some(1), None, Some(2)], [None; LED_COUNT]);
    let t2 = a.push(1, 26_000_000, frame(26e6), Vec::new());
    a.label(1, [Some(0), Some(1), None, Some(2)], [None; LED_COUNT]);
    // The other camera's blobs at a later pair time.
    let moved = a.alignment(&rig, 1, 33_000_000);
    let want = at(33e6);
    assert_eq!(moved.len(), 3);
    for MovedBlob {
        blob: i, moved: p, ..
    } in moved
    {
        assert!((p[0] - want[i][0]).hypot(p[1] - want[i][1]) < 1e-6, "{i}");
    }
    // The pair's own camera: every blob at the frame's (median row) time.
    let mut points = PairPoints::default();
    a.prepare(&rig, 1, t2, &mut points);
    let want = at(t2 as f64);
    for (i, p) in points.pixels(CameraId::Right).iter().enumerate() {
        assert!((p[0] - want[i][0]).hypot(p[1] - want[i][1]) < 1e-6, "{i}");
    }
    // A global shutter leaves the own frame's blobs where they were imaged.
    let mut g = TimeAlignment::new(OPTIONS);
    g.push(1, 10_000_000, frame(10e6), Vec::new());
    assert_eq!(g.push(1, 26_000_000, frame(26e6), Vec::new()), 26_000_000);
    g.prepare(&rig, 1, 26_000_000, &mut points);
    assert_eq!(points.pixels(CameraId::Right), frame(26e6).as_slice());
}

/// Without labels or a pose (the pen just reappeared) the blobs of consecutive frames are
/// matched along the pen line, in any blob order, and moved with their measured velocity.
#[test]
fn unlabelled_blobs_on_the_pen_line_move_with_their_velocity() {
    let rig = rig();
    let mut a = TimeAlignment::new(OPTIONS);
    let v = [2.0e-7, -1.0e-7];
    let start = [[400.0, 300.0], [432.0, 324.0], [472.0, 354.0]];
    let at = |t: u64| -> Vec<[f64; 2]> {
        start
            .iter()
            .map(|b| [b[0] + v[0] * t as f64, b[1] + v[1] * t as f64])
            .collect()
    };
    a.push(1, 10_000_000, at(10_000_000), Vec::new());
    let mut shuffled = at(76_000_000);
    shuffled.swap(0, 2);
    a.push(1, 76_000_000, shuffled, Vec::new());
    let moved = a.alignment(&rig, 1, 100_000_000);
    assert_eq!(moved.len(), 3);
    let mut want = at(100_000_000);
    want.swap(0, 2);
    for MovedBlob {
        blob: i,
        moved: p,
        velocity: vel,
        ..
    } in moved
    {
        assert!((p[0] - want[i][0]).abs() < 1e-9 && (p[1] - want[i][1]).abs() < 1e-9);
        assert!((vel[0] - v[0]).abs() < 1e-15 && (vel[1] - v[1]).abs() < 1e-15);
    }
    // Blobs that are not on one line (interference) are not moved.
    let mut off = at(142_000_000);
    off[1][1] += 8.0;
    a.push(1, 142_000_000, off, Vec::new());
    assert!(a.alignment(&rig, 1, 150_000_000).is_empty());
}

/// The rigid pen's translation at an LED nothing measured: a velocity field linear in the LEDs'
/// offsets is reproduced exactly at LED 1 from LEDs 2-4, one measured LED gives its own velocity,
/// and none gives nothing.
#[test]
fn the_rigid_translation_follows_a_line_in_the_led_offsets() {
    let offsets = OPTIONS.pen.led_offsets;
    let field = |s: f64| [1e-7 + 4e-7 * s, -2e-7 + 1e-6 * s];
    let measured: Vec<MeasuredTranslation> = (1..LED_COUNT)
        .map(|k| MeasuredTranslation {
            led: k,
            velocity: field(offsets[k]),
            error_px: 0.1 * k as f64,
        })
        .collect();
    let v = rigid_translation(&measured, &offsets, 0).unwrap();
    let want = field(offsets[0]);
    assert!(
        (v[0] - want[0]).abs() < 1e-20 && (v[1] - want[1]).abs() < 1e-20,
        "{v:?}"
    );
    let one = rigid_translation(&measured[1..2], &offsets, 0).unwrap();
    assert_eq!(one, measured[1].velocity);
    assert_eq!(rigid_translation(&[], &offsets, 0), None);
}
