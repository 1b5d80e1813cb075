//! Closed-form checks of the sensor physics: IMU at rest, camera projection through the stored calibration.

use fires_protocol::ScaleFactors;
use fires_record::RecordingReader;
use fires_sim::imu::{kinematics, Imu};
use fires_sim::motion::trajectory::orientation_from_axis;
use fires_sim::motion::{Pose, Trajectory};
use fires_sim::objects::V3;
use fires_sim::rng::SimRng;
use fires_sim::{run_scenario, scenario, SimOptions};
use nalgebra::Matrix3;

#[test]
fn a_pen_at_rest_reads_gravity_and_the_earth_field_through_the_scale_factors() {
    let sc = scenario("fires-v2", 11, 1.0, None).unwrap();
    // Keep hard and soft iron; remove noise and biases so the comparison is exact up to quantisation.
    let mut cfg = sc.imu.ideal();
    cfg.hard_iron = sc.imu.hard_iron;
    cfg.soft_iron = sc.imu.soft_iron;
    let s = ScaleFactors::FIRES_PEN;
    let soft_inv: Matrix3<f64> = cfg.soft_iron.try_inverse().unwrap();
    let mut rng = SimRng::stream(5, 5);
    for trial in 0..50 {
        let axis = V3::new(rng.normal(), rng.normal(), rng.normal()).normalize();
        let pose = Pose {
            tip: V3::new(rng.range(-0.2, 0.2), 0.1, 0.6),
            q: orientation_from_axis(&axis, rng.range(-3.0, 3.0)),
        };
        let traj = Trajectory::stationary(pose);
        let mut imu = Imu::new(cfg.clone(), SimRng::stream(1, 1));
        let k = kinematics(&traj, &cfg, 1.0);
        let p = imu.measure(&k, trial as u8, 0.01);
        // Closed forms: f = R^T (-g), omega = 0, m = S R^T B + h.
        let f = pose.q.inverse() * (-cfg.gravity_world);
        let b = pose.q.inverse() * cfg.earth_field_world;
        for i in 0..3 {
            let acc = f64::from(p.accel[i]) * s.accel_mps2_per_count;
            assert!(
                (acc - f[i]).abs() <= 0.5 * s.accel_mps2_per_count + 1e-9,
                "accel {i}: {acc} vs {}",
                f[i]
            );
            assert_eq!(p.gyro[i], 0, "gyro at rest");
        }
        let m = V3::new(
            f64::from(p.mag[0]),
            f64::from(p.mag[1]),
            f64::from(p.mag[2]),
        ) * s.mag_tesla_per_count;
        let corrected = soft_inv * (m - cfg.hard_iron);
        // Quantisation error is at most half a count per axis, mapped through S^-1.
        let bound = soft_inv.norm() * 0.5 * 3f64.sqrt() * s.mag_tesla_per_count;
        assert!((corrected - b).norm() <= bound, "mag {corrected} vs {b}");
        // |f| is standard gravity, |B| is 47 uT.
        assert!((f.norm() - 9.80665).abs() < 1e-12);
        assert!((b.norm() - 47e-6).abs() < 1e-15);
    }
}

#[test]
fn with_noise_the_rest_reading_averages_to_the_closed_form() {
    let sc = scenario("fires-v1", 3, 1.0, None).unwrap();
    let cfg = sc.imu.clone();
    let pose = Pose {
        tip: V3::new(0.0, 0.0, 0.7),
        q: orientation_from_axis(&V3::new(0.3, 0.5, 0.8).normalize(), 0.4),
    };
    let traj = Trajectory::stationary(pose);
    let mut imu = Imu::new(cfg.clone(), SimRng::stream(9, 2));
    let n = 2000;
    let mut sum = V3::zeros();
    for i in 0..n {
        let k = kinematics(&traj, &cfg, f64::from(i) * 0.01);
        let p = imu.measure(&k, i as u8, 0.01);
        sum += V3::new(
            f64::from(p.accel[0]),
            f64::from(p.accel[1]),
            f64::from(p.accel[2]),
        ) * cfg.scale.accel_mps2_per_count;
    }
    let mean = sum / f64::from(n);
    let expected = pose.q.inverse() * (-cfg.gravity_world) + cfg.accel_bias;
    assert!((mean - expected).norm() < 3e-3, "{mean} vs {expected}");
}

