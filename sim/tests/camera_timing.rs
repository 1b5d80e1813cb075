//! The cameras' timing: a rolling shutter exposes each LED at its own row's time, an exposure smears a moving spot
//! symmetrically about its mid-exposure position, free-running clocks keep their own period, and the `webcam`
//! rig has the geometry its description gives.

use fires_record::{CalibratedCamera, CameraModel, Extrinsics, GrayImage};
use fires_sim::camera::{draw_spot, CameraConfig, CameraOutput, ImageModel, SensorTiming, Spot};
use fires_sim::motion::trajectory::orientation_from_axis;
use fires_sim::motion::Pose;
use fires_sim::objects::V3;
use fires_sim::pen::Pen;
use fires_sim::rng::SimRng;
use fires_sim::scenario;

fn camera(timing: SensorTiming) -> CameraConfig {
    CameraConfig {
        cal: CalibratedCamera {
            intrinsics: CameraModel::from_hfov(640, 480, 1.1),
            extrinsics: Extrinsics::IDENTITY,
        },
        rate_hz: 60.0,
        offset_s: 0.0,
        jitter_s: 0.0,
        timestamp_noise_s: 0.0,
        timing,
        output: CameraOutput::Images(ImageModel {
            background: 2.0,
            noise_sigma: 0.0,
            gain: 500.0,
            led_diameter_m: 0.005,
            blur_px: 0.8,
        }),
        min_brightness: 0.0,
        reflection_rate: 0.0,
        sunlight_rate: 0.0,
    }
}

/// The pen 0.6 m away, its back towards the camera and tilted so its LEDs span many rows, moving at 0.3 m/s
/// diagonally across the image.
fn moving_pen(t: f64) -> Pose {
    let axis = V3::new(0.2, 0.8, 1.0).normalize();
    Pose {
        tip: V3::new(-0.05, -0.05, 0.6) + V3::new(0.2, 0.22, 0.0) * t,
        q: orientation_from_axis(&axis, 0.3),
    }
}

fn project(cam: &CameraConfig, p: &V3) -> [f64; 2] {
    cam.cal.project_world([p.x, p.y, p.z]).expect("in front")
}

#[test]
fn a_rolling_shutter_images_each_led_at_its_own_rows_time() {
    let pen = Pen::fires_default();
    let readout = 0.015;
    let rolling = camera(SensorTiming {
        exposure_s: 0.0,
        readout_s: readout,
        rate_error: 0.0,
    });
    let global = camera(SensorTiming::IDEAL);
    let t = 0.1;
    let mut rng = SimRng::stream(1, 1);
    let obs = rolling.observe(t, &moving_pen, &pen, None, None, &mut rng);
    let flat = global.observe(t, &moving_pen, &pen, None, None, &mut rng);
    let mut largest_shift: f64 = 0.0;
    for (i, (led, still)) in obs.leds.iter().zip(&flat.leds).enumerate() {
        let px = led.pixel.expect("projects");
        // Where the LED is at the time of the row it images on: the same pixel.
        let s = t + readout * px[1] / 480.0;
        let at_row_time = project(
            &rolling,
            &pen.leds_world(&moving_pen(s).tip, &moving_pen(s).q)[i],
        );
        assert!(
            (px[0] - at_row_time[0]).hypot(px[1] - at_row_time[1]) < 1e-3,
            "LED {i}: {px:?} against {at_row_time:?}"
        );
        // A global shutter images every LED at the frame time.
        let at_frame = project(
            &global,
            &pen.leds_world(&moving_pen(t).tip, &moving_pen(t).q)[i],
        );
        let g = still.pixel.expect("projects");
        assert!((g[0] - at_frame[0]).hypot(g[1] - at_frame[1]) < 1e-9);
        largest_shift = largest_shift.max((px[0] - g[0]).hypot(px[1] - g[1]));
    }
    // Rows around the middle of the image are exposed about 7 ms late: at 0.3 m/s and 0.6 m, several pixels.
    assert!(
        largest_shift > 1.0,
        "rolling shutter moved the LEDs by {largest_shift} px only"
    );
}

