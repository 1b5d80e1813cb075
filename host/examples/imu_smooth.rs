//! IMU-aided smoothing of one stroke: a 3 cm circle drawn at 1.5 turns per second, seen as vision
//! tips at 15 or 30 Hz whose depth (z) is `DEPTH_NOISE_MM` off per tip while the tracker claims 0.1
//! mm, with the IMU's tip acceleration at 100 Hz carrying white noise and a gravity leak of 0.17
//! m/s²; prints the tips' and the smoothed path's RMS error per axis.
//!
//! ```text
//! cargo run --release -p fires-host --example imu_smooth [TIP_HZ] [DEPTH_NOISE_MM]
//! ```

use fires_host::rng::SplitMix64;
use fires_host::stroke::{imu_smooth, ImuSmoothOptions, TimedAccel, TimedPoint};

const W: f64 = 1.5 * std::f64::consts::TAU;

fn circle(t: f64) -> [f64; 3] {
    [0.03 * (W * t).cos(), 0.03 * (W * t).sin(), 0.5 + 0.02 * t]
}

fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let hz = args.first().copied().unwrap_or(30.0).max(1.0);
    let depth_mm = args.get(1).copied().unwrap_or(3.0);
    let mut rng = SplitMix64::new(3);
    let seconds = 3.0;
    let tips: Vec<TimedPoint> = (0..(seconds * hz) as u64)
        .map(|k| {
            let t = k as f64 / hz;
            let p = circle(t);
            let n = [0.2, 0.2, depth_mm].map(|s| s * 1e-3 * rng.gaussian());
            TimedPoint {
                t_ns: (t * 1e9) as u64,
                p: std::array::from_fn(|i| p[i] + n[i]),
                sigma_m: Some(1e-4),
            }
        })
        .collect();
    let accel: Vec<TimedAccel> = (0..=(seconds * 100.0) as u64 + 1)
        .map(|k| {
            let t = k as f64 / 100.0;
            let a = [
                -0.03 * W * W * (W * t).cos(),
                -0.03 * W * W * (W * t).sin(),
                0.0,
            ];
            TimedAccel {
                t_ns: (t * 1e9) as u64,
                a: std::array::from_fn(|i| a[i] + 0.17 + 0.2 * rng.gaussian()),
            }
        })
        .collect();
    let Some(out) = imu_smooth(&tips, &accel, &ImuSmoothOptions::default()) else {
        eprintln!("the smoother declined the stroke");
        std::process::exit(2);
    };
    let rms = |pick: &dyn Fn(usize) -> [f64; 3], axis: usize| {
        let s: f64 = (0..tips.len())
            .map(|i| (pick(i)[axis] - circle(tips[i].t_ns as f64 * 1e-9)[axis]).powi(2))
            .sum();
        (s / tips.len() as f64).sqrt() * 1e3
    };
    println!("{} tips at {hz} Hz, depth noise {depth_mm} mm", tips.len());
    println!("axis  tips_rms_mm  smoothed_rms_mm");
    for (axis, name) in ["x", "y", "z"].iter().enumerate() {
        println!(
            "{name}     {:>10.3}  {:>15.3}",
            rms(&|i| tips[i].p, axis),
            rms(&|i| out[i], axis)
        );
    }
}
