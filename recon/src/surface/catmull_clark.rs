//! One Catmull-Clark step on a [`ControlMesh`] (any polygons in, quads out) with sharp rules and curve
//! keeping.
//!
//! Rules (Catmull & Clark, *Recursively generated B-spline surfaces on arbitrary topological meshes*, 1978;
//! sharp rules of Hoppe et al., *Piecewise smooth surface reconstruction*, SIGGRAPH 1994, §3, and DeRose,
//! Kass & Truong, *Subdivision surfaces in character animation*, SIGGRAPH 1998, §2 with infinite
//! sharpness):
//! * face point: the average of the face's vertices;
//! * edge point: `(a + b + f₀ + f₁)/4`; on a **crease** edge (along a sharp curve, or a boundary edge) the
//!   midpoint `(a + b)/2`;
//! * vertex point: `(Q + 2R + (n − 3)v)/n` (Q the average of the new face points, R of the edge midpoints,
//!   n the valence); with two crease edges (a crease vertex) `(a + 6v + b)/8` along them; with more than
//!   two (a corner), or a [`VertexTag::Corner`] on a sharp curve, the vertex is fixed. One crease edge (a
//!   dart) uses the smooth rule.
//!
//! Tags: the two children of a curve edge get the halves of its [`CurveSpan`], its edge point is
//! [`VertexTag::OnCurve`] at the span's mid-parameter; old vertices keep their tags; face points and the
//! edges inside faces are free.
//!
//! # Keeping the curves ([`CurveKeeping`])
//! Catmull-Clark approximates: left alone it pulls the surface off the drawn curves (a crease's limit is the
//! cubic B-spline of its vertices). Two remedies, chosen by [`CatmullClarkOptions::keep`]:
//! * [`CurveKeeping::Snap`] (the default; FIRES thesis §6.3, NULISSmod's edge rule): every curve vertex is
//!   put at its curve point (its parameter's point on the polyline) and every curve edge's edge point at its
//!   span's mid-parameter point. All other points use the rules above (the vertices next to a non-sharp
//!   curve average both sides), but undoing the Catmull-Clark shrinkage on the curve only leaves a ridge
//!   along it: measured on the sphere of three great circles (FIRESV2, soft flow), the
//!   normals across the curves differ by 25° after three levels, so this mode suits sharp curves, or levels
//!   followed by ones of another kind;
//! * [`CurveKeeping::Limit`] (FIRESV2's choice; Schaefer, Warren & Zorin, *Lofting curve networks using subdivision surfaces*,
//!   SGP 2004, §4, in spirit: move the control points so that the limit surface passes through the curves):
//!   before the step, the curve vertices are moved (Gauss-Seidel on the limit stencils) so that their
//!   Catmull-Clark limit positions are their curve points (on the C1 cubic through the polyline's samples,
//!   [`smooth_point_at`]), then the plain rules apply; finish with
//!   [`limit_positions`]. The surface stays C1 across non-sharp curves and passes through the curve vertices
//!   of every level (same sphere: 0.04°; a bumpy height-field grid 0.13°).
//!   With [`CatmullClarkOptions::limit_fit_spread`] the fit first moves the free vertices too, along their
//!   normals by the harmonic extension of the curve vertices' normal corrections (FIRESV1's choice, v1.rs):
//!   where the whole control net lies on the surface (an interpolatory level before), moving the curve
//!   vertices alone lifts them out of it, and the limit surface gets a narrow ridge along every curve (C1,
//!   but bent within a face or two of the curve).
//! * [`CurveKeeping::None`]: the plain rules.

use super::control::{ControlMesh, CurvePoint, CurveSpan, VertexTag};
use super::error::SurfaceError;
use crate::geometry::Vec3;
use crate::mesh::{Edge, SurfaceMesh, Vertex};

/// How a subdivision step keeps the surface on the curves (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum CurveKeeping {
    /// Plain sharp Catmull-Clark: the surface leaves the curves.
    None,
    /// Curve vertices and curve edge points are put on their curves.
    #[default]
    Snap,
    /// Curve vertices are moved so the limit surface passes through their curve points.
    Limit,
}

