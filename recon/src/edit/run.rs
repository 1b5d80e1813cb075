//! One-call editing for the CLI: resolve, factor, solve, measure (`fires edit`), and the
//! repeated-move benchmark (`fires bench edit`).

use std::collections::BTreeMap;
use std::str::FromStr;
use std::time::Instant;

use faer::Mat;

use super::implicit::{ImplicitEditor, ImplicitOptions};
use super::local::cotan_stiffness;
use super::lse::{LseEditor, LseOptions};
use super::naive::NaiveLaplacian;
use super::poisson::PoissonEditor;
use super::problem::EditProblem;
use super::session::EditMethod;
use super::similarity::{axis_angle, Similarity};
use super::spec::{EditSpec, HandleSpec, Select, TransformSpec};
use super::{detail_error, EditError};
use crate::geometry::Vec3;
use crate::mesh::SurfaceMesh;
use crate::solve::{CholeskyOptions, CholeskySolver, SubtreeThreads};

/// The editing methods.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// Laplacian surface editing (with two re-fitting iterations in [`edit_mesh`]).
    Lse,
    /// Poisson gradient-field editing.
    Poisson,
    /// Implicit Laplacian editing (both solves).
    Implicit,
    /// Naive Laplacian editing (the baseline).
    Naive,
}

impl Method {
    /// The method's CLI name.
    pub fn name(self) -> &'static str {
        match self {
            Method::Lse => "lse",
            Method::Poisson => "poisson",
            Method::Implicit => "implicit",
            Method::Naive => "naive",
        }
    }
}

impl FromStr for Method {
    type Err = EditError;
    fn from_str(s: &str) -> Result<Self, EditError> {
        match s {
            "lse" => Ok(Method::Lse),
            "poisson" => Ok(Method::Poisson),
            "implicit" => Ok(Method::Implicit),
            "naive" => Ok(Method::Naive),
            _ => Err(EditError::Spec(format!(
                "unknown method {s:?} (lse, poisson, implicit, naive)"
            ))),
        }
    }
}

/// What `fires edit` prints.
#[derive(Debug, Clone, serde::Serialize)]
pub struct EditReport {
    /// Method name.
    pub method: String,
    /// Vertices in the ROI.
    pub roi_vertices: usize,
    /// Resolving the ROI, ring, anchors and handles, ms.
    pub build_ms: f64,
    /// Assembling and factoring the method's systems, ms.
    pub factor_ms: f64,
    /// Solving for the specification's transforms, ms (LSE: re-fitting included).
    pub solve_ms: f64,
    /// Normalised ARAP energy of the result over the ROI ([`detail_error()`]).
    pub detail_error: f64,
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

fn timed<M: EditMethod>(
    p: &EditProblem,
    o: &M::Options,
) -> Result<(Vec<Vec3>, f64, f64), EditError> {
    let t = Instant::now();
    let mut m = M::factor(p, o)?;
    let f = ms(t);
    let t = Instant::now();
    let x = m.solve(p, &p.spec_transforms)?;
    Ok((x, f, ms(t)))
}

/// Edits `mesh` by `spec` with `method`; returns all new positions and the report.
pub fn edit_mesh(
    mesh: &SurfaceMesh,
    spec: &EditSpec,
    method: Method,
) -> Result<(Vec<Vec3>, EditReport), EditError> {
    let t = Instant::now();
    let p = EditProblem::new(mesh, spec)?;
    let build_ms = ms(t);
    let (local, factor_ms, solve_ms) = match method {
        Method::Lse => timed::<LseEditor>(
            &p,
            &LseOptions {
                refit_iterations: 2,
            },
        )?,
        Method::Poisson => timed::<PoissonEditor>(&p, &Default::default())?,
        Method::Implicit => timed::<ImplicitEditor>(
            &p,
            &ImplicitOptions {
                drag_basis: false,
                ..Default::default()
            },
        )?,
        Method::Naive => timed::<NaiveLaplacian>(&p, &Default::default())?,
    };
    let x = p.scatter(mesh.positions(), &local);
    let roi: Vec<usize> = p.global[..p.n_roi].to_vec();
    let err = detail_error(mesh, &x, Some(&roi))?;
    Ok((
        x,
        EditReport {
            method: method.name().into(),
            roi_vertices: p.n_roi,
            build_ms,
            factor_ms,
            solve_ms,
            detail_error: err,
        },
    ))
}

/// What `fires bench edit` prints.
#[derive(Debug, Clone, serde::Serialize)]
pub struct BenchEditReport {
    /// Method name.
    pub method: String,
    /// Vertices in the ROI.
    pub roi_vertices: usize,
    /// Assembly and factorisation, ms.
    pub factor_ms: f64,
    /// Median time of one handle move (one solve; LSE without re-fitting), ms.
    pub per_move_ms: f64,
    /// Median time of the same ROI's plain cotangent solve with 3 right-hand sides, one
    /// just before every timed move, ms.
    pub cotan_solve_ms: f64,
    /// Factor time of that cotangent system, ms.
    pub cotan_factor_ms: f64,
    /// Stored entries of the method's main factor (0 when not tracked).
    pub factor_entries: usize,
    /// LSE and implicit (first system) only: time to precompute the 12 affine responses per
    /// handle ([`super::AffineBasis`]), ms.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub basis_ms: Option<f64>,
    /// LSE and implicit only: median move from the precomputed affine responses (no solve;
    /// implicit: the drag, with the degenerate vertices' pull-back), ms.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub per_move_basis_ms: Option<f64>,
    /// Implicit only: median move (one solve) with the backward substitution on two
    /// threads ([`crate::solve::SubtreeThreads::FactorAndSolve`]), ms.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub per_move_two_threads_ms: Option<f64>,
    /// Where `factor_ms` went, by part (implicit: the first system, Eq. 2.8, and its
    /// assembly, ordering, numeric factorisation and shared right-hand side, then the
    /// second system, Eq. 2.10; LSE: its system's parts), ms.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub factor_parts: BTreeMap<String, f64>,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        0.0
    } else {
        v[v.len() / 2]
    }
}

