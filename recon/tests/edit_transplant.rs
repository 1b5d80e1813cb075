//! Transplanting a patch onto a closed surface (Sorkine et al. 2004 §6).

use fires_recon::edit::detail_error;
use fires_recon::edit::transplant::{transplant, TransplantSpec};
use fires_recon::generate::icosphere;
use fires_recon::{SurfaceMesh, Vec3};

/// The faces of `mesh` whose vertices all satisfy `keep`, compacted into a new mesh.
fn submesh(mesh: &SurfaceMesh, keep: impl Fn(Vec3) -> bool) -> SurfaceMesh {
    let x = mesh.positions();
    let mut map = vec![usize::MAX; x.len()];
    let mut pts = Vec::new();
    let mut faces = Vec::new();
    for f in mesh.face_index_lists() {
        if f.iter().all(|&v| keep(x[v])) {
            faces.push(
                f.iter()
                    .map(|&v| {
                        if map[v] == usize::MAX {
                            map[v] = pts.len();
                            pts.push(x[v]);
                        }
                        map[v]
                    })
                    .collect::<Vec<_>>(),
            );
        }
    }
    SurfaceMesh::from_faces(&pts, &faces).unwrap()
}

#[test]
fn transplanted_bump_is_watertight() {
    let target = icosphere(3, 1.0);
    // A finer, bumpier cap registered over the north pole.
    let mut patch = submesh(&icosphere(4, 1.0), |p| p.z > 0.93);
    for p in patch.positions_mut() {
        let r = (p.x * p.x + p.y * p.y).sqrt();
        *p = *p * (1.0 + 0.15 * (1.0 - r / 0.37).max(0.0));
    }
    let rest_patch = patch.clone();
    let spec = TransplantSpec::from_json(
        r#"{"region": {"sphere": {"center": [0, 0, 1], "radius": 0.3}}, "transition_rings": 2}"#,
    )
    .unwrap();
    let out = transplant(&target, &patch, &spec).unwrap();
    assert!(out.mesh.is_closed(), "result has a boundary");
    assert!(out.mesh.validate().is_ok());
    assert_eq!(out.mesh.euler_characteristic(), 2);
    assert!(out.seam_faces > 0);
    assert!(out.mesh.positions().iter().all(|p| p.is_finite()));
    let x: Vec<Vec3> = out
        .patch_vertices
        .iter()
        .map(|&v| out.mesh.positions()[v])
        .collect();
    let e = detail_error(&rest_patch, &x, None).unwrap();
    println!(
        "transplant: {} seam triangles, patch detail_error {e:.3e}",
        out.seam_faces
    );
    assert!(e < 0.05);
    assert!(TransplantSpec::from_json(r#"{"region": "all", "rings": 2}"#).is_err());
}
