//! End to end without hardware: the simulator writes a recording, the replay tracks it, and the result is
//! checked against the recording's ground truth.

use std::path::PathBuf;

use fires_host::replay::bar::{bar_report, measure_bar, smooth_bar, BarSmoothing};
use fires_host::replay::report::{accuracy, world_report, Accuracy};
use fires_host::replay::run::world_reference;
use fires_host::replay::strokes_vs_truth::{
    strokes_summary, strokes_vs_truth, StrokeCompareOptions,
};
use fires_host::replay::{replay, ReplayConfig, ReplayOutput};
use fires_host::stereo::TriangulationMethod;
use fires_record::RecordingReader;
use fires_sim::{run_scenario, SimOptions};

fn simulate(name: &str, seconds: f64, seed: u64) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("fires-replay-{name}-{seed}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    run_scenario(name, seed, seconds, &dir, SimOptions::default()).expect("simulate");
    dir
}

/// Simulates `name`, replays it with the default configuration and checks that its labels were
/// checked against the truth (over a thousand) and none was wrong.
fn track(
    name: &str,
    seconds: f64,
    seed: u64,
) -> (PathBuf, RecordingReader, ReplayOutput, Accuracy) {
    let dir = simulate(name, seconds, seed);
    let reader = RecordingReader::open(&dir).expect("open");
    let out = replay(&reader, &ReplayConfig::default()).expect("replay");
    let truth = reader.exposure_truth().expect("truth").expect("simulated");
    let acc = accuracy(&out, &truth);
    assert!(acc.labels_checked > 1000, "{name} seed {seed}: {acc:?}");
    assert_eq!(acc.mislabels, 0, "{name} seed {seed}: {acc:?}");
    (dir, reader, out, acc)
}

/// The replay with its start tracked once only (no second pass once the world is accepted).
fn replay_without_retracking(reader: &RecordingReader) -> ReplayOutput {
    let config = ReplayConfig {
        retrack_startup: false,
        ..ReplayConfig::default()
    };
    replay(reader, &config).expect("replay")
}

