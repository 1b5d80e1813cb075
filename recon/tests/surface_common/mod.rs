//! Generated control meshes for the surface tests: polygons whose edges follow densely sampled curves.
#![allow(dead_code)]

use fires_recon::geometry::Vec3;
use fires_recon::mesh::{SurfaceMesh, Vertex};
use fires_recon::surface::{ControlMesh, Curve, CurvePoint, CurveSpan, VertexTag};
use std::f64::consts::PI;

/// One curve of a generated network: the chain of mesh vertices it runs through, the function sampling
/// it between consecutive chain vertices (`seg(k, s)`, `s ∈ [0, 1]`, `k` the segment), samples per
/// segment, and its crease flag.
pub struct CurveSpec<'a> {
    /// Mesh vertex indices along the curve.
    pub chain: Vec<usize>,
    /// The curve's point on segment `k` at `s ∈ [0, 1]`.
    pub seg: Box<dyn Fn(usize, f64) -> Vec3 + 'a>,
    /// Samples per segment (≥ 1).
    pub samples: usize,
    /// Crease flag.
    pub sharp: bool,
}

/// A control mesh from polygons and curves: each curve's chain edges get spans, chain interiors are
/// `OnCurve`, chain ends and vertices on two curves are `Corner`.
pub fn control(points: &[Vec3], faces: &[Vec<usize>], specs: Vec<CurveSpec<'_>>) -> ControlMesh {
    let mesh = SurfaceMesh::from_faces(points, faces).expect("valid polygons");
    let mut edge_curve = vec![None; mesh.edges_size()];
    let mut vertex_tag = vec![VertexTag::Free; mesh.vertices_size()];
    let mut curves = Vec::new();
    for (ci, spec) in specs.into_iter().enumerate() {
        let mut pts = Vec::new();
        for k in 0..spec.chain.len() - 1 {
            for j in 0..spec.samples {
                pts.push((spec.seg)(k, j as f64 / spec.samples as f64));
            }
        }
        pts.push((spec.seg)(spec.chain.len() - 2, 1.0));
        // Knot k sits at sample k * samples.
        let curve = Curve::new(pts, spec.sharp);
        let t_at = |k: usize| curve.arc[k * spec.samples];
        for k in 0..spec.chain.len() - 1 {
            let (a, b) = (Vertex::new(spec.chain[k]), Vertex::new(spec.chain[k + 1]));
            let e = mesh.find_edge(a, b).expect("curve runs along mesh edges");
            let (t0, t1) = if mesh.edge_vertices(e).0 == a {
                (t_at(k), t_at(k + 1))
            } else {
                (t_at(k + 1), t_at(k))
            };
            edge_curve[e.idx()] = Some(CurveSpan { curve: ci, t0, t1 });
        }
        let n = spec.chain.len();
        let closed = spec.chain[0] == spec.chain[n - 1];
        for (k, &v) in spec.chain.iter().enumerate() {
            let end = (k == 0 || k == n - 1) && !closed;
            vertex_tag[v] = match vertex_tag[v] {
                VertexTag::Free if !end => VertexTag::OnCurve(CurvePoint {
                    curve: ci,
                    t: t_at(k),
                }),
                _ => VertexTag::Corner,
            };
        }
        curves.push(curve);
    }
    ControlMesh {
        mesh,
        curves,
        edge_curve,
        vertex_tag,
    }
}

/// The cube `[-1, 1]³` as six quads, every edge a straight curve (sharp or not).
pub fn cube(sharp: bool) -> ControlMesh {
    let points: Vec<Vec3> = (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            )
        })
        .collect();
    let faces = cube_faces();
    let mesh = SurfaceMesh::from_faces(&points, &faces).unwrap();
    let specs = mesh
        .edges()
        .map(|e| {
            let (a, b) = mesh.edge_vertices(e);
            let (pa, pb) = (points[a.idx()], points[b.idx()]);
            CurveSpec {
                chain: vec![a.idx(), b.idx()],
                seg: Box::new(move |_, s| pa * (1.0 - s) + pb * s),
                samples: 1,
                sharp,
            }
        })
        .collect();
    control(&points, &faces, specs)
}

/// The six outward quads of the cube with vertex `i` at the signs of its bits (x = bit 0, ...).
pub fn cube_faces() -> Vec<Vec<usize>> {
    vec![
        vec![0, 2, 3, 1],
        vec![4, 5, 7, 6],
        vec![0, 1, 5, 4],
        vec![2, 6, 7, 3],
        vec![0, 4, 6, 2],
        vec![1, 3, 7, 5],
    ]
}

