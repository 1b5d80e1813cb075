//! Poisson editing's per-move fast path (factor-order right-hand side, one-axis face maps)
//! against the plain computation it replaces: per-vertex quaternions, per-face 3×3 maps,
//! the divergence in local numbering and [`FixedSolver::solve`]. Both must agree to
//! round-off for every kind of move, and the solver's factor-order entry points must agree
//! with their plain counterparts.

mod edit_common;

use edit_common::{bbox_diag, relief_cylinder, ring, twist_spec};
use faer::Mat;
use fires_recon::edit::{
    EditMethod, EditProblem, EditSpec, HandleSpec, PoissonEditor, PoissonOptions, RotateSpec,
    Select, Similarity, TransformSpec,
};
use fires_recon::solve::{
    sparse_from_triplets, CholeskyOptions, CholeskySolver, FactorMode, FixedSolver,
};
use fires_recon::{SurfaceMesh, Vec3};

/// The pre-fast-path solve: propagated vertex transforms, per-face maps, plain solve.
fn plain(editor: &PoissonEditor, p: &EditProblem, t: &[Similarity]) -> Vec<Vec3> {
    let vt = editor.vertex_transforms(p, t);
    let maps = PoissonEditor::face_maps(p, &vt);
    let targets = p.targets(t).unwrap();
    editor.solve_with_face_maps(p, &maps, &targets).unwrap()
}

/// Largest difference between the fast and the plain solve, relative to the mesh size.
fn fast_vs_plain(
    mesh: &SurfaceMesh,
    spec: &EditSpec,
    opt: PoissonOptions,
    t: &[Similarity],
) -> f64 {
    let p = EditProblem::new(mesh, spec).unwrap();
    let mut e = PoissonEditor::factor(&p, &opt).unwrap();
    let fast = e.solve(&p, t).unwrap();
    let slow = plain(&e, &p, t);
    let d = fast
        .iter()
        .zip(&slow)
        .map(|(a, b)| a.distance(*b))
        .fold(0.0, f64::max);
    println!("fast vs plain {:.3e}", d / bbox_diag(&slow));
    d / bbox_diag(&slow)
}

fn rot(axis: [f64; 3], deg: f64) -> Option<RotateSpec> {
    Some(RotateSpec { axis, deg })
}

fn moves(p: &EditProblem) -> Vec<Vec<Similarity>> {
    let n = p.handles.len();
    let c = |h: usize| p.handles[h].centroid;
    let sim = |h: usize, deg: f64, scale: f64, dz: f64| Similarity {
        scale,
        rotation: fires_recon::edit::similarity::axis_angle(Vec3::new(0.3, -0.5, 1.0), deg)
            .unwrap(),
        about: c(h),
        translate: Vec3::new(0.1, 0.0, dz),
    };
    vec![
        // Rigid, then with a scale (the σ part), then a half turn and a turn past it.
        (0..n).map(|h| sim(h, 40.0, 1.0, 0.3)).collect(),
        (0..n).map(|h| sim(h, -75.0, 1.3, -0.2)).collect(),
        (0..n).map(|h| sim(h, 180.0, 0.8, 0.0)).collect(),
        (0..n).map(|h| sim(h, 250.0, 1.0, 0.5)).collect(),
        p.spec_transforms.clone(),
    ]
}

#[test]
fn one_transform_handle_equals_the_quaternion_face_maps() {
    let mesh = relief_cylinder();
    for deg in [0.0, 90.0] {
        let spec = twist_spec(deg);
        let p = EditProblem::new(&mesh, &spec).unwrap();
        for propagate in [true, false] {
            for t in moves(&p) {
                let err = fast_vs_plain(&mesh, &spec, PoissonOptions { propagate }, &t);
                assert!(err < 1e-12, "propagate {propagate}: {err:e}");
            }
        }
    }
}

#[test]
fn two_handles_and_a_partial_roi_equal_the_plain_path() {
    let mesh = relief_cylinder();
    let roi: Vec<usize> = (ring(5)[0]..ring(35)[0]).collect();
    let spec = EditSpec {
        roi: Select::Vertices(roi),
        anchors: Some(Select::Vertices(ring(20))),
        anchor_weight: 1.0,
        handles: vec![
            HandleSpec::with_transform(
                Select::Vertices(ring(8)),
                TransformSpec {
                    rotate: rot([1.0, 0.0, 0.0], 30.0),
                    ..Default::default()
                },
            ),
            HandleSpec::with_transform(Select::Vertices(ring(31)), TransformSpec::default()),
        ],
    };
    let p = EditProblem::new(&mesh, &spec).unwrap();
    for t in moves(&p) {
        let err = fast_vs_plain(&mesh, &spec, PoissonOptions::default(), &t);
        assert!(err < 1e-12, "{err:e}");
    }
}

