//! Runs a scenario and writes the recording (through `fires-record`).
//!
//! Time: the simulator's session time `t` (seconds) maps to the host monotonic clock as
//! `host_ns = HOST_ORIGIN_NS + round(t * 1e9)`. The pen's clock runs at `1 + drift` device seconds per host second
//! and samples every 10 ms of device time. Every random model draws from its own ChaCha8 stream of the seed, and
//! nothing depends on wall-clock time, thread scheduling or hash order, so a seed gives byte-identical files.

use crate::camera::{CameraOutput, NoiseTable};
use crate::imu::{kinematics, Imu};
use crate::link::{host_ns, transmit, PenFirmware, Produced};
use crate::motion::trajectory::{orientation_from_axis, random_direction_near};
use crate::motion::{Pose, Scene, Trajectory, MAX_PLANNED_STROKES};
use crate::objects::{ObjectKind, V3};
use crate::rng::SimRng;
use crate::scenario::{scenario, world_up, MotionSpec, Scenario};
use crate::SimError;
use fires_record::{
    CameraFrame, CameraStream, EncodedImage, ExposureTruth, FrameContent, ImageEncoder, ImuTruth,
    Meta, PacketFate, PenGeometry, PoseTruth, RecordingWriter, RigCalibration, Source, StrokeTruth,
    WorldTruth, WriterOptions,
};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Host-clock time of session time 0, nanoseconds (100 s, so the pen's boot lies after host time 0).
pub const HOST_ORIGIN_NS: u64 = 100_000_000_000;

/// Options of a run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimOptions {
    /// Write 8-bit images for cameras that deliver images (otherwise they deliver ideal blob lists).
    pub images: bool,
    /// Override the object of drawing scenarios.
    pub object: Option<ObjectKind>,
    /// Write ground truth (`truth/`).
    pub truth: bool,
    /// Pen mode held while drawing each planned stroke, by stroke id (0: curve insertion; the curve
    /// network maps modes to tools, docs/network.md). All 0 by default: only the draw button.
    pub stroke_modes: [u8; MAX_PLANNED_STROKES],
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions {
            images: true,
            object: None,
            truth: true,
            stroke_modes: [0; MAX_PLANNED_STROKES],
        }
    }
}

/// What a run produced (`fires sim` prints it as one JSON line).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SimSummary {
    /// Output directory.
    #[serde(rename = "out")]
    pub out_dir: PathBuf,
    /// Scenario name.
    pub scenario: String,
    /// Seed.
    pub seed: u64,
    /// Simulated duration, seconds.
    pub duration_s: f64,
    /// IMU samples taken (sensor packets produced).
    pub imu_samples: u64,
    /// Status packets produced.
    pub status_packets: u64,
    /// Packets that arrived intact.
    pub delivered: u64,
    /// Sensor packets the pen dropped itself.
    pub pen_dropped: u64,
    /// Packets lost whole in the radio.
    pub lost: u64,
    /// Packets sent while disconnected.
    pub disconnected: u64,
    /// Packets with dropped or corrupted bytes.
    pub damaged: u64,
    /// Bytes received by the host.
    pub link_bytes: u64,
    /// Frames per camera.
    pub frames: Vec<u64>,
    /// Images written.
    pub images: u64,
    /// Strokes drawn (started within the duration).
    pub strokes: usize,
}

/// Runs the named scenario: see [`crate::scenario::SCENARIOS`].
pub fn run_scenario(
    name: &str,
    seed: u64,
    duration_s: f64,
    out_dir: &Path,
    opts: SimOptions,
) -> Result<SimSummary, SimError> {
    check_duration(duration_s)?;
    let sc = scenario(name, seed, duration_s, opts.object)?;
    run(&sc, seed, duration_s, out_dir, opts)
}

fn check_duration(duration_s: f64) -> Result<(), SimError> {
    if duration_s.is_finite() && duration_s > 0.0 && duration_s <= 24.0 * 3600.0 {
        Ok(())
    } else {
        Err(SimError::BadDuration(duration_s))
    }
}

