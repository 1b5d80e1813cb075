//! Border gluing by a tube, the thesis's own construction (FIRES thesis §5.1.3 and §5.2.3, Fig. 5.4): the
//! user draws a curve from border A to border B and a second one that separates the tube into two halves;
//! both are inserted, and the system adds two faces f₁, f₂ with exactly the same four vertices
//! (a₁, a₂, b₁, b₂) whose edges have different polylines: f₁ = half a₁ → a₂ of A, curve 2, half b₂ → b₁
//! of B, curve 1 backwards; f₂ = the other halves with the curves the other way.
//!
//! The thesis lets the user pick which half-curve of B goes with which of A. With orientation stored per
//! face use only one choice keeps the two borders' faces consistent: each border is traversed opposite
//! to the face already on it. That is `flip_second: false`. The other choice (`flip_second: true`)
//! reverses the orientation of every face of B's surface first, which is only possible when B's surface is
//! not A's (otherwise the tube would be a Möbius band: refused, rule "orientable gluing").
//!
//! Bookkeeping with the four ends on edge interiors: ΔV = 4, ΔE = 4 + 2, ΔF = 2, so Δχ = 0 and two
//! boundaries fewer (genus +1 on one surface: a cylinder's two ends joined make a torus).

use super::border::{is_border, loop_vertices};
use super::gluing::{anchor, loop_at};
use super::{widened_m, CurveInput, End, ToolError};
use crate::network::geom::P3;
use crate::network::mesh::{EdgeUse, Network, Origin, PolylineAttrs};
use crate::network::{EdgeId, FaceId, Transaction, VertexId};

/// Options of [`glue_tube`] (millimetres).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct TubeOptions {
    /// The curves' ends must be this close to a boundary.
    pub snap_mm: f64,
    /// An end this close to a vertex of its boundary edge goes onto the vertex.
    pub vertex_snap_mm: f64,
    /// Distances are widened to this many times the strokes' σ when that is larger.
    pub sigma_factor: f64,
    /// Which half-curve of B goes with which of A.
    pub halves: TubeHalves,
}

/// How [`glue_tube`] pairs the half-curves of the two borders.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TubeHalves {
    /// The pairing that keeps both surfaces' orientation.
    #[default]
    Oriented,
    /// The other pairing: B's surface is reversed first (it must not be A's).
    Flipped,
    /// The pairing the half directions choose (as in skinning).
    Auto,
}

impl Default for TubeOptions {
    fn default() -> Self {
        TubeOptions {
            snap_mm: 8.0,
            vertex_snap_mm: 4.0,
            sigma_factor: 3.0,
            halves: TubeHalves::Oriented,
        }
    }
}

/// What [`glue_tube`] made.
#[derive(Clone, Debug, PartialEq)]
pub struct TubeReport {
    /// a₁, b₁, a₂, b₂.
    pub vertices: [VertexId; 4],
    /// The two inserted curves (a₁ → b₁, a₂ → b₂).
    pub edges: [EdgeId; 2],
    /// The two tube faces.
    pub faces: [FaceId; 2],
    /// B's surface was reversed.
    pub flipped: bool,
}

fn component(net: &Network, v: VertexId) -> std::collections::HashSet<VertexId> {
    let mut seen = std::collections::HashSet::from([v]);
    let mut stack = vec![v];
    while let Some(x) = stack.pop() {
        for &e in net.vertex(x).map(|x| &x.edges[..]).unwrap_or(&[]) {
            if let Some(ed) = net.edge(e) {
                for y in [ed.from, ed.to] {
                    if seen.insert(y) {
                        stack.push(y);
                    }
                }
            }
        }
    }
    seen
}

