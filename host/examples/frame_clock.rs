//! A webcam's frame times from its host stamps: a 60 Hz camera whose crystal runs 0.1% slow,
//! stamped on USB arrival with 1 ms of jitter, timed by [`FrameClock`]; prints the stamps' and the
//! clock's RMS error against the true exposures, per second of the session.
//!
//! ```text
//! cargo run --release -p fires-host --example frame_clock [SECONDS] [STAMP_JITTER_MS]
//! ```

use fires_host::rng::SplitMix64;
use fires_host::track::frame_clock::{FrameClock, FrameTiming};

fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let seconds = args.first().copied().unwrap_or(10.0);
    let jitter_ns = args.get(1).copied().unwrap_or(1.0) * 1e6;
    let period = 1e9 / 60.0 * 1.001;
    let mut clock = FrameClock::new(FrameTiming {
        period_ns: 1e9 / 60.0,
        exposure_jitter_ns: 0.0,
        stamp_noise_ns: jitter_ns,
    });
    let mut rng = SplitMix64::new(1);
    let frames = (seconds * 60.0) as usize;
    println!("second  stamps_rms_ms  clock_rms_ms");
    let (mut raw, mut timed, mut n) = (0.0, 0.0, 0.0);
    for k in 0..frames {
        let exposure = 2e9 + period * k as f64;
        let stamp = (exposure + jitter_ns * rng.gaussian()).round() as u64;
        let t = clock.time(stamp) as f64;
        raw += (stamp as f64 - exposure).powi(2);
        timed += (t - exposure).powi(2);
        n += 1.0;
        if (k + 1) % 60 == 0 {
            println!(
                "{:6}  {:12.3}  {:12.3}",
                (k + 1) / 60,
                (raw / n).sqrt() * 1e-6,
                (timed / n).sqrt() * 1e-6
            );
            (raw, timed, n) = (0.0, 0.0, 0.0);
        }
    }
}
