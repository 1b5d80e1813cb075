//! Catmull-Clark on control meshes: sharp rules, tag propagation, curve keeping, the known limit.

mod surface_common;

use fires_recon::geometry::Vec3;
use fires_recon::mesh::{SurfaceMesh, Vertex};
use fires_recon::surface::{
    catmull_clark, catmull_clark_n, limit_positions, CatmullClarkOptions, ControlMesh,
    CurveKeeping, VertexTag,
};
use surface_common::{control, cube, face_planarity, CurveSpec};

fn opts(keep: CurveKeeping) -> CatmullClarkOptions {
    CatmullClarkOptions {
        keep,
        ..Default::default()
    }
}

fn plain(mesh: SurfaceMesh) -> ControlMesh {
    let (ne, nv) = (mesh.edges_size(), mesh.vertices_size());
    ControlMesh {
        mesh,
        curves: vec![],
        edge_curve: vec![None; ne],
        vertex_tag: vec![VertexTag::Free; nv],
    }
}

#[test]
fn a_cube_with_all_edges_sharp_stays_a_cube_with_planar_faces() {
    for keep in [CurveKeeping::None, CurveKeeping::Snap, CurveKeeping::Limit] {
        let c = catmull_clark_n(&cube(true), 3, &opts(keep)).unwrap();
        assert_eq!(c.mesh.n_faces(), 6 * 64);
        for v in c.mesh.vertices() {
            let p = c.mesh.position(v);
            let m = p.x.abs().max(p.y.abs()).max(p.z.abs());
            assert!((m - 1.0).abs() < 1e-12, "{keep:?}: {p:?} off the cube");
        }
        for f in c.mesh.faces() {
            assert!(face_planarity(&c.mesh, f) < 1e-12, "{keep:?}");
        }
        // The corners stay put.
        for i in 0..8 {
            let p = c.mesh.position(Vertex::new(i));
            assert!(
                (p.x.abs() - 1.0).abs() + (p.y.abs() - 1.0).abs() + (p.z.abs() - 1.0).abs() < 1e-15
            );
        }
        // Every edge of the cube's edges is still sharp: 12 edges × 8 pieces.
        let sharp = c.mesh.edges().filter(|&e| c.is_sharp(e)).count();
        assert_eq!(sharp, 12 * 8, "{keep:?}");
    }
}

#[test]
fn a_smooth_cube_converges_to_the_known_limit_corner() {
    // Corner of the cube [-1, 1]³ (valence 3): limit (9v + 4Σe + Σf)/24 = (½, ½, ½) (Halstead et al. 1993).
    let mut c = plain(cube(false).mesh);
    let lim = limit_positions(&c, &CatmullClarkOptions::default());
    assert!((lim[7] - Vec3::new(0.5, 0.5, 0.5)).norm() < 1e-15);
    let mut errs = Vec::new();
    for _ in 0..7 {
        c = catmull_clark(&c, &opts(CurveKeeping::None)).unwrap();
        errs.push((c.mesh.position(Vertex::new(7)) - Vec3::new(0.5, 0.5, 0.5)).norm());
        // The limit stencil applied at any level gives the same limit point.
        let lim = limit_positions(&c, &CatmullClarkOptions::default());
        assert!((lim[7] - Vec3::new(0.5, 0.5, 0.5)).norm() < 1e-12);
    }
    for w in errs.windows(2) {
        assert!(w[1] < 0.7 * w[0], "{errs:?}");
    }
    assert!(errs[6] < 5e-3, "{errs:?}");
    // The face centres converge to the limit of the face centre by symmetry: on the axis.
    let f = (0..c.mesh.vertices_size())
        .map(|i| c.mesh.position(Vertex::new(i)))
        .filter(|p| p.x.abs() < 1e-12 && p.y.abs() < 1e-12 && p.z > 0.0)
        .count();
    assert_eq!(f, 1);
}

#[test]
fn any_polygons_in_quads_out_with_the_euler_counts() {
    let pts = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.5, 0.8, 0.1),
        Vec3::new(0.5, 1.4, 0.0),
        Vec3::new(-0.4, 0.8, 0.2),
        Vec3::new(0.5, -1.0, 0.0),
    ];
    let faces = vec![vec![0, 1, 2, 3, 4], vec![0, 5, 1]];
    let c = plain(SurfaceMesh::from_faces(&pts, &faces).unwrap());
    let (v, e, f) = (c.mesh.n_vertices(), c.mesh.n_edges(), c.mesh.n_faces());
    let d = catmull_clark(&c, &CatmullClarkOptions::default()).unwrap();
    assert_eq!(d.mesh.n_vertices(), v + e + f);
    assert_eq!(d.mesh.n_faces(), 5 + 3);
    assert!(d.mesh.faces().all(|f| d.mesh.face_valence(f) == 4));
    d.mesh.validate().unwrap();
}

