//! Mirroring: the result lies in the curve's least-squares plane, is closed and symmetric about the
//! end-point axis to 1e-9 m (FIRES thesis, §5.1), and makes a valid boundary.

mod common;

use common::disc::Rng;
use fires_recon::network::tools::{
    insert_boundary, mirror_curve, BoundaryOptions, CurveInput, ToolError,
};
use fires_recon::network::Network;

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[test]
fn mirrored_curve_is_planar_closed_and_symmetric() {
    for seed in 1..=20u64 {
        let mut rng = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
        // A half outline in a random tilted plane, with 0.3 mm of out-of-plane noise.
        let (e1, e2) = {
            let t = rng.range(0.0, 1.0);
            (
                [t.cos(), t.sin(), 0.3],
                [-t.sin() * 0.5, t.cos() * 0.5, 0.8],
            )
        };
        let o = [
            rng.range(-0.2, 0.2),
            rng.range(-0.2, 0.2),
            rng.range(0.4, 0.8),
        ];
        let n = 80;
        let pts: Vec<[f64; 3]> = (0..=n)
            .map(|i| {
                let s = i as f64 / n as f64;
                let x = 0.1 * (s - 0.5);
                let y = 0.04 * (std::f64::consts::PI * s).sin() * (1.0 + 0.3 * s);
                let z = rng.range(-3e-4, 3e-4);
                [
                    o[0] + x * e1[0] + y * e2[0] + z,
                    o[1] + x * e1[1] + y * e2[1],
                    o[2] + x * e1[2] + y * e2[2],
                ]
            })
            .collect();
        let m = mirror_curve(&pts).unwrap();
        let p = &m.points;
        assert_eq!(p.len(), 2 * n + 1);
        assert_eq!(p[0], p[p.len() - 1], "closed");
        let c = p[0];
        for q in p {
            let h = dot([q[0] - c[0], q[1] - c[1], q[2] - c[2]], m.normal);
            assert!(h.abs() < 1e-12, "seed {seed}: {h} off the plane");
        }
        // Point k of the first half and point 2n − k of the second are mirror images about the axis.
        let (a, u) = m.axis;
        for k in 0..=n {
            let (q, r) = (p[k], p[2 * n - k]);
            let mid = [
                (q[0] + r[0]) / 2.0 - a[0],
                (q[1] + r[1]) / 2.0 - a[1],
                (q[2] + r[2]) / 2.0 - a[2],
            ];
            let along = dot(mid, u);
            let off = [
                mid[0] - along * u[0],
                mid[1] - along * u[1],
                mid[2] - along * u[2],
            ];
            assert!(
                dot(off, off).sqrt() < 1e-9,
                "seed {seed}: midpoint off the axis"
            );
            let d = [q[0] - r[0], q[1] - r[1], q[2] - r[2]];
            assert!(
                dot(d, u).abs() < 1e-9,
                "seed {seed}: chord not perpendicular to the axis"
            );
        }
        let mut net = Network::new();
        insert_boundary(&mut net, CurveInput::new(p), &BoundaryOptions::default()).unwrap();
        net.validate().unwrap();
    }
    let line = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.0, 0.0]];
    assert!(matches!(mirror_curve(&line), Err(ToolError::BadCurve(_))));
}
