//! Measuring a surface against the truth: exact point-triangle distance, the BVH's exact nearest triangle,
//! and `compare_surface` on analytic cases (a grid against an offset plane, an inscribed sphere mesh).

use fires_recon::generate::{icosphere, plane_grid};
use fires_recon::geometry::{closest_point_on_triangle, TriangleBvh};
use fires_recon::surface::{compare_surface, CompareError, CompareOptions};
use fires_recon::{SurfaceMesh, Vec3};

/// A small deterministic generator for the test inputs.
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn point(&mut self, s: f64) -> Vec3 {
        Vec3::new(
            s * (2.0 * self.next() - 1.0),
            s * (2.0 * self.next() - 1.0),
            s * (2.0 * self.next() - 1.0),
        )
    }
}

#[test]
fn closest_point_on_triangle_matches_a_dense_barycentric_search() {
    let mut rng = Lcg(3);
    for case in 0..300 {
        let (a, b) = (rng.point(1.0), rng.point(1.0));
        // Every tenth triangle degenerate (collinear corners).
        let c = if case % 10 == 0 {
            a + (b - a) * 2.5
        } else {
            rng.point(1.0)
        };
        let p = rng.point(2.0);
        let q = closest_point_on_triangle(p, a, b, c);
        let d = (q - p).norm();
        // The point is on the triangle: its barycentric coordinates are in [0, 1] (non-degenerate case).
        let n = 400;
        let mut brute = f64::INFINITY;
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                brute = brute.min((a + (b - a) * u + (c - a) * v - p).norm());
            }
        }
        // The grid's spacing bounds how far above the minimum the brute force can be.
        let h = ((b - a).norm() + (c - a).norm()) / n as f64;
        assert!(d <= brute + 1e-12, "case {case}: {d} > brute {brute}");
        assert!(brute - d <= h, "case {case}: {d} far below brute {brute}");
    }
}

#[test]
fn the_bvh_finds_the_exact_nearest_triangle() {
    let mut rng = Lcg(5);
    let mesh = icosphere(3, 0.1);
    let pts: Vec<Vec3> = mesh
        .positions()
        .iter()
        .map(|&p| p * (1.0 + 0.05 * (rng.next() - 0.5)))
        .collect();
    let tris: Vec<[usize; 3]> = mesh
        .face_index_lists()
        .iter()
        .map(|f| [f[0], f[1], f[2]])
        .collect();
    let bvh = TriangleBvh::from_indexed(&pts, &tris);
    assert_eq!(bvh.len(), tris.len());
    for _ in 0..500 {
        let p = rng.point(0.15);
        let hit = bvh.closest(p).expect("non-empty");
        let brute = tris
            .iter()
            .map(|t| (closest_point_on_triangle(p, pts[t[0]], pts[t[1]], pts[t[2]]) - p).norm())
            .fold(f64::INFINITY, f64::min);
        assert_eq!(hit.distance, brute);
        assert!(((hit.point - p).norm() - hit.distance).abs() < 1e-15);
    }
    assert!(TriangleBvh::new(Vec::new()).closest(Vec3::ZERO).is_none());
    assert!(bvh.closest(Vec3::new(f64::NAN, 0.0, 0.0)).is_none());
}

/// A 100 mm x 80 mm grid in z = 0, and a drawn region on the plane z = d inside its footprint.
fn plane_case(d: f64) -> (SurfaceMesh, Vec<Vec3>) {
    let mesh = plane_grid(10, 8, 0.1, 0.08, true);
    let region: Vec<Vec3> = (0..=45)
        .flat_map(|i| {
            (0..=35).map(move |j| Vec3::new(0.005 + 0.002 * i as f64, 0.005 + 0.002 * j as f64, d))
        })
        .collect();
    (mesh, region)
}

#[test]
fn a_flat_grid_against_an_offset_plane_is_off_by_the_offset_exactly() {
    for d in [0.0005, 0.002, 0.004] {
        let (mesh, region) = plane_case(d);
        let curve: Vec<Vec3> = (0..=20)
            .map(|i| Vec3::new(0.005 * i as f64, 0.04, 0.0))
            .collect();
        let c = compare_surface(
            &mesh,
            &curve,
            |p| (p.z - d).abs(),
            &region,
            &CompareOptions::default(),
        )
        .unwrap();
        let dm = d * 1e3;
        for (name, v) in [
            ("rms", c.rms_mm),
            ("p95", c.p95_mm),
            ("hausdorff", c.hausdorff_mm),
            ("truth to surface", c.truth_to_surface_max_mm),
            ("surface to truth", c.surface_to_truth_max_mm),
        ] {
            assert!((v - dm).abs() < 1e-12, "{name}: {v} vs {dm}");
        }
        let diag = (0.09f64.powi(2) + 0.07f64.powi(2)).sqrt() * 1e3;
        assert!((c.diag_mm - diag).abs() < 1e-9, "{}", c.diag_mm);
        assert!((c.rms_pct_diag - 100.0 * dm / diag).abs() < 1e-9);
        assert_eq!(c.completeness_3mm, if d < 3e-3 { 1.0 } else { 0.0 });
        assert_eq!(c.curve_rms_mm, Some(0.0));
        // 1 mm spacing over 8000 mm^2: about 8000 samples.
        assert!(
            (c.surface_samples as f64 - 8000.0).abs() < 300.0,
            "{}",
            c.surface_samples
        );
        assert_eq!(c.region_samples, region.len());
    }
}

