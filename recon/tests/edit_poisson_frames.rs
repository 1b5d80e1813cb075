//! Poisson editing's boundary-condition editing with local frames (issue 16 item 3; Yu et
//! al. 2004, §3.3 and §4.1): handles given as explicit positions, their per-vertex frame
//! changes, and their propagation.

mod edit_common;

use edit_common::*;
use fires_recon::edit::similarity::axis_angle;
use fires_recon::edit::{
    detail_error, EditError, EditMethod, EditProblem, EditSession, EditSpec, HandleSpec,
    ImplicitEditor, LseEditor, NaiveLaplacian, PoissonEditor, PoissonOptions, RotateSpec, Select,
    Similarity, TransformSpec,
};
use fires_recon::{SurfaceMesh, Vec3};

fn run<M: EditMethod>(mesh: &SurfaceMesh, spec: &EditSpec, opts: M::Options) -> Vec<Vec3> {
    let mut s = EditSession::<M>::new(mesh, spec, opts).expect("factor");
    s.solve_spec().expect("solve")
}

/// Rings `from..=to` of the relief cylinder.
fn rings(from: usize, to: usize) -> Vec<usize> {
    (from..=to).flat_map(ring).collect()
}

/// ROI = all, anchors = bottom ring, one handle.
fn spec_with(handle: HandleSpec) -> EditSpec {
    EditSpec {
        roi: Select::All,
        anchors: Some(Select::Vertices(ring(0))),
        anchor_weight: 1.0,
        handles: vec![handle],
    }
}

/// The handle moved to `f(rest)`, positions in the listed order.
fn positions_handle(mesh: &SurfaceMesh, verts: &[usize], f: impl Fn(Vec3) -> Vec3) -> HandleSpec {
    let pos = verts
        .iter()
        .map(|&v| f(mesh.positions()[v]).to_array())
        .collect();
    HandleSpec::with_positions(Select::Vertices(verts.to_vec()), pos)
}

fn similarity_transform() -> TransformSpec {
    TransformSpec {
        scale: Some(1.2),
        rotate: Some(RotateSpec {
            axis: [0.3, 0.2, 1.0],
            deg: 70.0,
        }),
        about: None,
        translate: Some([0.2, -0.1, 0.5]),
    }
}

/// The analytic bend of the cylinder's axis into a quarter circle in the xz-plane: height `z`
/// goes to the angle `φ = θ z / H` and the cross-section turns with it.
fn bend(p: Vec3, theta_deg: f64) -> Vec3 {
    let h = CYL.1;
    let theta = theta_deg.to_radians();
    let rho = h / theta;
    let phi = theta * p.z / h;
    let (s, c) = phi.sin_cos();
    Vec3::new(rho * (1.0 - c) + p.x * c, p.y, rho * s - p.x * s)
}

/// ROI-wide relative distance.
fn rel(a: &[Vec3], b: &[Vec3]) -> f64 {
    max_dist(a, b) / bbox_diag(b)
}

#[test]
fn positions_of_a_similarity_reproduce_the_transform_edit() {
    let mesh = relief_cylinder();
    for verts in [ring(CYL.3 - 1), rings(CYL.3 - 3, CYL.3 - 1)] {
        let by_transform = spec_with(HandleSpec::with_transform(
            Select::Vertices(verts.clone()),
            similarity_transform(),
        ));
        let t = EditProblem::new(&mesh, &by_transform)
            .unwrap()
            .spec_transforms[0];
        // Listed in reverse: the positions follow the listed order.
        let mut listed = verts.clone();
        listed.reverse();
        let by_positions = spec_with(positions_handle(&mesh, &listed, |p| t.apply(p)));
        let p = EditProblem::new(&mesh, &by_positions).unwrap();
        let fit = p.spec_transforms[0];
        assert!(
            (fit.scale - 1.2).abs() < 1e-12,
            "fitted scale {}",
            fit.scale
        );
        assert!(fit.rotation.angle_to(&t.rotation) < 1e-12);
        let shape = p.handles[0].shape.as_ref().unwrap();
        for &(dq, dls) in &shape.frames {
            assert!(dq.angle() < 1e-12 && dls.abs() < 1e-12, "{dq:?} {dls}");
        }
        let a = run::<PoissonEditor>(&mesh, &by_transform, Default::default());
        let b = run::<PoissonEditor>(&mesh, &by_positions, Default::default());
        let err = rel(&b, &a);
        println!(
            "{} handle vertices: poisson positions vs transform {err:.3e}",
            verts.len()
        );
        assert!(err < 1e-9, "poisson: positions vs transform {err:e}");
        // The other methods read the same targets.
        let naive = rel(
            &run::<NaiveLaplacian>(&mesh, &by_positions, Default::default()),
            &run::<NaiveLaplacian>(&mesh, &by_transform, Default::default()),
        );
        let lse = rel(
            &run::<LseEditor>(&mesh, &by_positions, Default::default()),
            &run::<LseEditor>(&mesh, &by_transform, Default::default()),
        );
        let implicit = rel(
            &run::<ImplicitEditor>(&mesh, &by_positions, Default::default()),
            &run::<ImplicitEditor>(&mesh, &by_transform, Default::default()),
        );
        assert!(
            naive < 1e-9 && lse < 1e-9 && implicit < 1e-9,
            "{naive:e} {lse:e} {implicit:e}"
        );
    }
}

