//! Solvers: Dirichlet-constrained harmonic solve, refactorisation, errors.

use faer::Mat;
use fires_recon::generate::plane_grid;
use fires_recon::operators::cotan_matrix;
use fires_recon::solve::*;
use fires_recon::SurfaceMesh;

/// The cotangent stiffness `K = −C` of a mesh (symmetric positive semidefinite).
fn stiffness(m: &SurfaceMesh) -> SparseMatrix {
    let c = cotan_matrix(m).unwrap();
    let t: Vec<_> = sparse_triplets(c.as_ref())
        .into_iter()
        .map(|(i, j, v)| (i, j, -v))
        .collect();
    sparse_from_triplets(c.nrows(), c.ncols(), &t).unwrap()
}

#[test]
fn dirichlet_solve_reproduces_a_harmonic_function() {
    // f = x² − y² + 3xy + x is harmonic; the cotan Laplacian reproduces quadratics only
    // approximately, so use a linear function for exactness and a quadratic for convergence.
    let m = plane_grid(30, 30, 1.0, 1.0, false);
    let k = stiffness(&m);
    let boundary: Vec<usize> = m
        .vertices()
        .filter(|&v| m.is_boundary_vertex(v))
        .map(|v| v.idx())
        .collect();
    let solver =
        FixedSolver::precompute(k.as_ref(), &boundary, CholeskyOptions::default()).unwrap();
    let exact = |x: f64, y: f64| [2.0 * x - y + 1.0, x * x - y * y + 3.0 * x * y];
    let known = Mat::from_fn(solver.known().len(), 2, |r, c| {
        let p = m.positions()[solver.known()[r]];
        exact(p.x, p.y)[c]
    });
    let b = Mat::zeros(m.n_vertices(), 2);
    // A scaled matrix has the same pattern and the same harmonic solution: numeric refactorisation only.
    let mut solver = solver;
    let scaled = sparse_from_triplets(
        k.nrows(),
        k.ncols(),
        &sparse_triplets(k.as_ref())
            .into_iter()
            .map(|(i, j, v)| (i, j, 2.5 * v))
            .collect::<Vec<_>>(),
    )
    .unwrap();
    solver.refactorize(scaled.as_ref()).unwrap();
    let x = solver.solve(b.as_ref(), known.as_ref()).unwrap();
    for (i, p) in m.positions().iter().enumerate() {
        let e = exact(p.x, p.y);
        assert!((x[(i, 0)] - e[0]).abs() < 1e-10);
        assert!(
            (x[(i, 1)] - e[1]).abs() < 1e-10,
            "harmonic quadratic at {i}: {} vs {}",
            x[(i, 1)],
            e[1]
        );
    }
}

#[test]
fn fixed_solver_with_a_given_order_solves_as_with_its_own() {
    // The cotangent system of a grid with its boundary fixed, ordered by nested dissection
    // on the mesh graph (over all vertices, the fixed ones skipped) or by any permutation:
    // the solution is the default order's; an order missing a free vertex is an error.
    let m = plane_grid(30, 30, 1.0, 1.0, false);
    let k = stiffness(&m);
    let fixed: Vec<bool> = m.vertices().map(|v| m.is_boundary_vertex(v)).collect();
    let boundary: Vec<usize> = (0..fixed.len()).filter(|&v| fixed[v]).collect();
    let rings: Vec<Vec<usize>> = m
        .vertices()
        .map(|v| m.vertex_vertices(v).map(|u| u.idx()).collect())
        .collect();
    let opts = CholeskyOptions::default();
    let reference = FixedSolver::precompute(k.as_ref(), &boundary, opts).unwrap();
    let known = Mat::from_fn(boundary.len(), 3, |r, c| (r * (c + 2) % 7) as f64);
    let b = Mat::from_fn(m.n_vertices(), 3, |i, c| ((i + c) % 5) as f64 - 2.0);
    let x0 = reference.solve(b.as_ref(), known.as_ref()).unwrap();
    let dissected = OrderingSkeleton::new(&rings, 1)
        .unwrap()
        .order_free(&fixed)
        .unwrap();
    let reversed: Vec<usize> = (0..m.n_vertices()).rev().collect();
    for order in [dissected, reversed] {
        let s = FixedSolver::precompute_ordered(k.as_ref(), &boundary, opts, &order).unwrap();
        let x = s.solve(b.as_ref(), known.as_ref()).unwrap();
        for i in 0..x.nrows() {
            for c in 0..3 {
                assert!((x[(i, c)] - x0[(i, c)]).abs() < 1e-11 * (1.0 + x0[(i, c)].abs()));
            }
        }
    }
    let free = (0..fixed.len()).find(|&v| !fixed[v]).unwrap();
    let short: Vec<usize> = (0..fixed.len()).filter(|&v| v != free).collect();
    assert!(FixedSolver::precompute_ordered(k.as_ref(), &boundary, opts, &short).is_err());
}

fn spd(n: usize, shift: f64) -> SparseMatrix {
    let mut t = Vec::new();
    for i in 0..n {
        t.push((i, i, 2.0 + shift));
        if i + 1 < n {
            t.push((i, i + 1, -1.0));
            t.push((i + 1, i, -1.0));
        }
    }
    sparse_from_triplets(n, n, &t).unwrap()
}

