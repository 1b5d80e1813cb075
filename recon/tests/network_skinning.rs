//! Skinning's automatic half pairing (FIRES thesis, §5.2: halves paired where the dihedral angle is below 90°): ellipse profiles at consecutive
//! dihedral angles 0–80°, random in-plane rotations and spine placements, halves labelled at random:
//! the pairing is right in 100% of cases.

mod common;

use common::disc::Rng;
use fires_recon::network::tools::pair_halves;
use std::f64::consts::PI;

/// Points of the ellipse (a, b) rotated by `phi` in the plane spanned by `u`, `v` at `o`, from angle
/// `t0` to `t1`.
#[allow(clippy::too_many_arguments)]
fn arc(
    o: [f64; 3],
    u: [f64; 3],
    v: [f64; 3],
    a: f64,
    b: f64,
    phi: f64,
    t0: f64,
    t1: f64,
) -> Vec<[f64; 3]> {
    (0..=60)
        .map(|k| {
            let t = t0 + (t1 - t0) * k as f64 / 60.0;
            let (x, y) = (a * t.cos(), b * t.sin());
            let (x, y) = (x * phi.cos() - y * phi.sin(), x * phi.sin() + y * phi.cos());
            [
                o[0] + x * u[0] + y * v[0],
                o[1] + x * u[1] + y * v[1],
                o[2] + x * u[2] + y * v[2],
            ]
        })
        .collect()
}

#[test]
fn half_pairing_is_right_in_every_randomised_case() {
    let mut rng = Rng(0xC0FFEE);
    let mut cases = 0;
    for _ in 0..2000 {
        let dihedral = rng.range(0.0, 80f64.to_radians());
        // Profile i in the plane z = 0; profile j in a plane tilted by `dihedral` about the x axis,
        // 60 mm further along the spine direction.
        let (ui, vi) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        let (uj, vj) = ([1.0, 0.0, 0.0], [0.0, dihedral.cos(), dihedral.sin()]);
        let oj = [rng.range(-0.01, 0.01), rng.range(-0.01, 0.01), 0.06];
        let (a, b) = (rng.range(0.03, 0.06), rng.range(0.015, 0.03));
        let (a2, b2) = (a * rng.range(0.7, 1.3), b * rng.range(0.7, 1.3));
        let (phi_i, phi_j) = (rng.range(0.0, 2.0 * PI), rng.range(0.0, 2.0 * PI));
        // The spines cross each profile at two angles (not necessarily opposite); profile j's spine
        // points correspond to profile i's (same ellipse angles relative to its rotation, perturbed).
        let s0 = rng.range(0.0, 2.0 * PI);
        let s1 = s0 + rng.range(0.6 * PI, 1.4 * PI);
        let (e0, e1) = (rng.range(-0.2, 0.2), rng.range(-0.2, 0.2));
        let hi0 = arc([0.0; 3], ui, vi, a, b, phi_i, s0, s1);
        let hi1 = arc([0.0; 3], ui, vi, a, b, phi_i, s1, s0 + 2.0 * PI);
        // Profile j is drawn with the same in-plane rotation as i's (the object continues smoothly) plus
        // a random offset of up to ±0.3 rad, which moves its halves only a little.
        let phi_j = phi_i + (phi_j - PI).clamp(-0.3, 0.3);
        let hj0 = arc(oj, uj, vj, a2, b2, phi_j, s0 + e0, s1 + e1);
        let hj1 = arc(oj, uj, vj, a2, b2, phi_j, s1 + e1, s0 + e0 + 2.0 * PI);
        let swap = rng.unit() < 0.5;
        let j = if swap {
            [&hj1[..], &hj0[..]]
        } else {
            [&hj0[..], &hj1[..]]
        };
        let straight = pair_halves([&hi0, &hi1], j).unwrap();
        assert_eq!(straight, !swap, "dihedral {:.1}°", dihedral.to_degrees());
        cases += 1;
    }
    assert_eq!(cases, 2000);
}
