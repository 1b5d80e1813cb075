//! The thesis's bar experiment (§7.1, experiment 1): a rigid bar with one LED at each end (81.0 mm)
//! moved through the working volume; each stereo frame gives one measured length. The thesis reports 75% of
//! lengths within ±2 mm at up to 1 m.
//!
//! Per left frame with two blobs, the right camera's two blobs are interpolated to the left exposure time
//! between the right frames that bracket it (the cameras are not synchronised), both left/right pairings are
//! triangulated, and the pairing with the smaller total ray gap wins.
//!
//! A single frame's length carries the full triangulation noise of both ends (at 1 m the fires-v1 rig's
//! 0.5 px centroid noise is 2.3 mm of depth per LED). The tracker filters positions over time, so the
//! headline figure measures the length between the *filtered* LED positions ([`smooth_bar`]: a local
//! quadratic fit of each LED's track over a short window, the same frames every tracked point sees);
//! the single-frame figure is reported beside it.

pub use fires_record::report::{BarFigures, BarSmoothing};
use fires_record::{CameraFrame, ExposureTruth, RecordingReader};

use super::ReplayError;
use crate::meta::stereo_rig;
use crate::stereo::{StereoRig, TriangulationMethod, Triangulator};

/// Total ray gap under which the second pairing is also plausible, metres.
const AMBIGUOUS_GAP_M: f64 = 0.010;

/// One measured bar length.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct BarSample {
    /// Left frame index.
    pub index: u64,
    /// Left exposure time, nanoseconds.
    pub t_ns: u64,
    /// Measured LED-to-LED distance, metres.
    pub length_m: f64,
    /// Distance of the bar's midpoint from the left camera, metres (measured).
    pub range_m: f64,
    /// The two LED positions, left camera frame, metres.
    pub leds_m: [[f64; 3]; 2],
}

impl BarSample {
    /// A sample from the two measured LED positions.
    fn new(index: u64, t_ns: u64, leds: [nalgebra::Vector3<f64>; 2]) -> Self {
        BarSample {
            index,
            t_ns,
            length_m: (leds[0] - leds[1]).norm(),
            range_m: ((leds[0] + leds[1]) / 2.0).norm(),
            leds_m: leds.map(Into::into),
        }
    }
}

/// Replaces each sample's LED positions by a local quadratic least-squares fit of that LED's track
/// over the frames within `half_window_ns` (each neighbour's ends matched to this frame's by
/// proximity: the ends are 81 mm apart and move millimetres per frame), and recomputes its length.
/// Noise falls by about √(frames / 2.3) for a centred quadratic (Savitzky–Golay) fit.
pub fn smooth_bar(samples: &[BarSample], config: BarSmoothing) -> Vec<BarSample> {
    use nalgebra::{Matrix3, Vector3};
    samples
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let lo = samples[..i].partition_point(|o| o.t_ns + config.half_window_ns < s.t_ns);
            let hi = i + samples[i..].partition_point(|o| o.t_ns <= s.t_ns + config.half_window_ns);
            let window = &samples[lo..hi];
            if window.len() < config.min_frames {
                return *s;
            }
            let own = s.leds_m.map(Vector3::from);
            let mut ata = Matrix3::zeros();
            let mut atb = [nalgebra::Matrix3x2::<f64>::zeros(); 3];
            for o in window {
                let [a, b] = o.leds_m.map(Vector3::from);
                let (p, q) = if (a - own[0]).norm() + (b - own[1]).norm()
                    <= (a - own[1]).norm() + (b - own[0]).norm()
                {
                    (a, b)
                } else {
                    (b, a)
                };
                let tau = (o.t_ns as f64 - s.t_ns as f64) * 1e-9;
                let basis = Vector3::new(1.0, tau, tau * tau);
                ata += basis * basis.transpose();
                for (k, m) in atb.iter_mut().enumerate() {
                    *m += basis * nalgebra::RowVector2::new(p[k], q[k]);
                }
            }
            let Some(inv) = ata.try_inverse() else {
                return *s;
            };
            // Row 0 of the solution is the fitted value at this frame's time.
            let at = |k: usize| (inv * atb[k]).row(0).into_owned();
            let (x, y, z) = (at(0), at(1), at(2));
            let fitted = [0, 1].map(|e| Vector3::new(x[e], y[e], z[e]));
            BarSample::new(s.index, s.t_ns, fitted)
        })
        .collect()
}

fn two_blobs(f: &CameraFrame) -> Option<[[f64; 2]; 2]> {
    match f.blobs.as_deref() {
        Some([a, b]) => Some([[a.x, a.y], [b.x, b.y]]),
        _ => None,
    }
}

/// Right blobs at time `t`, linearly interpolated between two right frames (blobs matched by proximity).
fn right_at(t: u64, a: (u64, [[f64; 2]; 2]), b: (u64, [[f64; 2]; 2])) -> [[f64; 2]; 2] {
    let d = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
    let bb = if d(a.1[0], b.1[0]) + d(a.1[1], b.1[1]) <= d(a.1[0], b.1[1]) + d(a.1[1], b.1[0]) {
        b.1
    } else {
        [b.1[1], b.1[0]]
    };
    let w = if b.0 > a.0 {
        (t as f64 - a.0 as f64) / (b.0 - a.0) as f64
    } else {
        0.0
    };
    [0, 1].map(|i| [0, 1].map(|k| a.1[i][k] + w * (bb[i][k] - a.1[i][k])))
}