fn pose_truth(sc: &Scenario, p: &Pose) -> PoseTruth {
    let q = p.q.quaternion();
    PoseTruth {
        tip_m: [p.tip.x, p.tip.y, p.tip.z],
        orientation_xyzw: [q.i, q.j, q.k, q.w],
        leds_m: sc
            .pen
            .leds_world(&p.tip, &p.q)
            .iter()
            .map(|l| [l.x, l.y, l.z])
            .collect(),
    }
}

/// Builds the trajectory of a scenario.
pub fn build_trajectory(sc: &Scenario, seed: u64, duration_s: f64) -> Trajectory {
    let mut rng = SimRng::stream(seed, 1);
    let cams: Vec<V3> = sc
        .cameras
        .iter()
        .map(|c| V3::from(c.cal.extrinsics.centre_world()))
        .collect();
    let eye = cams.iter().fold(V3::zeros(), |a, c| a + c) / cams.len().max(1) as f64;
    match &sc.motion {
        MotionSpec::Drawing {
            object,
            centre,
            size,
            style,
        } => {
            let up = world_up();
            let shape = object.build(*centre, *size, up);
            let yaw = nalgebra::Rotation3::from_axis_angle(
                &nalgebra::Unit::new_normalize(up),
                style.view_yaw,
            );
            let view = yaw * (centre - eye).normalize();
            let scene = Arc::new(Scene::new(shape, view, up, eye, style.extent * size));
            Trajectory::drawing(scene, duration_s, *style, &mut rng)
        }
        MotionSpec::Pivot { tip, cone } => {
            // Rest-to-rest turns about the tip to random directions in the cone, each with a roll.
            let back0 = (eye - tip).normalize();
            let start = Pose {
                tip: *tip,
                q: orientation_from_axis(&(-back0), 0.0),
            };
            let mut legs = Vec::new();
            let mut t = 0.5;
            while t < duration_s {
                let back = random_direction_near(&back0, *cone, &mut rng);
                let q = orientation_from_axis(&(-back), rng.range(-3.2, 3.2));
                let dt = rng.range(0.6, 1.2);
                legs.push((dt, Pose { tip: *tip, q }));
                t += dt;
            }
            Trajectory::waypoints(start, 0.5, &legs)
        }
        MotionSpec::Free(free) => {
            let free = *free;
            Trajectory::free(duration_s, free, &mut rng, |rng, depth| {
                let mut best = None;
                for _ in 0..200 {
                    let z = depth + rng.range(-0.03, 0.03);
                    let tip = V3::new(
                        rng.range(-0.45 * z, 0.45 * z + 0.25),
                        rng.range(-0.3 * z, 0.3 * z),
                        z,
                    );
                    let back = random_direction_near(&(eye - tip), free.max_off_axis, rng);
                    let pose = Pose {
                        tip,
                        q: orientation_from_axis(&(-back), rng.range(-3.2, 3.2)),
                    };
                    let ok = sc.pen.leds_world(&pose.tip, &pose.q).iter().all(|l| {
                        sc.cameras.iter().all(|c| {
                            c.cal.project_world([l.x, l.y, l.z]).is_some_and(|px| {
                                let m = &c.cal.intrinsics;
                                let (w, h) = (f64::from(m.width), f64::from(m.height));
                                px[0] > 0.03 * w
                                    && px[0] < 0.97 * w
                                    && px[1] > 0.03 * h
                                    && px[1] < 0.97 * h
                            })
                        })
                    });
                    best = Some(pose);
                    if ok {
                        break;
                    }
                }
                best.unwrap_or(Pose {
                    tip: V3::new(0.1, 0.0, depth),
                    q: orientation_from_axis(&V3::z(), 0.0),
                })
            })
        }
    }
}

