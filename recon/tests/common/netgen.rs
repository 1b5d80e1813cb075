//! Curve networks built from generated polygon meshes: one network vertex per mesh vertex, one edge per
//! mesh edge (its polyline sampled from a caller's curve), one face per polygon (same orientation).

#![allow(dead_code)]

use std::collections::HashMap;

use fires_recon::mesh::SurfaceMesh;
use fires_recon::network::{Network, NetworkFile, PolylineAttrs};
use fires_recon::Vec3;
use serde_json::{json, Value};

/// The network of polygons `faces` over `points`; `polyline(a, b)` gives the points of the edge from
/// vertex `a` to vertex `b` (`a < b`; its ends are set to the two positions) and `sharpness(a, b)` its
/// sharpness.
pub fn network_from_polygons(
    points: &[[f64; 3]],
    faces: &[Vec<usize>],
    polyline: impl Fn(usize, usize) -> Vec<[f64; 3]>,
    sharpness: impl Fn(usize, usize) -> f64,
) -> Network {
    let mut edge_of: HashMap<(usize, usize), usize> = HashMap::new();
    let mut edges: Vec<Value> = Vec::new();
    let mut polylines: Vec<Value> = Vec::new();
    let mut vedges: Vec<Vec<usize>> = vec![Vec::new(); points.len()];
    let mut frecs = Vec::new();
    for (fi, f) in faces.iter().enumerate() {
        let mut uses = Vec::new();
        for k in 0..f.len() {
            let (a, b) = (f[k], f[(k + 1) % f.len()]);
            let key = (a.min(b), a.max(b));
            let ei = *edge_of.entry(key).or_insert_with(|| {
                let id = edges.len();
                let mut pts = polyline(key.0, key.1);
                pts[0] = points[key.0];
                let n = pts.len();
                pts[n - 1] = points[key.1];
                let attrs = PolylineAttrs {
                    sharpness: sharpness(key.0, key.1),
                    ..PolylineAttrs::default()
                };
                let mut rec = serde_json::to_value(attrs).unwrap();
                rec["id"] = json!(id);
                rec["points"] = json!(pts);
                polylines.push(rec);
                edges.push(
                    json!({"id": id, "from": key.0, "to": key.1, "polyline": id, "faces": []}),
                );
                vedges[key.0].push(id);
                vedges[key.1].push(id);
                id
            });
            edges[ei]["faces"].as_array_mut().unwrap().push(json!(fi));
            uses.push(json!({"edge": ei, "reversed": a > b}));
        }
        frecs.push(json!({"id": fi, "edges": uses}));
    }
    let mut file = serde_json::to_value(NetworkFile::from_network(&Network::new())).unwrap();
    file["slots"] = json!([points.len(), edges.len(), faces.len(), polylines.len()]);
    file["vertices"] = Value::Array(
        points
            .iter()
            .enumerate()
            .map(|(i, p)| json!({"id": i, "p": p, "edges": vedges[i]}))
            .collect(),
    );
    file["polylines"] = Value::Array(polylines);
    file["edges"] = Value::Array(edges);
    file["faces"] = Value::Array(frecs);
    let file: NetworkFile = serde_json::from_value(file).unwrap();
    file.to_network().expect("generated network is valid")
}

/// Straight polyline from `a` to `b` with `n` segments.
pub fn straight(a: [f64; 3], b: [f64; 3], n: usize) -> Vec<[f64; 3]> {
    (0..=n)
        .map(|i| {
            let t = i as f64 / n as f64;
            [
                a[0] + t * (b[0] - a[0]),
                a[1] + t * (b[1] - a[1]),
                a[2] + t * (b[2] - a[2]),
            ]
        })
        .collect()
}

