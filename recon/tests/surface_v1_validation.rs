//! FIRESV1 against known surfaces (the FIRES thesis's validation, §7.2): a coarse quad mesh of a known
//! surface, polylines sampled on the surface along its edges, the network of these, reconstructed with V1
//! and compared with the surface (two-sided Hausdorff distance); and the surface's smoothness across the
//! drawn curves.

mod common;

use common::netgen::{network_from_polygons, parametric_network};
use fires_recon::network::Network;
use fires_recon::surface::{reconstruct_v1, ControlMesh, CurveKeeping, V1Options, VertexTag};
use fires_recon::Vec3;

fn v(p: [f64; 3]) -> Vec3 {
    Vec3::from_array(p)
}

use common::netgen::MeshDistance;
use std::f64::consts::{PI, TAU};

/// Two-sided Hausdorff distance between the reconstruction and a known surface: `dist` gives a point's
/// distance to the known surface, `truth` samples it densely.
fn hausdorff(s: &ControlMesh, dist: &dyn Fn(Vec3) -> f64, truth: &[Vec3]) -> (f64, f64) {
    let m = &s.mesh;
    let mut fwd: f64 = 0.0;
    for x in m.vertices() {
        fwd = fwd.max(dist(m.position(x)));
    }
    for f in m.faces() {
        let c = m
            .face_vertices(f)
            .map(|x| m.position(x))
            .fold(Vec3::ZERO, |a, p| a + p)
            / m.face_valence(f) as f64;
        fwd = fwd.max(dist(c));
    }
    let q = MeshDistance::new(m);
    let back = truth.iter().map(|&p| q.distance(p)).fold(0.0, f64::max);
    (fwd, back)
}

fn diag(pts: &[Vec3]) -> f64 {
    let lo = pts
        .iter()
        .fold(Vec3::new(f64::MAX, f64::MAX, f64::MAX), |a, p| {
            Vec3::new(a.x.min(p.x), a.y.min(p.y), a.z.min(p.z))
        });
    let hi = pts
        .iter()
        .fold(Vec3::new(f64::MIN, f64::MIN, f64::MIN), |a, p| {
            Vec3::new(a.x.max(p.x), a.y.max(p.y), a.z.max(p.z))
        });
    (hi - lo).norm()
}

fn grid_samples(f: &dyn Fn(f64, f64) -> [f64; 3], n: usize) -> Vec<Vec3> {
    (0..=n)
        .flat_map(|j| (0..=n).map(move |i| (i, j)))
        .map(|(i, j)| v(f(i as f64 / n as f64, j as f64 / n as f64)))
        .collect()
}

/// A cube's surface, `n × n` quads per side, outward, with its vertices pushed onto the sphere of radius
/// `r` and each edge's polyline the projection of the straight cube edge.
fn cube_sphere_network(n: usize, r: f64, samples: usize) -> Network {
    let mut index = std::collections::HashMap::new();
    let mut pts: Vec<[f64; 3]> = Vec::new();
    let lattice: Vec<[usize; 3]> = (0..=n)
        .flat_map(|i| (0..=n).flat_map(move |j| (0..=n).map(move |k| [i, j, k])))
        .filter(|p| p.iter().any(|&c| c == 0 || c == n))
        .collect();
    let cube_pt = |p: [usize; 3]| p.map(|c| c as f64 / n as f64 - 0.5);
    let project = move |q: [f64; 3]| {
        let l = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
        q.map(|c| c / l * r)
    };
    for p in &lattice {
        index.insert(*p, pts.len());
        pts.push(project(cube_pt(*p)));
    }
    let mut faces = Vec::new();
    for axis in 0..3 {
        let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in [0, n] {
            for i in 0..n {
                for j in 0..n {
                    let at = |di: usize, dj: usize| {
                        let mut p = [0; 3];
                        p[axis] = side;
                        p[a1] = i + di;
                        p[a2] = j + dj;
                        index[&p]
                    };
                    let mut q = vec![at(0, 0), at(1, 0), at(1, 1), at(0, 1)];
                    if side == 0 {
                        q.reverse();
                    }
                    faces.push(q);
                }
            }
        }
    }
    let lat = lattice.clone();
    network_from_polygons(
        &pts,
        &faces,
        move |a, b| {
            let (pa, pb) = (cube_pt(lat[a]), cube_pt(lat[b]));
            (0..=samples)
                .map(|k| {
                    let t = k as f64 / samples as f64;
                    project([0, 1, 2].map(|d| pa[d] + t * (pb[d] - pa[d])))
                })
                .collect()
        },
        |_, _| 0.0,
    )
}