#[test]
fn a_fires_v1_session_is_tracked_within_2mm_with_no_wrong_labels() {
    let (dir, reader, out, acc) = track("fires-v1", 6.0, 7);
    // fires-v1: 0.5 px centroid noise at 1024x768, 45 degree field of view, 0.25 m baseline.
    assert!(acc.frac_within_2mm.is_some_and(|f| f > 0.9), "{acc:?}");
    assert!(acc.tip_rmse_mm < 2.0, "{acc:?}");
    assert_eq!(out.imu.stats.sensor_frames as usize, out.imu.samples.len());

    // The world reference was estimated from the session itself, close to the simulated one.
    let world = reader.world_truth().expect("truth").expect("simulated");
    let w = world_report(&out, Some(&world_reference(&world)));
    assert_eq!(w.source, "estimated");
    assert!(w.accepted_after_s.is_some_and(|t| t < 5.0), "{w:?}");
    assert!(w.up_error_deg.is_some_and(|e| e < 1.5), "{w:?}");

    // Replaying the same recording gives the same samples.
    let again = replay(&reader, &ReplayConfig::default()).expect("replay");
    assert_eq!(out.samples, again.samples);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_fires_v2_session_with_images_yields_strokes() {
    let dir = simulate("fires-v2", 12.0, 3);
    let reader = RecordingReader::open(&dir).expect("open");
    let out = replay(&reader, &ReplayConfig::default()).expect("replay");
    let strokes = reader.strokes().expect("truth").expect("simulated");
    let complete = strokes.iter().filter(|s| s.complete).count();
    assert!(complete >= 1, "{strokes:?}");
    // Every pen-down that finished becomes a stroke (the last may still be open at the end).
    assert!(
        out.strokes.len() + 1 >= complete && out.strokes.len() <= strokes.len(),
        "{} vs {}",
        out.strokes.len(),
        strokes.len()
    );
    assert!(out.strokes.iter().all(|s| s.len() >= 2));
    let truth = reader.exposure_truth().expect("truth").expect("simulated");
    assert_eq!(accuracy(&out, &truth).mislabels, 0);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_bar_is_measured_near_its_length() {
    let dir = simulate("bar", 6.0, 2);
    let reader = RecordingReader::open(&dir).expect("open");
    let samples = measure_bar(&reader, TriangulationMethod::Midpoint).expect("measure");
    let truth = reader.exposure_truth().expect("truth");
    let report = bar_report(&samples, 0.081, truth.as_deref());
    assert!(report.bar_frames > 100, "{report:?}");
    let mut errors: Vec<f64> = samples.iter().map(|s| (s.length_m - 0.081).abs()).collect();
    errors.sort_by(f64::total_cmp);
    assert!(
        errors[errors.len() / 2] < 0.003,
        "median error {}",
        errors[errors.len() / 2]
    );
    // Seed 2 keeps the bar within 1 m: every length is a standalone measurement, with no gross
    // error (right frames that bracket the left exposure are consecutive, never seconds apart).
    assert!(report.bar_frames_le_1m > 100, "{report:?}");
    assert!(
        report.bar_frac_within_2mm_le_1m.is_some_and(|f| f > 0.8),
        "{report:?}"
    );
    assert!(report.bar_rmse_mm_le_1m < 2.5, "{report:?}");
    assert!(
        errors[errors.len() - 1] < 0.010,
        "worst error {}",
        errors[errors.len() - 1]
    );
    // Filtered positions (the headline figure): the 90% within ±2 mm, and less noise.
    let filtered = bar_report(
        &smooth_bar(&samples, BarSmoothing::default()),
        0.081,
        truth.as_deref(),
    );
    assert!(
        filtered.bar_frac_within_2mm_le_1m.is_some_and(|f| f >= 0.9),
        "{filtered:?}"
    );
    assert!(
        filtered.bar_rmse_mm_le_1m < 0.8 * report.bar_rmse_mm_le_1m,
        "{filtered:?} vs {report:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The default rig: two 60 Hz rolling-shutter IR webcams. Every drawn stroke is tracked, no label is
/// wrong, and the strokes stay on the pen's path: its LEDs image at about 0.2 px centroid noise, which at
/// 0.6 m, fx 520 px and a 0.20 m baseline is about 0.3 mm of depth per LED.
#[test]
fn a_webcam_session_tracks_every_stroke_on_the_pens_path() {
    let (dir, reader, out, _) = track("webcam", 14.0, 4);
    let true_strokes = reader.strokes().expect("truth").expect("simulated");
    let complete: Vec<_> = true_strokes.into_iter().filter(|s| s.complete).collect();
    assert!(complete.len() >= 2, "{complete:?}");
    let entries = strokes_vs_truth(&out.strokes, &complete, &StrokeCompareOptions::default());
    let summary = strokes_summary(&entries);
    assert_eq!(summary.kept, complete.len(), "{summary:?}");
    assert!(
        summary.rms_mm.median.is_some_and(|m| m < 1.0),
        "{summary:?}"
    );
    // The worst stroke is the boundary drawn with the pen pointing almost at one camera, whose LED
    // spots then merge: the median stroke is covered.
    assert!(
        summary.coverage_3mm.median.is_some_and(|c| c > 0.95),
        "{summary:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_stress_session_never_accepts_a_wrong_label() {
    // Seed 4 moves the pen about one LED spacing per frame along its axis early on: blob velocities
    // from nearest neighbours aliased there and accepted 3 wrong labels in the first 5 s.
    for (seed, seconds) in [(1, 8.0), (2, 8.0), (4, 5.0)] {
        let dir = simulate("stress", seconds, seed);
        let reader = RecordingReader::open(&dir).expect("open");
        let out = replay(&reader, &ReplayConfig::default()).expect("replay");
        let truth = reader.exposure_truth().expect("truth").expect("simulated");
        let acc = accuracy(&out, &truth);
        assert!(acc.labels_checked > 0, "{acc:?}");
        assert_eq!(acc.mislabels, 0, "seed {seed}: {acc:?}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// The speed-bounded twin test (the twin scale bound from the measured pen speed, not 1.5 m/s)
/// accepts no wrong label over many seeds of the scenarios with three-LED twins in view. Long: run
/// with `cargo test -p fires-e2e --release --test replay_sim -- --ignored`.
#[test]
#[ignore]
fn the_speed_bounded_twin_test_accepts_no_wrong_label_over_many_seeds() {
    let runs = (1..=20)
        .map(|s| ("stress", s, 10.0))
        .chain((1..=5).map(|s| ("fires-v2", s, 20.0)))
        .chain((1..=5).map(|s| ("fires-v1", s, 20.0)));
    for (name, seed, seconds) in runs {
        let dir = simulate(name, seconds, seed);
        let reader = RecordingReader::open(&dir).expect("open");
        let out = replay(&reader, &ReplayConfig::default()).expect("replay");
        let truth = reader.exposure_truth().expect("truth").expect("simulated");
        let acc = accuracy(&out, &truth);
        assert!(acc.labels_checked > 0, "{name} seed {seed}: {acc:?}");
        assert_eq!(acc.mislabels, 0, "{name} seed {seed}: {acc:?}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// Strokes begun before the world estimate was accepted are tracked once more with it: on the
/// webcam rig's seed 1 the world is accepted while the boundary stroke is drawn, and its
/// re-tracked version (same id) has more tracked points and covers more of the true path than
/// the first pass's, with no wrong label; the later strokes are the first pass's.
#[test]
fn strokes_begun_before_the_world_is_accepted_are_retracked() {
    let (dir, reader, out, _) = track("webcam", 9.0, 1);
    let first = replay_without_retracking(&reader);
    let (accepted, _) = out.world_fit.expect("world accepted");
    let true_strokes = reader.strokes().expect("truth").expect("simulated");
    let boundary = &true_strokes[0];
    assert!(
        boundary.start_time_ns < accepted,
        "boundary from {} ns, world accepted at {accepted} ns",
        boundary.start_time_ns
    );
    eprintln!(
        "boundary {}-{} ns, world accepted at {accepted} ns",
        boundary.start_time_ns, boundary.end_time_ns
    );
    let ids = |o: &ReplayOutput| o.strokes.iter().map(|s| s.id).collect::<Vec<_>>();
    assert_eq!(ids(&out), ids(&first));
    let points = |o: &ReplayOutput| {
        o.strokes
            .iter()
            .find(|s| s.id == 0)
            .map_or(0, |s| s.raw_points)
    };
    assert!(
        points(&out) > points(&first),
        "{} vs {}",
        points(&out),
        points(&first)
    );
    let coverage = |o: &ReplayOutput| {
        strokes_vs_truth(
            &o.strokes,
            &true_strokes[..1],
            &StrokeCompareOptions::default(),
        )[0]
        .coverage_3mm
        .unwrap_or(0.0)
    };
    assert!(
        coverage(&out) > coverage(&first),
        "{} vs {}",
        coverage(&out),
        coverage(&first)
    );
    for (a, b) in out.strokes.iter().zip(&first.strokes) {
        if a.t_start_ns >= accepted {
            assert_eq!(a, b);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A session without strokes before the world is accepted (the thesis's tip experiment) has its
/// start re-tracked too: with the world the tip's axis is fused with the IMU's, so more of the
/// early tips are within 2 mm; the samples after the second pass are the first pass's.
#[test]
fn the_start_of_a_session_without_early_strokes_is_retracked() {
    use fires_host::replay::report::tip_errors;
    let (dir, reader, out, _) = track("tip", 6.0, 1);
    let first = replay_without_retracking(&reader);
    let (accepted, _) = out.world_fit.expect("world accepted");
    let truth = reader.exposure_truth().expect("truth").expect("simulated");
    let within_2mm_before = |o: &ReplayOutput| {
        let early: Vec<f64> = tip_errors(o, &truth)
            .into_iter()
            .filter(|(t, _)| *t < accepted)
            .map(|(_, e)| e)
            .collect();
        assert!(early.len() > 100, "{} early tips", early.len());
        early.iter().filter(|e| **e < 0.002).count() as f64 / early.len() as f64
    };
    let (before, after) = (within_2mm_before(&first), within_2mm_before(&out));
    eprintln!(
        "world accepted at {:.2} s; early tips within 2 mm: {before:.3} -> {after:.3}",
        accepted as f64 * 1e-9
    );
    assert!(after > 0.95 && after > before + 0.05, "{before} -> {after}");
    let late = |o: &ReplayOutput| -> Vec<(u64, Option<[f64; 3]>)> {
        o.samples
            .iter()
            .filter(|s| s.t_ns > accepted + 1_000_000_000)
            .map(|s| (s.t_ns, s.tip))
            .collect()
    };
    assert_eq!(late(&out), late(&first));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A mode button held while drawing reaches the curve network (curve network issue, item 4): the simulator
/// holds the sharp mode while it draws stroke 2, the link carries it in the status packets, the tracker
/// keeps it as the stroke's buttons, and the network built from the tracked strokes tags exactly that
/// stroke's curves sharp.
#[test]
fn a_sharp_mode_stroke_is_a_sharp_curve_of_the_tracked_network() {
    use fires_recon::network::{build_network, BuildOptions, PenMode};
    let dir = std::env::temp_dir().join(format!("fires-replay-modes-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut opts = SimOptions::default();
    opts.stroke_modes[2] = 1;
    run_scenario("fires-v1", 7, 18.0, &dir, opts).expect("simulate");
    let reader = RecordingReader::open(&dir).expect("open");
    let truth = reader.strokes().expect("truth").expect("simulated");
    let modes: Vec<u8> = truth.iter().map(|s| s.mode).collect();
    assert!(
        truth.iter().filter(|s| s.complete).count() >= 4,
        "{truth:?}"
    );
    assert!(
        modes
            .iter()
            .enumerate()
            .all(|(i, &m)| m == u8::from(i == 2)),
        "{modes:?}"
    );

    let out = replay(&reader, &ReplayConfig::default()).expect("replay");
    let sharp: Vec<u32> = out
        .strokes
        .iter()
        .filter(|s| PenMode::from_mode(s.buttons >> 1) == PenMode::Sharp)
        .map(|s| s.id)
        .collect();
    assert_eq!(
        sharp.len(),
        1,
        "{:?}",
        out.strokes
            .iter()
            .map(|s| (s.id, s.buttons))
            .collect::<Vec<_>>()
    );
    // The sharp stroke is the one drawn while truth stroke 2 was.
    let s = out
        .strokes
        .iter()
        .find(|s| s.id == sharp[0])
        .expect("stroke");
    assert!(s.t_start_ns < truth[2].end_time_ns && s.t_end_ns > truth[2].start_time_ns);

    // The strokes as `fires replay` hands them to the network.
    let inputs =
        fires_cli::network::tracked_inputs(&fires_record::StrokesFile::new(out.strokes.clone()));
    let (net, report) = build_network(&inputs, &BuildOptions::default());
    net.validate().expect("valid network");
    assert!(report.used.contains(&sharp[0]), "{report:?}");
    let mut tagged = 0;
    for (_, p) in net.polylines() {
        let is_sharp = p.attrs.stroke == Some(sharp[0]);
        assert_eq!(
            p.attrs.sharpness,
            if is_sharp { 1.0 } else { 0.0 },
            "{:?}",
            p.attrs
        );
        tagged += usize::from(is_sharp);
    }
    assert!(
        tagged >= 2,
        "the sharp stroke crosses an earlier one: {tagged} pieces"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
