//! The register-blocked column kernels of the supernodal triangular solves
//! (`solve/column_kernels.rs`): the same solutions as faer's own supernodal solve for
//! every number of right-hand sides (blocks of four, three carried in four lanes, the
//! remainders), on factors whose supernodes span the widths the kernels cut into blocks
//! (1–3 column remainders, hundreds of columns), by every solve path.

use faer::Mat;
use fires_recon::generate::{icosphere, plane_grid};
use fires_recon::solve::*;

mod common;

use common::systems::{max_rel_diff, mesh_system, rhs, sparse_mul_dense_sym};

fn solver(a: &SparseMatrix, kernel: SolveKernel) -> CholeskySolver {
    CholeskySolver::new(
        a.as_ref(),
        CholeskyOptions {
            kernel,
            mode: FactorMode::Supernodal,
            ordering: FillOrdering::NestedDissection,
            ..Default::default()
        },
    )
    .expect("SPD")
}

/// Editing-shaped systems: 1 and 3 unknowns per vertex, 1- to 4-ring coupling (wide
/// separators), on a sphere and on a grid.
fn systems() -> Vec<SparseMatrix> {
    let sphere = icosphere(3, 1.0);
    let grid = plane_grid(40, 40, 1.0, 1.0, false);
    vec![
        mesh_system(&sphere, 1, 1, 0.5),
        mesh_system(&sphere, 4, 1, 0.5),
        mesh_system(&sphere, 2, 3, 0.5),
        mesh_system(&grid, 3, 1, 0.5),
    ]
}

#[test]
fn blocked_solve_agrees_with_faers_for_one_to_nine_right_hand_sides() {
    for a in systems() {
        let ours = solver(&a, SolveKernel::Auto);
        let faers = solver(&a, SolveKernel::Faer);
        for c in 1..=9 {
            let b = rhs(a.nrows(), c, 17 + c as u64);
            let x = ours.solve(b.as_ref()).unwrap();
            let y = faers.solve(b.as_ref()).unwrap();
            let d = max_rel_diff(&x, &y);
            assert!(d < 1e-11, "{c} right-hand sides: {d:e} from faer's solve");
            // And it is a solution: the residual against the full symmetric matrix.
            let r = sparse_mul_dense_sym(&a, &x);
            assert!(
                max_rel_diff(&r, &b) < 1e-11,
                "{c} right-hand sides: residual"
            );
        }
    }
}

#[test]
fn sparse_and_shared_right_hand_sides_agree_with_the_plain_solve() {
    for a in systems() {
        let s = solver(&a, SolveKernel::Auto);
        let n = a.nrows();
        for c in [1, 3, 4] {
            let b = rhs(n, c, 5);
            // Nonzero on two rows only: the forward substitution visits their reach.
            let mut sparse = Mat::zeros(n, c);
            for i in [1, n - 2] {
                for j in 0..c {
                    sparse[(i, j)] = b[(i, j)];
                }
            }
            let expect = s.solve(sparse.as_ref()).unwrap();
            let r = sparse_mul_dense_sym(&a, &expect);
            assert!(max_rel_diff(&r, &sparse) < 1e-11, "sparse residual");
            // The same right-hand side as a shared part plus that sparse part.
            let shared = s.share_rhs(b.as_ref()).unwrap();
            let mut plus = sparse.clone();
            s.solve_in_place_plus(&shared, plus.as_mut()).unwrap();
            let whole = Mat::from_fn(n, c, |i, j| b[(i, j)] + sparse[(i, j)]);
            let direct = s.solve(whole.as_ref()).unwrap();
            assert!(max_rel_diff(&plus, &direct) < 1e-11, "shared + sparse");
        }
    }
}

#[test]
fn the_lanes_past_the_right_hand_sides_do_not_leak_into_them() {
    // Three right-hand sides run in four lanes: solving them alone or as the first
    // three of four gives the same bits in the first three columns.
    let a = mesh_system(&icosphere(3, 1.0), 3, 1, 0.5);
    let s = solver(&a, SolveKernel::Auto);
    let b4 = rhs(a.nrows(), 4, 9);
    let b3 = Mat::from_fn(a.nrows(), 3, |i, j| b4[(i, j)]);
    let x4 = s.solve(b4.as_ref()).unwrap();
    let x3 = s.solve(b3.as_ref()).unwrap();
    for j in 0..3 {
        for i in 0..a.nrows() {
            assert_eq!(x3[(i, j)].to_bits(), x4[(i, j)].to_bits());
        }
    }
}