#[test]
fn led_truth_pixels_follow_the_stored_calibration_in_closed_form() {
    let dir = tempfile::tempdir().unwrap();
    run_scenario(
        "fires-v2",
        4,
        1.0,
        dir.path(),
        SimOptions {
            images: false,
            ..SimOptions::default()
        },
    )
    .unwrap();
    let r = RecordingReader::open(dir.path()).unwrap();
    let meta = r.meta();
    let exposures = r.exposure_truth().unwrap().unwrap();
    assert!(!exposures.is_empty());
    let mut checked = 0;
    for e in &exposures {
        let cam = &meta.rig.cameras[e.camera as usize];
        let (m, x) = (&cam.intrinsics, &cam.extrinsics);
        for (led, world) in e.leds.iter().zip(&e.pose.leds_m) {
            // Hand-written pinhole + OpenCV distortion, independent of CameraModel::project.
            let rr = x.rotation;
            let t = x.translation_m;
            let pc: Vec<f64> = (0..3)
                .map(|i| rr[i][0] * world[0] + rr[i][1] * world[1] + rr[i][2] * world[2] + t[i])
                .collect();
            let (a, b) = (pc[0] / pc[2], pc[1] / pc[2]);
            let r2 = a * a + b * b;
            let radial = 1.0 + m.k1 * r2 + m.k2 * r2 * r2 + m.k3 * r2 * r2 * r2;
            let xd = a * radial + 2.0 * m.p1 * a * b + m.p2 * (r2 + 2.0 * a * a);
            let yd = b * radial + m.p1 * (r2 + 2.0 * b * b) + 2.0 * m.p2 * a * b;
            let (u, v) = (m.fx * xd + m.cx, m.fy * yd + m.cy);
            let px = led.pixel.unwrap();
            assert!(
                (px[0] - u).abs() < 1e-9 && (px[1] - v).abs() < 1e-9,
                "{px:?} vs {u} {v}"
            );
            checked += 1;
        }
    }
    assert!(checked > 50);
    // The right camera really has distortion and a baseline of 6 cm.
    let right = &meta.rig.cameras[1];
    assert!(right.intrinsics.k1 != 0.0 && right.intrinsics.p1 != 0.0 && right.intrinsics.k3 != 0.0);
    let c = right.extrinsics.centre_world();
    assert!(((c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt() - 0.06).abs() < 1e-12);
}

#[test]
fn blobs_and_images_show_the_visible_leds() {
    // fires-v1 reports blobs: every visible LED has a blob within 5 sigma (0.5 px noise) of its true pixel.
    let dir = tempfile::tempdir().unwrap();
    run_scenario("fires-v1", 8, 1.5, dir.path(), SimOptions::default()).unwrap();
    let r = RecordingReader::open(dir.path()).unwrap();
    let truth = r.exposure_truth().unwrap().unwrap();
    let mut matched = 0;
    for cam in 0..2u8 {
        for f in r.frames(cam).unwrap() {
            let t = truth
                .iter()
                .find(|e| e.camera == cam && e.index == f.index)
                .unwrap();
            let blobs = f.blobs.as_ref().unwrap();
            assert!(blobs.len() <= 4);
            for led in t
                .leds
                .iter()
                .filter(|l| l.visibility == fires_record::Visibility::Visible)
            {
                let p = led.pixel.unwrap();
                if blobs.iter().any(|b| (b.x - p[0]).hypot(b.y - p[1]) < 2.5) {
                    matched += 1;
                }
            }
        }
    }
    assert!(matched > 500, "{matched}");

    // fires-v2 delivers images: the pixel at a visible LED is bright, the median pixel is background.
    let dir = tempfile::tempdir().unwrap();
    run_scenario("fires-v2", 8, 1.0, dir.path(), SimOptions::default()).unwrap();
    let r = RecordingReader::open(dir.path()).unwrap();
    let truth = r.exposure_truth().unwrap().unwrap();
    let mut bright = 0;
    for f in r.frames(0).unwrap() {
        let img = r.image(&f).unwrap().unwrap();
        let t = truth
            .iter()
            .find(|e| e.camera == 0 && e.index == f.index)
            .unwrap();
        let mut sorted = img.data.clone();
        sorted.sort_unstable();
        assert!((8..=20).contains(&sorted[sorted.len() / 2]));
        for led in t
            .leds
            .iter()
            .filter(|l| l.visibility == fires_record::Visibility::Visible)
        {
            let p = led.pixel.unwrap();
            let idx = p[1].round() as usize * img.width as usize + p[0].round() as usize;
            assert!(img.data[idx] > 100, "LED pixel {}", img.data[idx]);
            bright += 1;
        }
    }
    assert!(bright > 20);
}

#[test]
fn a_moving_pen_reads_the_closed_form_specific_force_and_rate() {
    // Minimum-jerk translation by L along world x in T seconds at constant orientation, then a minimum-jerk
    // rotation by theta about the pen's own x axis (the IMU sits on that axis, so no lever-arm terms).
    let sc = scenario("fires-v1", 1, 1.0, None).unwrap();
    let cfg = sc.imu.ideal();
    let q = orientation_from_axis(&V3::new(0.2, 0.4, 0.9).normalize(), 0.3);
    let a = Pose {
        tip: V3::new(0.0, 0.0, 0.8),
        q,
    };
    let (l, big_t) = (0.2, 1.0);
    let b = Pose {
        tip: a.tip + V3::new(l, 0.0, 0.0),
        q,
    };
    let theta = 1.2;
    let rot = nalgebra::UnitQuaternion::from_axis_angle(&nalgebra::Vector3::x_axis(), theta);
    let c = Pose {
        tip: b.tip,
        q: q * rot,
    };
    let traj = Trajectory::waypoints(a, 0.5, &[(big_t, b), (big_t, c)]);
    let mj1 = |u: f64| 30.0 * u * u - 60.0 * u.powi(3) + 30.0 * u.powi(4);
    let w = fires_sim::imu::FILTER_WINDOW_S;
    for &t in &[0.6, 0.8, 1.0, 1.3, 1.45] {
        // Mean acceleration over the filter window = velocity difference / window.
        let v = |t: f64| l / big_t * mj1(((t - 0.5) / big_t).clamp(0.0, 1.0));
        let acc = V3::new((v(t + w / 2.0) - v(t - w / 2.0)) / w, 0.0, 0.0);
        let expected = q.inverse() * (acc - cfg.gravity_world);
        let k = kinematics(&traj, &cfg, t);
        assert!(
            (k.specific_force - expected).norm() < 1e-3,
            "t={t}: {} vs {expected}",
            k.specific_force
        );
        assert!(k.angular_velocity.norm() < 1e-9);
    }
    let h = 1e-3;
    for &t in &[1.7, 2.0, 2.2] {
        let m = |t: f64| fires_sim::motion::min_jerk((t - 1.5) / big_t);
        let rate = theta * (m(t + w / 2.0 + h) - m(t - w / 2.0 - h)) / (w + 2.0 * h);
        let k = kinematics(&traj, &cfg, t);
        assert!(
            (k.angular_velocity - V3::new(rate, 0.0, 0.0)).norm() < 1e-9,
            "t={t}: {}",
            k.angular_velocity
        );
        // Pure rotation about the axis through the IMU: specific force is gravity only.
        let expected = traj.pose(t).q.inverse() * (-cfg.gravity_world);
        assert!((k.specific_force - expected).norm() < 1e-6);
    }
}
