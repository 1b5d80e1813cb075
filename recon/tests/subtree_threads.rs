//! The two-thread supernodal factorisation and backward substitution
//! (`SubtreeThreads`): the same solutions as faer's one-thread factor on the shapes the
//! editors factor, a split found wherever nested dissection leaves two heavy halves, and
//! the same errors on bad input.

use faer::Mat;
use fires_recon::generate::{icosphere, plane_grid};
use fires_recon::solve::*;
use fires_recon::SurfaceMesh;

mod common;

use common::disc::Rng;
use common::systems::{below, max_rel_diff, mesh_system, rhs, sparse_mul_dense_sym};

fn options(threads: SubtreeThreads) -> CholeskyOptions {
    CholeskyOptions {
        threads,
        ordering: FillOrdering::NestedDissection,
        mode: FactorMode::Supernodal,
        ..Default::default()
    }
}

fn one_rings(m: &SurfaceMesh) -> Vec<Vec<usize>> {
    m.vertices()
        .map(|v| m.vertex_vertices(v).map(|u| u.idx()).collect())
        .collect()
}

/// Every solve path of `solver` on `b`: the plain solve, the factor-row-order solve, and
/// the shared-right-hand-side solve with the shared part split off.
fn all_solves(solver: &CholeskySolver, b: &Mat<f64>) -> [Mat<f64>; 3] {
    let plain = solver.solve(b.as_ref()).unwrap();
    let order = solver.factor_order();
    let mut w: Vec<[f64; 3]> = order
        .iter()
        .map(|&i| std::array::from_fn(|c| b[(i, c)]))
        .collect();
    solver.solve_factor_rows(&mut w).unwrap();
    let mut rows = Mat::zeros(b.nrows(), 3);
    for (&i, r) in order.iter().zip(&w) {
        for c in 0..3 {
            rows[(i, c)] = r[c];
        }
    }
    // B = B₀ + R with R nonzero on three rows (a handle move).
    let mut r = Mat::zeros(b.nrows(), 3);
    for i in [0, b.nrows() / 2, b.nrows() - 1] {
        for c in 0..3 {
            r[(i, c)] = b[(i, c)];
        }
    }
    let b0 = Mat::from_fn(b.nrows(), 3, |i, c| b[(i, c)] - r[(i, c)]);
    let shared = solver.share_rhs(b0.as_ref()).unwrap();
    solver.solve_in_place_plus(&shared, r.as_mut()).unwrap();
    [plain, rows, r]
}

#[test]
fn two_threads_solve_as_one_thread_on_editing_systems() {
    // Cotangent-like 1-ring systems, LSE's 2-ring 3×3 blocks and implicit editing's
    // 4-ring operator (ordered on the mesh skeleton, as the editor does).
    let sphere = icosphere(4, 1.0);
    let grid = plane_grid(60, 60, 1.0, 1.0, false);
    let cases = [
        ("grid 1-ring", mesh_system(&grid, 1, 1, 0.01), None),
        ("sphere 2-ring 3x3", mesh_system(&sphere, 2, 3, 0.5), None),
        ("sphere 4-ring", mesh_system(&sphere, 4, 1, 1.0), Some(4)),
    ];
    for (name, a, band) in cases {
        let b = rhs(a.nrows(), 3, 5);
        let analyze = |threads| match band {
            Some(band) => {
                let order = OrderingSkeleton::new(&one_rings(&sphere), band)
                    .unwrap()
                    .order_free(&vec![false; a.nrows()])
                    .unwrap();
                CholeskySolver::analyze_ordered(a.as_ref(), options(threads), &order).unwrap()
            }
            None => CholeskySolver::analyze(a.as_ref(), options(threads)).unwrap(),
        };
        let mut one = analyze(SubtreeThreads::Off);
        one.factorize(a.as_ref()).unwrap();
        let reference = one.solve(b.as_ref()).unwrap();
        assert!(
            max_rel_diff(&sparse_mul_dense_sym(&a, &reference), &b) < 1e-10,
            "{name}"
        );
        for threads in [SubtreeThreads::Factor, SubtreeThreads::FactorAndSolve] {
            let mut two = analyze(threads);
            two.factorize(a.as_ref()).unwrap();
            let cost = two.subtree_split_cost();
            assert!(
                cost.is_some_and(|c| c < 0.85),
                "{name}: split cost {cost:?}"
            );
            assert_eq!(two.factor_len(), one.factor_len(), "{name}");
            for (k, x) in all_solves(&two, &b).iter().enumerate() {
                let d = max_rel_diff(x, &reference);
                assert!(d < 1e-11, "{name} {threads:?} solve {k}: {d:e}");
            }
        }
    }
}

