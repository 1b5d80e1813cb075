//! Gradient-field denoising (Yu et al. 2004 §4.3) on a noisy sphere.

use fires_recon::edit::denoise::{denoise, DenoiseOptions};
use fires_recon::generate::icosphere;
use fires_recon::operators::volume;
use fires_recon::Vec3;

/// Deterministic standard normal samples (xorshift + Box–Muller).
fn normals(n: usize, mut s: u64) -> Vec<f64> {
    let mut u = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            let (a, b) = (u().max(1e-300), u());
            (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()
        })
        .collect()
}

fn rms_distance_to_unit_sphere(x: &[Vec3]) -> f64 {
    (x.iter().map(|p| (p.norm() - 1.0).powi(2)).sum::<f64>() / x.len() as f64).sqrt()
}

#[test]
fn denoising_a_noisy_sphere_gets_three_times_closer_and_keeps_volume() {
    let clean = icosphere(4, 1.0);
    let v0 = volume(&clean);
    let mut noisy = clean.clone();
    let g = normals(noisy.vertices_size(), 0x9e3779b97f4a7c15);
    for (p, e) in noisy.positions_mut().iter_mut().zip(g) {
        *p = *p * (1.0 + 0.01 * e);
    }
    let before = rms_distance_to_unit_sphere(noisy.positions());
    let raw = denoise(
        &noisy,
        &DenoiseOptions {
            preserve_volume: false,
            ..Default::default()
        },
    )
    .unwrap();
    let out = denoise(&noisy, &DenoiseOptions::default()).unwrap();
    let after = rms_distance_to_unit_sphere(&out);
    let mut m = noisy.clone();
    m.positions_mut().copy_from_slice(&out);
    let dv = (volume(&m) - v0).abs() / v0;
    m.positions_mut().copy_from_slice(&raw);
    let dv_raw = (volume(&m) - v0) / v0;
    println!(
        "without volume preservation: rms {:.3e}, volume change {dv_raw:+.2e}",
        rms_distance_to_unit_sphere(&raw)
    );
    println!(
        "rms distance before {before:.3e} after {after:.3e} (×{:.1}), volume change {dv:.2e}",
        before / after
    );
    assert!(after * 3.0 <= before, "{before} → {after}");
    assert!(dv <= 0.01, "volume changed by {dv}");
}
