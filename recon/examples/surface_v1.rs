//! FIRESV1 on a curve network: reads `network.json` (or generates a 50-face torus network), reconstructs
//! the surface, prints one JSON line with the sizes and timings, and optionally writes the surface.
//!
//! ```text
//! cargo run --release -p fires-recon --example surface_v1 -- [NETWORK.json|-] [OUT.obj|.ply|.off]
//! ```
//!
//! The timing is single-threaded (FIRESV1 runs on one thread) and reports the median of repeated runs:
//! `v1_ms` for the default V1 to the first subdivision level (about 3,000 vertices for 50 faces), and
//! `levels` for the subdivision of the refined mesh to K = 2, 3, 4 levels (NULISSmod, then Catmull-Clark with
//! the limit fit; one run each).

use std::f64::consts::TAU;
use std::time::Instant;

use fires_recon::io::{write_mesh_file, PolygonSoup};
use fires_recon::network::{Network, NetworkFile, PolylineAttrs};
use fires_recon::surface::{
    base_mesh, nuliss_mod, reconstruct_v1, refine, refined_v1, subdivide_v1, triquadrify, V1Options,
};
use serde_json::{json, Value};

/// A torus network: `ns × nt` quads, every edge's polyline `samples` segments sampled on the torus.
fn torus_network(
    ns: usize,
    nt: usize,
    samples: usize,
) -> Result<Network, Box<dyn std::error::Error>> {
    let (rr, r) = (0.1, 0.04);
    let at = |s: f64, t: f64| {
        let (a, b) = (TAU * s, TAU * t);
        let rho = rr + r * b.cos();
        [rho * a.cos(), rho * a.sin(), r * b.sin()]
    };
    let id = |i: usize, j: usize| (i % ns) + ns * (j % nt);
    let mut polylines = Vec::new();
    let mut edges: Vec<Value> = Vec::new();
    let mut vedges = vec![Vec::new(); ns * nt];
    let mut edge_of = std::collections::HashMap::new();
    let mut faces = Vec::new();
    let mut add_edge =
        |i: usize, j: usize, di: usize, dj: usize, edges: &mut Vec<Value>| -> usize {
            let (a, b) = (id(i, j), id(i + di, j + dj));
            *edge_of.entry((a, b)).or_insert_with(|| {
                let e = edges.len();
                let pts: Vec<[f64; 3]> = (0..=samples)
                    .map(|k| {
                        let w = k as f64 / samples as f64;
                        at(
                            (i as f64 + w * di as f64) / ns as f64,
                            (j as f64 + w * dj as f64) / nt as f64,
                        )
                    })
                    .collect();
                let mut rec = serde_json::to_value(PolylineAttrs::default()).unwrap_or(json!({}));
                rec["id"] = json!(e);
                rec["points"] = json!(pts);
                polylines.push(rec);
                edges.push(json!({"id": e, "from": a, "to": b, "polyline": e, "faces": []}));
                vedges[a].push(e);
                vedges[b].push(e);
                e
            })
        };
    for j in 0..nt {
        for i in 0..ns {
            let f = faces.len();
            // The loop (i,j) → (i+1,j) → (i+1,j+1) → (i,j+1): bottom, right forward; top, left backward.
            let uses = [
                (add_edge(i, j, 1, 0, &mut edges), false),
                (add_edge(i + 1, j, 0, 1, &mut edges), false),
                (add_edge(i, j + 1, 1, 0, &mut edges), true),
                (add_edge(i, j, 0, 1, &mut edges), true),
            ];
            for (e, _) in uses {
                if let Some(list) = edges[e]["faces"].as_array_mut() {
                    list.push(json!(f));
                }
            }
            let uses: Vec<Value> = uses
                .iter()
                .map(|&(e, rev)| json!({"edge": e, "reversed": rev}))
                .collect();
            faces.push(json!({"id": f, "edges": uses}));
        }
    }
    let mut file = serde_json::to_value(NetworkFile::from_network(&Network::new()))?;
    file["slots"] = json!([ns * nt, edges.len(), faces.len(), polylines.len()]);
    file["vertices"] = Value::Array(
        (0..ns * nt)
            .map(|k| json!({"id": k, "p": at((k % ns) as f64 / ns as f64, (k / ns) as f64 / nt as f64), "edges": vedges[k]}))
            .collect(),
    );
    file["polylines"] = Value::Array(polylines);
    file["edges"] = Value::Array(edges);
    file["faces"] = Value::Array(faces);
    Ok(serde_json::from_value::<NetworkFile>(file)?.to_network()?)
}

fn median_ms(mut f: impl FnMut(), runs: usize) -> f64 {
    let mut t: Vec<f64> = (0..runs)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let net = match args.first().map(String::as_str) {
        Some(path) if path != "-" => NetworkFile::parse(&std::fs::read_to_string(path)?)?,
        _ => torus_network(10, 5, 16)?,
    };
    let opts = V1Options {
        levels: 1,
        ..V1Options::default()
    };
    let surface = reconstruct_v1(&net, &opts)?;
    let v1_ms = median_ms(
        || {
            let _ = reconstruct_v1(&net, &opts);
        },
        21,
    );
    let refined = refined_v1(&net, &opts)?;
    let refine_ms = median_ms(
        || {
            let _ = refined_v1(&net, &opts);
        },
        21,
    );
    // Stage by stage.
    let base = base_mesh(&net)?;
    let tq = triquadrify(&base, &opts.triquad)?;
    let stages = json!({
        "base_mesh": median_ms(|| { let _ = base_mesh(&net); }, 21),
        "triquadrify": median_ms(|| { let _ = triquadrify(&base, &opts.triquad); }, 21),
        "refine": median_ms(|| { let _ = refine(&tq, &opts.refine); }, 21),
        "nuliss_mod": median_ms(|| { let _ = nuliss_mod(&refined, &opts.nuliss); }, 21),
    });
    // Further Catmull-Clark levels: the whole subdivision from the refined mesh to K = 2, 3, 4 levels.
    let mut levels = Vec::new();
    for k in 2..=4 {
        let o = V1Options { levels: k, ..opts };
        let s = Instant::now();
        let out = subdivide_v1(&refined, &o)?;
        levels.push(json!({"levels": k, "vertices": out.mesh.n_vertices(), "ms": s.elapsed().as_secs_f64() * 1e3}));
    }
    println!(
        "{}",
        json!({
            "method": "v1",
            "network_faces": net.n_faces(),
            "refined_vertices": refined.mesh.n_vertices(),
            "refine_ms": refine_ms,
            "vertices": surface.mesh.n_vertices(),
            "faces": surface.mesh.n_faces(),
            "v1_ms": v1_ms,
            "threads": 1,
            "stages_ms": stages,
            "levels": levels,
        })
    );
    if let Some(out) = args.get(1) {
        write_mesh_file(out, &PolygonSoup::from_mesh(&surface.mesh))?;
    }
    Ok(())
}