/// Largest distance of a face's vertices from their least-squares plane (via the face normal of Newell's
/// method through the centroid).
pub fn face_planarity(mesh: &SurfaceMesh, f: fires_recon::mesh::Face) -> f64 {
    let pts: Vec<Vec3> = mesh.face_vertices(f).map(|v| mesh.position(v)).collect();
    let c = pts.iter().fold(Vec3::ZERO, |s, &p| s + p) / pts.len() as f64;
    let mut n = Vec3::ZERO;
    for k in 0..pts.len() {
        let (a, b) = (pts[k] - c, pts[(k + 1) % pts.len()] - c);
        n += a.cross(b);
    }
    let n = n.normalize_or_zero();
    pts.iter()
        .map(|&p| (p - c).dot(n).abs())
        .fold(0.0, f64::max)
}

/// The unit normal of a face (Newell).
pub fn face_normal(mesh: &SurfaceMesh, f: fires_recon::mesh::Face) -> Vec3 {
    let pts: Vec<Vec3> = mesh.face_vertices(f).map(|v| mesh.position(v)).collect();
    let mut n = Vec3::ZERO;
    for k in 0..pts.len() {
        n += pts[k].cross(pts[(k + 1) % pts.len()]);
    }
    n.normalize_or_zero()
}

/// Two quads folded along the sharp curve y = 1: z = a·|y − 1| over [0, 3] × [0, 2], the other curves bowed
/// in their half's plane (x only), so the patches are not trivially flat.
pub fn folded_sheet(a: f64) -> ControlMesh {
    let p = move |x: f64, y: f64| Vec3::new(x, y, a * (y - 1.0).abs());
    let pts = vec![
        p(0., 0.),
        p(3., 0.),
        p(0., 1.),
        p(3., 1.),
        p(0., 2.),
        p(3., 2.),
    ];
    let faces = vec![vec![0, 1, 3, 2], vec![2, 3, 5, 4]];
    let curve = |i: usize, j: usize, sharp: bool| {
        let (pa, pb) = (pts[i], pts[j]);
        CurveSpec {
            chain: vec![i, j],
            seg: Box::new(move |_, s| {
                let q = pa * (1.0 - s) + pb * s;
                let bow = if pa.x == pb.x {
                    0.2 * (PI * s).sin()
                } else {
                    0.0
                };
                Vec3::new(q.x + bow, q.y, q.z)
            }),
            samples: 32,
            sharp,
        }
    };
    let specs = vec![
        curve(0, 1, false),
        curve(4, 5, false),
        curve(2, 3, true),
        curve(0, 2, false),
        curve(2, 4, false),
        curve(1, 3, false),
        curve(3, 5, false),
    ];
    control(&pts, &faces, specs)
}

/// The octahedron network of three orthogonal great circles of radius `r`: 6 vertices, 12 quarter arcs
/// (sampled 64 times each), 8 triangular faces.
pub fn sphere_network(r: f64) -> ControlMesh {
    let pts = vec![
        Vec3::new(r, 0.0, 0.0),
        Vec3::new(-r, 0.0, 0.0),
        Vec3::new(0.0, r, 0.0),
        Vec3::new(0.0, -r, 0.0),
        Vec3::new(0.0, 0.0, r),
        Vec3::new(0.0, 0.0, -r),
    ];
    let faces = vec![
        vec![0, 2, 4],
        vec![2, 1, 4],
        vec![1, 3, 4],
        vec![3, 0, 4],
        vec![2, 0, 5],
        vec![1, 2, 5],
        vec![3, 1, 5],
        vec![0, 3, 5],
    ];
    let mesh = SurfaceMesh::from_faces(&pts, &faces).unwrap();
    let specs = mesh
        .edges()
        .map(|e| {
            let (a, b) = mesh.edge_vertices(e);
            let (pa, pb) = (pts[a.idx()], pts[b.idx()]);
            CurveSpec {
                chain: vec![a.idx(), b.idx()],
                seg: Box::new(move |_, s| {
                    let th = s * std::f64::consts::FRAC_PI_2;
                    pa * th.cos() + pb * th.sin()
                }),
                samples: 64,
                sharp: false,
            }
        })
        .collect();
    control(&pts, &faces, specs)
}