/// Joins border A (where both curves start) to border B (where they end) by a tube of two faces.
pub fn glue_tube(
    net: &mut Network,
    first: CurveInput<'_>,
    second: CurveInput<'_>,
    options: &TubeOptions,
) -> Result<(TubeReport, Transaction), ToolError> {
    let mut curves: Vec<Vec<P3>> = Vec::with_capacity(2);
    for c in [&first, &second] {
        if c.points.len() < 2 {
            return Err(ToolError::BadCurve(
                "a gluing curve needs at least 2 points".into(),
            ));
        }
        if !c.points.iter().flatten().all(|x| x.is_finite()) {
            return Err(ToolError::BadCurve("a point is not finite".into()));
        }
        curves.push(c.points.to_vec());
    }
    let sigma = [first.sigma_mm, second.sigma_mm]
        .into_iter()
        .flatten()
        .fold(None, |m: Option<f64>, s| Some(m.map_or(s, |m| m.max(s))));
    let r = widened_m(options.snap_mm, sigma, options.sigma_factor);
    let vsnap = widened_m(options.vertex_snap_mm, sigma, options.sigma_factor);
    let ends = [
        (curves[0][0], End::Start),
        (curves[0][curves[0].len() - 1], End::End),
        (curves[1][0], End::Start),
        (curves[1][curves[1].len() - 1], End::End),
    ];
    for (p, end) in ends {
        super::border::border_end(net, p, end, r)?;
    }
    let attrs = |c: &CurveInput<'_>| PolylineAttrs {
        stroke: c.stroke,
        origin: Origin::User,
        ..PolylineAttrs::default()
    };
    let (attrs1, attrs2) = (attrs(&first), attrs(&second));
    net.transact(|net| {
        let mut vs = [VertexId::new(0); 4];
        for (k, (p, end)) in ends.iter().enumerate() {
            vs[k] = anchor(net, *p, *end, r, vsnap)?;
        }
        let [a1, b1, a2, b2] = vs;
        let loop_a = loop_at(net, a1)?;
        let va = loop_vertices(net, &loop_a);
        let pa2 = va.iter().position(|&x| x == a2);
        if va.contains(&b1) || va.contains(&b2) {
            return Err(ToolError::DifferentBoundaries {
                first: loop_a[0].edge,
                second: loop_a[0].edge,
            });
        }
        let flip = match options.halves {
            TubeHalves::Oriented => false,
            TubeHalves::Flipped => true,
            TubeHalves::Auto => {
                let lb = loop_at(net, b1)?;
                let vb = loop_vertices(net, &lb);
                let (Some(pa2), Some(pb2)) = (pa2, vb.iter().position(|&x| x == b2)) else {
                    return Err(ToolError::DifferentBoundaries {
                        first: loop_a[0].edge,
                        second: lb[0].edge,
                    });
                };
                let pts = |uses: &[EdgeUse]| -> Vec<P3> {
                    let mut out: Vec<P3> = Vec::new();
                    for u in uses {
                        let mut p = net
                            .edge_polyline(u.edge)
                            .map(|p| p.points.clone())
                            .unwrap_or_default();
                        if u.reversed {
                            p.reverse();
                        }
                        let skip = usize::from(!out.is_empty());
                        out.extend(p.into_iter().skip(skip));
                    }
                    out
                };
                let (a0, a_1) = (pts(&loop_a[..pa2]), pts(&loop_a[pa2..]));
                let (b0, b_1) = (pts(&lb[..pb2]), pts(&lb[pb2..]));
                // Unflipped, A's first half goes with B's second (closing directions); flip when the
                // directions pair it with B's first.
                super::pair_halves([&a0, &a_1], [&b0, &b_1])?
            }
        };
        let mut flipped = false;
        if flip {
            let comp = component(net, b1);
            if comp.contains(&a1) {
                return Err(ToolError::CrossedGluing);
            }
            let faces: Vec<FaceId> = net
                .faces()
                .filter(|(_, f)| {
                    f.uses
                        .first()
                        .and_then(|u| net.use_start(*u))
                        .is_some_and(|v| comp.contains(&v))
                })
                .map(|(id, _)| id)
                .collect();
            for f in faces {
                let Some(mut face) = net.face(f).cloned() else {
                    continue;
                };
                face.uses = face
                    .uses
                    .iter()
                    .rev()
                    .map(|u| EdgeUse {
                        edge: u.edge,
                        reversed: !u.reversed,
                    })
                    .collect();
                net.set_face(f, Some(face));
            }
            flipped = true;
        }
        let loop_b = loop_at(net, b1)?;
        let vb = loop_vertices(net, &loop_b);
        let pb2 = vb.iter().position(|&x| x == b2);
        let (Some(pa2), Some(pb2)) = (pa2, pb2) else {
            return Err(ToolError::DifferentBoundaries {
                first: loop_a[0].edge,
                second: loop_b[0].edge,
            });
        };
        if pa2 == 0 || pb2 == 0 {
            return Err(ToolError::DegenerateGluing);
        }
        debug_assert!(loop_a.iter().chain(&loop_b).all(|u| is_border(net, u.edge)));
        let c1 = net.add_edge(a1, b1, curves[0].clone(), attrs1);
        let c2 = net.add_edge(a2, b2, curves[1].clone(), attrs2);
        let (fwd, rev) = (
            |edge| EdgeUse {
                edge,
                reversed: false,
            },
            |edge| EdgeUse {
                edge,
                reversed: true,
            },
        );
        let mut l1: Vec<EdgeUse> = loop_a[..pa2].to_vec();
        l1.push(fwd(c2));
        l1.extend_from_slice(&loop_b[pb2..]);
        l1.push(rev(c1));
        let mut l2: Vec<EdgeUse> = loop_a[pa2..].to_vec();
        l2.push(fwd(c1));
        l2.extend_from_slice(&loop_b[..pb2]);
        l2.push(rev(c2));
        let f1 = net.add_face(l1);
        let f2 = net.add_face(l2);
        net.validate().map_err(|e| match e {
            crate::network::InvariantError::InconsistentOrientation(_) => ToolError::CrossedGluing,
            other => ToolError::BadCurve(format!("internal: tube gluing broke {other}")),
        })?;
        Ok(TubeReport {
            vertices: vs,
            edges: [c1, c2],
            faces: [f1, f2],
            flipped,
        })
    })
}