/// A 4×2 grid of unit squares in z = 0 whose middle row line y = 1 is a curve bent by `bump`.
fn grid_with_curve(sharp: bool, bump: f64) -> ControlMesh {
    let (nx, ny) = (4usize, 2usize);
    let z = move |x: f64| bump * (std::f64::consts::PI * x / 4.0).sin();
    let mut pts = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let x = i as f64;
            pts.push(Vec3::new(x, j as f64, if j == 1 { z(x) } else { 0.0 }));
        }
    }
    let id = |i: usize, j: usize| j * (nx + 1) + i;
    let mut faces = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            faces.push(vec![id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let spec = CurveSpec {
        chain: (0..=nx).map(|i| id(i, 1)).collect(),
        seg: Box::new(move |k, s| {
            let x = k as f64 + s;
            Vec3::new(x, 1.0, z(x))
        }),
        samples: 64,
        sharp,
    };
    control(&pts, &faces, vec![spec])
}

#[test]
fn curve_edges_split_into_halved_spans_and_snapped_edge_points() {
    let c = grid_with_curve(false, 0.5);
    let d = catmull_clark(&c, &opts(CurveKeeping::Snap)).unwrap();
    let curve = &d.curves[0];
    let mut pieces = 0;
    for e in d.mesh.edges() {
        let Some(s) = d.span(e) else { continue };
        pieces += 1;
        let (a, b) = d.mesh.edge_vertices(e);
        assert!((d.mesh.position(a) - curve.point_at(s.t0)).norm() < 1e-12);
        assert!((d.mesh.position(b) - curve.point_at(s.t1)).norm() < 1e-12);
        assert!(((s.t1 - s.t0).abs() - curve.length() / 8.0).abs() < 0.02 * curve.length());
    }
    assert_eq!(pieces, 8);
    let on_curve = d
        .vertex_tag
        .iter()
        .filter(|t| matches!(t, VertexTag::OnCurve(_)))
        .count();
    assert_eq!(
        on_curve,
        3 + 4,
        "3 old interior curve vertices and 4 edge points"
    );
}

#[test]
fn a_crease_vertex_gets_the_one_six_one_rule_and_a_crease_edge_its_midpoint() {
    let c = grid_with_curve(true, 0.5);
    let d = catmull_clark(&c, &opts(CurveKeeping::None)).unwrap();
    let p = |i: usize| c.mesh.position(Vertex::new(i));
    // Vertex (2, 1) is index 7 with crease neighbours 6 and 8.
    let want = (p(6) + p(7) * 6.0 + p(8)) / 8.0;
    assert!((d.mesh.position(Vertex::new(7)) - want).norm() < 1e-15);
    let e = c.mesh.find_edge(Vertex::new(6), Vertex::new(7)).unwrap();
    let ep = d
        .mesh
        .position(Vertex::new(c.mesh.vertices_size() + e.idx()));
    assert!((ep - (p(6) + p(7)) * 0.5).norm() < 1e-15);
    // Snap keeps both on the curve instead.
    let s = catmull_clark(&c, &opts(CurveKeeping::Snap)).unwrap();
    assert!((s.mesh.position(Vertex::new(7)) - p(7)).norm() < 1e-15);
}

#[test]
fn limit_keeping_puts_the_limit_of_every_curve_vertex_on_the_curve() {
    let c = grid_with_curve(false, 0.5);
    let o = opts(CurveKeeping::Limit);
    let d = catmull_clark_n(&c, 2, &o).unwrap();
    let lim = limit_positions(&d, &o);
    let mut worst: f64 = 0.0;
    for v in d.mesh.vertices() {
        if let VertexTag::OnCurve(q) = d.tag(v) {
            // Interior curve vertices (the fit is exact there up to the Gauss-Seidel residual).
            worst = worst.max((lim[v.idx()] - d.curves[q.curve].point_at(q.t)).norm());
        }
    }
    assert!(worst < 2e-3, "limit off the curve by {worst}");
}

#[test]
fn the_smooth_curve_passes_through_the_samples_and_follows_a_circle_closer_than_the_polyline() {
    use fires_recon::surface::{smooth_point_at, Curve};
    let n = 16;
    let pts: Vec<Vec3> = (0..=n)
        .map(|k| {
            let a = std::f64::consts::FRAC_PI_2 * k as f64 / n as f64;
            Vec3::new(a.cos(), a.sin(), 0.0)
        })
        .collect();
    let c = Curve::new(pts.clone(), false);
    for (k, p) in pts.iter().enumerate() {
        assert!((smooth_point_at(&c, c.arc[k]) - *p).norm() < 1e-15);
    }
    let (mut lin, mut cub) = (0.0f64, 0.0f64);
    for k in 0..n {
        let t = 0.5 * (c.arc[k] + c.arc[k + 1]);
        lin = lin.max((c.point_at(t).norm() - 1.0).abs());
        cub = cub.max((smooth_point_at(&c, t).norm() - 1.0).abs());
    }
    // Chord sagitta (π/32)²/8 ≈ 1.2e-3; the cubic is two orders closer.
    assert!(lin > 1e-3 && cub < 2e-5, "{lin} {cub}");
}
