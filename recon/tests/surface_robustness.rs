//! Surfaces from networks built from noisy tracked strokes: a network the webcam tracker made (the default
//! demo scenario, seed 4, 60 s; `tests/data/tracked_webcam_network.json`) has faces that fold back on
//! themselves. Neither method may return a surface far outside the network: FIRESV2 either stays within the
//! network's extent or refuses with a typed error (its flow once returned a surface 30 m across), and
//! FIRESV1, which solves nothing, always gives one near its curves.

use fires_recon::geometry::{bounding_box, Vec3};
use fires_recon::network::NetworkFile;
use fires_recon::surface::{reconstruct_v1, reconstruct_v2, SurfaceError, V1Options, V2Options};

#[test]
fn a_tracked_network_with_folded_faces_gives_a_bounded_surface_or_a_typed_error() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/tracked_webcam_network.json"
    ))
    .unwrap();
    let net = NetworkFile::parse(&text).unwrap();
    assert!(net.n_faces() >= 1);
    let points: Vec<Vec3> = net
        .polylines()
        .flat_map(|(_, p)| p.points.iter().map(|q| Vec3::new(q[0], q[1], q[2])))
        .collect();
    let (lo, hi) = bounding_box(&points);
    let diag = (hi - lo).norm();
    let within = |p: &Vec3| {
        let d = |x: f64, l: f64, h: f64| (l - x).max(0.0).max(x - h);
        Vec3::new(d(p.x, lo.x, hi.x), d(p.y, lo.y, hi.y), d(p.z, lo.z, hi.z)).norm() <= diag
    };
    match reconstruct_v2(&net, &V2Options::default()) {
        Ok(s) => assert!(
            s.mesh.positions().iter().all(within),
            "V2 left the network's extent"
        ),
        Err(SurfaceError::Degenerate(why)) => assert!(why.contains("diverged"), "{why}"),
        Err(e) => panic!("unexpected error: {e}"),
    }
    let v1 =
        reconstruct_v1(&net, &V1Options::default()).expect("V1 solves nothing and cannot diverge");
    assert!(v1.mesh.positions().iter().all(within));
}
