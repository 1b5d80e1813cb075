//! Shared fixtures of the editing tests: generated meshes and specifications.
#![allow(dead_code)]

use fires_recon::edit::{EditSpec, HandleSpec, RotateSpec, Select, TransformSpec};
use fires_recon::generate::cylinder;
use fires_recon::{SurfaceMesh, Vec3};

/// Radius, height, vertices around and rings of the relief cylinder.
pub const CYL: (f64, f64, usize, usize) = (1.0, 4.0, 40, 41);

/// A triangulated open cylinder around z with a sine relief
/// `r = 1 + 0.06 sin(6φ) sin(2π z / 2)`.
pub fn relief_cylinder() -> SurfaceMesh {
    let (r, h, na, nr) = CYL;
    let mut m = cylinder(r, h, na, nr, false);
    for p in m.positions_mut() {
        let phi = p.y.atan2(p.x);
        let rad = r + 0.06 * (6.0 * phi).sin() * (std::f64::consts::PI * p.z).sin();
        let s = rad / (p.x * p.x + p.y * p.y).sqrt();
        p.x *= s;
        p.y *= s;
    }
    m
}

/// Indices of ring `k` of the relief cylinder.
pub fn ring(k: usize) -> Vec<usize> {
    let na = CYL.2;
    (k * na..(k + 1) * na).collect()
}

/// ROI = all, anchors = bottom ring, handle = top ring turned by `deg` about z.
pub fn twist_spec(deg: f64) -> EditSpec {
    EditSpec {
        roi: Select::All,
        anchors: Some(Select::Vertices(ring(0))),
        anchor_weight: 1.0,
        handles: vec![HandleSpec::with_transform(
            Select::Vertices(ring(CYL.3 - 1)),
            TransformSpec {
                rotate: Some(RotateSpec {
                    axis: [0.0, 0.0, 1.0],
                    deg,
                }),
                ..Default::default()
            },
        )],
    }
}

/// Bounding-box diagonal.
pub fn bbox_diag(x: &[Vec3]) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in x {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    ((0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>()).sqrt()
}

/// Largest distance between corresponding points.
pub fn max_dist(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| p.distance(*q))
        .fold(0.0, f64::max)
}
