//! End-to-end identification stress and accuracy tests on the reference rig (1024x768, 45 deg
//! HFOV, 0.25 m baseline, 0.5 px centroid noise): image blobs with independent per-camera LED
//! occlusions and spurious blobs go through undistortion, correspondence, triangulation and
//! identification; no accepted frame may carry a wrong label. Also the `bar` and `tip` figures.

use crate::stereo::{
    CameraId, CorrespondenceConfig, Correspondences, StereoRig, TriangulationMethod, Triangulator,
};
use crate::track::identify::{Identifier, IdentifyConfig, IdentifyPrior, RangeNoise};
use crate::track::pen::{PenGeometry, LED_COUNT};
use crate::track::synth::{project_leds, PenPose, SplitMix64};
use crate::track::tip::TipEstimator;
use nalgebra::{UnitQuaternion, Vector3};

fn rig() -> StereoRig {
    StereoRig::parallel(1024, 768, 45f64.to_radians(), 0.25)
}

/// A pose whose LED 1 is between the cameras' view at depth `z`.
fn pose(rng: &mut SplitMix64, z_min: f64, z_max: f64) -> PenPose {
    let mut p = PenPose::random(rng, z_min, z_max, 1.0);
    p.led1.x += 0.125;
    p
}

fn normalise(rig: &StereoRig, cam: CameraId, px: &[[f64; 2]]) -> Vec<[f64; 2]> {
    px.iter()
        .map(|p| rig.camera(cam).undistort(*p).unwrap())
        .collect()
}

#[test]
fn stress_no_wrong_label_is_ever_accepted() {
    let rig = rig();
    let pen = PenGeometry::thesis();
    let tr = Triangulator::new(&rig, TriangulationMethod::Midpoint);
    let mut id = Identifier::new(pen, IdentifyConfig::default())
        .unwrap()
        .with_rig(&rig, 0.5);
    let mut corr = Correspondences::default();
    // FIRES_STRESS_SEED / FIRES_STRESS_FRAMES run longer campaigns (e.g. in release mode).
    let env = |k: &str, d: u64| {
        std::env::var(k)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(d)
    };
    let mut rng = SplitMix64::new(env("FIRES_STRESS_SEED", 2024));
    let (mut frames, mut accepted, mut wrong) = (0usize, 0usize, 0usize);
    for _ in 0..env("FIRES_STRESS_FRAMES", 20_000) {
        let pose = pose(&mut rng, 0.3, 1.5);
        let proj = project_leds(&rig, &pen, &pose, 0.5, &mut rng);
        let leds = pen.led_positions(&pose.led1, &pose.rotation);
        let mut blobs: [Vec<[f64; 2]>; 2] = [Vec::new(), Vec::new()];
        let mut truth: [Vec<Option<usize>>; 2] = [Vec::new(), Vec::new()];
        for c in 0..2 {
            for (i, p) in proj[c].iter().enumerate() {
                // Each camera independently loses each LED with probability 0.2.
                if let (Some(p), true) = (p, rng.unit() > 0.2) {
                    blobs[c].push(*p);
                    truth[c].push(Some(i));
                }
            }
            // 0-3 spurious blobs (reflections, sunlight) anywhere in the image.
            for _ in 0..(rng.next_u64() % 4) {
                blobs[c].push([rng.uniform(0.0, 1024.0), rng.uniform(0.0, 768.0)]);
                truth[c].push(None);
            }
        }
        let l = normalise(&rig, CameraId::Left, &blobs[0]);
        let r = normalise(&rig, CameraId::Right, &blobs[1]);
        let cands = corr.compute(&rig, &tr, &CorrespondenceConfig::default(), &l, &r);
        // The fused direction prior, 3 degrees off.
        let noisy_dir = UnitQuaternion::from_scaled_axis(rng.unit_vector() * 3f64.to_radians())
            * pose.direction();
        let prior = IdentifyPrior {
            direction: Some(noisy_dir),
            previous: [None; LED_COUNT],
            ..Default::default()
        };
        frames += 1;
        let Ok(res) = id.identify_with_images(cands, &prior, &l, &r) else {
            continue;
        };
        accepted += 1;
        for (led, a) in res.assignment.iter().enumerate() {
            let Some(k) = a else { continue };
            let c = &cands[*k];
            // A blob is right if it is that LED's, or a spurious blob within 3 px of where the LED
            // projects; a pair is also right if it triangulates within 5 mm of the LED (either way
            // the spurious blob is indistinguishable from the occluded LED's own).
            let right_blob = |cam: usize, idx: usize, id: CameraId| {
                truth[cam][idx] == Some(led)
                    || rig.project(id, &leds[led]).is_ok_and(|p| {
                        (p[0] - blobs[cam][idx][0]).hypot(p[1] - blobs[cam][idx][1]) < 3.0
                    })
            };
            let on_led = (c.point - leds[led]).norm() < 0.005;
            let blobs_right =
                right_blob(0, c.left, CameraId::Left) && right_blob(1, c.right, CameraId::Right);
            if !(on_led || blobs_right) {
                wrong += 1;
                if wrong < 6 {
                    let tl: Vec<_> = truth[0].clone();
                    let trr: Vec<_> = truth[1].clone();
                    eprintln!(
                        "WRONG led {led} truthL {tl:?} truthR {trr:?} res {:?} {:?} count {}",
                        res.assignment,
                        res.resolution,
                        res.count()
                    );
                    for (k, c) in cands.iter().enumerate() {
                        let near: Vec<String> = leds
                            .iter()
                            .map(|l| format!("{:.1}", (c.point - l).norm() * 1e3))
                            .collect();
                        let rn = RangeNoise::from_rig(&rig, 0.5);
                        let sd: Vec<String> = cands
                            .iter()
                            .map(|o| {
                                format!(
                                    "{:.1}/{:.1}",
                                    rn.distance_sigma(&c.point, &o.point) * 1e3,
                                    (c.point - o.point).norm() * 1e3
                                )
                            })
                            .collect();
                        eprintln!("  cand {k}: z {:.2} L{} R{} gap {:.2}mm epi {:.2} dist-to-leds {near:?} sigma/dist {sd:?}", c.point.z, c.left, c.right, c.ray_gap * 1e3, c.epipolar_px);
                    }
                }
            }
        }
    }
    eprintln!("stress: {accepted}/{frames} frames labelled, {wrong} wrong labels");
    assert_eq!(wrong, 0);
    // Frames are independent here (no continuity prior), so three-LED frames whose twin triple
    // fits up to scale are refused: about 42% of the frames are labelled.
    assert!(accepted * 5 > frames * 2, "{accepted}/{frames}");
}

