//! Quality figures of the editing methods on generated meshes (issue 16): identity,
//! rigid covariance, exact rotation field, and detail preservation against naive editing.

mod edit_common;

use edit_common::*;
use fires_recon::edit::similarity::axis_angle;
use fires_recon::edit::{
    detail_error, EditMethod, EditProblem, EditSession, EditSpec, ImplicitEditor, LseEditor,
    LseOptions, NaiveLaplacian, PoissonEditor, Similarity,
};
use fires_recon::{SurfaceMesh, Vec3};

fn run<M: EditMethod>(mesh: &SurfaceMesh, spec: &EditSpec, opts: M::Options) -> Vec<Vec3> {
    let mut s = EditSession::<M>::new(mesh, spec, opts).expect("factor");
    s.solve_spec().expect("solve")
}

fn identity_check<M: EditMethod>(opts: M::Options) {
    let mesh = relief_cylinder();
    let out = run::<M>(&mesh, &twist_spec(0.0), opts);
    let err = max_dist(&out, mesh.positions()) / bbox_diag(mesh.positions());
    assert!(
        err < 1e-12,
        "{}: identity moved the mesh by {err:e} of the bbox",
        std::any::type_name::<M>()
    );
}

#[test]
fn identity_leaves_mesh_unchanged() {
    identity_check::<NaiveLaplacian>(Default::default());
    identity_check::<PoissonEditor>(Default::default());
    identity_check::<LseEditor>(Default::default());
    identity_check::<LseEditor>(LseOptions {
        refit_iterations: 2,
    });
    identity_check::<ImplicitEditor>(Default::default());
}

/// Moving mesh, anchors and handles by one rigid motion moves the result by it.
fn rigid_check<M: EditMethod>(opts: M::Options) {
    let mesh = relief_cylinder();
    let spec = twist_spec(60.0);
    let mut s = EditSession::<M>::new(&mesh, &spec, opts.clone()).unwrap();
    let t = s.spec_transforms();
    // A second handle-like move: also translate the top ring.
    let t: Vec<Similarity> = t
        .iter()
        .map(|x| Similarity {
            translate: Vec3::new(0.3, -0.2, 0.4),
            ..*x
        })
        .collect();
    let a = s.move_handles(&t).unwrap();
    let g = Similarity::rigid(
        axis_angle(Vec3::new(0.3, -0.5, 0.8), 137.0).unwrap(),
        Vec3::new(2.0, -1.0, 5.0),
    );
    let mut moved = mesh.clone();
    for p in moved.positions_mut() {
        *p = g.apply(*p);
    }
    let mut s2 = EditSession::<M>::new(&moved, &spec, opts).unwrap();
    let t2: Vec<Similarity> = t.iter().map(|x| x.conjugate_by(&g)).collect();
    let b = s2.move_handles(&t2).unwrap();
    let ga: Vec<Vec3> = a.iter().map(|p| g.apply(*p)).collect();
    let err = max_dist(&ga, &b) / bbox_diag(&b);
    assert!(
        err < 1e-9,
        "{}: rigid covariance error {err:e}",
        std::any::type_name::<M>()
    );
}

#[test]
fn rigid_motion_of_the_problem_moves_the_result_rigidly() {
    rigid_check::<NaiveLaplacian>(Default::default());
    rigid_check::<PoissonEditor>(Default::default());
    rigid_check::<LseEditor>(LseOptions {
        refit_iterations: 1,
    });
    rigid_check::<ImplicitEditor>(Default::default());
}

#[test]
fn poisson_with_exact_rotation_field_is_rigid() {
    let mesh = relief_cylinder();
    let spec = twist_spec(0.0);
    let problem = EditProblem::new(&mesh, &spec).unwrap();
    let mut s = EditSession::<PoissonEditor>::new(&mesh, &spec, Default::default()).unwrap();
    let g = Similarity::rigid(
        axis_angle(Vec3::new(0.2, 0.9, 0.1), 120.0).unwrap(),
        Vec3::new(1.0, 2.0, -3.0),
    );
    let maps = vec![g.linear(); problem.faces.len()];
    let targets: Vec<Vec3> = problem.rest.iter().map(|p| g.apply(*p)).collect();
    let out = s
        .method_mut()
        .solve_with_face_maps(&problem, &maps, &targets)
        .unwrap();
    let err = max_dist(&out, &targets) / bbox_diag(&targets);
    assert!(err < 1e-9, "rotation field error {err:e}");
}