#[test]
fn an_inscribed_sphere_mesh_deviates_by_its_sagitta_and_converges_quadratically() {
    let r = 0.05;
    let mut previous: Option<f64> = None;
    for level in [2u32, 3, 4] {
        let mesh = icosphere(level, r);
        let pts = mesh.positions();
        // The faces lie inside the sphere; a face's farthest point from it is its circumcentre, at the
        // sagitta r - sqrt(r^2 - rc^2) (rc the circumradius).
        let sagitta = mesh
            .face_index_lists()
            .iter()
            .map(|f| {
                let (a, b, c) = (pts[f[0]], pts[f[1]], pts[f[2]]);
                let (la, lb, lc) = ((b - c).norm(), (c - a).norm(), (a - b).norm());
                let area = 0.5 * (b - a).cross(c - a).norm();
                let rc = la * lb * lc / (4.0 * area);
                r - (r * r - rc * rc).sqrt()
            })
            .fold(0.0, f64::max);
        // The drawn region: the cap z > 0.02 of the true sphere, 2 mm apart.
        let region: Vec<Vec3> = (-25..=25)
            .flat_map(|i| (-25..=25).map(move |j| (0.002 * i as f64, 0.002 * j as f64)))
            .filter_map(|(x, y)| {
                let z2 = r * r - x * x - y * y;
                (z2 > 0.02 * 0.02).then(|| Vec3::new(x, y, z2.sqrt()))
            })
            .collect();
        let opts = CompareOptions {
            sample_spacing_m: 0.5e-3,
            ..Default::default()
        };
        let c = compare_surface(&mesh, &[], |p| (p.norm() - r).abs(), &region, &opts).unwrap();
        let s = sagitta * 1e3;
        assert!(c.surface_to_truth_max_mm <= s + 1e-12, "{c:?} vs {s}");
        assert!(c.surface_to_truth_max_mm >= 0.9 * s, "{c:?} vs {s}");
        assert!(c.truth_to_surface_max_mm <= s + 1e-12);
        assert!(c.rms_mm < s && c.p95_mm <= s + 1e-12);
        assert_eq!(c.completeness_3mm, 1.0);
        assert_eq!(c.curve_rms_mm, None);
        if let Some(prev) = previous {
            // Halving the edge length quarters the deviation.
            let ratio = prev / c.rms_mm;
            assert!((3.5..4.5).contains(&ratio), "level {level}: ratio {ratio}");
        }
        previous = Some(c.rms_mm);
    }
}

#[test]
fn the_region_margin_keeps_only_the_surface_over_the_drawn_region() {
    let (mesh, region) = plane_case(0.0);
    // The truth is the plane z = 0 except that it says the part x > 0.095 is 5 mm off: outside the drawn
    // region (x <= 0.095), so a margin of 1 mm leaves it out.
    let truth = |p: Vec3| if p.x > 0.096 { 0.005 } else { p.z.abs() };
    let all = compare_surface(&mesh, &[], truth, &region, &CompareOptions::default()).unwrap();
    assert!(all.hausdorff_mm > 4.9);
    let opts = CompareOptions {
        region_margin_m: Some(1e-3),
        ..Default::default()
    };
    let near = compare_surface(&mesh, &[], truth, &region, &opts).unwrap();
    assert!(near.hausdorff_mm < 1e-9, "{}", near.hausdorff_mm);
    assert!(near.surface_samples < all.surface_samples);
}

#[test]
fn bad_inputs_are_typed_errors() {
    let (mesh, region) = plane_case(0.001);
    let opts = CompareOptions::default();
    let d = |p: Vec3| p.z.abs();
    assert!(matches!(
        compare_surface(&mesh, &[], d, &[], &opts),
        Err(CompareError::EmptyRegion)
    ));
    assert!(matches!(
        compare_surface(&mesh, &[], d, &region[..1], &opts),
        Err(CompareError::EmptyRegion)
    ));
    assert!(matches!(
        compare_surface(&SurfaceMesh::new(), &[], d, &region, &opts),
        Err(CompareError::EmptySurface)
    ));
    assert!(matches!(
        compare_surface(&mesh, &[], |_| f64::NAN, &region, &opts),
        Err(CompareError::NonFinite(_))
    ));
    assert!(matches!(
        compare_surface(&mesh, &[Vec3::new(f64::NAN, 0.0, 0.0)], d, &region, &opts),
        Err(CompareError::NonFinite(_))
    ));
    for bad in [
        CompareOptions {
            sample_spacing_m: 0.0,
            ..opts
        },
        CompareOptions {
            region_margin_m: Some(-1.0),
            ..opts
        },
    ] {
        assert!(matches!(
            compare_surface(&mesh, &[], d, &region, &bad),
            Err(CompareError::BadOption(_))
        ));
    }
    // A sample cap widens the spacing instead of running away.
    let capped = CompareOptions {
        max_samples: 100,
        ..opts
    };
    let c = compare_surface(&mesh, &[], d, &region, &capped).unwrap();
    assert!(c.surface_samples <= 130, "{}", c.surface_samples);
}