/// Runs a fully specified scenario.
pub fn run(
    sc: &Scenario,
    seed: u64,
    duration_s: f64,
    out_dir: &Path,
    opts: SimOptions,
) -> Result<SimSummary, SimError> {
    check_duration(duration_s)?;
    let mut traj = build_trajectory(sc, seed, duration_s);
    traj.set_stroke_modes(&opts.stroke_modes);
    let meta = Meta::new(
        Source {
            kind: "simulator".to_string(),
            scenario: Some(sc.name.clone()),
            seed: Some(seed),
            generator: Some(format!("fires-sim {}", env!("CARGO_PKG_VERSION"))),
        },
        RigCalibration {
            cameras: sc.cameras.iter().map(|c| c.cal).collect(),
        },
        // The board's accelerometer position is part of the pen's description, as its LEDs are.
        PenGeometry {
            imu_position_m: Some(sc.imu.lever_arm_m.into()),
            ..sc.pen.geometry.clone()
        },
        sc.cameras
            .iter()
            .enumerate()
            .map(|(i, c)| CameraStream {
                id: i as u8,
                provides: match c.output {
                    CameraOutput::Images(_) if opts.images => FrameContent::Images,
                    _ => FrameContent::Blobs,
                },
                nominal_rate_hz: c.rate_hz,
                exposure_s: c.timing.exposure_s,
                readout_s: c.timing.readout_s,
                exposure_jitter_s: c.jitter_s,
                timestamp_noise_s: c.timestamp_noise_s,
            })
            .collect(),
        opts.truth,
    );
    // Images are stored compressed (a 60 s session of a 60 Hz stereo webcam is 2.2 GB as plain PGM: see
    // `render_camera`), and buffered: a simulated recording can be made again, so it needs no per-record
    // durability.
    let mut w = RecordingWriter::create_with(out_dir, &meta, WriterOptions::buffered())?;
    let mut summary = SimSummary {
        out_dir: out_dir.to_path_buf(),
        scenario: sc.name.clone(),
        seed,
        duration_s,
        imu_samples: 0,
        status_packets: 0,
        delivered: 0,
        pen_dropped: 0,
        lost: 0,
        disconnected: 0,
        damaged: 0,
        link_bytes: 0,
        frames: Vec::new(),
        images: 0,
        strokes: 0,
    };

    // IMU and pen firmware.
    let drift = sc.pen_clock_drift_ppm * 1e-6;
    let mut imu = Imu::new(sc.imu.clone(), SimRng::stream(seed, 2));
    let mut fw_rng = SimRng::stream(seed, 3);
    let mut fw = PenFirmware::new(sc.link.status_period_s);
    let mut produced: Vec<Produced> = Vec::new();
    let period_us = 1_000_000 / u64::from(fires_protocol::SAMPLE_RATE_HZ);
    let first_dev_us = ((sc.pen_boot_s + sc.stream_start_s * (1.0 + drift)) * 1e6).ceil() as u64;
    let first_dev_us = first_dev_us.div_ceil(period_us) * period_us;
    let dt = period_us as f64 * 1e-6 / (1.0 + drift);
    for k in 0u64.. {
        let dev_us = first_dev_us + k * period_us;
        let t = (dev_us as f64 * 1e-6 - sc.pen_boot_s) / (1.0 + drift);
        if t > duration_s {
            break;
        }
        let kin = kinematics(&traj, &sc.imu, t);
        let bias = imu.gyro_bias();
        let packet = imu.measure(&kin, k as u8, dt);
        let buttons = traj.buttons(t);
        fw.on_sample(
            t,
            dev_us,
            packet,
            buttons,
            &sc.link,
            &mut fw_rng,
            &mut produced,
        );
        if opts.truth {
            let pose = traj.pose(t);
            let v = |x: V3| [x.x, x.y, x.z];
            w.write_imu_truth(&ImuTruth {
                sample_index: k,
                counter: k as u8,
                device_time_us: dev_us,
                time_ns: host_ns(HOST_ORIGIN_NS, t),
                pose: pose_truth(sc, &pose),
                specific_force_mps2: v(kin.specific_force),
                angular_velocity_radps: v(kin.angular_velocity),
                earth_field_t: v(kin.earth_field),
                gyro_bias_radps: v(bias),
                buttons,
            })?;
        }
        summary.imu_samples += 1;
    }

    // Link.
    let link = transmit(
        &produced,
        &sc.link,
        HOST_ORIGIN_NS,
        &mut SimRng::stream(seed, 4),
    );
    for c in &link.chunks {
        summary.link_bytes += c.bytes.len() as u64;
        w.write_link_chunk(c)?;
    }
    for p in &link.truth {
        if matches!(p.frame, fires_protocol::Frame::Status(_)) {
            summary.status_packets += 1;
        }
        match p.fate {
            PacketFate::Delivered => summary.delivered += 1,
            PacketFate::PenDropped => summary.pen_dropped += 1,
            PacketFate::Lost => summary.lost += 1,
            PacketFate::Disconnected => summary.disconnected += 1,
            PacketFate::Damaged => summary.damaged += 1,
        }
        if opts.truth {
            w.write_packet_truth(p)?;
        }
    }

    // Cameras: each renders (and compresses) on its own thread from its own random streams, so the files do
    // not depend on scheduling; the frames are then written in order.
    let scene = traj.scene().map(|s| s.as_ref());
    let traj_ref = &traj;
    let rendered: Vec<RenderedCamera> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..sc.cameras.len())
            .map(|ci| scope.spawn(move || render_camera(sc, ci, traj_ref, seed, duration_s, opts)))
            .collect();
        workers
            .into_iter()
            .map(|w| w.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .collect::<Result<_, _>>()
    })?;
    let mut exposures: Vec<ExposureTruth> = Vec::new();
    for cam in rendered {
        for (frame, image) in &cam.frames {
            w.write_frame_encoded(frame, image.as_ref())?;
        }
        summary.images += cam.frames.iter().filter(|f| f.1.is_some()).count() as u64;
        summary.frames.push(cam.frames.len() as u64);
        exposures.extend(cam.exposures);
    }
    exposures.sort_by_key(|e| (e.exposure_time_ns, e.camera, e.index));
    for e in &exposures {
        w.write_exposure_truth(e)?;
    }

    // Strokes.
    let strokes = true_strokes(&traj, duration_s);
    summary.strokes = strokes.len();
    if opts.truth {
        w.write_strokes(&strokes)?;
        let v = |x: V3| [x.x, x.y, x.z];
        let s = &sc.imu.soft_iron;
        w.write_world_truth(&WorldTruth {
            gravity_world_mps2: v(sc.imu.gravity_world),
            earth_field_world_t: v(sc.imu.earth_field_world),
            hard_iron_t: v(sc.imu.hard_iron),
            soft_iron: [
                [s[(0, 0)], s[(0, 1)], s[(0, 2)]],
                [s[(1, 0)], s[(1, 1)], s[(1, 2)]],
                [s[(2, 0)], s[(2, 1)], s[(2, 2)]],
            ],
            accel_bias_mps2: v(sc.imu.accel_bias),
            pen_clock_drift_ppm: sc.pen_clock_drift_ppm,
            pen_clock_origin_ns: HOST_ORIGIN_NS
                .saturating_sub(((sc.pen_boot_s / (1.0 + drift)) * 1e9).round() as u64),
            disconnects: link.disconnects.clone(),
            object: scene.map_or_else(|| "none".to_string(), |s| s.shape.describe()),
            target: scene.map(|s| s.to_truth()),
        })?;
    }
    w.finish()?;
    Ok(summary)
}