/// The benchmark edit: ROI = the `roi_fraction` of vertices nearest (along edges) to a
/// seed vertex, handle = the innermost 2% of the ROI (at least one vertex), anchors = the
/// ring outside (or, for a fraction of 1, the farthest 2% of the mesh).
pub fn bench_spec(mesh: &SurfaceMesh, roi_fraction: f64) -> Result<EditSpec, EditError> {
    let n = mesh.n_vertices();
    let seed = mesh
        .vertices()
        .next()
        .ok_or_else(|| EditError::EmptySelection("mesh".into()))?;
    let d = crate::operators::geodesic_dijkstra(mesh, &[seed])?;
    let mut order: Vec<usize> = mesh.vertices().map(|v| v.idx()).collect();
    order.sort_by(|&a, &b| d[a].total_cmp(&d[b]));
    let k = ((roi_fraction.clamp(0.0, 1.0) * n as f64).round() as usize).clamp(2, n);
    let h = (k / 50).max(1);
    let anchors = (k == n).then(|| Select::Vertices(order[n - (n / 50).max(1)..].to_vec()));
    let roi = if k == n {
        Select::All
    } else {
        Select::Vertices(order[..k].to_vec())
    };
    Ok(EditSpec {
        roi,
        anchors,
        anchor_weight: 1.0,
        handles: vec![HandleSpec::with_transform(
            Select::Vertices(order[..h].to_vec()),
            TransformSpec::default(),
        )],
    })
}

/// Move `k`: a translation along z growing with k plus a rotation about a tilted axis.
fn bench_move(p: &EditProblem, k: usize, scale: f64) -> Vec<Similarity> {
    let c = p.handles[0].centroid;
    let rot = axis_angle(Vec3::new(0.3, 0.2, 1.0), 3.0 * k as f64).unwrap_or_default();
    vec![Similarity {
        scale: 1.0,
        rotation: rot,
        about: c,
        translate: Vec3::new(0.0, 0.0, 0.02 * scale * k as f64),
    }]
}

/// Factor time, per-move times, factor entries and the factor's parts of one method.
type BenchRun = (f64, Vec<f64>, usize, BTreeMap<String, f64>);

/// The same ROI's plain cotangent system, factored, whose 3-right-hand-side solve every
/// timed move is compared with: it is solved just before each move, so machine noise hits
/// both alike.
struct CotanReference {
    chol: CholeskySolver,
    times: Vec<f64>,
}

impl CotanReference {
    /// One 3-right-hand-side solve, timed.
    fn solve(&mut self) -> Result<(), EditError> {
        let r = self.times.len();
        let mut rhs = Mat::from_fn(self.chol.dim(), 3, |i, c| ((i * (c + 3) + r) % 17) as f64);
        let t = Instant::now();
        self.chol.solve_in_place(rhs.as_mut())?;
        self.times.push(ms(t));
        std::hint::black_box(rhs);
        Ok(())
    }
}

/// The time of each of `moves` (at least one) handle moves answered by `solve`, ms, each
/// after one timed `reference` solve.
fn move_times(
    p: &EditProblem,
    moves: usize,
    scale: f64,
    reference: &mut CotanReference,
    mut solve: impl FnMut(&[Similarity]) -> Result<Vec<Vec3>, EditError>,
) -> Result<Vec<f64>, EditError> {
    (0..moves.max(1))
        .map(|k| {
            let tr = bench_move(p, k + 1, scale);
            reference.solve()?;
            let t = Instant::now();
            std::hint::black_box(solve(&tr)?);
            Ok(ms(t))
        })
        .collect()
}

