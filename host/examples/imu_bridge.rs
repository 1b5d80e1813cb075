//! Bridging a gap in a stroke: a pen drawing a 3 cm circle in 0.8 s is seen at 60 Hz with 0.3 mm of tip
//! noise, its accelerometer reads the tip's acceleration with a 0.15 m/s² bias and 0.05 m/s² of noise; for
//! gaps of 50-300 ms, prints the largest distance from the true path of the chord across the gap and of
//! the IMU bridge ([`imu_bridge`]), averaged over gap positions around the circle.
//!
//! ```text
//! cargo run --release -p fires-host --example imu_bridge
//! ```

use fires_host::rng::SplitMix64;
use fires_host::stroke::{imu_bridge, ImuBridgeOptions, TimedAccel, TimedPoint};

const MS: u64 = 1_000_000;
const RADIUS: f64 = 0.015;
const OMEGA: f64 = std::f64::consts::TAU / 0.8;

fn circle(t_ns: u64) -> [f64; 3] {
    let w = OMEGA * t_ns as f64 * 1e-9;
    [RADIUS * w.cos(), RADIUS * w.sin(), 0.6]
}

fn circle_accel(t_ns: u64) -> [f64; 3] {
    let w = OMEGA * t_ns as f64 * 1e-9;
    let a = RADIUS * OMEGA * OMEGA;
    [-a * w.cos(), -a * w.sin(), 0.0]
}

fn main() {
    let mut rng = SplitMix64::new(7);
    let mut gauss = move || rng.gaussian();
    let options = ImuBridgeOptions::default();
    println!("gap_ms  chord_mm  imu_mm");
    for gap_ms in [50u64, 100, 150, 200, 250, 300] {
        let (mut chord, mut imu, mut n) = (0.0, 0.0, 0.0);
        for start in (200..1400).step_by(50) {
            let gap = (start, start + gap_ms);
            let tips: Vec<TimedPoint> = (0..100u64)
                .map(|k| k * 50 / 3)
                .filter(|&ms| ms <= gap.0 || ms >= gap.1)
                .map(|ms| {
                    let p = circle(ms * MS);
                    TimedPoint {
                        t_ns: ms * MS,
                        p: std::array::from_fn(|k| p[k] + 3e-4 * gauss()),
                        sigma_m: Some(3e-4),
                    }
                })
                .collect();
            let accel: Vec<TimedAccel> = (0..170u64)
                .map(|k| {
                    let a = circle_accel(k * 10 * MS);
                    TimedAccel {
                        t_ns: k * 10 * MS,
                        a: std::array::from_fn(|i| a[i] + 0.15 + 0.05 * gauss()),
                    }
                })
                .collect();
            let Some(i) = (0..tips.len() - 1).find(|&i| tips[i + 1].t_ns - tips[i].t_ns > 20 * MS)
            else {
                continue;
            };
            let Some(bridge) = imu_bridge(&tips, i, &accel, &options) else {
                continue;
            };
            let (a, b) = (tips[i], tips[i + 1]);
            let off = |t: u64, p: [f64; 3]| {
                let q = circle(t);
                (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt()
            };
            let worst_chord = bridge
                .iter()
                .map(|&(t, _)| {
                    let w = (t - a.t_ns) as f64 / (b.t_ns - a.t_ns) as f64;
                    off(t, std::array::from_fn(|k| a.p[k] + w * (b.p[k] - a.p[k])))
                })
                .fold(0.0, f64::max);
            let worst_imu = bridge.iter().map(|&(t, p)| off(t, p)).fold(0.0, f64::max);
            chord += worst_chord;
            imu += worst_imu;
            n += 1.0;
        }
        println!(
            "{gap_ms:>6}  {:>8.2}  {:>6.2}",
            chord / n * 1e3,
            imu / n * 1e3
        );
    }
}