#[test]
fn symbolic_analysis_is_reused_and_many_rhs_solve_together() {
    let a = spd(50, 0.0);
    let mut s = CholeskySolver::analyze(a.as_ref(), CholeskyOptions::default()).unwrap();
    assert_eq!(s.solve_vec(&[0.0; 50]), Err(SolveError::NotFactorized));
    for shift in [0.0, 0.5, 3.0] {
        let a = spd(50, shift);
        s.factorize(a.as_ref()).unwrap();
        let b = Mat::from_fn(50, 3, |i, j| (i * (j + 1)) as f64);
        let x = s.solve(b.as_ref()).unwrap();
        let r = sparse_mul_dense(a.as_ref(), x.as_ref()).unwrap();
        for i in 0..50 {
            for j in 0..3 {
                assert!((r[(i, j)] - b[(i, j)]).abs() < 1e-9);
            }
        }
    }
    let other = spd(49, 0.0);
    assert_eq!(s.factorize(other.as_ref()), Err(SolveError::PatternChanged));
    let ldlt = CholeskySolver::new(
        a.as_ref(),
        CholeskyOptions {
            factorization: Factorization::Ldlt,
            ..Default::default()
        },
    )
    .unwrap();
    let x = ldlt.solve_vec(&[1.0; 50]).unwrap();
    assert!(x.iter().all(|v| v.is_finite()));
}

#[test]
fn indefinite_matrix_gives_a_typed_error() {
    let a = spd(10, -3.0);
    assert!(matches!(
        CholeskySolver::new(a.as_ref(), CholeskyOptions::default()),
        Err(SolveError::NotPositiveDefinite { .. })
    ));
    let singular =
        sparse_from_triplets(2, 2, &[(0, 0, 1.0), (1, 1, 0.0), (0, 1, 0.0), (1, 0, 0.0)]).unwrap();
    let opts = CholeskyOptions {
        factorization: Factorization::Ldlt,
        ..Default::default()
    };
    assert!(CholeskySolver::new(singular.as_ref(), opts).is_err());
    assert!(sparse_from_triplets(2, 2, &[(5, 0, 1.0)]).is_err());
}

#[test]
fn least_squares_of_stacked_constraints() {
    // Smoothness rows (x_i − x_{i+1} = 0, weight 1) plus soft anchors at both ends (weight 1e6).
    let n = 20;
    let mut d = Vec::new();
    for i in 0..n - 1 {
        d.push((i, i, 1.0));
        d.push((i, i + 1, -1.0));
    }
    let dmat = sparse_from_triplets(n - 1, n, &d).unwrap();
    let anchors = sparse_from_triplets(2, n, &[(0, 0, 1.0), (1, n - 1, 1.0)]).unwrap();
    let ls = LeastSquaresSolver::new(
        n,
        &[(1.0, dmat.as_ref()), (1e6, anchors.as_ref())],
        CholeskyOptions::default(),
    )
    .unwrap();
    let b0 = Mat::zeros(n - 1, 1);
    let b1 = Mat::from_fn(2, 1, |i, _| if i == 0 { 0.0 } else { 1.0 });
    let x = ls.solve(&[b0.as_ref(), b1.as_ref()]).unwrap();
    for i in 0..n {
        assert!((x[(i, 0)] - i as f64 / (n - 1) as f64).abs() < 1e-4);
    }
}

#[test]
fn supernodal_and_simplicial_factors_agree_on_a_mesh_laplacian() {
    // The 70x70 grid's top separator is 70 columns wide: many four-column blocks.
    for m in [
        fires_recon::generate::icosphere(4, 1.0),
        plane_grid(70, 70, 1.0, 1.0, false),
    ] {
        check_modes_agree(&m);
    }
}

fn check_modes_agree(m: &fires_recon::SurfaceMesh) {
    let lower = fires_recon::bench::laplacian_system(m).unwrap();
    let n = lower.nrows();
    let b = Mat::from_fn(n, 7, |i, j| ((i * 31 + j * 7) % 13) as f64 - 6.0);
    let mut results = Vec::new();
    for mode in [
        FactorMode::Simplicial,
        FactorMode::Supernodal,
        FactorMode::Auto,
    ] {
        let s = CholeskySolver::new(
            lower.as_ref(),
            CholeskyOptions {
                mode,
                ..Default::default()
            },
        )
        .unwrap();
        results.push(s.solve(b.as_ref()).unwrap());
    }
    // Residual of the supernodal solve against the full symmetric matrix.
    let full_t: Vec<_> = sparse_triplets(lower.as_ref())
        .into_iter()
        .flat_map(|(i, j, v)| {
            if i == j {
                vec![(i, j, v)]
            } else {
                vec![(i, j, v), (j, i, v)]
            }
        })
        .collect();
    let full = sparse_from_triplets(n, n, &full_t).unwrap();
    let r = sparse_mul_dense(full.as_ref(), results[1].as_ref()).unwrap();
    for i in 0..n {
        for j in 0..7 {
            assert!((r[(i, j)] - b[(i, j)]).abs() < 1e-8);
            assert!((results[0][(i, j)] - results[1][(i, j)]).abs() < 1e-8);
        }
    }
}