#[test]
fn v1_reconstructs_known_surfaces_within_half_a_percent_of_the_diagonal() {
    let opts = V1Options::default();
    let mut report = Vec::new();
    // 1. A torus (genus 1): R = 0.1 m, r = 0.04 m, 8 × 6 coarse quads.
    let (rr, r) = (0.1, 0.04);
    let torus = move |s: f64, t: f64| {
        let (a, b) = (TAU * s, TAU * t);
        let rho = rr + r * b.cos();
        [rho * a.cos(), rho * a.sin(), r * b.sin()]
    };
    let net = parametric_network(&torus, 8, 6, (true, true), 16);
    let s = reconstruct_v1(&net, &opts).unwrap();
    let truth = grid_samples(&torus, 120);
    let d = |p: Vec3| (((p.x * p.x + p.y * p.y).sqrt() - rr).hypot(p.z) - r).abs();
    report.push((
        "torus 8x6",
        s.mesh.n_vertices(),
        hausdorff(&s, &d, &truth),
        diag(&truth),
    ));
    // 2. A sphere from a cube's 2 × 2-per-side quads (valence-3 corners), R = 0.08 m.
    let rs = 0.08;
    let net = cube_sphere_network(2, rs, 16);
    let s = reconstruct_v1(&net, &opts).unwrap();
    let truth: Vec<Vec3> = (0..=60)
        .flat_map(|j| (0..=120).map(move |i| (i, j)))
        .map(|(i, j)| {
            let (a, b) = (TAU * i as f64 / 120.0, PI * j as f64 / 60.0);
            Vec3::new(b.sin() * a.cos(), b.sin() * a.sin(), b.cos()) * rs
        })
        .collect();
    let d = |p: Vec3| (p.norm() - rs).abs();
    report.push((
        "cube-sphere 2x2x6",
        s.mesh.n_vertices(),
        hausdorff(&s, &d, &truth),
        diag(&truth),
    ));
    // 3. A bumpy height field with a boundary, 0.2 m square, 5 × 5 coarse quads.
    let h = |s: f64, t: f64| 0.02 * (TAU * s).sin() * (PI * t).cos() + 0.01 * (3.0 * PI * t).sin();
    let bumpy = move |s: f64, t: f64| [0.2 * s, 0.2 * t, h(s, t)];
    let net = parametric_network(&bumpy, 5, 5, (false, false), 16);
    let s = reconstruct_v1(&net, &opts).unwrap();
    let truth = grid_samples(&bumpy, 100);
    // Vertical gap: an upper bound of the distance to the height field.
    let d = |p: Vec3| (p.z - h(p.x / 0.2, p.y / 0.2)).abs();
    report.push((
        "bumpy grid 5x5",
        s.mesh.n_vertices(),
        hausdorff(&s, &d, &truth),
        diag(&truth),
    ));
    // 4. The torus again with pairs of quads merged into hexagons (triquadrification on a curved surface):
    // the hexagons' cuts come from Q''s Coons patch, not from the torus.
    let (ns, nt) = (8, 6);
    let at = |i: usize, j: usize| (i % ns) + ns * (j % nt);
    let mut faces = Vec::new();
    for j in 0..nt {
        for i in (0..ns).step_by(2) {
            faces.push(vec![
                at(i, j),
                at(i + 1, j),
                at(i + 2, j),
                at(i + 2, j + 1),
                at(i + 1, j + 1),
                at(i, j + 1),
            ]);
        }
    }
    let pts: Vec<[f64; 3]> = (0..ns * nt)
        .map(|k| torus((k % ns) as f64 / ns as f64, (k / ns) as f64 / nt as f64))
        .collect();
    let uv = |k: usize| ((k % ns) as f64 / ns as f64, (k / ns) as f64 / nt as f64);
    let net = network_from_polygons(
        &pts,
        &faces,
        |a, b| {
            let (pa, mut pb) = (uv(a), uv(b));
            if (pb.0 - pa.0).abs() > 0.5 {
                pb.0 += if pb.0 < pa.0 { 1.0 } else { -1.0 };
            }
            if (pb.1 - pa.1).abs() > 0.5 {
                pb.1 += if pb.1 < pa.1 { 1.0 } else { -1.0 };
            }
            (0..=16)
                .map(|k| {
                    let w = k as f64 / 16.0;
                    torus(pa.0 + w * (pb.0 - pa.0), pa.1 + w * (pb.1 - pa.1))
                })
                .collect()
        },
        |_, _| 0.0,
    );
    let s = reconstruct_v1(&net, &opts).unwrap();
    let truth = grid_samples(&torus, 120);
    let d = |p: Vec3| (((p.x * p.x + p.y * p.y).sqrt() - rr).hypot(p.z) - r).abs();
    report.push((
        "torus of hexagons",
        s.mesh.n_vertices(),
        hausdorff(&s, &d, &truth),
        diag(&truth),
    ));
    for (name, nv, (fwd, back), dg) in &report {
        let hd = fwd.max(*back);
        eprintln!(
            "{name}: {nv} vertices, Hausdorff {:.3} mm (surface→truth {:.3}, truth→surface {:.3}) = {:.3} % of the {:.1} mm diagonal",
            hd * 1e3,
            fwd * 1e3,
            back * 1e3,
            100.0 * hd / dg,
            dg * 1e3
        );
    }
    for (name, _, (fwd, back), dg) in &report {
        assert!(fwd.max(*back) <= 0.005 * dg, "{name}");
    }
}