/// Options of [`catmull_clark`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CatmullClarkOptions {
    /// How the curves are kept (default [`CurveKeeping::Snap`], exact at every level; FIRESV2 uses
    /// [`CurveKeeping::Limit`], see the module docs).
    pub keep: CurveKeeping,
    /// Boundary edges are creases (the usual boundary rules); default true.
    pub boundary_is_crease: bool,
    /// Gauss-Seidel sweeps of the limit fit of [`CurveKeeping::Limit`] (default 8).
    pub limit_fit_sweeps: usize,
    /// Spread the limit fit's correction over the free vertices ([`CurveKeeping::Limit`]; module docs):
    /// Gauss-Seidel sweeps of the harmonic extension of its normal part per fit sweep (default 0: only the
    /// curve vertices move).
    pub limit_fit_spread: usize,
}

impl Default for CatmullClarkOptions {
    fn default() -> Self {
        Self {
            keep: CurveKeeping::Snap,
            boundary_is_crease: true,
            limit_fit_sweeps: 8,
            limit_fit_spread: 0,
        }
    }
}

/// How the rules see one control mesh: crease edges and the per-vertex rule.
struct Classes {
    crease: Vec<bool>,
    rule: Vec<Rule>,
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum Rule {
    Smooth,
    /// Along two crease edges to these neighbours.
    Crease(Vertex, Vertex),
    Fixed,
}

fn check(c: &ControlMesh) -> Result<(), SurfaceError> {
    if c.mesh.has_garbage() {
        return Err(SurfaceError::BadControlMesh(
            "the mesh has deleted elements".into(),
        ));
    }
    let nc = c.curves.len();
    for s in c.edge_curve.iter().flatten() {
        if s.curve >= nc {
            return Err(SurfaceError::BadControlMesh(format!(
                "edge tag names curve {}, which does not exist",
                s.curve
            )));
        }
    }
    for t in &c.vertex_tag {
        if let VertexTag::OnCurve(p) = t {
            if p.curve >= nc {
                return Err(SurfaceError::BadControlMesh(format!(
                    "vertex tag names curve {}, which does not exist",
                    p.curve
                )));
            }
        }
    }
    Ok(())
}

fn classify(c: &ControlMesh, boundary_is_crease: bool) -> Classes {
    let m = &c.mesh;
    let crease: Vec<bool> = m
        .edges()
        .map(|e| c.is_sharp(e) || (boundary_is_crease && m.is_boundary_edge(e)))
        .collect();
    let rule = m
        .vertices()
        .map(|v| {
            if m.is_isolated(v) {
                return Rule::Fixed;
            }
            let ends: Vec<Vertex> = m
                .vertex_halfedges(v)
                .filter(|h| crease[h.edge().idx()])
                .map(|h| m.to_vertex(h))
                .collect();
            let on_sharp = m.vertex_halfedges(v).any(|h| c.is_sharp(h.edge()));
            match ends.len() {
                _ if on_sharp && c.tag(v) == VertexTag::Corner => Rule::Fixed,
                0 | 1 => Rule::Smooth,
                2 => Rule::Crease(ends[0], ends[1]),
                _ => Rule::Fixed,
            }
        })
        .collect();
    Classes { crease, rule }
}

/// The point of the curves a tagged vertex must lie on: its own curve point for
/// [`VertexTag::OnCurve`], the end of an incident curve edge's span for [`VertexTag::Corner`]; `None` for
/// free vertices (or a corner without curve edges).
pub fn curve_target(c: &ControlMesh, v: Vertex) -> Option<Vec3> {
    match c.tag(v) {
        VertexTag::Free => None,
        VertexTag::OnCurve(p) => c.curves.get(p.curve).map(|cv| cv.point_at(p.t)),
        VertexTag::Corner => c.mesh.vertex_halfedges(v).find_map(|h| {
            let e = h.edge();
            let s = c.span(e)?;
            let t = if c.mesh.edge_vertices(e).0 == v {
                s.t0
            } else {
                s.t1
            };
            c.curves.get(s.curve).map(|cv| cv.point_at(t))
        }),
    }
}

/// [`curve_target`] on the C1 cubic (Hermite, arc-length parameters) through the curve's samples
/// instead of the polyline: the target the limit fit uses, so that a surface finer than the polyline's
/// sampling does not inherit the polyline's kinks at its samples (it still passes through every sample).
pub fn smooth_curve_target(c: &ControlMesh, v: Vertex) -> Option<Vec3> {
    match c.tag(v) {
        VertexTag::OnCurve(p) => c.curves.get(p.curve).map(|cv| smooth_point_at(cv, p.t)),
        _ => curve_target(c, v),
    }
}

/// The point at arc length `t` of the cubic Hermite interpolant of `curve`'s samples in arc length, with
/// three-point parabolic tangents (C1, third-order accurate between samples).
pub fn smooth_point_at(curve: &super::control::Curve, t: f64) -> Vec3 {
    let (p, a) = (&curve.points, &curve.arc);
    let n = p.len();
    if n < 3 || a.len() != n || t <= 0.0 || t >= curve.length() {
        return curve.point_at(t);
    }
    let j = a.partition_point(|&x| x <= t).clamp(1, n - 1);
    let (a0, a1) = (a[j - 1], a[j]);
    let h = a1 - a0;
    if h <= 0.0 {
        return curve.point_at(t);
    }
    // Derivative of the parabola through three consecutive samples (second-order accurate for any
    // spacing), at the middle sample inside the curve and at the end sample at its ends.
    let tangent = |k: usize| {
        let i = k.clamp(1, n - 2);
        let (h0, h1) = (a[i] - a[i - 1], a[i + 1] - a[i]);
        if h0 <= 0.0 || h1 <= 0.0 {
            return Vec3::ZERO;
        }
        let (q0, q1, q2) = (p[i - 1], p[i], p[i + 1]);
        let s = h0 + h1;
        if k == 0 {
            q0 * (-(2.0 * h0 + h1) / (h0 * s)) + q1 * (s / (h0 * h1)) - q2 * (h0 / (h1 * s))
        } else if k == n - 1 {
            q0 * (h1 / (h0 * s)) - q1 * (s / (h0 * h1)) + q2 * ((2.0 * h1 + h0) / (h1 * s))
        } else {
            q0 * (-h1 / (h0 * s)) + q1 * ((h1 - h0) / (h0 * h1)) + q2 * (h0 / (h1 * s))
        }
    };
    let (m0, m1) = (tangent(j - 1) * h, tangent(j) * h);
    let s = (t - a0) / h;
    let (s2, s3) = (s * s, s * s * s);
    p[j - 1] * (2.0 * s3 - 3.0 * s2 + 1.0)
        + m0 * (s3 - 2.0 * s2 + s)
        + p[j] * (-2.0 * s3 + 3.0 * s2)
        + m1 * (s3 - s2)
}

/// The Catmull-Clark limit position of every vertex of an all-quad mesh, with the crease rules of the
/// module docs: smooth `(n²v + 4Σeⱼ + Σfⱼ)/(n(n + 5))` (Halstead, Kass & DeRose, *Efficient, fair
/// interpolation using Catmull-Clark surfaces*, SIGGRAPH 1993, appendix A: eⱼ the edge neighbours, fⱼ the
/// opposite corners of the quads), crease `(a + 4v + b)/6`, corners fixed. A vertex next to a non-quad face
/// is given its own position.
pub fn limit_positions(c: &ControlMesh, opts: &CatmullClarkOptions) -> Vec<Vec3> {
    let cls = classify(c, opts.boundary_is_crease);
    let m = &c.mesh;
    m.vertices()
        .map(|v| limit_of(m, &cls, v, m.positions()).unwrap_or(m.position(v)))
        .collect()
}

/// `(limit position, weight of v itself)` of one vertex, or `None` where no stencil applies.
fn limit_stencil(m: &SurfaceMesh, cls: &Classes, v: Vertex, p: &[Vec3]) -> Option<(Vec3, f64)> {
    match cls.rule[v.idx()] {
        Rule::Fixed => Some((p[v.idx()], 1.0)),
        Rule::Crease(a, b) => Some((
            (p[a.idx()] + p[v.idx()] * 4.0 + p[b.idx()]) / 6.0,
            4.0 / 6.0,
        )),
        Rule::Smooth => {
            let mut n = 0usize;
            let (mut se, mut sf) = (Vec3::ZERO, Vec3::ZERO);
            for h in m.vertex_halfedges(v) {
                if m.is_boundary_halfedge(h) {
                    return None;
                }
                let h1 = m.next_halfedge(h);
                let h2 = m.next_halfedge(h1);
                if m.next_halfedge(m.next_halfedge(h2)) != h {
                    return None;
                }
                n += 1;
                se += p[m.to_vertex(h).idx()];
                sf += p[m.to_vertex(h1).idx()];
            }
            if n < 3 {
                return None;
            }
            let nf = n as f64;
            let d = nf * (nf + 5.0);
            Some((
                (p[v.idx()] * (nf * nf) + se * 4.0 + sf) / d,
                nf / (nf + 5.0),
            ))
        }
    }
}

fn limit_of(m: &SurfaceMesh, cls: &Classes, v: Vertex, p: &[Vec3]) -> Option<Vec3> {
    limit_stencil(m, cls, v, p).map(|s| s.0)
}

/// Moves the curve vertices so their limit positions are their curve targets ([`CurveKeeping::Limit`]).
fn fit_limit(c: &ControlMesh, cls: &Classes, sweeps: usize, spread: usize) -> Vec<Vec3> {
    let m = &c.mesh;
    let targets: Vec<(Vertex, Vec3)> = m
        .vertices()
        .filter(|&v| cls.rule[v.idx()] != Rule::Fixed)
        .filter_map(|v| smooth_curve_target(c, v).map(|t| (v, t)))
        .collect();
    let p = if spread > 0 {
        spread_fit(m, cls, &targets, sweeps, spread)
    } else {
        m.positions().to_vec()
    };
    gauss_seidel(m, cls, p, &targets, sweeps)
}

/// The limit fit with its correction spread over the free vertices: the curve vertices take their limit
/// residuals (accumulated over `outer` rounds), and the free vertices move along their normals by the
/// harmonic extension of the curve vertices' normal corrections (zero at fixed vertices; `sweeps`
/// Gauss-Seidel sweeps of the uniform Laplacian per round, warm-started), so that a face's interior moves
/// with its curves instead of leaving a ridge of moved curve vertices. Only the normal part is spread: the
/// tangential part only slides a curve vertex along the surface, and averaged over a curved face it
/// would move the interior off it.
fn spread_fit(
    m: &SurfaceMesh,
    cls: &Classes,
    targets: &[(Vertex, Vec3)],
    outer: usize,
    sweeps: usize,
) -> Vec<Vec3> {
    let p0 = m.positions();
    let mut pinned: Vec<bool> = cls.rule.iter().map(|&r| r == Rule::Fixed).collect();
    for &(v, _) in targets {
        pinned[v.idx()] = true;
    }
    // Vertex normals: the sum of the incident faces' (Newell) normals.
    let mut normal = vec![Vec3::ZERO; p0.len()];
    for f in m.faces() {
        let vs: Vec<Vertex> = m.face_vertices(f).collect();
        let mut n = Vec3::ZERO;
        for (k, &v) in vs.iter().enumerate() {
            n += p0[v.idx()].cross(p0[vs[(k + 1) % vs.len()].idx()]);
        }
        for v in vs {
            normal[v.idx()] += n;
        }
    }
    for n in &mut normal {
        *n = n.normalize_or_zero();
    }
    let free: Vec<Vertex> = m.vertices().filter(|v| !pinned[v.idx()]).collect();
    // The free vertices' neighbours, gathered once for the sweeps.
    let mut start = Vec::with_capacity(free.len() + 1);
    let mut nbr: Vec<usize> = Vec::new();
    for &v in &free {
        start.push(nbr.len());
        nbr.extend(m.vertex_vertices(v).map(|w| w.idx()));
    }
    start.push(nbr.len());
    let mut d = vec![Vec3::ZERO; p0.len()];
    let mut s = vec![0.0f64; p0.len()];
    let mut p = p0.to_vec();
    for _ in 0..outer {
        for &(v, t) in targets {
            if let Some((l, _)) = limit_stencil(m, cls, v, &p) {
                d[v.idx()] += t - l;
                s[v.idx()] = d[v.idx()].dot(normal[v.idx()]);
            }
        }
        for _ in 0..sweeps {
            for (i, &v) in free.iter().enumerate() {
                let ns = &nbr[start[i]..start[i + 1]];
                if !ns.is_empty() {
                    s[v.idx()] = ns.iter().map(|&w| s[w]).sum::<f64>() / ns.len() as f64;
                }
            }
        }
        for &(v, _) in targets {
            p[v.idx()] = p0[v.idx()] + d[v.idx()];
        }
        for &v in &free {
            p[v.idx()] = p0[v.idx()] + normal[v.idx()] * s[v.idx()];
        }
    }
    p
}

/// Gauss-Seidel on the limit stencils: each sweep moves every target vertex so its limit is its target.
/// The stencil matrix is the tensor product of `(1, 4, 1)/6` on regular quads (symmetric positive
/// definite, condition number ≤ 9), so the sweeps converge.
fn gauss_seidel(
    m: &SurfaceMesh,
    cls: &Classes,
    mut p: Vec<Vec3>,
    targets: &[(Vertex, Vec3)],
    sweeps: usize,
) -> Vec<Vec3> {
    for _ in 0..sweeps {
        for &(v, t) in targets {
            if let Some((l, w)) = limit_stencil(m, cls, v, &p) {
                p[v.idx()] += (t - l) / w;
            }
        }
    }
    p
}

/// Interpolating Catmull-Clark control points (Halstead, Kass & DeRose 1993, §3, solved here by
/// Gauss-Seidel sweeps): a control mesh whose limit surface passes through every vertex of `c` (curve
/// vertices through their curve targets instead); corners and vertices without a quad stencil stay.
pub fn interpolating_control(
    c: &ControlMesh,
    opts: &CatmullClarkOptions,
    sweeps: usize,
) -> ControlMesh {
    let m = &c.mesh;
    let cls = classify(c, opts.boundary_is_crease);
    let targets: Vec<(Vertex, Vec3)> = m
        .vertices()
        .filter(|&v| cls.rule[v.idx()] != Rule::Fixed)
        .map(|v| (v, smooth_curve_target(c, v).unwrap_or(m.position(v))))
        .collect();
    let p = gauss_seidel(m, &cls, m.positions().to_vec(), &targets, sweeps);
    let mut out = c.clone();
    out.mesh.positions_mut().copy_from_slice(&p);
    out
}

/// One Catmull-Clark step (module docs). Vertex `v` of the input keeps index `v`; edge `e` gets vertex
/// `n_vertices + e`, face `f` gets `n_vertices + n_edges + f`. The result is all quads.
pub fn catmull_clark(
    c: &ControlMesh,
    opts: &CatmullClarkOptions,
) -> Result<ControlMesh, SurfaceError> {
    check(c)?;
    let m = &c.mesh;
    let cls = classify(c, opts.boundary_is_crease);
    let p: Vec<Vec3> = if opts.keep == CurveKeeping::Limit {
        fit_limit(c, &cls, opts.limit_fit_sweeps, opts.limit_fit_spread)
    } else {
        m.positions().to_vec()
    };
    let (ne, nf) = (m.edges_size(), m.faces_size());
    let snap = opts.keep == CurveKeeping::Snap;

    // Face points.
    let mut fp = vec![Vec3::ZERO; nf];
    for f in m.faces() {
        let (mut s, mut k) = (Vec3::ZERO, 0usize);
        for v in m.face_vertices(f) {
            s += p[v.idx()];
            k += 1;
        }
        fp[f.idx()] = s / k.max(1) as f64;
    }
    // Edge points.
    let mut ep = vec![Vec3::ZERO; ne];
    for e in m.edges() {
        let (a, b) = m.edge_vertices(e);
        let mid = (p[a.idx()] + p[b.idx()]) * 0.5;
        let snapped = if snap {
            c.span(e).and_then(|s| {
                c.curves
                    .get(s.curve)
                    .map(|cv| cv.point_at(0.5 * (s.t0 + s.t1)))
            })
        } else {
            None
        };
        ep[e.idx()] = if let Some(q) = snapped {
            q
        } else if cls.crease[e.idx()] {
            mid
        } else {
            let (f0, f1) = (m.face(e.halfedge(0)), m.face(e.halfedge(1)));
            match (f0, f1) {
                (Some(f0), Some(f1)) => (mid * 2.0 + fp[f0.idx()] + fp[f1.idx()]) * 0.25,
                _ => mid,
            }
        };
    }
    // Vertex points.
    let mut vp = p.clone();
    for v in m.vertices() {
        if snap {
            if let Some(t) = curve_target(c, v) {
                vp[v.idx()] = t;
                continue;
            }
        }
        vp[v.idx()] = match cls.rule[v.idx()] {
            Rule::Fixed => p[v.idx()],
            Rule::Crease(a, b) => (p[a.idx()] + p[v.idx()] * 6.0 + p[b.idx()]) * 0.125,
            Rule::Smooth => {
                let (mut q, mut r, mut n, mut nfaces) = (Vec3::ZERO, Vec3::ZERO, 0usize, 0usize);
                for h in m.vertex_halfedges(v) {
                    r += (p[v.idx()] + p[m.to_vertex(h).idx()]) * 0.5;
                    n += 1;
                    if let Some(f) = m.face(h) {
                        q += fp[f.idx()];
                        nfaces += 1;
                    }
                }
                if nfaces < n || n < 3 {
                    // An open fan without crease boundary edges: keep the vertex.
                    p[v.idx()]
                } else {
                    let nf = n as f64;
                    (q / nf + r * (2.0 / nf) + p[v.idx()] * (nf - 3.0)) / nf
                }
            }
        };
    }

    build_child(c, vp, ep, fp)
}

/// The child control mesh of one Catmull-Clark-topology split of `c`, given the new vertex points (one per
/// vertex), edge points (one per edge) and face points (one per face); tags as in the module docs.
pub(crate) fn build_child(
    c: &ControlMesh,
    vp: Vec<Vec3>,
    ep: Vec<Vec3>,
    fp: Vec<Vec3>,
) -> Result<ControlMesh, SurfaceError> {
    let m = &c.mesh;
    let (nv, ne, nf) = (m.vertices_size(), m.edges_size(), m.faces_size());
    let mut points = vp;
    points.extend(ep);
    points.extend(fp);
    let mut faces: Vec<[usize; 4]> = Vec::with_capacity(4 * nf);
    let mut hs = Vec::new();
    for f in m.faces() {
        hs.clear();
        hs.extend(m.face_halfedges(f));
        let n = hs.len();
        let centre = nv + ne + f.idx();
        for k in 0..n {
            let (h_in, h_out) = (hs[k], hs[(k + 1) % n]);
            faces.push([
                m.to_vertex(h_in).idx(),
                nv + h_out.edge().idx(),
                centre,
                nv + h_in.edge().idx(),
            ]);
        }
    }
    let mesh = SurfaceMesh::from_faces(&points, &faces)?;
    Ok(propagate_tags(c, mesh))
}

/// The child mesh's tags from the parent's (module docs).
fn propagate_tags(c: &ControlMesh, mesh: SurfaceMesh) -> ControlMesh {
    let m = &c.mesh;
    let (nv, ne) = (m.vertices_size(), m.edges_size());
    let mut vertex_tag: Vec<VertexTag> = (0..nv).map(|i| c.tag(Vertex::new(i))).collect();
    vertex_tag.resize(mesh.vertices_size(), VertexTag::Free);
    for e in m.edges() {
        if let Some(s) = c.span(e) {
            vertex_tag[nv + e.idx()] = VertexTag::OnCurve(CurvePoint {
                curve: s.curve,
                t: 0.5 * (s.t0 + s.t1),
            });
        }
    }
    let mut edge_curve = vec![None; mesh.edges_size()];
    for ce in mesh.edges() {
        let (p, q) = mesh.edge_vertices(ce);
        let (pi, qi) = (p.idx(), q.idx());
        // A half of parent edge e joins an old vertex to the edge point nv + e.
        let (old, mid, old_first) = if pi < nv && (nv..nv + ne).contains(&qi) {
            (pi, qi - nv, true)
        } else if qi < nv && (nv..nv + ne).contains(&pi) {
            (qi, pi - nv, false)
        } else {
            continue;
        };
        let e = Edge::new(mid);
        let Some(s) = c.span(e) else { continue };
        let t_old = if m.edge_vertices(e).0.idx() == old {
            s.t0
        } else {
            s.t1
        };
        let tm = 0.5 * (s.t0 + s.t1);
        let (t0, t1) = if old_first { (t_old, tm) } else { (tm, t_old) };
        edge_curve[ce.idx()] = Some(CurveSpan {
            curve: s.curve,
            t0,
            t1,
        });
    }
    ControlMesh {
        mesh,
        curves: c.curves.clone(),
        edge_curve,
        vertex_tag,
    }
}

/// Applies [`catmull_clark`] `levels` times.
pub fn catmull_clark_n(
    c: &ControlMesh,
    levels: usize,
    opts: &CatmullClarkOptions,
) -> Result<ControlMesh, SurfaceError> {
    let mut m = c.clone();
    for _ in 0..levels {
        m = catmull_clark(&m, opts)?;
    }
    Ok(m)
}
