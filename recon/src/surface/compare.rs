//! A reconstructed surface measured against the true object (`report.json` → `surface`, docs/report.md).
//!
//! The truth comes in as data, so this crate needs neither the simulator nor the recording format: a function
//! giving the Euclidean distance (metres) from a point to the true object's surface, and a point sample of the
//! true drawn region (the part of the object inside the true boundary stroke, on the side facing the cameras;
//! the simulator's `drawn_region`). The figures, in millimetres:
//! * `rms_mm`, `p95_mm`: RMS and 95th percentile (nearest rank) of the distances from **surface samples** to the
//!   true object. The samples are uniform in area: every face is triangulated
//!   ([`crate::operators::face_triangles`]), each triangle gets `area / spacing²` samples in expectation
//!   (stochastic rounding) at uniformly distributed barycentric positions, from a seeded generator, so the
//!   figures are area-weighted means that do not depend on how the mesh is tessellated.
//! * `hausdorff_mm`: the symmetric Hausdorff distance, the larger of the farthest surface sample from the true
//!   object and the farthest drawn-region sample from the surface (exact point-to-mesh distances through a
//!   [`TriangleBvh`]).
//! * `diag_mm`: the diagonal of the bounding box of the drawn-region sample; `rms_pct_diag = 100 rms / diag`.
//! * `completeness_3mm`: the fraction of the drawn-region samples within 3 mm of the surface.
//! * `curve_rms_mm`: RMS distance from the network's curve points to the surface (`None` without points).
//!
//! A surface from a curve network ends at the network's boundary curve, which follows the drawn boundary, so by
//! default every face is sampled. [`CompareOptions::region_margin_m`] restricts the samples to those within
//! that distance of a drawn-region sample, for surfaces that extend past the drawn region.

use std::collections::HashMap;

use crate::geometry::{triangle_area, TriangleBvh, Vec3};
use crate::mesh::SurfaceMesh;
use crate::operators::{face_triangles, OperatorError};

/// The completeness threshold, metres.
pub const COMPLETENESS_THRESHOLD_M: f64 = 3e-3;

/// Options of [`compare_surface`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompareOptions {
    /// Mean spacing of the surface samples, metres (default 1 mm: `area / spacing²` samples).
    pub sample_spacing_m: f64,
    /// Upper bound on the number of surface samples; the spacing is widened to stay below it (default 2
    /// million).
    pub max_samples: usize,
    /// Keep only surface samples within this distance of a drawn-region sample (default None: all).
    pub region_margin_m: Option<f64>,
    /// Seed of the sample positions.
    pub seed: u64,
}

impl Default for CompareOptions {
    fn default() -> Self {
        CompareOptions {
            sample_spacing_m: 1e-3,
            max_samples: 2_000_000,
            region_margin_m: None,
            seed: 1,
        }
    }
}

/// A surface against the truth (module docs); millimetres.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SurfaceComparison {
    /// RMS distance of the surface samples from the true object.
    pub rms_mm: f64,
    /// 95th percentile of those distances.
    pub p95_mm: f64,
    /// Symmetric Hausdorff distance (the larger of the two one-sided ones below).
    pub hausdorff_mm: f64,
    /// Farthest surface sample from the true object.
    pub surface_to_truth_max_mm: f64,
    /// Farthest drawn-region sample from the surface.
    pub truth_to_surface_max_mm: f64,
    /// Diagonal of the bounding box of the drawn-region sample.
    pub diag_mm: f64,
    /// `rms_mm` as a percentage of `diag_mm`.
    pub rms_pct_diag: f64,
    /// Fraction of the drawn-region samples within 3 mm of the surface.
    pub completeness_3mm: f64,
    /// RMS distance of the curve points from the surface (None without curve points).
    pub curve_rms_mm: Option<f64>,
    /// Surface samples measured.
    pub surface_samples: usize,
    /// Drawn-region samples measured.
    pub region_samples: usize,
}