#[test]
fn twist_detail_errors_beat_naive() {
    let mesh = relief_cylinder();
    let spec = twist_spec(90.0);
    let e = |x: &[Vec3]| detail_error(&mesh, x, None).unwrap();
    let naive = e(&run::<NaiveLaplacian>(&mesh, &spec, Default::default()));
    let poisson = e(&run::<PoissonEditor>(&mesh, &spec, Default::default()));
    let lse = e(&run::<LseEditor>(&mesh, &spec, Default::default()));
    let lse2 = e(&run::<LseEditor>(
        &mesh,
        &spec,
        LseOptions {
            refit_iterations: 2,
        },
    ));
    let implicit = e(&run::<ImplicitEditor>(&mesh, &spec, Default::default()));
    println!(
        "detail_error naive {naive:.4e} poisson {poisson:.4e} lse {lse:.4e} \
         lse+2 refits {lse2:.4e} implicit {implicit:.4e}"
    );
    assert!(poisson < naive);
    assert!(lse2 < naive);
    assert!(implicit < naive);
}

#[test]
fn lse_affine_basis_equals_the_solve() {
    let mesh = relief_cylinder();
    let spec = twist_spec(0.0);
    let p = EditProblem::new(&mesh, &spec).unwrap();
    let lse = LseEditor::factor(&p, &LseOptions::default()).unwrap();
    let mut lse_solve = lse.clone();
    let basis = lse.precompute_basis(&p).unwrap();
    let t = vec![Similarity {
        scale: 1.3,
        rotation: axis_angle(Vec3::new(0.1, 0.4, 1.0), 50.0).unwrap(),
        about: Vec3::new(0.0, 0.0, 4.0),
        translate: Vec3::new(0.2, 0.1, -0.3),
    }];
    let a = basis.combine(&p, &t).unwrap();
    let b = lse_solve.solve(&p, &t).unwrap();
    assert!(max_dist(&a, &b) / bbox_diag(&b) < 1e-10);
}

/// Implicit editing's drag from its affine basis against the drag by one solve: two
/// handles (one fixing its gradient) on the relief cylinder, and a flat patch whose every
/// interior vertex is degenerate (displaced, then pulled back).
#[test]
fn implicit_drag_basis_equals_the_solve() {
    use fires_recon::edit::{HandleSpec, ImplicitOptions, Select, TransformSpec};
    use fires_recon::generate::plane_grid;
    let mut spec = twist_spec(0.0);
    let mut middle =
        HandleSpec::with_transform(Select::Vertices(ring(20)), TransformSpec::default());
    middle.fix_gradient = true;
    spec.handles.push(middle);
    let flat = plane_grid(8, 8, 1.0, 1.0, false);
    let flat_spec = EditSpec::from_json(
        r#"{"roi": {"box": {"min": [0.1, 0.1, -1], "max": [0.9, 0.9, 1]}},
            "handles": [{"select": {"sphere": {"center": [0.5, 0.5, 0], "radius": 0.01}},
                         "fix_gradient": true}]}"#,
    )
    .unwrap();
    for (mesh, spec) in [(relief_cylinder(), spec), (flat, flat_spec)] {
        let p = EditProblem::new(&mesh, &spec).unwrap();
        let plain = ImplicitOptions {
            drag_basis: false,
            ..Default::default()
        };
        let mut by_solve = ImplicitEditor::factor(&p, &plain).unwrap();
        let mut by_basis = ImplicitEditor::factor(&p, &Default::default()).unwrap();
        assert!(by_basis.drag_basis_ms() > 0.0 && by_solve.drag_basis_ms() == 0.0);
        for k in 0..3 {
            let t: Vec<Similarity> = (0..p.handles.len())
                .map(|h| Similarity {
                    scale: 1.0 + 0.1 * (k + h) as f64,
                    rotation: axis_angle(
                        Vec3::new(0.1, 0.4 + h as f64, 1.0),
                        20.0 * (k + 1) as f64,
                    )
                    .unwrap(),
                    about: p.handles[h].centroid,
                    translate: Vec3::new(0.05 * k as f64, -0.1, 0.2 * h as f64),
                })
                .collect();
            let a = by_basis.solve_drag(&p, &t).unwrap();
            let b = by_solve.solve_drag(&p, &t).unwrap();
            let moved = max_dist(&b, &p.rest);
            assert!(moved > 1e-2 * bbox_diag(&b), "the move moves the mesh");
            assert!(max_dist(&a, &b) / bbox_diag(&b) < 1e-10, "move {k}");
            // The release solves from the drag's gradients either way.
            let a = by_basis.solve_release(&p, &t).unwrap();
            let b = by_solve.solve_release(&p, &t).unwrap();
            assert!(max_dist(&a, &b) / bbox_diag(&b) < 1e-10, "release {k}");
        }
    }
}
