//! Named scenario presets.
//!
//! Common to all: the rig is pitched 15 degrees down (so gravity is not along a camera axis), the Earth field is
//! 47 uT at 60 degrees inclination with a seeded heading, the pen clock drifts by a seeded +-50 ppm, and the
//! IMU biases, hard and soft iron are seeded.

use crate::camera::{CameraConfig, CameraOutput, HandModel, ImageModel, SensorTiming};
use crate::imu::ImuConfig;
use crate::link::LinkConfig;
use crate::motion::trajectory::{DrawStyle, FreeMotion};
use crate::objects::{ObjectKind, V3};
use crate::pen::Pen;
use crate::rng::SimRng;
use crate::SimError;
use fires_protocol::ScaleFactors;
use fires_record::{CalibratedCamera, CameraModel, Extrinsics, PenGeometry};
use nalgebra::{Matrix3, Rotation3};

/// The scenario names and one-line descriptions: the one list of scenarios ([`scenario`] builds exactly
/// these, error messages and help texts list them from here).
pub const SCENARIOS: &[(&str, &str)] = &[
    ("fires-v1", "two Wii-remote-like IR blob cameras: 1024x768, 45 deg hFOV, 100 Hz, parallel, 0.25 m baseline; pen draws a curve network on a sphere"),
    ("webcam", "two PlayStation-Eye-class IR webcams: 640x480 8-bit images, 60 Hz free-running clocks, rolling shutter, 0.20 m baseline toed in to 0.6 m; pen draws a curve network on a freeform blob"),
    ("fires-v2", "Minoru-like stereo webcam: 640x480 8-bit images, 15 Hz, rolling shutter, 6 cm baseline; pen draws a curve network on a freeform blob"),
    ("bar", "thesis 7.1 experiment 1: an 81.0 mm bar with an LED at each end moved through 0.35-1.5 m in front of the fires-v1 rig"),
    ("tip", "thesis 7.1 experiment 2: the pen with its tip at LED 1, which is never rendered; 0.35-1.5 m in front of the fires-v1 rig"),
    ("stress", "fires-v2 rig with a box: hand occlusion, reflections, sunlight, link faults with a disconnect, fast motion"),
    ("pivot", "tip pivot calibration on the fires-v1 rig: the tip held on one point 0.7 m away while the pen sweeps a 35 deg cone and rolls"),
];