/// One method factored and moved; the factored method is returned for further timings.
fn bench_method<M: EditMethod>(
    p: &EditProblem,
    o: &M::Options,
    moves: usize,
    scale: f64,
    reference: &mut CotanReference,
) -> Result<(BenchRun, M), EditError> {
    let t = Instant::now();
    let mut m = M::factor(p, o)?;
    let f = ms(t);
    let per = move_times(p, moves, scale, reference, |tr| m.solve(p, tr))?;
    let parts = m
        .factor_parts()
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
    Ok(((f, per, m.factor_len(), parts), m))
}

/// `fires bench edit`: one factorisation, then `moves` handle moves; the same ROI's
/// cotangent system (free = ROI minus handles and anchors) is factored and solved with 3
/// right-hand sides in the same run for comparison. Every solve is single-threaded except
/// `per_move_two_threads_ms`; implicit editing factors on two threads.
pub fn bench_edit(
    mesh: &SurfaceMesh,
    method: Method,
    roi_fraction: f64,
    moves: usize,
) -> Result<BenchEditReport, EditError> {
    let spec = bench_spec(mesh, roi_fraction)?;
    let p = EditProblem::new(mesh, &spec)?;
    let scale = p.mean_edge_length() * 10.0;
    // Plain cotangent solve of the same ROI.
    let k = cotan_stiffness(&p)?;
    let free: Vec<usize> = (0..p.len()).filter(|&l| !p.is_constrained(l)).collect();
    let mut slot = vec![usize::MAX; p.len()];
    for (s, &l) in free.iter().enumerate() {
        slot[l] = s;
    }
    let t: Vec<_> = crate::solve::sparse_triplets(k.as_ref())
        .into_iter()
        .filter(|&(i, j, _)| slot[i] != usize::MAX && slot[j] != usize::MAX && i >= j)
        .map(|(i, j, v)| (slot[i], slot[j], v))
        .collect();
    let kuu = crate::solve::sparse_from_triplets(free.len(), free.len(), &t)?;
    let tf = Instant::now();
    let chol = CholeskySolver::new(kuu.as_ref(), CholeskyOptions::default())?;
    let cotan_factor_ms = ms(tf);
    let mut cotan = CotanReference {
        chol,
        times: Vec::new(),
    };
    let mut basis_ms = None;
    let mut per_move_basis_ms = None;
    let mut per_move_two_threads_ms = None;
    let (factor_ms, per, entries, factor_parts) = match method {
        Method::Lse => {
            let (r, lse) =
                bench_method::<LseEditor>(&p, &LseOptions::default(), moves, scale, &mut cotan)?;
            let t = Instant::now();
            let basis = lse.precompute_basis(&p)?;
            basis_ms = Some(ms(t));
            let per = move_times(&p, moves, scale, &mut cotan, |tr| basis.combine(&p, tr))?;
            per_move_basis_ms = Some(median(per));
            r
        }
        Method::Poisson => {
            bench_method::<PoissonEditor>(&p, &Default::default(), moves, scale, &mut cotan)?.0
        }
        Method::Implicit => {
            // The drag: first system only, one solve per move, on one thread and (another
            // editor) on two, the moves interleaved so machine noise hits both alike; then
            // from the drag basis.
            let options = ImplicitOptions {
                second_solve: false,
                drag_basis: false,
                ..Default::default()
            };
            let (mut r, mut editor) =
                bench_method::<ImplicitEditor>(&p, &options, 1, scale, &mut cotan)?;
            let two = ImplicitOptions {
                threads: SubtreeThreads::FactorAndSolve,
                ..options
            };
            let mut editor2 = ImplicitEditor::factor(&p, &two)?;
            let (mut one_ms, mut two_ms) = (Vec::new(), Vec::new());
            for k in 0..moves.max(1) {
                let tr = bench_move(&p, k + 1, scale);
                cotan.solve()?;
                for (ed, times) in [(&mut editor, &mut one_ms), (&mut editor2, &mut two_ms)] {
                    let t = Instant::now();
                    std::hint::black_box(ed.solve(&p, &tr)?);
                    times.push(ms(t));
                }
            }
            r.1 = one_ms;
            per_move_two_threads_ms = Some(median(two_ms));
            editor.precompute_drag_basis(&p)?;
            basis_ms = Some(editor.drag_basis_ms());
            let per = move_times(&p, moves, scale, &mut cotan, |tr| editor.solve_drag(&p, tr))?;
            per_move_basis_ms = Some(median(per));
            r
        }
        Method::Naive => {
            bench_method::<NaiveLaplacian>(&p, &Default::default(), moves, scale, &mut cotan)?.0
        }
    };
    Ok(BenchEditReport {
        method: method.name().into(),
        roi_vertices: p.n_roi,
        factor_ms,
        per_move_ms: median(per),
        cotan_solve_ms: median(cotan.times),
        cotan_factor_ms,
        factor_entries: entries,
        basis_ms,
        per_move_basis_ms,
        per_move_two_threads_ms,
        factor_parts,
    })
}
