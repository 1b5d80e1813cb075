//! Quality figures of the editing methods on generated meshes (issue 16): identity,
//! rigid covariance, exact rotation field, and detail preservation against naive editing.

mod edit_common;

use edit_common::*;
use fires_recon::edit::{
    detail_error, EditMethod, EditSession, EditSpec, LseEditor, LseOptions, NaiveLaplacian,
    PoissonEditor, Select, Similarity,
};
use fires_recon::edit::similarity::axis_angle;
use fires_recon::SurfaceMesh;

fn run<M: EditMethod>(mesh: &SurfaceMesh, spec: &EditSpec, opts: M::Options) -> Vec<fires_recon::Vec3> {
    let mut s = EditSession::<M>::new(mesh, spec, opts).expect("factor");
    s.solve_spec().expect("solve")
}

fn identity_check<M: EditMethod>(opts: M::Options) {
    let mesh = relief_cylinder();
    let out = run::<M>(&mesh, &twist_spec(0.0), opts);
    let err = max_dist(&out, mesh.positions()) / bbox_diag(mesh.positions());
    println!("{} identity error {err:e}", std::any::type_name::<M>());
    assert!(err < 1e-12, "identity moved the mesh by {err:e} of the bbox");
}

#[test]
fn identity_leaves_mesh_unchanged() {
    identity_check::<NaiveLaplacian>(Default::default());
    identity_check::<PoissonEditor>(Default::default());
    identity_check::<LseEditor>(Default::default());
    identity_check::<LseEditor>(LseOptions { refit_iterations: 2 });
}

#[test]
fn twist_detail_errors_beat_naive() {
    let mesh = relief_cylinder();
    let spec = twist_spec(90.0);
    let e = |x: &[fires_recon::Vec3]| detail_error(&mesh, x, None).unwrap();
    let naive = e(&run::<NaiveLaplacian>(&mesh, &spec, Default::default()));
    let poisson = e(&run::<PoissonEditor>(&mesh, &spec, Default::default()));
    let lse = e(&run::<LseEditor>(&mesh, &spec, Default::default()));
    let lse2 = e(&run::<LseEditor>(&mesh, &spec, LseOptions { refit_iterations: 2 }));
    println!("detail_error naive {naive:.4e} poisson {poisson:.4e} lse {lse:.4e} lse+refit {lse2:.4e}");
    assert!(poisson < naive);
    assert!(lse2 < naive);
}