fn percentile_within(errors: &[f64], limit: f64) -> f64 {
    errors.iter().filter(|e| **e <= limit).count() as f64 / errors.len() as f64
}

#[test]
fn bar_lengths_within_2mm_at_up_to_1m() {
    let rig = rig();
    let mut rng = SplitMix64::new(81);
    let methods = [
        TriangulationMethod::NormalEquations,
        TriangulationMethod::Linear,
        TriangulationMethod::Midpoint,
    ];
    let mut errors: [Vec<f64>; 3] = Default::default();
    let bar = PenGeometry {
        led_offsets: [0.0, 0.081, 0.2, 0.3],
        tip_offset: 0.0,
    };
    for _ in 0..10_000 {
        let pose = pose(&mut rng, 0.3, 1.0);
        let proj = project_leds(&rig, &bar, &pose, 0.5, &mut rng);
        let (Some(a_l), Some(b_l), Some(a_r), Some(b_r)) =
            (proj[0][0], proj[0][1], proj[1][0], proj[1][1])
        else {
            continue;
        };
        let l = normalise(&rig, CameraId::Left, &[a_l, b_l]);
        let r = normalise(&rig, CameraId::Right, &[a_r, b_r]);
        for (m, errs) in methods.iter().zip(errors.iter_mut()) {
            let tr = Triangulator::new(&rig, *m);
            if let (Ok(a), Ok(b)) = (tr.triangulate(l[0], r[0]), tr.triangulate(l[1], r[1])) {
                errs.push(((a.point - b.point).norm() - 0.081).abs());
            }
        }
    }
    let rms: Vec<f64> = errors
        .iter()
        .map(|e| (e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64).sqrt())
        .collect();
    for (m, e) in methods.iter().zip(&errors) {
        let p = percentile_within(e, 0.002);
        eprintln!(
            "bar {m:?}: {:.1}% within 2 mm over {} frames",
            p * 100.0,
            e.len()
        );
        assert!(e.len() > 5000 && p >= 0.9);
    }
    // The three triangulation methods (FIRES thesis, §4.1.1) agree within 10% in RMS error.
    assert!(
        rms.iter().fold(0.0f64, |a, b| a.max(*b))
            <= 1.1 * rms.iter().fold(f64::INFINITY, |a, b| a.min(*b))
    );
}

