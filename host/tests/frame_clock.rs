//! The frame clock: exposure times recovered from jittered host stamps, with the error the
//! least-squares line predicts, dropped frames and a restarted stream.

use fires_host::rng::SplitMix64;
use fires_host::track::frame_clock::{FrameClock, FrameTiming};

/// A 60 Hz webcam whose crystal runs 0.1% slow, from a random phase.
const PERIOD: f64 = 1e9 / 60.0 * 1.001;
const NOMINAL: f64 = 1e9 / 60.0;

/// `(true exposure, stamp)` of frames `0..n` (those `keep` admits), exposures jittered by
/// `exposure_ns` about their period and stamps by `stamp_ns` about the exposures.
fn frames(
    n: usize,
    exposure_ns: f64,
    stamp_ns: f64,
    seed: u64,
    keep: impl Fn(usize) -> bool,
) -> Vec<(f64, u64)> {
    let mut g = SplitMix64::new(seed);
    let phase = 3.3e6;
    (0..n)
        .map(|k| {
            let t = 5e9 + phase + PERIOD * k as f64 + exposure_ns * g.gaussian();
            (t, (t + stamp_ns * g.gaussian()).round() as u64)
        })
        .enumerate()
        .filter(|(k, _)| keep(*k))
        .map(|(_, f)| f)
        .collect()
}

/// RMS of `time − exposure` over the frames from `from` on, and of the raw stamps.
fn rms_errors(clock: &mut FrameClock, frames: &[(f64, u64)], from: usize) -> (f64, f64) {
    let (mut e, mut r, mut n) = (0.0, 0.0, 0.0);
    for (i, &(t, stamp)) in frames.iter().enumerate() {
        let got = clock.time(stamp) as f64;
        if i >= from {
            e += (got - t).powi(2);
            r += (stamp as f64 - t).powi(2);
            n += 1.0;
        }
    }
    ((e / n).sqrt(), (r / n).sqrt())
}

fn timing(exposure_ns: f64, stamp_ns: f64) -> FrameTiming {
    FrameTiming {
        period_ns: NOMINAL,
        exposure_jitter_ns: exposure_ns,
        stamp_noise_ns: stamp_ns,
    }
}

#[test]
fn noise_free_stamps_come_back_exactly() {
    let f = frames(1000, 0.0, 0.0, 1, |_| true);
    let mut clock = FrameClock::new(timing(0.0, 1e6));
    for &(t, stamp) in &f {
        assert!((clock.time(stamp) as f64 - t).abs() <= 1.0);
    }
}

#[test]
fn exact_stamps_an_unknown_period_or_a_broken_model_leave_the_stamps_as_they_are() {
    let f = frames(500, 2e5, 1e6, 2, |_| true);
    for t in [
        timing(2e5, 0.0),
        FrameTiming::default(),
        timing(f64::NAN, 1e6),
        timing(-1.0, 1e6),
        FrameTiming {
            period_ns: f64::INFINITY,
            ..timing(0.0, 1e6)
        },
    ] {
        let mut clock = FrameClock::new(t);
        assert!(f.iter().all(|&(_, s)| clock.time(s) == s));
    }
}

/// A crystal-clocked webcam stamped on USB arrival (1 ms): the line's error at the window's end is
/// about `2σ/√N` (0.13 ms for the 240-frame window), eight times less than the stamps'.
#[test]
fn a_crystal_clocks_jittered_stamps_become_its_exposure_times() {
    for seed in 3..8 {
        let f = frames(3600, 5e4, 1e6, seed, |_| true);
        let mut clock = FrameClock::new(timing(5e4, 1e6));
        let (e, raw) = rms_errors(&mut clock, &f, 240);
        assert!(raw > 0.9e6 && raw < 1.1e6, "stamps {raw}");
        assert!(e < 0.18e6, "seed {seed}: {e} ns");
    }
}

/// Exposures that jitter themselves (2 ms, the Minoru-like rig) with 1 ms stamp noise: the best
/// combination of line and stamp has error `σₑσₛ/√(σₑ²+σₛ²)` = 0.89 ms.
#[test]
fn jittered_exposures_keep_most_of_their_stamps() {
    let f = frames(2000, 2e6, 1e6, 9, |_| true);
    let mut clock = FrameClock::new(timing(2e6, 1e6));
    let (e, raw) = rms_errors(&mut clock, &f, 240);
    let best = 2e6 * 1e6 / (4e12f64 + 1e12).sqrt();
    assert!(e < raw && e < 1.08 * best, "{e} vs {best}, stamps {raw}");
}

#[test]
fn dropped_frames_keep_their_place() {
    // Every seventh frame lost, and a burst of five.
    let f = frames(3600, 5e4, 1e6, 11, |k| {
        k % 7 != 3 && !(1000..1005).contains(&k)
    });
    let mut clock = FrameClock::new(timing(5e4, 1e6));
    let (e, _) = rms_errors(&mut clock, &f, 240);
    assert!(e < 0.2e6, "{e} ns");
}

#[test]
fn a_restarted_stream_is_fitted_again() {
    let mut f = frames(3000, 5e4, 1e6, 13, |_| true);
    // At frame 1500 the exposures jump by 7.3 ms (the stream restarted at a new phase).
    for x in &mut f[1500..] {
        x.0 += 7.3e6;
        x.1 += 7_300_000;
    }
    let mut clock = FrameClock::new(timing(5e4, 1e6));
    let (before, _) = rms_errors(&mut clock, &f[..1500], 240);
    let mut errors = f[1500..]
        .iter()
        .map(|&(t, s)| (clock.time(s) as f64 - t).abs())
        .collect::<Vec<_>>();
    // A jump of 7 stamp deviations rejects most frames after it (returned as stamped); the few
    // within 6σ of the old line land on it, 7.3 ms off, until four rejections restart the fit.
    let off_line = errors[..20].iter().filter(|&&e| e > 4e6).count();
    assert!(off_line <= 3, "{:?}", &errors[..20]);
    assert!(errors[20..].iter().all(|&e| e < 4e6));
    let late = errors.split_off(300);
    let rms = (late.iter().map(|e| e * e).sum::<f64>() / late.len() as f64).sqrt();
    assert!(before < 0.18e6 && rms < 0.18e6, "{before} {rms}");
}