/// The largest angle between the normals of two faces sharing an edge, across edges on drawn curves and
/// across all others.
fn dihedrals(s: &ControlMesh) -> (f64, f64) {
    let m = &s.mesh;
    let normal = |f| {
        let p: Vec<Vec3> = m.face_vertices(f).map(|x| m.position(x)).collect();
        (p[2] - p[0]).cross(p[3] - p[1]).normalize_or_zero()
    };
    let (mut on, mut off) = (0.0f64, 0.0f64);
    for e in m.edges() {
        let h = e.halfedge(0);
        let (Some(f0), Some(f1)) = (m.face(h), m.face(h.opposite())) else {
            continue;
        };
        let a = normal(f0)
            .dot(normal(f1))
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees();
        if s.span(e).is_some_and(|sp| !s.curves[sp.curve].generated) {
            on = on.max(a);
        } else {
            off = off.max(a);
        }
    }
    (on, off)
}

#[test]
fn v1_is_smooth_across_the_drawn_curves_and_stays_near_them() {
    let (rr, r) = (0.1, 0.04);
    let torus = move |s: f64, t: f64| {
        let (a, b) = (TAU * s, TAU * t);
        let rho = rr + r * b.cos();
        [rho * a.cos(), rho * a.sin(), r * b.sin()]
    };
    let net = parametric_network(&torus, 8, 6, (true, true), 16);
    let opts = V1Options {
        levels: 3,
        ..V1Options::default()
    };
    // Default (limit fit): the surface bends across the curves no more than between faces elsewhere.
    let s = reconstruct_v1(&net, &opts).unwrap();
    let (on, off) = dihedrals(&s);
    eprintln!("limit fit: max dihedral across drawn curves {on:.2}°, elsewhere {off:.2}°");
    assert!(
        on <= 1.5 * off,
        "a kink along the curves: {on}° against {off}°"
    );
    let mut dev: f64 = 0.0;
    for x in s.mesh.vertices() {
        if let VertexTag::OnCurve(p) = s.tag(x) {
            if !s.curves[p.curve].generated {
                dev = dev.max((s.mesh.position(x) - s.curves[p.curve].point_at(p.t)).norm());
            }
        }
    }
    eprintln!(
        "limit fit: curve vertices within {:.4} mm of their curves",
        dev * 1e3
    );
    assert!(dev <= 1e-4, "curve vertices {dev} m off their curves");
    // Snapping keeps the Coons patches' kink along the curves.
    let mut snap = opts;
    snap.catmull_clark.keep = CurveKeeping::Snap;
    let (on_s, off_s) = dihedrals(&reconstruct_v1(&net, &snap).unwrap());
    eprintln!("snap: max dihedral across drawn curves {on_s:.2}°, elsewhere {off_s:.2}°");
    assert!(on_s > 2.0 * off_s);
}