/// Triangulates the better of the two pairings; returns the two LED positions.
fn measure(
    rig: &StereoRig,
    tri: &Triangulator,
    l: [[f64; 2]; 2],
    r: [[f64; 2]; 2],
) -> Option<[nalgebra::Vector3<f64>; 2]> {
    let (l0, l1) = (
        rig.left.undistort(l[0]).ok()?,
        rig.left.undistort(l[1]).ok()?,
    );
    let (r0, r1) = (
        rig.right.undistort(r[0]).ok()?,
        rig.right.undistort(r[1]).ok()?,
    );
    let pairing = |a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]| {
        let p = tri.triangulate(a, b).ok()?;
        let q = tri.triangulate(c, d).ok()?;
        Some((p.ray_gap + q.ray_gap, p.point, q.point))
    };
    let mut options: Vec<_> = [pairing(l0, r0, l1, r1), pairing(l0, r1, l1, r0)]
        .into_iter()
        .flatten()
        .collect();
    options.sort_by(|a, b| a.0.total_cmp(&b.0));
    let best = options.first()?;
    // Both pairings consistent (the bar lies along an epipolar plane): refuse rather than guess.
    if options
        .get(1)
        .is_some_and(|second| second.0 < AMBIGUOUS_GAP_M)
    {
        return None;
    }
    Some([best.1, best.2])
}

/// A right frame: index, reported exposure time and its two blobs (if it shows exactly two).
type RightFrame = (u64, u64, Option<[[f64; 2]; 2]>);

/// Measures the bar in every left frame that shows exactly two blobs.
pub fn measure_bar(
    reader: &RecordingReader,
    method: TriangulationMethod,
) -> Result<Vec<BarSample>, ReplayError> {
    let rig = stereo_rig(reader.meta())?;
    let tri = Triangulator::new(&rig, method);
    // Every right frame (not only those with two blobs): the frames that bracket a left exposure
    // must be the two consecutive exposures around it, never frames seconds apart with the bar
    // out of view in between.
    let right: Vec<RightFrame> = reader
        .frames(1)?
        .iter()
        .map(|f| (f.index, f.exposure_time_ns, two_blobs(f)))
        .collect();
    let mut out = Vec::new();
    for f in reader.frames(0)? {
        let (Some(l), t) = (two_blobs(&f), f.exposure_time_ns) else {
            continue;
        };
        let i = right.partition_point(|(_, tr, _)| *tr <= t);
        let (Some(a), Some(b)) = (i.checked_sub(1).and_then(|k| right.get(k)), right.get(i)) else {
            continue;
        };
        let ((ia, ta, Some(ra)), (ib, tb, Some(rb))) = (*a, *b) else {
            continue;
        };
        if ib != ia + 1 {
            continue;
        }
        if let Some(leds) = measure(&rig, &tri, l, right_at(t, (ta, ra), (tb, rb))) {
            out.push(BarSample::new(f.index, t, leds));
        }
    }
    Ok(out)
}

/// Summarises the lengths against the nominal bar; `truth` (left-camera exposures, matched by frame index
/// since the frame stream's times are jittered) gives the true range when present, otherwise the measured
/// range is used.
pub fn bar_report(
    samples: &[BarSample],
    nominal_m: f64,
    truth: Option<&[ExposureTruth]>,
) -> BarFigures {
    let by_index: std::collections::HashMap<u64, &ExposureTruth> = truth
        .into_iter()
        .flatten()
        .filter(|e| e.camera == 0)
        .map(|e| (e.index, e))
        .collect();
    let true_range = |i: u64| -> Option<f64> {
        let e = by_index.get(&i)?;
        let [a, b] = e.pose.leds_m.get(..2)? else {
            return None;
        };
        Some(
            (0..3)
                .map(|k| ((a[k] + b[k]) / 2.0).powi(2))
                .sum::<f64>()
                .sqrt(),
        )
    };
    let within = |s: &BarSample| (s.length_m - nominal_m).abs() <= 0.002;
    let near: Vec<&BarSample> = samples
        .iter()
        .filter(|s| true_range(s.index).unwrap_or(s.range_m) <= 1.0)
        .collect();
    let frac = |v: &[&BarSample]| {
        (!v.is_empty()).then(|| v.iter().filter(|s| within(s)).count() as f64 / v.len() as f64)
    };
    let all: Vec<&BarSample> = samples.iter().collect();
    let rmse = if near.is_empty() {
        0.0
    } else {
        (near
            .iter()
            .map(|s| (s.length_m - nominal_m).powi(2))
            .sum::<f64>()
            / near.len() as f64)
            .sqrt()
    };
    BarFigures {
        bar_nominal_mm: nominal_m * 1e3,
        bar_frames: samples.len(),
        bar_frames_le_1m: near.len(),
        bar_frac_within_2mm_le_1m: frac(&near),
        bar_frac_within_2mm: frac(&all),
        bar_rmse_mm_le_1m: rmse * 1e3,
    }
}

