//! Mesh files: bit-exact round trips and hostile input.

use std::io::Cursor;

use fires_recon::generate::{cube, icosphere, torus};
use fires_recon::io::*;
use fires_recon::Vec3;

fn awkward_soup() -> PolygonSoup {
    let mut s = PolygonSoup::from_mesh(&torus(2.0, 0.5, 7, 5, true));
    for (k, p) in s.points.iter_mut().enumerate() {
        let k = k as f64;
        *p = Vec3::new(
            p.x + 0.1 + 0.2,
            p.y * 1e-300 + k * 1e-17,
            -p.z * 123456.789e10 + 1.0 / 3.0,
        );
    }
    s
}

fn bits(s: &PolygonSoup) -> Vec<[u64; 3]> {
    s.points
        .iter()
        .map(|p| p.to_array().map(f64::to_bits))
        .collect()
}

#[test]
fn text_and_binary_formats_round_trip_bit_exactly() {
    let soup = awkward_soup();
    let check = |back: PolygonSoup| {
        assert_eq!(bits(&back), bits(&soup));
        assert_eq!(back.face_starts, soup.face_starts);
        assert_eq!(back.indices, soup.indices);
    };
    let mut buf = Vec::new();
    write_off(&mut buf, &soup).unwrap();
    check(read_off(Cursor::new(&buf)).unwrap());
    buf.clear();
    write_obj(&mut buf, &soup).unwrap();
    check(read_obj(Cursor::new(&buf)).unwrap());
    for enc in [PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian] {
        buf.clear();
        write_ply(&mut buf, &soup, enc).unwrap();
        check(read_ply(Cursor::new(&buf)).unwrap());
    }
}

#[test]
fn stl_round_trips_f32_coordinates_and_welds_vertices() {
    let mut soup = PolygonSoup::from_mesh(&icosphere(2, 1.0));
    for p in &mut soup.points {
        *p = Vec3::from_array(p.to_array().map(|c| c as f32 as f64));
    }
    for enc in [StlEncoding::Ascii, StlEncoding::Binary] {
        let mut buf = Vec::new();
        write_stl(&mut buf, &soup, enc).unwrap();
        let back = read_stl(Cursor::new(&buf)).unwrap();
        // Welding numbers vertices by first use: compare sorted coordinates and each face's corners.
        let (mut a, mut b) = (bits(&back), bits(&soup));
        a.sort_unstable();
        b.sort_unstable();
        assert!(a == b, "{enc:?}: coordinates differ");
        for (fb, fs) in back.faces().zip(soup.faces()) {
            for (ib, is) in fb.iter().zip(fs) {
                assert_eq!(
                    back.points[*ib].to_array().map(f64::to_bits),
                    soup.points[*is].to_array().map(f64::to_bits)
                );
            }
        }
        back.to_mesh().unwrap().validate().unwrap();
    }
    // Quads are fan-triangulated.
    let mut buf = Vec::new();
    write_stl(
        &mut buf,
        &PolygonSoup::from_mesh(&cube(1.0, true)),
        StlEncoding::Binary,
    )
    .unwrap();
    assert_eq!(read_stl(Cursor::new(&buf)).unwrap().n_faces(), 12);
}

