//! Stress of the repairing reader: generated meshes with shuffled orientations, merged
//! vertices (bow-ties, non-manifold edges, repeated corners), random polygons, duplicate
//! and dropped faces, unreferenced vertices. Nothing may panic; every result must be a
//! valid halfedge mesh that keeps the file's vertex indices and accounts for every face;
//! the Laplacian benchmark either runs or names degenerate triangles.

use fires_recon::bench::{bench_laplacian, BenchError};
use fires_recon::generate::{cube, icosphere, plane_grid, torus, uv_sphere};
use fires_recon::io::{read_mesh_file_repaired, write_mesh_file, PolygonSoup};
use fires_recon::mesh::{mesh_info, RepairOptions, SurfaceMesh, Vertex};
use fires_recon::operators::cotan_matrix;
use fires_recon::Vec3;

/// SplitMix64: a small deterministic generator (seeded per case).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn chance(&mut self, p: f64) -> bool {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64 <= p
    }
}

fn base(rng: &mut Rng) -> SurfaceMesh {
    match rng.below(6) {
        0 => icosphere(1, 1.0),
        1 => torus(
            2.0,
            0.6,
            8 + rng.below(6),
            5 + rng.below(4),
            rng.chance(0.5),
        ),
        2 => uv_sphere(6 + rng.below(6), 4 + rng.below(4), 1.0, rng.chance(0.5)),
        3 => plane_grid(
            3 + rng.below(5),
            2 + rng.below(5),
            2.0,
            1.0,
            rng.chance(0.5),
        ),
        4 => cube(1.0, rng.chance(0.5)),
        _ => icosphere(0, 1.0),
    }
}

fn random_case(seed: u64) -> (Vec<Vec3>, Vec<Vec<usize>>) {
    let mut rng = Rng(seed);
    let soup = PolygonSoup::from_mesh(&base(&mut rng));
    let mut pts = soup.points.clone();
    let mut faces: Vec<Vec<usize>> = soup.faces().map(<[usize]>::to_vec).collect();
    let n = pts.len();
    let p_flip = [0.0, 0.1, 0.5][rng.below(3)];
    for f in &mut faces {
        if rng.chance(p_flip) {
            f.reverse();
        }
    }
    // Merge vertex pairs: bow-ties, non-manifold edges, repeated corners.
    for _ in 0..rng.below(4) {
        let (a, b) = (rng.below(n), rng.below(n));
        for f in &mut faces {
            for v in f.iter_mut() {
                if *v == b {
                    *v = a;
                }
            }
        }
    }
    // Random polygons (repeats allowed), duplicates, drops, unreferenced vertices.
    for _ in 0..rng.below(4) {
        let k = 3 + rng.below(5);
        faces.push((0..k).map(|_| rng.below(n)).collect());
    }
    for _ in 0..rng.below(3) {
        let mut f = faces[rng.below(faces.len())].clone();
        if rng.chance(0.5) {
            f.reverse();
        }
        faces.push(f);
    }
    faces.retain(|_| !rng.chance(0.05));
    for _ in 0..rng.below(3) {
        pts.push(Vec3::new(rng.below(7) as f64, 0.5, -1.0));
    }
    // Shuffle the face order.
    for i in (1..faces.len()).rev() {
        faces.swap(i, rng.below(i + 1));
    }
    (pts, faces)
}

#[test]
fn repairing_reader_survives_random_damage() {
    let dir = std::env::temp_dir().join(format!("fires-stress-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (mut ran, mut named_degenerate) = (0, 0);
    for seed in 0..400u64 {
        let (pts, faces) = random_case(seed);
        let (m, r) = SurfaceMesh::from_polygons_repaired(
            &pts,
            faces.iter().map(Vec::as_slice),
            &RepairOptions::default(),
        )
        .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        m.validate().unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        assert_eq!(
            m.n_faces(),
            faces.len() - r.degenerate_faces_removed - r.duplicate_faces_removed,
            "seed {seed}"
        );
        assert_eq!(
            m.n_vertices(),
            pts.len() + r.vertex_copies_added,
            "seed {seed}"
        );
        for (i, p) in pts.iter().enumerate() {
            assert_eq!(m.position(Vertex::new(i)), *p, "seed {seed}");
        }
        for (k, &v) in r.vertex_source.iter().enumerate() {
            assert_eq!(
                m.position(Vertex::new(pts.len() + k)),
                pts[v],
                "seed {seed}"
            );
        }
        // Each mesh face is its source face up to rotation and reversal, with copies
        // mapped back to their originals.
        let original = |v: usize| {
            if v < pts.len() {
                v
            } else {
                r.vertex_source[v - pts.len()]
            }
        };
        for (f, &src) in m.faces().zip(&r.face_source) {
            let mut a: Vec<usize> = m.face_vertices(f).map(|v| original(v.idx())).collect();
            let mut b = faces[src].clone();
            b.dedup();
            while b.len() > 1 && b.first() == b.last() {
                b.pop();
            }
            a.sort_unstable();
            b.sort_unstable();
            assert_eq!(a, b, "seed {seed}");
        }
        let info = mesh_info(&m, &r);
        assert_eq!(info.faces, m.n_faces());
        assert!(cotan_matrix(&m).is_ok(), "seed {seed}");
        // Through a file and the benchmark.
        let path = dir.join(format!("s{seed}.off"));
        let mut soup = PolygonSoup::new();
        soup.points = pts.clone();
        for f in &faces {
            soup.push_face(f);
        }
        write_mesh_file(&path, &soup).unwrap();
        let (m2, r2) = read_mesh_file_repaired(&path).unwrap();
        assert_eq!((m2.n_faces(), r2), (m.n_faces(), r.clone()), "seed {seed}");
        match bench_laplacian(&path, 0, 1) {
            Ok(_) => ran += 1,
            Err(BenchError::DegenerateTriangles { .. }) => {
                // Only where the read report already saw zero-area faces.
                assert!(r.zero_area_faces > 0, "seed {seed}");
                named_degenerate += 1
            }
            Err(e) => panic!("seed {seed}: {e}"),
        }
        std::fs::remove_file(&path).ok();
    }
    eprintln!("stress: {ran} ran, {named_degenerate} named degenerate triangles");
    assert!(ran > 300);
}
