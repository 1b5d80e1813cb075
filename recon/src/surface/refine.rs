//! Basic refinement by Coons patches (FIRES thesis §6.2): every quad becomes four quads and every triangle
//! three, with all new vertices on polylines.
//!
//! One step, per face: the Coons patch of its sides (a triangle's with one side collapsed to a corner);
//! every edge is split at the arc-length midpoint of its polyline (parameter ½), the face centre is
//! x(½, ½), and new polylines join the centre to the side midpoints, sampled from the patch on the lines
//! u = ½ and v = ½ at the parameters i/(n_s + 1). With S steps, n_s = 2^(S−s+1) − 1 at step s (n_S = 1;
//! the thesis's recurrence n_s = 2 n_{s+1} + 1 with its lost subscripts restored), so each later midpoint
//! split falls on an existing sample. A triangle gets only three new polylines, to the midpoints of its
//! three real sides. New polylines are [`Curve`]s with `generated = true`, not sharp.

use super::control::{ControlMesh, Curve, CurvePoint, VertexTag};
use super::coons::{halfedge_polyline, CoonsPatch};
use super::error::SurfaceError;
use super::from_network::Builder;
use crate::geometry::Vec3;
use crate::mesh::Halfedge;

/// Options of [`refine`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefineOptions {
    /// Number of refinement steps S (default 2, "sufficient in practice", §6.2).
    pub steps: usize,
    /// Sample the centre lines at least as densely as the face's sides (default true): the thesis's count
    /// n_s + 1 = 2^(S−s+1) segments across the face is multiplied by the smallest m with m·2^(S−s+1) ≥ the
    /// mean segment count of the face's sides, so the next step's Coons patches see the curved centre lines
    /// and not their chords (with the thesis's count a 45° patch loses about a third of its accuracy to
    /// the chords). False: the thesis's count.
    pub match_density: bool,
}

impl Default for RefineOptions {
    fn default() -> Self {
        RefineOptions {
            steps: 2,
            match_density: true,
        }
    }
}

/// Applies `opts.steps` basic-refinement steps; the result has only quads.
pub fn refine(cm: &ControlMesh, opts: &RefineOptions) -> Result<ControlMesh, SurfaceError> {
    let mut cur = cm.clone();
    for s in 1..=opts.steps {
        let segments = 1usize << (opts.steps - s + 1).min(20);
        cur = refine_step(&cur, segments, opts.match_density)?;
    }
    Ok(cur)
}

/// One basic-refinement step; the centre lines have `segments` (even, ≥ 2) segments across the whole face
/// (the thesis's n_s + 1), times the density multiplier of [`RefineOptions::match_density`] when
/// `match_density`.
pub fn refine_step(
    cm: &ControlMesh,
    segments: usize,
    match_density: bool,
) -> Result<ControlMesh, SurfaceError> {
    let segments = segments.max(2) & !1;
    let m = &cm.mesh;
    let mut b = Builder::from_control_without_spans(cm);
    b.faces.reserve(4 * m.n_faces());
    // Edge midpoints.
    let mut mid: Vec<usize> = vec![usize::MAX; m.edges_size()];
    for e in m.edges() {
        let h = e.halfedge(0);
        let (a, z) = (m.from_vertex(h).idx(), m.to_vertex(h).idx());
        let v = match cm
            .span(e)
            .and_then(|s| cm.curves.get(s.curve).map(|c| (s, c)))
        {
            Some((s, c)) => {
                let t = 0.5 * (s.t0 + s.t1);
                let v = b.vertex(
                    c.point_at(t),
                    VertexTag::OnCurve(CurvePoint { curve: s.curve, t }),
                );
                b.span(a, v, s.curve, s.t0, t);
                b.span(v, z, s.curve, t, s.t1);
                v
            }
            None => {
                let p = (m.position(m.from_vertex(h)) + m.position(m.to_vertex(h))) * 0.5;
                b.vertex(p, VertexTag::Free)
            }
        };
        mid[e.idx()] = v;
    }
    for f in m.faces() {
        let hs: Vec<Halfedge> = m.face_halfedges(f).collect();
        let sides: Vec<Vec<Vec3>> = hs.iter().map(|&h| halfedge_polyline(cm, h)).collect();
        let across = if match_density {
            let mean = sides.iter().map(|s| s.len() - 1).sum::<usize>() as f64 / sides.len() as f64;
            segments * ((mean / segments as f64).ceil() as usize).clamp(1, 1 << 12)
        } else {
            segments
        };
        let half = across / 2;
        let step = 1.0 / across as f64;
        let corner: Vec<usize> = hs.iter().map(|&h| m.from_vertex(h).idx()).collect();
        let mids: Vec<usize> = hs.iter().map(|&h| mid[h.edge().idx()]).collect();
        let patch = match sides.len() {
            3 => {
                let [s0, s1, s2]: [Vec<Vec3>; 3] = sides.try_into().map_err(|_| bad(f))?;
                CoonsPatch::triangle(s0, s1, s2)
            }
            4 => {
                let [s0, s1, s2, s3]: [Vec<Vec3>; 4] = sides.try_into().map_err(|_| bad(f))?;
                CoonsPatch::from_loop([s0, s1, s2, s3])
            }
            n => {
                return Err(SurfaceError::BadControlMesh(format!(
                    "basic refinement takes triangles and quads, face {f} has {n} sides"
                )))
            }
        };
        let centre_p = patch.eval(0.5, 0.5);
        if !centre_p.is_finite() {
            return Err(SurfaceError::Degenerate(format!("face {f}'s Coons patch")));
        }
        let centre = b.vertex(centre_p, VertexTag::Free);
        // (side index, direction in (u, v) from the centre to that side's midpoint)
        let spokes: &[(usize, (f64, f64))] = if hs.len() == 4 {
            &[
                (0, (0.0, -1.0)),
                (1, (1.0, 0.0)),
                (2, (0.0, 1.0)),
                (3, (-1.0, 0.0)),
            ]
        } else {
            &[(0, (0.0, -1.0)), (1, (1.0, 0.0)), (2, (0.0, 1.0))]
        };
        for &(k, (du, dv)) in spokes {
            let mut pts: Vec<Vec3> = (0..=half)
                .map(|i| {
                    let w = (i as f64 * step).min(0.5);
                    patch.eval(0.5 + du * w, 0.5 + dv * w)
                })
                .collect();
            pts[0] = centre_p;
            pts[half] = b.points[mids[k]];
            let mut c = Curve::new(pts, false);
            c.generated = true;
            let l = c.length();
            let ci = b.curves.len();
            b.curves.push(c);
            b.span(centre, mids[k], ci, 0.0, l);
        }
        if hs.len() == 4 {
            for k in 0..4 {
                b.faces
                    .push(vec![corner[k], mids[k], centre, mids[(k + 3) % 4]]);
            }
        } else {
            for k in 0..3 {
                b.faces
                    .push(vec![corner[k], mids[k], centre, mids[(k + 2) % 3]]);
            }
        }
    }
    b.finish()
}

fn bad(f: crate::mesh::Face) -> SurfaceError {
    SurfaceError::BadControlMesh(format!("face {f}"))
}