/// Tip from LEDs 2-4 (tip at LED 1), single frames, vision axis only vs. an axis 0.3 degrees off
/// the truth (the accuracy the fused filter reaches on the synthetic runs).
#[test]
fn tip_from_leds_2_to_4() {
    let rig = rig();
    let pen = PenGeometry::thesis();
    let est = TipEstimator::new(&pen);
    let tr = Triangulator::new(&rig, TriangulationMethod::Midpoint);
    let mut rng = SplitMix64::new(7);
    let (mut vision, mut fused) = (Vec::new(), Vec::new());
    for _ in 0..10_000 {
        let pose = pose(&mut rng, 0.3, 1.0);
        let proj = project_leds(&rig, &pen, &pose, 0.5, &mut rng);
        let mut pts = [None; LED_COUNT];
        for (i, pt) in pts.iter_mut().enumerate().skip(1) {
            if let (Some(l), Some(r)) = (proj[0][i], proj[1][i]) {
                let l = rig.left.undistort(l).unwrap();
                let r = rig.right.undistort(r).unwrap();
                *pt = tr.triangulate(l, r).ok().map(|t| t.point);
            }
        }
        if pts.iter().flatten().count() < 3 {
            continue;
        }
        let truth = pen.tip_position(&pose.led1, &pose.rotation);
        vision.push((est.estimate(&pts).unwrap().tip - truth).norm());
        let axis = UnitQuaternion::from_scaled_axis(rng.unit_vector() * 0.3f64.to_radians())
            * pose.direction();
        fused.push((est.estimate_with_direction(&pts, &axis).unwrap().tip - truth).norm());
    }
    let (pv, pf) = (
        percentile_within(&vision, 0.002),
        percentile_within(&fused, 0.002),
    );
    eprintln!(
        "tip LEDs 2-4 <= 1 m: vision axis {:.1}% < 2 mm, fused-quality axis {:.1}%",
        pv * 100.0,
        pf * 100.0
    );
    assert!(pf >= 0.9);
    assert!(pv >= 0.6);
}

#[test]
fn spurious_points_near_the_pen_do_not_flip_three_led_frames() {
    // Mirror reflections: a copy of the pen 2-10 cm away adds ghost candidates.
    let pen = PenGeometry::thesis();
    let mut id = Identifier::new(pen, IdentifyConfig::default()).unwrap();
    let mut rng = SplitMix64::new(5);
    for _ in 0..2000 {
        let pose = pose(&mut rng, 0.4, 1.0);
        let leds = pen.led_positions(&pose.led1, &pose.rotation);
        let shift = rng.unit_vector() * rng.uniform(0.02, 0.1);
        let mut cands = Vec::new();
        for (k, p) in leds.iter().enumerate().skip(1) {
            cands.push(crate::stereo::Candidate::at(k, k, *p));
        }
        // The reflection shows LEDs 1-2 only; a reflected point landing on the hidden LED 1
        // (within 2 cm) is indistinguishable from it and is not tested.
        if (0..2).any(|k| leds.iter().any(|l| (leds[k] + shift - l).norm() < 0.02)) {
            continue;
        }
        for (k, p) in leds.iter().enumerate().take(2) {
            cands.push(crate::stereo::Candidate::at(10 + k, 10 + k, p + shift));
        }
        if let Ok(r) = id.identify(
            &cands,
            &IdentifyPrior {
                direction: Some(pose.direction()),
                ..Default::default()
            },
        ) {
            for (led, a) in r.assignment.iter().enumerate() {
                if let Some(k) = a {
                    let ok = (cands[*k].point - leds[led]).norm() < 1e-9
                        || (cands[*k].point - leds[led] - shift).norm() < 1e-9;
                    assert!(
                        ok,
                        "led {led} cand {k} {:?} shift {:.1} mm res {r:?}",
                        r.assignment,
                        shift.norm() * 1e3
                    );
                    assert!(
                        cands[*k].left < 10 || r.count() == 2,
                        "reflection labelled in a 3-LED frame"
                    );
                }
            }
        }
        let _ = Vector3::<f64>::zeros();
    }
}

#[test]
#[ignore]
fn calibrate_noise_model() {
    let rig = rig();
    let pen = PenGeometry::thesis();
    let tr = Triangulator::new(&rig, TriangulationMethod::Midpoint);
    let rn = RangeNoise::from_rig(&rig, 0.5);
    let mut rng = SplitMix64::new(3);
    let mut z = Vec::new();
    for _ in 0..20000 {
        let pose = pose(&mut rng, 0.3, 1.5);
        let proj = project_leds(&rig, &pen, &pose, 0.5, &mut rng);
        let (Some(a), Some(b), Some(c), Some(d)) = (proj[0][2], proj[0][3], proj[1][2], proj[1][3])
        else {
            continue;
        };
        let p = tr
            .triangulate(
                rig.left.undistort(a).unwrap(),
                rig.right.undistort(c).unwrap(),
            )
            .unwrap()
            .point;
        let q = tr
            .triangulate(
                rig.left.undistort(b).unwrap(),
                rig.right.undistort(d).unwrap(),
            )
            .unwrap()
            .point;
        z.push((((p - q).norm() - 0.05) / rn.distance_sigma(&p, &q)).abs());
    }
    let f = |t: f64| z.iter().filter(|v| **v > t).count() as f64 / z.len() as f64;
    eprintln!(
        "n {} >1: {:.3} >2: {:.3} >3: {:.4} >4: {:.5} >6: {:.5}",
        z.len(),
        f(1.0),
        f(2.0),
        f(3.0),
        f(4.0),
        f(6.0)
    );
}