#[test]
fn an_exposure_smears_a_spot_symmetrically_about_its_mid_exposure_position() {
    let pen = Pen::fires_default();
    let exposure = 0.004;
    let cam = camera(SensorTiming {
        exposure_s: exposure,
        readout_s: 0.0,
        rate_error: 0.0,
    });
    let mut rng = SimRng::stream(2, 2);
    let t = 0.2;
    let obs = cam.observe(t, &moving_pen, &pen, None, None, &mut rng);
    let spot = obs.led_spots[0];
    let led = |s: f64| pen.leds_world(&moving_pen(s).tip, &moving_pen(s).q)[0];
    let (a, b) = (
        project(&cam, &led(t - exposure / 2.0)),
        project(&cam, &led(t + exposure / 2.0)),
    );
    assert!((spot.streak[0] - (b[0] - a[0])).abs() < 1e-9);
    assert!((spot.streak[1] - (b[1] - a[1])).abs() < 1e-9);
    // Render a dim (unsaturated) streak far from the border: its centroid is the mid-exposure position and its
    // variance along the streak grows by length^2 / 12 (a uniform smear).
    let streak = [6.0, 2.0];
    let centre = [100.3, 80.6];
    let sigma = 1.2;
    let moments = |streak: [f64; 2]| {
        let mut img = GrayImage::new(200, 160);
        draw_spot(
            &mut img,
            &Spot {
                px: centre,
                peak: 100.0,
                sigma,
                streak,
            },
        );
        let (mut w, mut x, mut y) = (0.0, 0.0, 0.0);
        for (i, &v) in img.data.iter().enumerate() {
            let v = f64::from(v);
            w += v;
            x += v * (i % 200) as f64;
            y += v * (i / 200) as f64;
        }
        let (cx, cy) = (x / w, y / w);
        let u = [streak[0], streak[1]];
        let len = u[0].hypot(u[1]).max(1e-12);
        let mut var = 0.0;
        for (i, &v) in img.data.iter().enumerate() {
            let d = ((i % 200) as f64 - cx) * u[0] / len + ((i / 200) as f64 - cy) * u[1] / len;
            var += f64::from(v) * d * d;
        }
        (cx, cy, var / w, w)
    };
    let (cx, cy, var, energy) = moments(streak);
    assert!((cx - centre[0]).abs() < 0.05 && (cy - centre[1]).abs() < 0.05);
    let (_, _, var_still, energy_still) = moments([1e-9, 0.0]);
    let len2 = streak[0] * streak[0] + streak[1] * streak[1];
    assert!(
        ((var - var_still) - len2 / 12.0).abs() < 0.1 * len2 / 12.0,
        "variance grew by {} against {}",
        var - var_still,
        len2 / 12.0
    );
    // The smear spreads the same light (to the rounding of each pixel).
    assert!((energy - energy_still).abs() < 0.02 * energy_still);
}

#[test]
fn a_free_running_clock_keeps_its_own_period() {
    let mut cam = camera(SensorTiming {
        rate_error: 1.5e-3,
        ..SensorTiming::IDEAL
    });
    cam.offset_s = 0.004;
    let period = cam.nominal_frame_time(1000) - cam.nominal_frame_time(999);
    assert!((period - 1.0 / (60.0 * 1.0015)).abs() < 1e-12);
    assert!((cam.nominal_frame_time(0) - 0.004).abs() < 1e-15);
    // Row 240 of 480 is exposed half the readout after row 0.
    cam.timing.readout_s = 0.015;
    assert!((cam.row_delay(240.0) - 0.0075).abs() < 1e-15);
    assert_eq!(cam.row_delay(-5.0), 0.0);
}

#[test]
fn the_webcam_rig_has_the_stated_geometry_and_clocks() {
    let mut apart = Vec::new();
    for seed in 1..=40 {
        let sc = scenario::scenario("webcam", seed, 60.0, None).unwrap();
        let [c0, c1] = [&sc.cameras[0], &sc.cameras[1]];
        // 640x480 at 60 Hz, fx near 520 px (75 deg diagonal), rolling shutter 15 ms, exposure 4 ms.
        for c in [c0, c1] {
            let m = c.cal.intrinsics;
            assert_eq!((m.width, m.height, c.rate_hz), (640, 480, 60.0));
            let diag = 2.0 * (400.0 / m.fx).atan().to_degrees();
            assert!((diag - 75.0).abs() < 0.5, "diagonal fov {diag}");
            assert_eq!((c.timing.readout_s, c.timing.exposure_s), (0.015, 0.004));
        }
        // 0.20 m baseline; the optical axes cross 0.6 m in front of its midpoint.
        let (o0, o1) = (
            V3::from(c0.cal.extrinsics.centre_world()),
            V3::from(c1.cal.extrinsics.centre_world()),
        );
        assert!(((o1 - o0).norm() - 0.20).abs() < 1e-12);
        let axis = |c: &CameraConfig| {
            let r = c.cal.extrinsics.rotation;
            V3::new(r[2][0], r[2][1], r[2][2])
        };
        let (a0, a1) = (axis(c0), axis(c1));
        // Closest points of the two axes.
        let w = o0 - o1;
        let (b, d, e) = (a0.dot(&a1), a0.dot(&w), a1.dot(&w));
        let denom = 1.0 - b * b;
        let (s, t) = ((b * e - d) / denom, (e - b * d) / denom);
        let (p0, p1) = (o0 + a0 * s, o1 + a1 * t);
        assert!((p0 - p1).norm() < 1e-9, "axes do not cross");
        let mid = (o0 + o1) / 2.0;
        assert!(((p0 - mid).norm() - 0.6).abs() < 1e-9);
        apart.push((c1.timing.rate_error - c0.timing.rate_error).abs());
    }
    assert!(
        apart.iter().all(|&d| (0.5e-3..=2e-3).contains(&d)),
        "{apart:?}"
    );
    // Seeded, not constant.
    assert!(apart.iter().any(|&d| d < 1e-3) && apart.iter().any(|&d| d > 1.5e-3));
}