#[test]
fn refactoring_new_values_overwrites_the_old_factor() {
    // Same pattern, twice the values: the solution halves (every block is re-zeroed).
    let a = mesh_system(&icosphere(4, 1.0), 2, 1, 1.0);
    let mut twice = a.clone();
    for v in twice.val_mut() {
        *v *= 2.0;
    }
    let b = rhs(a.nrows(), 3, 9);
    let mut solver = CholeskySolver::analyze(a.as_ref(), options(SubtreeThreads::Factor)).unwrap();
    solver.factorize(a.as_ref()).unwrap();
    let x1 = solver.solve(b.as_ref()).unwrap();
    solver.factorize(twice.as_ref()).unwrap();
    let x2 = solver.solve(b.as_ref()).unwrap();
    let half = Mat::from_fn(x1.nrows(), 3, |i, c| x1[(i, c)] / 2.0);
    assert!(max_rel_diff(&x2, &half) < 1e-12);
}

#[test]
fn any_elimination_order_factors_correctly() {
    // Random orders give elimination trees whose supernodes are not numbered as a
    // postorder: only contiguous subtrees may go to a thread, and the result is still
    // exact.
    let mut rng = Rng(3);
    let a = mesh_system(&plane_grid(30, 30, 1.0, 1.0, false), 1, 2, 0.5);
    let b = rhs(a.nrows(), 3, 2);
    let n = a.nrows();
    for _ in 0..6 {
        let mut order: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            order.swap(i, below(&mut rng, i + 1));
        }
        let one = {
            let mut s =
                CholeskySolver::analyze_ordered(a.as_ref(), options(SubtreeThreads::Off), &order)
                    .unwrap();
            s.factorize(a.as_ref()).unwrap();
            s.solve(b.as_ref()).unwrap()
        };
        let mut two = CholeskySolver::analyze_ordered(
            a.as_ref(),
            options(SubtreeThreads::FactorAndSolve),
            &order,
        )
        .unwrap();
        two.factorize(a.as_ref()).unwrap();
        for (k, x) in all_solves(&two, &b).iter().enumerate() {
            assert!(max_rel_diff(x, &one) < 1e-10, "solve {k}");
        }
    }
}

#[test]
fn an_indefinite_matrix_is_an_error_in_a_subtree_and_in_the_rest() {
    // One negative diagonal entry, first in the subtrees (eliminated early) and then in
    // the top separator (eliminated last): an error naming non-positive-definiteness.
    let a = mesh_system(&icosphere(4, 1.0), 2, 1, 1.0);
    let solver = CholeskySolver::analyze(a.as_ref(), options(SubtreeThreads::Factor)).unwrap();
    assert!(solver.subtree_split_cost().is_some());
    let order = solver.factor_order();
    for victim in [order[0], order[order.len() - 1]] {
        let mut bad = a.clone();
        let (col_ptr, row_idx) = (
            bad.symbolic().col_ptr().to_vec(),
            bad.symbolic().row_idx().to_vec(),
        );
        let at = (col_ptr[victim]..col_ptr[victim + 1])
            .find(|&k| row_idx[k] == victim)
            .unwrap();
        bad.val_mut()[at] = -1.0;
        let mut s = solver.share_symbolic();
        match s.factorize(bad.as_ref()) {
            Err(SolveError::NotPositiveDefinite { .. }) => {}
            other => panic!("row {victim}: {other:?}"),
        }
        assert!(matches!(
            s.solve(rhs(a.nrows(), 1, 1).as_ref()),
            Err(SolveError::NotFactorized)
        ));
    }
}

#[test]
fn small_and_simplicial_systems_fall_back_to_one_thread() {
    for n in [1usize, 2, 7] {
        let t: Vec<_> = (0..n).map(|i| (i, i, 2.0)).collect();
        let a = sparse_from_triplets(n, n, &t).unwrap();
        let s = CholeskySolver::new(a.as_ref(), options(SubtreeThreads::FactorAndSolve)).unwrap();
        assert_eq!(s.subtree_split_cost(), None);
        let x = s.solve_vec(&vec![4.0; n]).unwrap();
        assert!(x.iter().all(|&v| (v - 2.0).abs() < 1e-15));
    }
    let a = mesh_system(&plane_grid(20, 20, 1.0, 1.0, false), 1, 1, 1.0);
    let simplicial = CholeskyOptions {
        mode: FactorMode::Simplicial,
        ..options(SubtreeThreads::Factor)
    };
    let s = CholeskySolver::new(a.as_ref(), simplicial).unwrap();
    assert_eq!(s.subtree_split_cost(), None);
    let b = rhs(a.nrows(), 3, 4);
    let x = s.solve(b.as_ref()).unwrap();
    assert!(max_rel_diff(&sparse_mul_dense_sym(&a, &x), &b) < 1e-10);
}