#[test]
fn frames_from_a_rigid_motion_of_the_roi_are_its_rotation_field() {
    // The whole ROI moves by g; the handle (the top ring, a curve, and the top three rings,
    // a region) is given as g of its rest positions. Its per-vertex frame changes are g's
    // rotation, and that field over the ROI with every constraint moved by g reproduces g.
    let mesh = relief_cylinder();
    let g = Similarity::rigid(
        axis_angle(Vec3::new(0.2, 0.9, 0.1), 120.0).unwrap(),
        Vec3::new(1.0, 2.0, -3.0),
    );
    for verts in [ring(CYL.3 - 1), rings(CYL.3 - 3, CYL.3 - 1)] {
        let spec = spec_with(positions_handle(&mesh, &verts, |p| g.apply(p)));
        let problem = EditProblem::new(&mesh, &spec).unwrap();
        let s = EditSession::<PoissonEditor>::new(&mesh, &spec, Default::default()).unwrap();
        let vt = s
            .method()
            .vertex_transforms(&problem, &problem.spec_transforms);
        let h = &problem.handles[0];
        let mut worst = 0.0f64;
        for &l in &h.vertices {
            worst = worst.max(vt[l].0.angle_to(&g.rotation)).max(vt[l].1.abs());
        }
        assert!(worst < 1e-12, "handle frames differ from g by {worst:e}");
        let field = vec![vt[h.vertices[0]]; problem.len()];
        let maps = PoissonEditor::face_maps(&problem, &field);
        let targets: Vec<Vec3> = problem.rest.iter().map(|p| g.apply(*p)).collect();
        let out = s
            .method()
            .solve_with_face_maps(&problem, &maps, &targets)
            .unwrap();
        let err = rel(&out, &targets);
        assert!(err < 1e-9, "rigid motion from frames: {err:e}");
    }
}

#[test]
fn moving_the_whole_problem_rigidly_moves_a_positions_edit_rigidly() {
    let mesh = relief_cylinder();
    let verts = rings(CYL.3 - 3, CYL.3 - 1);
    let spec = spec_with(positions_handle(&mesh, &verts, |p| bend(p, 90.0)));
    let a = run::<PoissonEditor>(&mesh, &spec, Default::default());
    let g = Similarity::rigid(
        axis_angle(Vec3::new(0.3, -0.5, 0.8), 137.0).unwrap(),
        Vec3::new(2.0, -1.0, 5.0),
    );
    let mut moved = mesh.clone();
    for p in moved.positions_mut() {
        *p = g.apply(*p);
    }
    let spec_g = spec_with(positions_handle(&moved, &verts, |p| {
        g.apply(bend(g.inverse().apply(p), 90.0))
    }));
    let b = run::<PoissonEditor>(&moved, &spec_g, Default::default());
    let ga: Vec<Vec3> = a.iter().map(|p| g.apply(*p)).collect();
    let err = rel(&ga, &b);
    assert!(err < 1e-9, "rigid covariance of a positions edit: {err:e}");
}

