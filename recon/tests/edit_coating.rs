//! Coating transfer (Sorkine et al. 2004 §5.1).

mod edit_common;

use edit_common::*;
use fires_recon::edit::coating::{coat, smooth_base, CoatingOptions};
use fires_recon::edit::similarity::axis_angle;
use fires_recon::edit::Similarity;
use fires_recon::generate::icosphere;
use fires_recon::Vec3;

#[test]
fn coating_onto_its_own_smoothed_base_returns_the_mesh() {
    for mesh in [relief_cylinder(), {
        let mut s = icosphere(3, 1.0);
        for p in s.positions_mut() {
            *p = *p * (1.0 + 0.05 * (5.0 * p.x).sin() * (4.0 * p.y).cos());
        }
        s
    }] {
        let o = CoatingOptions::default();
        let base = smooth_base(&mesh, &o).unwrap();
        // The smoothing really removed detail.
        assert!(max_dist(&base, mesh.positions()) > 1e-3);
        let out = coat(&mesh, &base, &o).unwrap();
        let err = max_dist(&out, mesh.positions()) / bbox_diag(mesh.positions());
        assert!(err < 1e-9, "coating error {err:e}");
    }
}

#[test]
fn coating_follows_a_rigid_motion_of_the_base() {
    // Eq. 15: the transfer onto R·U + t is R·(transfer onto U) + t, detail rotating with
    // the base's frames.
    let mesh = relief_cylinder();
    let o = CoatingOptions::default();
    let base: Vec<Vec3> = smooth_base(&mesh, &o)
        .unwrap()
        .iter()
        .map(|p| Vec3::new(1.5 * p.x, 1.5 * p.y, p.z))
        .collect();
    let g = Similarity::rigid(
        axis_angle(Vec3::new(1.0, 2.0, 0.5), 75.0).unwrap(),
        Vec3::new(0.5, -3.0, 2.0),
    );
    let a = coat(&mesh, &base, &o).unwrap();
    let moved: Vec<Vec3> = base.iter().map(|p| g.apply(*p)).collect();
    let b = coat(&mesh, &moved, &o).unwrap();
    let ga: Vec<Vec3> = a.iter().map(|p| g.apply(*p)).collect();
    assert!(max_dist(&ga, &b) / bbox_diag(&b) < 1e-9);
    // And the detail really was added: the result differs from the bare base.
    assert!(max_dist(&a, &base) > 0.01);
}