/// Why a comparison cannot be made.
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    /// The surface has no face of positive area (or no sample is left after the region restriction).
    #[error("the surface has no area to sample")]
    EmptySurface,
    /// The drawn-region sample is empty, or all one point (no diagonal to scale by).
    #[error("the drawn-region sample is empty or has no extent")]
    EmptyRegion,
    /// An input point or a truth distance is NaN or infinite.
    #[error("non-finite {0}")]
    NonFinite(&'static str),
    /// The sample spacing or the margin is not positive and finite.
    #[error("bad option {0}")]
    BadOption(&'static str),
    /// The mesh cannot be triangulated (it has garbage).
    #[error(transparent)]
    Mesh(#[from] OperatorError),
}

/// SplitMix64 (Steele, Lea and Flood, *Fast splittable pseudorandom number generators*, OOPSLA 2014).
struct SplitMix(u64);

impl SplitMix {
    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Area-uniform samples of the triangles (module docs): `area / spacing²` per triangle in expectation.
pub fn sample_triangles(triangles: &[[Vec3; 3]], spacing: f64, seed: u64) -> Vec<Vec3> {
    let mut rng = SplitMix(seed);
    let density = 1.0 / (spacing * spacing);
    let mut out = Vec::new();
    for &[a, b, c] in triangles {
        let expected = triangle_area(a, b, c) * density;
        if !expected.is_finite() {
            continue;
        }
        let n = (expected + rng.next_f64()).floor() as usize;
        for _ in 0..n {
            let (mut r1, mut r2) = (rng.next_f64(), rng.next_f64());
            if r1 + r2 > 1.0 {
                (r1, r2) = (1.0 - r1, 1.0 - r2);
            }
            out.push(a + (b - a) * r1 + (c - a) * r2);
        }
    }
    out
}

/// Points grouped in cubes of side `cell`, to ask whether any lies within `cell` of a query point.
struct PointGrid {
    cell: f64,
    cells: HashMap<(i64, i64, i64), Vec<Vec3>>,
}

impl PointGrid {
    fn key(&self, p: Vec3) -> (i64, i64, i64) {
        let k = |x: f64| (x / self.cell).floor() as i64;
        (k(p.x), k(p.y), k(p.z))
    }

    fn new(points: &[Vec3], cell: f64) -> Self {
        let mut g = PointGrid {
            cell,
            cells: HashMap::new(),
        };
        for &p in points {
            let k = g.key(p);
            g.cells.entry(k).or_default().push(p);
        }
        g
    }

    fn any_within(&self, p: Vec3) -> bool {
        let (i, j, k) = self.key(p);
        let r2 = self.cell * self.cell;
        (-1..=1).any(|di| {
            (-1..=1).any(|dj| {
                (-1..=1).any(|dk| {
                    self.cells
                        .get(&(i + di, j + dj, k + dk))
                        .is_some_and(|v| v.iter().any(|q| (*q - p).norm_squared() <= r2))
                })
            })
        })
    }
}

fn rms(values: &[f64]) -> f64 {
    (values.iter().map(|d| d * d).sum::<f64>() / values.len() as f64).sqrt()
}

/// Distance from each of `points` to the surface (its faces, triangulated), metres: how far a surface lies
/// from the curves it was built from, without a truth.
pub fn point_distances(surface: &SurfaceMesh, points: &[Vec3]) -> Result<Vec<f64>, CompareError> {
    if points.iter().any(|p| !p.is_finite()) {
        return Err(CompareError::NonFinite("curve point"));
    }
    let pos = surface.positions();
    let triangles: Vec<[Vec3; 3]> = face_triangles(surface)?
        .iter()
        .map(|t| [pos[t[0]], pos[t[1]], pos[t[2]]])
        .collect();
    let bvh = TriangleBvh::new(triangles);
    if bvh.is_empty() {
        return Err(CompareError::EmptySurface);
    }
    Ok(points
        .iter()
        .map(|&p| bvh.closest(p).map_or(f64::INFINITY, |h| h.distance))
        .collect())
}

/// Measures `surface` against the truth (module docs): `truth_distance` gives the Euclidean distance in metres
/// from a point to the true object's surface, `truth_region` samples the true drawn region, `curve_points` are
/// the network's curve points (all in metres, the surface's frame).
pub fn compare_surface(
    surface: &SurfaceMesh,
    curve_points: &[Vec3],
    truth_distance: impl Fn(Vec3) -> f64,
    truth_region: &[Vec3],
    opts: &CompareOptions,
) -> Result<SurfaceComparison, CompareError> {
    if !(opts.sample_spacing_m.is_finite() && opts.sample_spacing_m > 0.0) {
        return Err(CompareError::BadOption("sample_spacing_m"));
    }
    if opts
        .region_margin_m
        .is_some_and(|m| !(m.is_finite() && m > 0.0))
    {
        return Err(CompareError::BadOption("region_margin_m"));
    }
    if truth_region.is_empty() {
        return Err(CompareError::EmptyRegion);
    }
    if truth_region.iter().any(|p| !p.is_finite()) {
        return Err(CompareError::NonFinite("drawn-region point"));
    }
    if curve_points.iter().any(|p| !p.is_finite()) {
        return Err(CompareError::NonFinite("curve point"));
    }
    let points = surface.positions();
    let triangles: Vec<[Vec3; 3]> = face_triangles(surface)?
        .iter()
        .map(|t| [points[t[0]], points[t[1]], points[t[2]]])
        .filter(|t| t.iter().all(|p| p.is_finite()))
        .collect();
    let area: f64 = triangles
        .iter()
        .map(|t| triangle_area(t[0], t[1], t[2]))
        .sum();
    if area.is_nan() || area <= 0.0 {
        return Err(CompareError::EmptySurface);
    }
    let spacing = opts
        .sample_spacing_m
        .max((area / opts.max_samples.max(1) as f64).sqrt());
    let mut samples = sample_triangles(&triangles, spacing, opts.seed);
    if let Some(margin) = opts.region_margin_m {
        let grid = PointGrid::new(truth_region, margin);
        samples.retain(|p| grid.any_within(*p));
    }
    if samples.is_empty() {
        return Err(CompareError::EmptySurface);
    }
    let mut to_truth: Vec<f64> = samples.iter().map(|&p| truth_distance(p)).collect();
    if to_truth.iter().any(|d| !d.is_finite()) {
        return Err(CompareError::NonFinite("truth distance"));
    }
    let bvh = TriangleBvh::new(triangles);
    let to_surface = |p: Vec3| bvh.closest(p).map_or(f64::INFINITY, |h| h.distance);
    let from_region: Vec<f64> = truth_region.iter().map(|&p| to_surface(p)).collect();
    let curve: Vec<f64> = curve_points.iter().map(|&p| to_surface(p)).collect();

    let rms_m = rms(&to_truth);
    to_truth.sort_by(|a, b| a.total_cmp(b));
    let rank = ((0.95 * to_truth.len() as f64).ceil() as usize).clamp(1, to_truth.len());
    let p95 = to_truth[rank - 1];
    let s_max = to_truth.last().copied().unwrap_or(0.0);
    let r_max = from_region.iter().copied().fold(0.0, f64::max);
    let (lo, hi) = crate::geometry::bounding_box(truth_region);
    let diag = (hi - lo).norm();
    if diag.is_nan() || diag <= 0.0 {
        return Err(CompareError::EmptyRegion);
    }
    let near = from_region
        .iter()
        .filter(|&&d| d <= COMPLETENESS_THRESHOLD_M)
        .count();
    Ok(SurfaceComparison {
        rms_mm: rms_m * 1e3,
        p95_mm: p95 * 1e3,
        hausdorff_mm: s_max.max(r_max) * 1e3,
        surface_to_truth_max_mm: s_max * 1e3,
        truth_to_surface_max_mm: r_max * 1e3,
        diag_mm: diag * 1e3,
        rms_pct_diag: 100.0 * rms_m / diag,
        completeness_3mm: near as f64 / truth_region.len() as f64,
        curve_rms_mm: (!curve.is_empty()).then(|| rms(&curve) * 1e3),
        surface_samples: samples.len(),
        region_samples: truth_region.len(),
    })
}