/// The names of [`SCENARIOS`], comma-separated.
pub fn scenario_names() -> String {
    SCENARIOS
        .iter()
        .map(|(name, _)| *name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// Rig pitch below the horizontal, radians.
const RIG_PITCH: f64 = 15.0 * std::f64::consts::PI / 180.0;

/// How the pen moves.
#[derive(Clone, Debug, PartialEq)]
pub enum MotionSpec {
    /// Drawing a curve network on an object.
    Drawing {
        /// Object kind.
        object: ObjectKind,
        /// Object centre, world, metres.
        centre: V3,
        /// Object size (radius), metres.
        size: f64,
        /// Speeds and tilt.
        style: DrawStyle,
    },
    /// Free motion through waypoints (no object).
    Free(FreeMotion),
    /// The tip held still on a point while the pen turns about it (pivot calibration).
    Pivot {
        /// The pivot point, world, metres.
        tip: V3,
        /// Largest angle of the pen's back from the direction to the cameras, radians.
        cone: f64,
    },
}

/// A fully specified simulation setup.
#[derive(Clone, Debug, PartialEq)]
pub struct Scenario {
    /// Name.
    pub name: String,
    /// Cameras (camera 0 defines the world frame).
    pub cameras: Vec<CameraConfig>,
    /// The pen.
    pub pen: Pen,
    /// The hand holding it, if simulated.
    pub hand: Option<HandModel>,
    /// Motion.
    pub motion: MotionSpec,
    /// IMU model.
    pub imu: ImuConfig,
    /// Link model.
    pub link: LinkConfig,
    /// Pen clock rate error, ppm.
    pub pen_clock_drift_ppm: f64,
    /// Pen device time at session time 0, seconds (time since the pen booted).
    pub pen_boot_s: f64,
    /// Session time of the first IMU sample, seconds.
    pub stream_start_s: f64,
}

/// World up (unit) for the pitched rig.
pub fn world_up() -> V3 {
    V3::new(0.0, -RIG_PITCH.cos(), -RIG_PITCH.sin())
}

fn wii_camera(extrinsics: Extrinsics) -> CalibratedCamera {
    let mut m = CameraModel::from_hfov(1024, 768, 45f64.to_radians());
    m.k1 = 0.015;
    CalibratedCamera {
        intrinsics: m,
        extrinsics,
    }
}

/// Intrinsics of the Minoru-like webcam (60 degree hFOV, moderate barrel distortion).
pub fn minoru_camera(extrinsics: Extrinsics, right: bool) -> CalibratedCamera {
    let mut m = CameraModel::from_hfov(640, 480, 60f64.to_radians());
    m.cx += if right { -2.3 } else { 1.7 };
    m.cy += if right { 1.1 } else { -0.8 };
    m.fy *= 1.002;
    m.k1 = -0.12;
    m.k2 = 0.05;
    m.p1 = 0.0008;
    m.p2 = -0.0005;
    m.k3 = -0.01;
    CalibratedCamera {
        intrinsics: m,
        extrinsics,
    }
}

fn parallel(baseline: f64, yaw_deg: f64) -> Extrinsics {
    let r = Rotation3::from_euler_angles(0.0, yaw_deg.to_radians(), 0.0);
    let m = r.matrix();
    // x_cam = R x_world + t with the camera centre at (baseline, 0, 0): t = -R c.
    let c = V3::new(baseline, 0.0, 0.0);
    let t = -(r * c);
    Extrinsics {
        rotation: [
            [m[(0, 0)], m[(0, 1)], m[(0, 2)]],
            [m[(1, 0)], m[(1, 1)], m[(1, 2)]],
            [m[(2, 0)], m[(2, 1)], m[(2, 2)]],
        ],
        translation_m: [t.x, t.y, t.z],
    }
}

fn wii_rig(link_jitter: f64) -> Vec<CameraConfig> {
    let image = ImageModel {
        background: 0.0,
        noise_sigma: 0.0,
        gain: 600.0,
        led_diameter_m: 0.005,
        blur_px: 1.0,
    };
    [0.0, 0.0037]
        .iter()
        .enumerate()
        .map(|(i, &offset)| CameraConfig {
            cal: wii_camera(if i == 0 {
                Extrinsics::IDENTITY
            } else {
                parallel(0.25, 0.0)
            }),
            rate_hz: 100.0,
            offset_s: 0.02 + offset,
            jitter_s: 0.0002,
            timestamp_noise_s: link_jitter,
            timing: SensorTiming::IDEAL,
            output: CameraOutput::Blobs {
                max_blobs: 4,
                centroid_noise_px: 0.5,
                image,
            },
            min_brightness: 0.02,
            reflection_rate: 0.01,
            sunlight_rate: 0.002,
        })
        .collect()
}

/// Clock rate errors of two free-running cameras: the first within +-0.1% of nominal, the second off the first
/// by a seeded 0.05-0.2% either way (crystal tolerances of consumer webcams).
fn free_running_rates(rng: &mut SimRng) -> [f64; 2] {
    let first = rng.range(-1e-3, 1e-3);
    let apart = rng.range(0.5e-3, 2e-3) * if rng.chance(0.5) { 1.0 } else { -1.0 };
    [first, first + apart]
}

fn minoru_rig(rates: [f64; 2]) -> Vec<CameraConfig> {
    let image = ImageModel {
        background: 14.0,
        noise_sigma: 3.0,
        gain: 500.0,
        led_diameter_m: 0.005,
        blur_px: 0.8,
    };
    [0.0, 0.023]
        .iter()
        .enumerate()
        .map(|(i, &offset)| CameraConfig {
            cal: minoru_camera(
                if i == 0 {
                    Extrinsics::IDENTITY
                } else {
                    parallel(0.06, -0.3)
                },
                i == 1,
            ),
            rate_hz: 15.0,
            offset_s: 0.03 + offset,
            jitter_s: 0.002,
            timestamp_noise_s: 0.001,
            // The Minoru's two VGA CMOS sensors are rolling-shutter parts read out at their 30 Hz frame time
            // and run at 15 Hz over one USB 2 port; 10 ms is an indoor auto-exposure.
            timing: SensorTiming {
                exposure_s: 0.010,
                readout_s: 0.030,
                rate_error: rates[i],
            },
            output: CameraOutput::Images(image),
            min_brightness: 0.02,
            reflection_rate: 0.02,
            sunlight_rate: 0.01,
        })
        .collect()
}

/// Intrinsics of the PlayStation-Eye-class webcam: 75 degree diagonal field of view (fx = fy = 400 px /
/// tan 37.5 deg = 521 px), moderate barrel distortion, principal point a few pixels off centre.
pub fn webcam_camera(extrinsics: Extrinsics, right: bool) -> CalibratedCamera {
    let mut m = CameraModel::from_hfov(640, 480, 2.0 * (320.0f64 / 521.3).atan());
    m.cx += if right { 2.1 } else { -1.4 };
    m.cy += if right { -1.6 } else { 0.9 };
    m.fy *= 0.9985;
    m.k1 = -0.09;
    m.k2 = 0.03;
    m.p1 = -0.0004;
    m.p2 = 0.0006;
    m.k3 = -0.004;
    CalibratedCamera {
        intrinsics: m,
        extrinsics,
    }
}

/// Distance from the webcam rig's baseline at which the two optical axes cross, metres.
const WEBCAM_CONVERGENCE_M: f64 = 0.6;
/// The webcam rig's baseline, metres.
const WEBCAM_BASELINE_M: f64 = 0.20;

/// Rotation about the camera y axis by `angle` as a row-major matrix (x_cam = R x).
fn yaw(angle: f64) -> Rotation3<f64> {
    Rotation3::from_euler_angles(0.0, angle, 0.0)
}

/// The webcam rig in its own frame: each camera's rotation (x_cam = R (x - c)) and centre, both toed in so
/// their optical axes cross `WEBCAM_CONVERGENCE_M` in front of the baseline's midpoint.
fn webcam_poses() -> [(Rotation3<f64>, V3); 2] {
    let half = 0.5 * WEBCAM_BASELINE_M;
    let toe = (half / WEBCAM_CONVERGENCE_M).atan();
    [
        (yaw(-toe), V3::new(-half, 0.0, 0.0)),
        (yaw(toe), V3::new(half, 0.0, 0.0)),
    ]
}

/// A point of the webcam rig's frame in the world (left camera) frame.
fn webcam_rig_to_world(p: V3) -> V3 {
    let [(r0, c0), _] = webcam_poses();
    r0 * (p - c0)
}

fn webcam_rig(rates: [f64; 2], phases: [f64; 2]) -> Vec<CameraConfig> {
    // IR-pass filter, 4 ms exposure, lowest gain: the frame is dark but for the LEDs. The OV7720-class sensor's
    // 60 dB dynamic range on its 10-bit ADC puts the dark noise near one 10-bit step, 0.25 DN at 8 bits.
    let image = ImageModel {
        background: 2.0,
        noise_sigma: 0.25,
        gain: 500.0,
        led_diameter_m: 0.005,
        blur_px: 0.8,
    };
    let [(r0, c0), (r1, c1)] = webcam_poses();
    // Camera 1 relative to camera 0 (the world frame): x_1 = R1 R0^T x_0 + R1 (c0 - c1).
    let rel = r1 * r0.inverse();
    let t = r1 * (c0 - c1);
    let m = rel.matrix();
    let right = Extrinsics {
        rotation: [
            [m[(0, 0)], m[(0, 1)], m[(0, 2)]],
            [m[(1, 0)], m[(1, 1)], m[(1, 2)]],
            [m[(2, 0)], m[(2, 1)], m[(2, 2)]],
        ],
        translation_m: [t.x, t.y, t.z],
    };
    (0..2)
        .map(|i| CameraConfig {
            cal: webcam_camera(if i == 0 { Extrinsics::IDENTITY } else { right }, i == 1),
            rate_hz: 60.0,
            offset_s: 0.03 + phases[i],
            // A free-running crystal: exposures keep their period; the host stamps frames on USB arrival.
            jitter_s: 0.000_05,
            timestamp_noise_s: 0.001,
            // Rows read out in 15 ms; 4 ms exposure.
            timing: SensorTiming {
                exposure_s: 0.004,
                readout_s: 0.015,
                rate_error: rates[i],
            },
            output: CameraOutput::Images(image),
            min_brightness: 0.02,
            reflection_rate: 0.02,
            sunlight_rate: 0.01,
        })
        .collect()
}

fn imu_config(rng: &mut SimRng) -> ImuConfig {
    let heading = rng.range(0.0, 2.0 * std::f64::consts::PI);
    let down = V3::new(0.0, RIG_PITCH.cos(), RIG_PITCH.sin());
    let forward = V3::new(0.0, -RIG_PITCH.sin(), RIG_PITCH.cos());
    let right = V3::x();
    let north = forward * heading.cos() + right * heading.sin();
    let (b, incl) = (47e-6, 60f64.to_radians());
    let sym = |rng: &mut SimRng| rng.range(-0.04, 0.04);
    let (a, bb, c) = (sym(rng), sym(rng), sym(rng));
    let soft = Matrix3::new(
        1.0 + sym(rng),
        a,
        bb,
        a,
        1.0 + sym(rng),
        c,
        bb,
        c,
        1.0 + sym(rng),
    );
    let v =
        |rng: &mut SimRng, s: f64| V3::new(rng.range(-s, s), rng.range(-s, s), rng.range(-s, s));
    ImuConfig {
        lever_arm_m: V3::new(-0.10, 0.0, 0.0),
        gravity_world: down * fires_protocol::scale::STANDARD_GRAVITY,
        earth_field_world: north * (b * incl.cos()) + down * (b * incl.sin()),
        accel_bias: v(rng, 0.05),
        accel_noise: 0.02,
        gyro_bias: v(rng, 0.01),
        gyro_bias_walk: 2e-4,
        gyro_noise: 0.003,
        hard_iron: v(rng, 10e-6),
        soft_iron: soft,
        mag_noise: 0.25e-6,
        scale: ScaleFactors::FIRES_PEN,
    }
}

fn mild_link() -> LinkConfig {
    LinkConfig {
        pen_drop_prob: 0.001,
        packet_loss_prob: 0.001,
        byte_drop_prob: 1e-4,
        byte_corrupt_prob: 1e-4,
        ..LinkConfig::clean()
    }
}

fn default_hand() -> HandModel {
    HandModel {
        centre_pen: V3::new(-0.06, 0.035, 0.0),
        radius: 0.028,
    }
}

fn drawing_style() -> DrawStyle {
    DrawStyle {
        mean_speed: (0.05, 0.15),
        max_speed: 0.28,
        tilt: (20f64.to_radians(), 60f64.to_radians()),
        pen_up_speed: (0.15, 0.3),
        away_lean_prob: 0.0,
        extent: 0.55,
        view_yaw: 0.0,
    }
}

/// Builds scenario `name` for `seed` and `duration_s` (fault times scale with the duration); `object` overrides
/// the object of drawing scenarios.
pub fn scenario(
    name: &str,
    seed: u64,
    duration_s: f64,
    object: Option<ObjectKind>,
) -> Result<Scenario, SimError> {
    if !SCENARIOS.iter().any(|(n, _)| *n == name) {
        return Err(SimError::UnknownScenario(name.to_string()));
    }
    let mut rng = SimRng::stream(seed, 0);
    let imu = imu_config(&mut rng);
    let pen_clock_drift_ppm = rng.range(-50.0, 50.0);
    let pen_boot_s = rng.range(2.0, 30.0);
    // Drawn after every earlier value, so those stay what they were for a seed.
    let rates = free_running_rates(&mut rng);
    let phases = [rng.range(0.0, 1.0 / 60.0), rng.range(0.0, 1.0 / 60.0)];
    let base = |cameras, pen, hand, motion, link| Scenario {
        name: name.to_string(),
        cameras,
        pen,
        hand,
        motion,
        imu: imu.clone(),
        link,
        pen_clock_drift_ppm,
        pen_boot_s,
        stream_start_s: 0.01,
    };
    let free = FreeMotion {
        depth: (0.35, 1.5),
        mean_speed: (0.1, 0.4),
        max_off_axis: 60f64.to_radians(),
    };
    let sc = match name {
        "fires-v1" => base(
            wii_rig(0.0001),
            Pen::fires_default(),
            Some(default_hand()),
            MotionSpec::Drawing {
                object: object.unwrap_or(ObjectKind::Sphere),
                centre: V3::new(0.125, 0.03, 0.85),
                size: 0.10,
                style: drawing_style(),
            },
            mild_link(),
        ),
        "webcam" => base(
            webcam_rig(rates, phases),
            Pen::fires_default(),
            Some(default_hand()),
            MotionSpec::Drawing {
                object: object.unwrap_or(ObjectKind::Blob),
                centre: webcam_rig_to_world(V3::new(0.0, 0.04, WEBCAM_CONVERGENCE_M)),
                size: 0.08,
                style: drawing_style(),
            },
            mild_link(),
        ),
        "fires-v2" => base(
            minoru_rig(rates),
            Pen::fires_default(),
            Some(default_hand()),
            MotionSpec::Drawing {
                object: object.unwrap_or(ObjectKind::Blob),
                centre: V3::new(0.03, 0.04, 0.55),
                size: 0.08,
                style: drawing_style(),
            },
            mild_link(),
        ),
        "bar" => base(
            wii_rig(0.0001),
            Pen::new(PenGeometry {
                led_positions_m: vec![0.0, 0.081],
                tip_offset_m: 0.0,
                imu_position_m: None,
            }),
            None,
            MotionSpec::Free(free),
            LinkConfig::clean(),
        ),
        "tip" => {
            let mut pen = Pen::new(PenGeometry {
                led_positions_m: vec![0.0, 0.070, 0.110, 0.160],
                tip_offset_m: 0.0,
                imu_position_m: None,
            });
            pen.disabled[0] = true;
            base(
                wii_rig(0.0001),
                pen,
                None,
                MotionSpec::Free(free),
                LinkConfig::clean(),
            )
        }
        "stress" => {
            let mut cams = minoru_rig(rates);
            for c in &mut cams {
                c.reflection_rate = 0.25;
                c.sunlight_rate = 0.3;
                c.jitter_s = 0.004;
            }
            let link = LinkConfig {
                pen_drop_prob: 0.01,
                packet_loss_prob: 0.01,
                byte_drop_prob: 0.001,
                byte_corrupt_prob: 0.001,
                latency_jitter_s: 0.01,
                disconnects: vec![(0.4 * duration_s, (0.1 * duration_s).min(1.5))],
                ..LinkConfig::clean()
            };
            base(
                cams,
                Pen::fires_default(),
                Some(HandModel {
                    centre_pen: V3::new(-0.065, 0.035, 0.0),
                    radius: 0.036,
                }),
                MotionSpec::Drawing {
                    object: object.unwrap_or(ObjectKind::Box),
                    centre: V3::new(0.03, 0.04, 0.55),
                    size: 0.08,
                    style: DrawStyle {
                        mean_speed: (0.15, 0.5),
                        max_speed: 0.8,
                        tilt: (20f64.to_radians(), 60f64.to_radians()),
                        pen_up_speed: (0.5, 1.2),
                        away_lean_prob: 0.3,
                        extent: 0.65,
                        view_yaw: 75f64.to_radians(),
                    },
                },
                link,
            )
        }
        "pivot" => base(
            wii_rig(0.0001),
            Pen::fires_default(),
            None,
            MotionSpec::Pivot {
                tip: V3::new(0.10, 0.05, 0.70),
                cone: 35f64.to_radians(),
            },
            LinkConfig::clean(),
        ),
        // Listed in SCENARIOS but not built here: a bug, caught by the api test that builds every listed name.
        other => return Err(SimError::UnknownScenario(other.to_string())),
    };
    Ok(sc)
}