/// The bar experiment of a two-LED recording: the report (every triangulation method, filtered and per
/// frame) and, for midpoint triangulation, the measured lengths (`bar.json`).
#[derive(Debug, Clone, PartialEq)]
pub struct BarExperiment {
    /// The report (`report.json`, `kind: "bar"`).
    pub report: fires_record::report::BarReport,
    /// Filtered midpoint samples.
    pub samples: Vec<BarSample>,
    /// Single-frame midpoint samples.
    pub single_frame_samples: Vec<BarSample>,
}

/// Measures the bar with every triangulation method (FIRES thesis §7.1).
pub fn bar_experiment(reader: &RecordingReader) -> Result<BarExperiment, ReplayError> {
    use fires_record::report::{BarMethod, BarReport, REPORT_FORMAT, REPORT_VERSION};
    let l = &reader.meta().pen.led_positions_m;
    let nominal = match l.as_slice() {
        [a, b] => (b - a).abs(),
        _ => 0.0,
    };
    let truth = reader.exposure_truth()?;
    let smoothing = BarSmoothing::default();
    let measure = |method| -> Result<(BarMethod, Vec<BarSample>, Vec<BarSample>), ReplayError> {
        let single = measure_bar(reader, method)?;
        let filtered = smooth_bar(&single, smoothing);
        let figures = BarMethod {
            filtered: bar_report(&filtered, nominal, truth.as_deref()),
            single_frame: bar_report(&single, nominal, truth.as_deref()),
        };
        Ok((figures, filtered, single))
    };
    let (midpoint, samples, single_frame_samples) = measure(TriangulationMethod::Midpoint)?;
    let (linear, ..) = measure(TriangulationMethod::Linear)?;
    let (normal_equations, ..) = measure(TriangulationMethod::NormalEquations)?;
    Ok(BarExperiment {
        report: BarReport {
            format: REPORT_FORMAT.into(),
            version: REPORT_VERSION.into(),
            recording: reader.dir().to_path_buf(),
            bar_smoothing: smoothing,
            damaged: reader.damage(),
            headline: midpoint.clone(),
            method_midpoint: midpoint,
            method_linear: linear,
            method_normal_equations: normal_equations,
        },
        samples,
        single_frame_samples,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    /// A bar whose ends follow quadratic paths in time, sampled at 100 Hz with optional noise.
    fn track(noise: f64, seed: u64) -> Vec<BarSample> {
        let mut state = seed;
        let mut gauss = || {
            // Box-Muller on a 64-bit LCG: deterministic, no dependency.
            let mut u = || {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
            };
            let (a, b) = (u(), u());
            (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
        };
        (0..200u64)
            .map(|i| {
                let t = i as f64 * 0.01;
                let p = Vector3::new(
                    0.1 + 0.2 * t - 0.05 * t * t,
                    -0.05 + 0.1 * t,
                    0.8 - 0.1 * t * t,
                );
                let dir = Vector3::new(0.6, 0.0, 0.8);
                let mut n = || Vector3::new(gauss(), gauss(), gauss()) * noise;
                let leds = [p + n(), p + dir * 0.081 + n()];
                // Every other frame lists the ends the other way round.
                let leds = if i % 2 == 0 { leds } else { [leds[1], leds[0]] };
                BarSample::new(i, i * 10_000_000, leds)
            })
            .collect()
    }

    #[test]
    fn smoothing_reproduces_noise_free_quadratic_motion_exactly() {
        let raw = track(0.0, 1);
        for (a, b) in raw.iter().zip(smooth_bar(&raw, BarSmoothing::default())) {
            assert!((a.length_m - b.length_m).abs() < 1e-9, "{a:?} {b:?}");
            for k in 0..2 {
                let d = Vector3::from(a.leds_m[k]) - Vector3::from(b.leds_m[k]);
                assert!(d.norm() < 1e-9);
            }
        }
    }

    #[test]
    fn smoothing_reduces_length_noise_by_the_window_factor() {
        let raw = track(0.002, 7);
        let smooth = smooth_bar(&raw, BarSmoothing::default());
        let rms = |v: &[BarSample]| {
            (v.iter().map(|s| (s.length_m - 0.081).powi(2)).sum::<f64>() / v.len() as f64).sqrt()
        };
        // A centred quadratic fit over 9 frames keeps 0.42 of the noise variance (Savitzky–Golay),
        // so the RMS should fall to about 0.65 of the single-frame value (window edges fit fewer frames).
        let ratio = rms(&smooth) / rms(&raw);
        assert!((0.5..0.8).contains(&ratio), "ratio {ratio}");
    }

    #[test]
    fn too_few_frames_keep_the_single_frame_length() {
        let raw: Vec<BarSample> = track(0.001, 3).into_iter().step_by(5).collect();
        assert_eq!(smooth_bar(&raw, BarSmoothing::default()), raw);
    }
}