#[test]
fn a_bend_given_by_positions_keeps_detail_better_than_naive_editing() {
    let mesh = relief_cylinder();
    let e = |x: &[Vec3]| detail_error(&mesh, x, None).unwrap();
    // Region handles (the top three rings bent, the top ten rings twisted: each ring turned
    // by its own angle, non-rigid) and a curve handle (the top ring, bent and ovalised:
    // non-rigid along the curve).
    let region = rings(CYL.3 - 3, CYL.3 - 1);
    let region10 = rings(CYL.3 - 10, CYL.3 - 1);
    let top = ring(CYL.3 - 1);
    let oval = |p: Vec3| bend(Vec3::new(1.25 * p.x, 0.8 * p.y, p.z), 90.0);
    let twist = |p: Vec3| {
        let (s, c) = (90f64.to_radians() * p.z / CYL.1).sin_cos();
        Vec3::new(c * p.x - s * p.y, s * p.x + c * p.y, p.z)
    };
    let cases = [
        (
            "region bend",
            positions_handle(&mesh, &region, |p| bend(p, 90.0)),
        ),
        ("region twist", positions_handle(&mesh, &region10, twist)),
        ("curve bend+oval", positions_handle(&mesh, &top, oval)),
    ];
    for (name, handle) in cases {
        let spec = spec_with(handle);
        let p = EditProblem::new(&mesh, &spec).unwrap();
        let naive = e(&run::<NaiveLaplacian>(&mesh, &spec, Default::default()));
        let poisson = e(&run::<PoissonEditor>(&mesh, &spec, Default::default()));
        let naive_poisson = e(&run::<PoissonEditor>(
            &mesh,
            &spec,
            PoissonOptions { propagate: false },
        ));
        // Frames from the fitted similarity only (no per-vertex frames).
        let mut s = EditSession::<PoissonEditor>::new(&mesh, &spec, Default::default()).unwrap();
        let vt_fit = {
            let mut q = p.clone();
            q.handles[0].shape = None;
            s.method().vertex_transforms(&q, &p.spec_transforms)
        };
        let targets = p.targets(&p.spec_transforms).unwrap();
        let fit_only = s
            .method_mut()
            .solve_with_face_maps(&p, &PoissonEditor::face_maps(&p, &vt_fit), &targets)
            .unwrap();
        let fit_only = e(&p.scatter(mesh.positions(), &fit_only));
        println!(
            "{name}: detail_error naive {naive:.4e} naive-poisson {naive_poisson:.4e} \
             poisson fit-only {fit_only:.4e} poisson frames {poisson:.4e}"
        );
        assert!(poisson < naive, "{name}: {poisson} vs naive {naive}");
        assert!(
            poisson < naive_poisson,
            "{name}: {poisson} vs {naive_poisson}"
        );
        // The handle lands on the given positions.
        let out = run::<PoissonEditor>(&mesh, &spec, Default::default());
        let shape = p.handles[0].shape.as_ref().unwrap();
        for (&l, t) in p.handles[0].vertices.iter().zip(&shape.positions) {
            assert!(out[p.global[l]].distance(*t) < 1e-12);
        }
    }
}

#[test]
fn new_positions_for_the_same_handle_never_refactor() {
    let mesh = relief_cylinder();
    let top = ring(CYL.3 - 1);
    let spec1 = spec_with(positions_handle(&mesh, &top, |p| bend(p, 30.0)));
    let spec2 = spec_with(positions_handle(&mesh, &top, |p| bend(p, 80.0)));
    let mut s = EditSession::<PoissonEditor>::new(&mesh, &spec1, Default::default()).unwrap();
    s.solve_spec().unwrap();
    s.set_spec(&spec2).unwrap();
    let a = s.solve_spec().unwrap();
    assert_eq!(s.stats().factorizations, 1);
    let b = run::<PoissonEditor>(&mesh, &spec2, Default::default());
    assert!(rel(&a, &b) < 1e-12);
}