/// One camera's frames (with their encoded images) and exposure truth.
struct RenderedCamera {
    frames: Vec<(CameraFrame, Option<EncodedImage>)>,
    exposures: Vec<ExposureTruth>,
}

/// Renders every frame of camera `ci` over the session: exposure times on its free-running clock, what it sees
/// (rolling shutter and smear, [`crate::camera::CameraConfig::observe`]), and the image or blob list.
fn render_camera(
    sc: &Scenario,
    ci: usize,
    traj: &Trajectory,
    seed: u64,
    duration_s: f64,
    opts: SimOptions,
) -> Result<RenderedCamera, SimError> {
    let cam = &sc.cameras[ci];
    let scene = traj.scene().map(|s| s.as_ref());
    let mut rng = SimRng::stream(seed, 10 + ci as u64);
    let mut render_rng = SimRng::stream(seed, 30 + ci as u64);
    let m = cam.cal.intrinsics;
    let images = opts.images && matches!(cam.output, CameraOutput::Images(_));
    let table = images.then(|| {
        NoiseTable::new(
            m.width,
            m.height,
            cam.output.image_model(),
            &mut SimRng::stream(seed, 20 + ci as u64),
        )
    });
    let mut out = RenderedCamera {
        frames: Vec::new(),
        exposures: Vec::new(),
    };
    let encode_error = |index, cause| SimError::Encode {
        camera: ci,
        index,
        cause,
    };
    let mut encoder = ImageEncoder::new(true).map_err(|e| encode_error(0, e))?;
    for i in 0u64.. {
        let nominal = cam.nominal_frame_time(i);
        if nominal > duration_s {
            break;
        }
        let t = (nominal + rng.gauss(cam.jitter_s)).max(0.0);
        let reported = (t + rng.gauss(cam.timestamp_noise_s)).max(0.0);
        let pose = traj.pose(t);
        let pose_at = |s: f64| traj.pose(s);
        let obs = cam.observe(t, &pose_at, &sc.pen, scene, sc.hand.as_ref(), &mut rng);
        let mut frame = CameraFrame {
            camera: ci as u8,
            index: i,
            exposure_time_ns: host_ns(HOST_ORIGIN_NS, reported),
            blobs: None,
            image: None,
        };
        let image = match &table {
            Some(table) => {
                let spots: Vec<_> = obs.led_spots.iter().chain(&obs.spurious).copied().collect();
                let img = table.render(m.width, m.height, &spots, &mut render_rng);
                Some(encoder.encode(&img).map_err(|e| encode_error(i, e))?)
            }
            None => {
                frame.blobs = Some(cam.blobs(&obs, &mut rng));
                None
            }
        };
        out.frames.push((frame, image));
        if opts.truth {
            out.exposures.push(ExposureTruth {
                camera: ci as u8,
                index: i,
                exposure_time_ns: host_ns(HOST_ORIGIN_NS, t),
                pose: pose_truth(sc, &pose),
                leds: obs.leds,
                spurious: obs.spurious.iter().map(|s| s.px).collect(),
            });
        }
    }
    Ok(out)
}

