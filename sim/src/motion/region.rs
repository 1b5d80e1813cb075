//! The true drawn region: the part of the object's camera-facing side inside the boundary stroke, as a point
//! sample (what a reconstructed surface's completeness is measured on), and the drawing scene as recorded in
//! the ground truth.
//!
//! The boundary polyline is projected onto the scene's parameter plane (`(p - origin)·e1`, `(p - origin)·e2`);
//! the plane points of a square grid of the given spacing (aligned with the plane's origin) that lie inside
//! the projected polygon (even-odd rule; the polygon is closed by joining its last point to its first) are
//! lifted onto the object along the viewing direction ([`Scene::lift`]), the way the simulator placed the
//! strokes. The sample is therefore uniform in the plane, not on the surface: its density on the surface is
//! `cos(angle between the normal and the view) / spacing²`.

use super::network::Scene;
use crate::objects::{from_truth, TruthError, V3};
use fires_record::{SceneTruth, StrokeKind, StrokeTruth, TargetTruth};

/// Options of [`drawn_region`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrawnRegionOptions {
    /// Grid spacing in the parameter plane, metres (default 1 mm).
    pub spacing_m: f64,
    /// Largest number of grid points considered; a finer grid is refused (default 4 million).
    pub max_points: usize,
}

impl Default for DrawnRegionOptions {
    fn default() -> Self {
        DrawnRegionOptions {
            spacing_m: 1e-3,
            max_points: 4_000_000,
        }
    }
}

impl Scene {
    /// The scene as the ground truth records it (`target` of `truth/world.json`).
    pub fn to_truth(&self) -> TargetTruth {
        let a = |x: &V3| [x.x, x.y, x.z];
        TargetTruth {
            object: self.shape.to_truth(),
            scene: SceneTruth {
                view: a(&self.view),
                e1: a(&self.e1),
                e2: a(&self.e2),
                origin_m: a(&self.origin),
                rho_m: self.rho,
                eye_m: a(&self.eye),
                up: a(&self.up),
            },
        }
    }

    /// The scene a ground truth records: its object rebuilt ([`from_truth`]) and its plane taken as recorded.
    pub fn from_truth(t: &TargetTruth) -> Result<Scene, TruthError> {
        let shape = from_truth(&t.object)?;
        let s = &t.scene;
        let finite = |a: [f64; 3], name| {
            if a.iter().all(|x| x.is_finite()) {
                Ok(V3::from(a))
            } else {
                Err(TruthError::NotFinite(name))
            }
        };
        let unit = |a: [f64; 3], name| {
            finite(a, name)?
                .try_normalize(1e-9)
                .ok_or(TruthError::NotADirection(name))
        };
        if !s.rho_m.is_finite() {
            return Err(TruthError::NotFinite("rho_m"));
        }
        Ok(Scene {
            shape,
            view: unit(s.view, "view")?,
            e1: unit(s.e1, "e1")?,
            e2: unit(s.e2, "e2")?,
            origin: finite(s.origin_m, "origin_m")?,
            rho: s.rho_m,
            eye: finite(s.eye_m, "eye_m")?,
            up: unit(s.up, "up")?,
        })
    }

    /// The plane point under the world point `p`.
    pub fn project(&self, p: &V3) -> [f64; 2] {
        let d = p - self.origin;
        [d.dot(&self.e1), d.dot(&self.e2)]
    }
}

/// The true boundary stroke of a session: the tip polyline of the first stroke of kind `boundary` in
/// `truth/strokes.json` (None if there is none, or it has fewer than three points).
pub fn boundary_polyline(strokes: &[StrokeTruth]) -> Option<Vec<V3>> {
    let s = strokes.iter().find(|s| s.kind == StrokeKind::Boundary)?;
    (s.tip_polyline_m.len() >= 3).then(|| s.tip_polyline_m.iter().map(|&p| V3::from(p)).collect())
}

/// Why a drawn region cannot be sampled.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RegionError {
    /// The boundary has fewer than three points, or a point is not finite.
    #[error("the boundary needs at least three finite points")]
    BadBoundary,
    /// The spacing is not positive and finite.
    #[error("grid spacing {0} m must be positive and finite")]
    BadSpacing(f64),
    /// The grid would have more than `max_points` points.
    #[error("the grid would have {0} points, more than the {1} allowed")]
    TooManyPoints(usize, usize),
}

/// Points of the object inside the projected `boundary` on the side facing the cameras (module docs).
pub fn drawn_region(
    scene: &Scene,
    boundary: &[V3],
    opts: &DrawnRegionOptions,
) -> Result<Vec<V3>, RegionError> {
    let h = opts.spacing_m;
    if !(h.is_finite() && h > 0.0) {
        return Err(RegionError::BadSpacing(h));
    }
    if boundary.len() < 3 || boundary.iter().any(|p| !p.iter().all(|x| x.is_finite())) {
        return Err(RegionError::BadBoundary);
    }
    let poly: Vec<[f64; 2]> = boundary.iter().map(|p| scene.project(p)).collect();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for q in &poly {
        for k in 0..2 {
            lo[k] = lo[k].min(q[k]);
            hi[k] = hi[k].max(q[k]);
        }
    }
    let (i0, i1) = ((lo[0] / h).ceil(), (hi[0] / h).floor());
    let (j0, j1) = ((lo[1] / h).ceil(), (hi[1] / h).floor());
    let (ni, nj) = ((i1 - i0 + 1.0).max(0.0), (j1 - j0 + 1.0).max(0.0));
    if ni * nj > opts.max_points as f64 {
        return Err(RegionError::TooManyPoints(
            (ni * nj).min(usize::MAX as f64) as usize,
            opts.max_points,
        ));
    }
    let mut out = Vec::new();
    for j in 0..nj as usize {
        let v = (j0 + j as f64) * h;
        for i in 0..ni as usize {
            let u = (i0 + i as f64) * h;
            if inside(&poly, [u, v]) {
                if let Some((p, _)) = scene.lift([u, v]) {
                    out.push(p);
                }
            }
        }
    }
    Ok(out)
}

/// Even-odd point-in-polygon test (the polygon closed from its last point to its first).
fn inside(poly: &[[f64; 2]], q: [f64; 2]) -> bool {
    let mut c = false;
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        if (a[1] > q[1]) != (b[1] > q[1]) {
            let x = a[0] + (q[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if q[0] < x {
                c = !c;
            }
        }
    }
    c
}