#[test]
fn a_positions_handle_equals_the_plain_path() {
    let mesh = relief_cylinder();
    let verts = ring(edit_common::CYL.3 - 1);
    let mut spec = twist_spec(0.0);
    let bend = |q: Vec3| Vec3::new(q.x + 0.1 * q.y * q.y, q.y, q.z + 0.05 * q.x);
    let positions = verts
        .iter()
        .map(|&v| bend(mesh.positions()[v]).to_array())
        .collect();
    spec.handles = vec![HandleSpec::with_positions(
        Select::Vertices(verts),
        positions,
    )];
    let p = EditProblem::new(&mesh, &spec).unwrap();
    assert!(p.handles[0].shape.is_some());
    for t in moves(&p) {
        let err = fast_vs_plain(&mesh, &spec, PoissonOptions::default(), &t);
        assert!(err < 1e-12, "{err:e}");
    }
}

/// A 2D grid Laplacian plus a small diagonal (SPD), full symmetric storage.
fn grid(nx: usize) -> fires_recon::solve::SparseMatrix {
    let n = nx * nx;
    let mut t = Vec::new();
    for i in 0..nx {
        for j in 0..nx {
            let a = i * nx + j;
            t.push((a, a, 0.01));
            for (di, dj) in [(1, 0), (0, 1)] {
                if i + di < nx && j + dj < nx {
                    let b = (i + di) * nx + j + dj;
                    t.extend([(a, a, 1.0), (b, b, 1.0), (a, b, -1.0), (b, a, -1.0)]);
                }
            }
        }
    }
    sparse_from_triplets(n, n, &t).unwrap()
}

#[test]
fn factor_order_solves_equal_the_plain_solves() {
    let a = grid(60);
    let n = a.nrows();
    let rhs = |i: usize, c: usize| ((i * (c + 3)) % 17) as f64 - 8.0;
    for mode in [FactorMode::Supernodal, FactorMode::Simplicial] {
        let opt = CholeskyOptions {
            mode,
            ..Default::default()
        };
        let chol = CholeskySolver::new(a.as_ref(), opt).unwrap();
        let want = chol.solve(Mat::from_fn(n, 3, rhs).as_ref()).unwrap();
        let order = chol.factor_order();
        let mut w: Vec<[f64; 3]> = order
            .iter()
            .map(|&i| [0, 1, 2].map(|c| rhs(i, c)))
            .collect();
        chol.solve_factor_rows(&mut w).unwrap();
        let mut err = 0.0f64;
        for (k, &i) in order.iter().enumerate() {
            for c in 0..3 {
                err = err.max((w[k][c] - want[(i, c)]).abs());
            }
        }
        assert!(err < 1e-12, "{mode:?}: {err:e}");

        // With fixed values: the reduced solve in factor order equals FixedSolver::solve.
        let known: Vec<usize> = (0..n).step_by(7).collect();
        let fixed = FixedSolver::precompute(a.as_ref(), &known, opt).unwrap();
        let kv = |r: usize, c: usize| (r as f64 * 0.1 + c as f64).sin();
        let b = Mat::from_fn(n, 3, rhs);
        let want = fixed
            .solve(
                b.as_ref(),
                Mat::from_fn(fixed.known().len(), 3, kv).as_ref(),
            )
            .unwrap();
        let rows = fixed.factor_rows();
        let mut w = vec![[0.0; 3]; fixed.unknown().len()];
        for (i, &r) in rows.iter().enumerate() {
            if r != usize::MAX {
                w[r] = [0, 1, 2].map(|c| b[(i, c)]);
            }
        }
        let k: Vec<[f64; 3]> = (0..fixed.known().len())
            .map(|r| [0, 1, 2].map(|c| kv(r, c)))
            .collect();
        fixed.solve_factor_rows(&mut w, &k).unwrap();
        let mut err = 0.0f64;
        for (i, &r) in rows.iter().enumerate() {
            if r != usize::MAX {
                for c in 0..3 {
                    err = err.max((w[r][c] - want[(i, c)]).abs());
                }
            }
        }
        assert!(err < 1e-12, "{mode:?} fixed: {err:e}");
    }
}
