//! A cheap, deterministic stand-in for the cargo-fuzz targets that runs in CI: valid files
//! of every format are truncated and have bytes flipped, and every reader must return
//! (Ok or Err) without panicking.

use std::io::Cursor;

use fires_recon::generate::{icosphere, torus};
use fires_recon::io::*;

/// xorshift64*: a tiny deterministic generator.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

fn samples() -> Vec<(&'static str, Vec<u8>)> {
    let soup = PolygonSoup::from_mesh(&icosphere(1, 1.0));
    let quads = PolygonSoup::from_mesh(&torus(2.0, 0.5, 5, 4, true));
    let mut out = Vec::new();
    let mut b = Vec::new();
    write_off(&mut b, &quads).unwrap();
    out.push(("off", std::mem::take(&mut b)));
    write_obj(&mut b, &soup).unwrap();
    out.push(("obj", std::mem::take(&mut b)));
    write_ply(&mut b, &soup, PlyEncoding::Ascii).unwrap();
    out.push(("ply", std::mem::take(&mut b)));
    write_ply(&mut b, &quads, PlyEncoding::BinaryLittleEndian).unwrap();
    out.push(("ply", std::mem::take(&mut b)));
    write_stl(&mut b, &soup, StlEncoding::Ascii).unwrap();
    out.push(("stl", std::mem::take(&mut b)));
    write_stl(&mut b, &soup, StlEncoding::Binary).unwrap();
    out.push(("stl", std::mem::take(&mut b)));
    let m = fires_recon::operators::cotan_matrix(&icosphere(0, 1.0)).unwrap();
    write_matrix_market_lower(&mut b, &m).unwrap();
    out.push(("mtx", std::mem::take(&mut b)));
    out
}

fn read_any(kind: &str, data: &[u8]) {
    let c = Cursor::new(data);
    let soup = match kind {
        "off" => read_off(c),
        "obj" => read_obj(c),
        "ply" => read_ply(c),
        "stl" => read_stl(c),
        _ => {
            if let Ok(m) = read_matrix_market(c) {
                let _ = m.lower_triangle();
            }
            return;
        }
    };
    if let Ok(s) = soup {
        if let Ok(mesh) = s.to_mesh() {
            mesh.validate().unwrap();
        }
        // Readers check indices, so the repairing build always succeeds and validates.
        let (mesh, _) = s.to_mesh_repaired().unwrap();
        mesh.validate().unwrap();
    }
}

#[test]
fn truncated_and_mutated_files_never_panic() {
    let interesting: &[u8] = b"0123456789 -+.eE\n\r\t/#nNaAiIfF\xff\x00\x7f";
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    for (kind, data) in samples() {
        for cut in (0..data.len()).step_by(data.len() / 97 + 1) {
            read_any(kind, &data[..cut]);
        }
        for _ in 0..300 {
            let mut d = data.clone();
            for _ in 0..1 + rng.below(4) {
                let at = rng.below(d.len());
                d[at] = if rng.below(2) == 0 {
                    interesting[rng.below(interesting.len())]
                } else {
                    rng.next() as u8
                };
            }
            read_any(kind, &d);
        }
    }
}