/// The strokes drawn in the first `duration_s` seconds of a drawing trajectory, as `truth/strokes.json`
/// holds them: the true tip every 10 ms of drawing, and the topology the plan implies, restricted to the
/// strokes drawn (a stroke cut off by the end of the session is `complete: false`).
pub fn true_strokes(traj: &Trajectory, duration_s: f64) -> Vec<StrokeTruth> {
    let drawn: Vec<u32> = traj
        .stroke_times()
        .iter()
        .filter(|s| s.1 <= duration_s)
        .map(|s| traj.strokes()[s.0].id)
        .collect();
    traj.stroke_times()
        .iter()
        .filter(|s| s.1 <= duration_s)
        .map(|&(idx, t0, t1)| {
            let st = &traj.strokes()[idx];
            let complete = t1 <= duration_s;
            let t1 = t1.min(duration_s);
            let n = ((t1 - t0) / 0.01).ceil().max(1.0) as usize;
            let tip_polyline_m = (0..=n)
                .map(|j| {
                    let t = if j == n { t1 } else { t0 + j as f64 * 0.01 };
                    let p = traj.pose(t).tip;
                    [p.x, p.y, p.z]
                })
                .collect();
            StrokeTruth {
                id: st.id,
                kind: st.kind,
                start_time_ns: host_ns(HOST_ORIGIN_NS, t0),
                end_time_ns: host_ns(HOST_ORIGIN_NS, t1),
                complete,
                starts_on: st.starts_on.filter(|id| drawn.contains(id)),
                ends_on: st.ends_on.filter(|id| drawn.contains(id)),
                crosses: st
                    .crosses
                    .iter()
                    .copied()
                    .filter(|id| drawn.contains(id))
                    .collect(),
                tip_polyline_m,
                mode: st.mode,
            }
        })
        .collect()
}