#[test]
fn positions_json_round_trips_and_bad_positions_are_named_errors() {
    let mesh = relief_cylinder();
    let err = |json: &str| {
        EditSpec::from_json(json).and_then(|s| EditProblem::new(&mesh, &s).map(|_| ()))
    };
    let ok = r#"{"roi": "all", "anchors": {"vertices": [0, 1, 2]},
        "handles": [{"select": {"vertices": [1600, 1601]},
                     "positions": [[1, 0, 4.5], [0.99, 0.16, 4.5]]}]}"#;
    let spec = EditSpec::from_json(ok).unwrap();
    assert_eq!(EditSpec::from_json(&spec.to_json()).unwrap(), spec);
    assert!(!spec.to_json().contains("transform"));
    err(ok).unwrap();

    let e = err(r#"{"roi": "all", "anchors": {"vertices": [0]},
        "handles": [{"select": {"vertices": [1600, 1601]}, "positions": [[1, 0, 4.5]]}]}"#)
    .unwrap_err();
    assert!(
        matches!(&e, EditError::BadPositions { handle: 0, reason } if reason.contains("1 positions for 2")),
        "{e}"
    );
    let e = err(r#"{"roi": "all", "anchors": {"vertices": [0]},
        "handles": [{"select": {"vertices": [1600]}, "positions": [[1, 0, 4.5]],
                     "transform": {"translate": [0, 0, 1]}}]}"#)
    .unwrap_err();
    assert!(
        matches!(&e, EditError::BadPositions { reason, .. } if reason.contains("not both")),
        "{e}"
    );
    let e = err(r#"{"roi": "all", "anchors": {"vertices": [0]},
        "handles": [{"select": {"vertices": [1600, 1600]}, "positions": [[1, 0, 4], [1, 0, 4]]}]}"#)
    .unwrap_err();
    assert!(
        matches!(&e, EditError::BadPositions { reason, .. } if reason.contains("listed twice")),
        "{e}"
    );
    let e = err(r#"{"roi": "all", "anchors": {"vertices": [0]},
        "handles": [{"select": {"vertices": [1600, 1601]}, "positions": [[1, 0, 4], [1, 0, 4]]}]}"#)
    .unwrap_err();
    assert!(
        matches!(&e, EditError::BadPositions { reason, .. } if reason.contains("one point")),
        "{e}"
    );
    let e = err(r#"{"roi": "all", "handles": [{"select": "all", "position": []}]}"#).unwrap_err();
    assert!(
        matches!(&e, EditError::Spec(m) if m.contains("position")),
        "{e}"
    );
    // Non-finite values cannot be written in JSON; through the library they are named.
    let mut bad = spec_with(HandleSpec::with_positions(
        Select::Vertices(vec![1600, 1601]),
        vec![[1.0, 0.0, 4.0], [f64::NAN, 0.0, 4.0]],
    ));
    let e = EditProblem::new(&mesh, &bad).unwrap_err();
    assert!(
        matches!(&e, EditError::BadPositions { reason, .. } if reason.contains("positions[1] is not finite")),
        "{e}"
    );
    // With a non-list selection the positions follow ascending vertex index.
    bad.handles[0] = HandleSpec::with_positions(
        Select::Sphere {
            center: mesh.positions()[1600].to_array(),
            radius: 1e-6,
        },
        vec![[1.0, 0.0, 4.5]],
    );
    let p = EditProblem::new(&mesh, &bad).unwrap();
    assert_eq!(p.handles[0].vertices, vec![p.local[1600]]);
    let target = p.targets(&p.spec_transforms).unwrap()[p.local[1600]];
    assert!(target.distance(Vec3::new(1.0, 0.0, 4.5)) < 1e-15);
}

#[test]
fn single_vertex_and_collinear_handles_fit_their_motion() {
    use fires_recon::edit::fit_similarity;
    let r = axis_angle(Vec3::new(1.0, 0.0, 0.0), 50.0).unwrap();
    let g = Similarity {
        scale: 1.5,
        rotation: r,
        about: Vec3::new(0.0, 0.0, 1.0),
        translate: Vec3::new(0.1, 0.2, 0.3),
    };
    // A line along z turned about x: the minimal rotation of the line is g's rotation.
    let line: Vec<Vec3> = (0..5).map(|k| Vec3::new(0.5, 0.0, k as f64)).collect();
    let moved: Vec<Vec3> = line.iter().map(|p| g.apply(*p)).collect();
    let fit = fit_similarity(&line, &moved, 0).unwrap();
    assert!(fit.rotation.angle_to(&r) < 1e-12 && (fit.scale - 1.5).abs() < 1e-12);
    for (p, q) in line.iter().zip(&moved) {
        assert!(fit.apply(*p).distance(*q) < 1e-12);
    }
    // One vertex: a translation.
    let one = fit_similarity(&line[..1], &moved[..1], 0).unwrap();
    assert!(one.rotation.angle() == 0.0 && one.scale == 1.0);
    assert!(one.apply(line[0]).distance(moved[0]) < 1e-15);
    // A single-vertex handle through the whole pipeline.
    let mesh = relief_cylinder();
    let top = ring(CYL.3 - 1);
    let spec = spec_with(positions_handle(&mesh, &top[..1], |p| {
        p + Vec3::new(0.0, 0.0, 0.3)
    }));
    let out = run::<PoissonEditor>(&mesh, &spec, Default::default());
    let want = mesh.positions()[top[0]] + Vec3::new(0.0, 0.0, 0.3);
    assert!(out[top[0]].distance(want) < 1e-12);
}