/// A coarse quad grid over a parametric surface `f(s, t)`, (s, t) in [0, 1]², `ns × nt` quads (wrapped in
/// s and/or t when `wrap`), its network with every edge's polyline sampled from `f` along the straight
/// parameter segment (`samples` segments per edge).
pub fn parametric_network(
    f: &dyn Fn(f64, f64) -> [f64; 3],
    ns: usize,
    nt: usize,
    wrap: (bool, bool),
    samples: usize,
) -> Network {
    let (cs, ct) = (
        if wrap.0 { ns } else { ns + 1 },
        if wrap.1 { nt } else { nt + 1 },
    );
    let idx = |i: usize, j: usize| (i % cs) + cs * (j % ct);
    let mut uv = Vec::new();
    let mut pts = Vec::new();
    for j in 0..ct {
        for i in 0..cs {
            let (s, t) = (i as f64 / ns as f64, j as f64 / nt as f64);
            uv.push((s, t));
            pts.push(f(s, t));
        }
    }
    let mut faces = Vec::new();
    for j in 0..nt {
        for i in 0..ns {
            faces.push(vec![
                idx(i, j),
                idx(i + 1, j),
                idx(i + 1, j + 1),
                idx(i, j + 1),
            ]);
        }
    }
    // Parameters of each edge's ends, unwrapped so the segment is short.
    let uv2 = uv.clone();
    network_from_polygons(
        &pts,
        &faces,
        move |a, b| {
            let (pa, mut pb) = (uv2[a], uv2[b]);
            let step = (1.0 / ns as f64, 1.0 / nt as f64);
            if (pb.0 - pa.0).abs() > 1.5 * step.0 {
                pb.0 += if pb.0 < pa.0 { 1.0 } else { -1.0 };
            }
            if (pb.1 - pa.1).abs() > 1.5 * step.1 {
                pb.1 += if pb.1 < pa.1 { 1.0 } else { -1.0 };
            }
            (0..=samples)
                .map(|k| {
                    let w = k as f64 / samples as f64;
                    f(pa.0 + w * (pb.0 - pa.0), pa.1 + w * (pb.1 - pa.1))
                })
                .collect()
        },
        |_, _| 0.0,
    )
}

/// Closest distance from `p` to the triangle `a, b, c` (Ericson, *Real-Time Collision Detection*, §5.1.5).
pub fn point_triangle_distance(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> f64 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.norm();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return bp.norm();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let t = d1 / (d1 - d3);
        return (a + ab * t - p).norm();
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return cp.norm();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let t = d2 / (d2 - d6);
        return (a + ac * t - p).norm();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * t - p).norm();
    }
    let denom = 1.0 / (va + vb + vc);
    let (vv, ww) = (vb * denom, vc * denom);
    (a + ab * vv + ac * ww - p).norm()
}

/// Distances from points to a polygon mesh's surface (fan-triangulated faces), through a uniform grid of
/// the triangles' boxes.
pub struct MeshDistance {
    tris: Vec<[Vec3; 3]>,
    cell: f64,
    grid: HashMap<(i64, i64, i64), Vec<usize>>,
}

impl MeshDistance {
    /// The distance query of `mesh`.
    pub fn new(mesh: &SurfaceMesh) -> Self {
        let mut tris = Vec::new();
        for f in mesh.faces() {
            let p: Vec<Vec3> = mesh.face_vertices(f).map(|v| mesh.position(v)).collect();
            for k in 1..p.len() - 1 {
                tris.push([p[0], p[k], p[k + 1]]);
            }
        }
        let mean_edge =
            mesh.edges().map(|e| mesh.edge_length(e)).sum::<f64>() / mesh.n_edges() as f64;
        let cell = 2.0 * mean_edge;
        let mut grid: HashMap<(i64, i64, i64), Vec<usize>> = HashMap::new();
        let key = |x: f64| (x / cell).floor() as i64;
        for (i, t) in tris.iter().enumerate() {
            let lo = [0, 1, 2].map(|d| t.iter().map(|p| p[d]).fold(f64::INFINITY, f64::min));
            let hi = [0, 1, 2].map(|d| t.iter().map(|p| p[d]).fold(f64::NEG_INFINITY, f64::max));
            for x in key(lo[0])..=key(hi[0]) {
                for y in key(lo[1])..=key(hi[1]) {
                    for z in key(lo[2])..=key(hi[2]) {
                        grid.entry((x, y, z)).or_default().push(i);
                    }
                }
            }
        }
        MeshDistance { tris, cell, grid }
    }

    /// The distance from `p` to the surface (exact within one grid cell, else a brute-force search).
    pub fn distance(&self, p: Vec3) -> f64 {
        let c = [p.x, p.y, p.z].map(|x| (x / self.cell).floor() as i64);
        let mut best = f64::INFINITY;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = self.grid.get(&(c[0] + dx, c[1] + dy, c[2] + dz)) {
                        for &i in list {
                            let [a, b, cc] = self.tris[i];
                            best = best.min(point_triangle_distance(p, a, b, cc));
                        }
                    }
                }
            }
        }
        if best <= self.cell {
            return best;
        }
        self.tris
            .iter()
            .map(|t| point_triangle_distance(p, t[0], t[1], t[2]))
            .fold(f64::INFINITY, f64::min)
    }
}