#[test]
fn files_on_disk_dispatch_by_extension() {
    let dir = std::env::temp_dir().join(format!("fires-recon-io-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let soup = awkward_soup();
    for ext in ["off", "obj", "ply"] {
        let path = dir.join(format!("m.{ext}"));
        write_mesh_file(&path, &soup).unwrap();
        assert_eq!(bits(&read_mesh_file(&path).unwrap()), bits(&soup));
    }
    assert!(matches!(
        read_mesh_file(dir.join("m.xyz")),
        Err(IoError::UnsupportedFormat(_))
    ));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn committed_sample_files_parse() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data");
    let quad = read_mesh_file(format!("{dir}/quad_cube.off")).unwrap();
    assert_eq!((quad.points.len(), quad.n_faces()), (8, 6));
    quad.to_mesh().unwrap().validate().unwrap();
    let tet = read_mesh_file(format!("{dir}/tetra_big_endian.ply")).unwrap();
    assert_eq!((tet.points.len(), tet.n_faces()), (4, 4));
    assert_eq!(tet.points[1], Vec3::new(1.0, 0.0, 0.0));
}

fn err<T: std::fmt::Debug>(r: Result<T, IoError>) -> String {
    r.unwrap_err().to_string()
}

#[test]
fn hostile_inputs_give_errors_not_panics() {
    // OFF: huge counts, truncation, NaN, index out of range, bad header.
    assert!(err(read_off(Cursor::new("OFF\n4000000000 1 0\n"))).contains("exceeds"));
    assert!(err(read_off(Cursor::new("OFF\n3 1 0\n0 0 0\n1 0 0\n"))).contains("line 5"));
    assert!(err(read_off(Cursor::new(
        "OFF\n3 1 0\n0 0 NaN\n1 0 0\n0 1 0\n3 0 1 2\n"
    )))
    .contains("line 3"));
    assert!(err(read_off(Cursor::new(
        "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n"
    )))
    .contains("out of range"));
    assert!(err(read_off(Cursor::new(
        "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n99999999 0 1 2\n"
    )))
    .contains("face degree"));
    assert!(read_off(Cursor::new("PLY\n")).is_err());
    assert!(read_off(Cursor::new("")).is_err());
    // OBJ.
    assert!(err(read_obj(Cursor::new(
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"
    )))
    .contains("out of range"));
    assert!(err(read_obj(Cursor::new("v 0 0 0\nf -5 1 1\n"))).contains("line 2"));
    assert!(err(read_obj(Cursor::new("v 0 inf 0\n"))).contains("non-finite"));
    let soup = read_obj(Cursor::new(
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf -3/1 -2/1/1 -1//1\n",
    ))
    .unwrap();
    assert_eq!(soup.face(0), &[0, 1, 2]);
    // PLY: huge count with no data, truncated binary, bad list length, bad index.
    let head = "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    let e = err(read_ply(Cursor::new(head.as_bytes().to_vec())));
    assert!(
        e.contains("truncated") && e.contains(&format!("byte {}", head.len())),
        "{e}"
    );
    let head = "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\nelement face 1\nproperty list int int vertex_indices\nend_header\n";
    let mut b = head.as_bytes().to_vec();
    b.extend_from_slice(&(-1i32).to_le_bytes());
    assert!(err(read_ply(Cursor::new(b))).contains("list length"));
    let ascii = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n3 0 0 5\n";
    assert!(err(read_ply(Cursor::new(ascii))).contains("out of range"));
    assert!(read_ply(Cursor::new("ply\nformat ascii 1.0\nelement vertex 1\n")).is_err());
    let empty = "ply\nformat binary_little_endian 1.0\nelement face 1000000000\nend_header\n";
    assert!(err(read_ply(Cursor::new(empty))).contains("no properties"));
    assert!(read_ply(Cursor::new(
        "ply\nformat ascii 1.0\nelement vertex 99999999999999999999\nend_header\n"
    ))
    .is_err());
    // STL: truncated binary, absurd count.
    let mut stl = vec![0u8; 80];
    stl.extend_from_slice(&u32::MAX.to_le_bytes());
    assert!(err(read_stl(Cursor::new(stl.clone()))).contains("exceeds"));
    stl[80..84].copy_from_slice(&10u32.to_le_bytes());
    stl.extend_from_slice(&[0u8; 60]);
    assert!(err(read_stl(Cursor::new(stl))).contains("byte 134"));
    assert!(read_stl(Cursor::new(
        "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nendloop\n"
    ))
    .is_err());
    // Very long line.
    let long = format!("OFF\n{}\n", "1".repeat(2 << 20));
    assert!(err(read_off(Cursor::new(long))).contains("too long"));
    // Non-manifold soup is rejected when building the mesh.
    let s = read_off(Cursor::new(
        "OFF\n5 3 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n3 0 1 2\n3 1 0 3\n3 0 1 4\n",
    ))
    .unwrap();
    assert!(matches!(s.to_mesh(), Err(IoError::Mesh(_))));
}

#[test]
fn matrix_market_round_trip() {
    let m = fires_recon::operators::cotan_matrix(&icosphere(1, 1.0)).unwrap();
    let mut buf = Vec::new();
    write_matrix_market_lower(&mut buf, &m).unwrap();
    let back = read_matrix_market(Cursor::new(&buf)).unwrap();
    assert_eq!(back.symmetry, MtxSymmetry::Symmetric);
    let full = back.full().unwrap();
    assert_eq!(full.to_dense(), m.to_dense());
    assert!(read_matrix_market(Cursor::new("%%MatrixMarket matrix array real general\n")).is_err());
    assert!(read_matrix_market(Cursor::new(
        "%%MatrixMarket matrix coordinate real symmetric\n2 2 1\n3 1 1.0\n"
    ))
    .is_err());
}
