//! Curve insertion (FIRES thesis §5.1 and §5.2.1): a curve that starts and ends on the network splits
//! the faces it runs through, one face split per pair of consecutive points where it meets the network.
//!
//! * **Meeting points.** For each existing polyline the curve comes within the intersection threshold of,
//!   the closest pair of points (see `crossings.rs`). The new vertex goes at the point on the old polyline,
//!   so existing curves do not move; the new polyline's ends are set onto it.
//! * **Vertex snapping.** A meeting point within the vertex snapping distance of an end vertex of its
//!   edge is moved onto that vertex and the edge is not split. Where that would make a piece break rule 1
//!   (the curve met two curves near their junction and the next meeting is on an edge at it), the
//!   meetings are taken where they are instead; a piece shorter than twice the vertex snapping distance
//!   that rule 1 refuses is folded into one meeting point (see `merge_slivers`).
//! * **Strokes as people draw them.** An end that stops short of the network by at most the snapping
//!   distance is extended by a straight segment to the nearest network point; an end that overshoots the
//!   first (last) crossing by at most `overshoot_mm` is trimmed there. Both are reported.
//! * **Ends the tracker lost.** An end the pen drew without being tracked (`untracked_mm`, the strokes
//!   file's button time against its first or last point) is first continued along its tangent, by at
//!   most that length and `overshoot_mm`, to the first curve the continuation meets (reported as an
//!   extension): the stroke began or ended on that curve, and its tracked end is not an overshoot.
//! * **Rule 1.** No piece of the curve may start and end on one polyline (that would make a two-sided face).
//! * **Rule 2.** Consecutive meeting points must share a face: a curve that passes over another without
//!   coming within the threshold, or leaves the surface, is refused.
//!
//! Thresholds default to 5 mm (intersection), 8 mm (short stops) and 4 mm (vertex snapping), a few times
//! the tracker's tip accuracy,
//! and are widened to `sigma_factor · σ` when the stroke's own uncertainty σ is larger.
//! Bookkeeping with both ends on edges, m crossings and no snapping: ΔV = m + 2, ΔE = 2m + 3, ΔF = m + 1.

use super::crossings::{arcs, find_hits, gap, nearest_point, Hit};
use super::{widened_m, CurveInput, End, ToolError};
use crate::network::geom::P3;
use crate::network::mesh::{Network, Origin, PolylineAttrs};
use crate::network::ops::SAME_POINT_M;
use crate::network::{EdgeId, FaceId, Transaction, VertexId};

/// Options of [`insert_curve`] (millimetres).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct InsertOptions {
    /// Two curves intersect where they come closer than this.
    pub intersect_mm: f64,
    /// Ends this close to the network are extended to it (short stops).
    pub snap_mm: f64,
    /// Meeting points (crossings and ends) this close to an end vertex of their edge go onto that vertex.
    /// Smaller than `snap_mm`: a curve crossing another this close to a junction is taken to pass through
    /// it; the simulator's grid keeps its junctions about 9 mm apart or more.
    pub vertex_snap_mm: f64,
    /// Longest tail past the first or last crossing that is trimmed.
    pub overshoot_mm: f64,
    /// Thresholds are widened to this many times the stroke's σ when that is larger.
    pub sigma_factor: f64,
    /// A curve whose ends are this close is closed: when its ends are not on the network it is inserted
    /// from its first crossing round to the same crossing.
    pub close_mm: f64,
}

impl Default for InsertOptions {
    fn default() -> Self {
        InsertOptions {
            intersect_mm: 5.0,
            snap_mm: 8.0,
            vertex_snap_mm: 4.0,
            overshoot_mm: 30.0,
            sigma_factor: 3.0,
            close_mm: 10.0,
        }
    }
}

/// A change made to how the curve was drawn.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Adjustment {
    /// The tail past the first/last crossing was cut off.
    Trimmed {
        /// Which end.
        end: End,
        /// Length cut, mm.
        length_mm: f64,
    },
    /// The end stopped short and was joined to the network by a straight segment.
    Extended {
        /// Which end.
        end: End,
        /// Length added, mm.
        gap_mm: f64,
    },
}

/// What [`insert_curve`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct InsertReport {
    /// The new edges, in order along the curve.
    pub edges: Vec<EdgeId>,
    /// The vertices the curve runs through, in order (ends included).
    pub vertices: Vec<VertexId>,
    /// The new faces that remain after all splits.
    pub faces: Vec<FaceId>,
    /// Meeting points between the ends.
    pub crossings: usize,
    /// Meeting points moved onto an existing vertex.
    pub snapped: usize,
    /// Trimmed and extended ends.
    pub adjustments: Vec<Adjustment>,
}

#[derive(Clone, Copy, Debug)]
enum Anchor {
    Vertex(VertexId),
    Edge { edge: EdgeId, seg: usize, t: f64 },
}

#[derive(Clone, Copy, Debug)]
struct Stop {
    sigma: f64,
    anchor: Anchor,
}

struct Ctx<'a> {
    net: &'a Network,
    pts: &'a [P3],
    total: f64,
    hits: &'a [Hit],
    near_ends: [Option<Hit>; 2],
    thr: f64,
    snap: f64,
    vertex_snap: f64,
    over: f64,
    report: f64,
}

/// Inserts `curve` into the network (see the module docs for the rules).
pub fn insert_curve(
    net: &mut Network,
    curve: CurveInput<'_>,
    options: &InsertOptions,
) -> Result<(InsertReport, Transaction), ToolError> {
    let mut pts = super::distinct_points(curve.points)?;
    if pts.len() < 2 {
        return Err(ToolError::BadCurve(
            "a curve needs at least 2 distinct points".into(),
        ));
    }
    let thr = widened_m(options.intersect_mm, curve.sigma_mm, options.sigma_factor);
    let snap = widened_m(options.snap_mm, curve.sigma_mm, options.sigma_factor);
    let vertex_snap = widened_m(options.vertex_snap_mm, curve.sigma_mm, options.sigma_factor);
    // Ends the tracker lost: continue them along their tangent to the curve they began or ended on.
    let mut untracked = Vec::new();
    for (k, end) in [End::Start, End::End].into_iter().enumerate() {
        let reach = curve.untracked_mm[k].min(options.overshoot_mm);
        if !(reach.is_finite() && reach > 0.0) {
            continue;
        }
        if let Some((p, gap_mm)) = untracked_end(net, &pts, end, reach * 1e-3, thr) {
            match end {
                End::Start => pts.insert(0, p),
                End::End => pts.push(p),
            }
            untracked.push(Adjustment::Extended { end, gap_mm });
        }
    }
    let mut arc = arcs(&pts);
    let (mut hits, mut near_ends) = find_hits(net, &pts, &arc, thr, snap);
    // A closed curve whose ends are not on the network starts and ends at its first crossing (thesis
    // §5.2.1: closed curves are accepted when they cross the network).
    let closed = pts.len() > 3 && gap(pts[0], pts[pts.len() - 1]) <= options.close_mm * 1e-3;
    let mut rotated_loop = false;
    if closed && near_ends.iter().all(|n| n.is_none()) {
        if let Some(h) = hits.first() {
            let i = arc
                .partition_point(|&s| s <= h.sigma)
                .clamp(1, pts.len() - 1)
                - 1;
            let span = arc[i + 1] - arc[i];
            let t = if span > 0.0 {
                (h.sigma - arc[i]) / span
            } else {
                0.0
            };
            let p = crate::network::geom::lerp(pts[i], pts[i + 1], t);
            let body = &pts[..pts.len() - 1];
            let mut rotated = vec![p];
            rotated.extend(body[i + 1..].iter().chain(&body[..=i]).copied());
            rotated.push(p);
            rotated.dedup_by(|b, a| gap(*a, *b) <= SAME_POINT_M);
            pts = rotated;
            arc = arcs(&pts);
            (hits, near_ends) = find_hits(net, &pts, &arc, thr, snap);
            rotated_loop = true;
        }
    }
    let total = arc[arc.len() - 1];
    let ctx = Ctx {
        net,
        pts: &pts,
        total,
        hits: &hits,
        near_ends,
        thr,
        snap,
        vertex_snap,
        over: options.overshoot_mm * 1e-3,
        report: options.intersect_mm * 1e-3,
    };
    let mut adjustments = untracked;
    let (start, adj) = ctx.resolve_end(End::Start)?;
    adjustments.extend(adj);
    let (mut end, adj) = ctx.resolve_end(End::End)?;
    adjustments.extend(adj);
    if rotated_loop {
        // The loop closes on the very point it starts from.
        end.anchor = start.anchor;
    }
    // Meeting points snap to vertices; where that would make a piece break rule 1 (two curves met near
    // their junction, both snapped onto it, and the next meeting is on an edge at that junction), the
    // crossings are taken where they are instead: a small face rather than a refused stroke.
    let mut stops = Vec::new();
    for crossing_snap in [ctx.vertex_snap, 0.0] {
        stops = vec![start];
        for h in &hits {
            if h.sigma > start.sigma && h.sigma < end.sigma {
                stops.push(ctx.stop_at(h, crossing_snap));
            }
        }
        stops.push(end);
        // Consecutive stops on one vertex are one stop.
        stops.dedup_by(|b, a| match (a.anchor, b.anchor) {
            (Anchor::Vertex(x), Anchor::Vertex(y)) => x == y,
            _ => false,
        });
        if crossing_snap == 0.0 {
            // Unsnapped, a curve passing near a junction also comes within the threshold of the
            // junction itself (the end of each edge there): that approach is not a crossing of its own
            // when the curve crosses an edge at that junction next to it.
            let mut k = 1;
            while k + 1 < stops.len() {
                let v = stops[k].anchor;
                if matches!(v, Anchor::Vertex(_))
                    && (ctx.breaks_rule_one(stops[k - 1].anchor, v)
                        || ctx.breaks_rule_one(v, stops[k + 1].anchor))
                {
                    stops.remove(k);
                } else {
                    k += 1;
                }
            }
        }
        ctx.merge_slivers(&mut stops);
        if stops
            .windows(2)
            .all(|w| !ctx.breaks_rule_one(w[0].anchor, w[1].anchor))
        {
            break;
        }
    }
    let snapped = stops
        .iter()
        .filter(|s| matches!(s.anchor, Anchor::Vertex(_)))
        .count();
    if stops.len() < 2 {
        return Err(ToolError::BadCurve(
            "the curve meets the network at one point only".into(),
        ));
    }
    for w in stops.windows(2) {
        ctx.check_rule_one(w[0].anchor, w[1].anchor)?;
    }
    let attrs = PolylineAttrs {
        stroke: curve.stroke,
        origin: Origin::User,
        ..PolylineAttrs::default()
    };
    let n_stops = stops.len();
    let (mut report, txn) = net.transact(|net| apply(net, &stops, &pts, &arc, attrs, thr))?;
    report.crossings = n_stops - 2;
    report.snapped = snapped;
    report.adjustments = adjustments;
    Ok((report, txn))
}

/// Where an untracked end meets the network: the first network point within `thr` of the end's
/// tangent ray, at most `reach` metres out, and the length added (mm). None when the end is already
/// within `thr` of the network or the ray meets nothing. The tangent is the chord over the last
/// [`TANGENT_M`] of the curve, so one noisy point does not turn it.
fn untracked_end(net: &Network, pts: &[P3], end: End, reach: f64, thr: f64) -> Option<(P3, f64)> {
    let ordered: Vec<P3> = match end {
        End::Start => pts.to_vec(),
        End::End => pts.iter().rev().copied().collect(),
    };
    let e = *ordered.first()?;
    if nearest_point(net, e, thr).is_some() {
        return None;
    }
    let inner = ordered
        .iter()
        .find(|q| gap(**q, e) >= TANGENT_M)
        .or(ordered.last())
        .copied()?;
    let len = gap(e, inner);
    if len <= SAME_POINT_M {
        return None;
    }
    let dir = [0, 1, 2].map(|k| (e[k] - inner[k]) / len);
    let far = [0, 1, 2].map(|k| e[k] + dir[k] * reach);
    let ray = [e, far];
    let (hits, _) = find_hits(net, &ray, &arcs(&ray), thr, 0.0);
    let h = hits.first()?;
    Some((h.point, gap(e, h.point) * 1e3))
}

/// Length of curve over which [`untracked_end`] takes an end's tangent, metres.
const TANGENT_M: f64 = 0.01;

impl Ctx<'_> {
    fn along(&self, end: End, h: &Hit) -> f64 {
        match end {
            End::Start => h.sigma,
            End::End => self.total - h.sigma,
        }
    }

    fn stop_of(&self, h: &Hit, sigma: f64) -> Stop {
        self.stop_with(h, sigma, self.vertex_snap)
    }

    /// An interior meeting point, snapped to a vertex within `snap`.
    fn stop_at(&self, h: &Hit, snap: f64) -> Stop {
        self.stop_with(h, h.sigma, snap)
    }

    fn stop_with(&self, h: &Hit, sigma: f64, snap: f64) -> Stop {
        let anchor = match self.net.edge(h.edge) {
            Some(ed) => {
                let pos = |v| {
                    self.net
                        .vertex(v)
                        .map_or(f64::INFINITY, |x| gap(x.position, h.point))
                };
                let (df, dt) = (pos(ed.from), pos(ed.to));
                if df <= snap && df <= dt {
                    Anchor::Vertex(ed.from)
                } else if dt <= snap {
                    Anchor::Vertex(ed.to)
                } else {
                    Anchor::Edge {
                        edge: h.edge,
                        seg: h.seg,
                        t: h.t,
                    }
                }
            }
            None => Anchor::Edge {
                edge: h.edge,
                seg: h.seg,
                t: h.t,
            },
        };
        Stop { sigma, anchor }
    }

    /// Where an end of the curve attaches, and how it was adjusted.
    fn resolve_end(&self, end: End) -> Result<(Stop, Option<Adjustment>), ToolError> {
        let p = match end {
            End::Start => self.pts[0],
            End::End => self.pts[self.pts.len() - 1],
        };
        let near = self.near_ends[match end {
            End::Start => 0,
            End::End => 1,
        }];
        // The outermost meeting point, except that a curve whose closest approach to an edge is its own
        // end point does not cross that edge: when another edge is nearer to that end, the end is on
        // the nearer one, and the farther approach is no meeting at all (a stroke ending on a curve a
        // few millimetres from where that curve meets a third one).
        let farther_end_approach = |h: &&Hit| {
            near.is_some_and(|n| {
                self.along(end, h) <= SAME_POINT_M && h.edge != n.edge && h.distance > n.distance
            })
        };
        let first = match end {
            End::Start => self.hits.iter().find(|h| !farther_end_approach(h)),
            End::End => self.hits.iter().rev().find(|h| !farther_end_approach(h)),
        };
        // Adjustments shorter than the (unwidened) intersection threshold are ordinary drawing and not
        // reported.
        let trimmed = |h: &Hit| {
            let along = self.along(end, h);
            let adj = if along > self.report {
                Some(Adjustment::Trimmed {
                    end,
                    length_mm: along * 1e3,
                })
            } else if along <= SAME_POINT_M && h.distance > self.report {
                Some(Adjustment::Extended {
                    end,
                    gap_mm: h.distance * 1e3,
                })
            } else {
                None
            };
            (self.stop_of(h, h.sigma), adj)
        };
        if let Some(near) = near {
            if let Some(h) = first {
                let on_it =
                    near.distance <= self.thr || gap(h.point, near.point) <= self.snap + self.thr;
                if on_it && self.along(end, h) <= self.snap + self.thr {
                    return Ok(trimmed(h));
                }
            }
            // Stopped short: extend to the nearest point.
            let sigma = match end {
                End::Start => -1.0,
                End::End => self.total + 1.0,
            };
            let adj = Adjustment::Extended {
                end,
                gap_mm: near.distance * 1e3,
            };
            return Ok((self.stop_of(&near, sigma), Some(adj)));
        }
        if let Some(h) = first {
            if self.along(end, h) <= self.over {
                return Ok(trimmed(h));
            }
        }
        let distance =
            nearest_point(self.net, p, f64::INFINITY).map_or(f64::INFINITY, |h| h.distance);
        Err(ToolError::EndNotOnNetwork {
            end,
            distance_mm: distance * 1e3,
            limit_mm: self.snap * 1e3,
        })
    }

    /// Whether the piece between two stops breaks rule 1.
    fn breaks_rule_one(&self, a: Anchor, b: Anchor) -> bool {
        self.check_rule_one(a, b).is_err()
    }

    /// Folds the slivers rule 1 would refuse into one meeting point: a piece shorter than twice the
    /// snapping distance between a vertex and an edge at it, or between two meetings with one edge, is
    /// a curve drawn across a junction (it meets both curves there, one of them snapped to the junction)
    /// or one that grazes a curve and comes back. The curve passes through the vertex, or does not cross
    /// the grazed curve at all; a longer such piece is still refused. An end is kept where it can be.
    fn merge_slivers(&self, stops: &mut Vec<Stop>) {
        let short = |a: &Stop, b: &Stop| {
            b.sigma.clamp(0.0, self.total) - a.sigma.clamp(0.0, self.total)
                <= 2.0 * self.vertex_snap
        };
        let mut i = 0;
        while i + 1 < stops.len() {
            let (a, b) = (stops[i], stops[i + 1]);
            if !(self.breaks_rule_one(a.anchor, b.anchor) && short(&a, &b)) {
                i += 1;
                continue;
            }
            let last = stops.len() - 1;
            match (a.anchor, b.anchor) {
                (Anchor::Vertex(_), _) => {
                    stops.remove(i + 1);
                }
                (_, Anchor::Vertex(_)) => {
                    stops.remove(i);
                }
                _ if i == 0 => {
                    stops.remove(1);
                }
                _ if i + 1 == last => {
                    stops.remove(i);
                }
                _ => {
                    stops.drain(i..i + 2);
                }
            }
            if stops.len() < 2 {
                return;
            }
            i = i.saturating_sub(1);
        }
    }

    fn check_rule_one(&self, a: Anchor, b: Anchor) -> Result<(), ToolError> {
        let ends = |e: EdgeId| self.net.edge(e).map(|x| (x.from, x.to));
        match (a, b) {
            (Anchor::Edge { edge: x, .. }, Anchor::Edge { edge: y, .. }) if x == y => {
                Err(ToolError::SamePolyline { edge: x })
            }
            (Anchor::Vertex(v), Anchor::Edge { edge, .. })
            | (Anchor::Edge { edge, .. }, Anchor::Vertex(v))
                if ends(edge).is_some_and(|(f, t)| f == v || t == v) =>
            {
                Err(ToolError::SamePolyline { edge })
            }
            _ => Ok(()),
        }
    }
}

fn apply(
    net: &mut Network,
    stops: &[Stop],
    pts: &[P3],
    arc: &[f64],
    attrs: PolylineAttrs,
    thr: f64,
) -> Result<InsertReport, ToolError> {
    let internal = |what: &str| ToolError::BadCurve(format!("internal: {what}"));
    let mut vs: Vec<Option<VertexId>> = stops
        .iter()
        .map(|s| match s.anchor {
            Anchor::Vertex(v) => Some(v),
            Anchor::Edge { .. } => None,
        })
        .collect();
    // Split each edge at its meeting points, last parameter first, so the first half keeps the
    // parameterisation of the remaining cuts.
    let mut cuts: Vec<(EdgeId, usize, f64, usize)> = stops
        .iter()
        .enumerate()
        .filter_map(|(k, s)| match s.anchor {
            Anchor::Edge { edge, seg, t } => Some((edge, seg, t, k)),
            Anchor::Vertex(_) => None,
        })
        .collect();
    cuts.sort_by(|a, b| a.0.cmp(&b.0).then(b.1.cmp(&a.1)).then(b.2.total_cmp(&a.2)));
    let mut current: Option<(EdgeId, EdgeId)> = None;
    let mut last: Option<(EdgeId, usize, f64, VertexId)> = None;
    for (edge, seg, t, k) in cuts {
        if let Some((le, ls, lt, lv)) = last {
            if le == edge && ls == seg && lt == t {
                vs[k] = Some(lv);
                continue;
            }
        }
        let target = match current {
            Some((orig, first_half)) if orig == edge => first_half,
            _ => edge,
        };
        let (v, halves) = net
            .split_edge(target, seg, t)
            .ok_or_else(|| internal("split edge"))?;
        vs[k] = Some(v);
        last = Some((edge, seg, t, v));
        current = Some((edge, halves.map_or(target, |h| h.0)));
    }
    let mut path: Vec<(VertexId, f64)> = Vec::with_capacity(stops.len());
    for (k, s) in stops.iter().enumerate() {
        let v = vs[k].ok_or_else(|| internal("unresolved stop"))?;
        if path.last().is_none_or(|l| l.0 != v) {
            path.push((v, s.sigma));
        }
    }
    let mut report = InsertReport {
        edges: Vec::new(),
        vertices: path.iter().map(|p| p.0).collect(),
        faces: Vec::new(),
        crossings: 0,
        snapped: 0,
        adjustments: Vec::new(),
    };
    for (piece, w) in path.windows(2).enumerate() {
        let ((a, sa), (b, sb)) = (w[0], w[1]);
        let pa = net.vertex(a).ok_or_else(|| internal("vertex"))?.position;
        let pb = net.vertex(b).ok_or_else(|| internal("vertex"))?.position;
        let mut points = vec![pa];
        for (i, p) in pts.iter().enumerate() {
            if arc[i] > sa
                && arc[i] < sb
                && gap(*p, pa) > SAME_POINT_M
                && gap(*p, pb) > SAME_POINT_M
            {
                points.push(*p);
            }
        }
        points.push(pb);
        let mid = points[points.len() / 2];
        let fa = net.vertex_faces(a);
        let fb = net.vertex_faces(b);
        let mut two_gon = None;
        let mut best: Option<(f64, FaceId)> = None;
        for f in fa.into_iter().filter(|f| fb.contains(f)) {
            let Some(cut) = net.face_cut(f, a, b) else {
                continue;
            };
            let (ab, ba) = cut.sides();
            if ab == 1 || ba == 1 {
                let face = net.face(f).ok_or_else(|| internal("face"))?;
                two_gon = Some(face.uses[if ab == 1 { cut.i } else { cut.j }].edge);
                continue;
            }
            let fp = net.face_points(f);
            let c = fp
                .iter()
                .fold([0.0; 3], |s, p| [s[0] + p[0], s[1] + p[1], s[2] + p[2]]);
            let n = fp.len().max(1) as f64;
            let d = gap([c[0] / n, c[1] / n, c[2] / n], mid);
            if best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, f));
            }
        }
        let Some((_, f)) = best else {
            return Err(match two_gon {
                Some(edge) => ToolError::SamePolyline { edge },
                None => ToolError::NoCommonFace {
                    piece,
                    threshold_mm: thr * 1e3,
                },
            });
        };
        let cut = net.face_cut(f, a, b).ok_or_else(|| internal("cut"))?;
        let (e, f1, f2) = net
            .split_face(f, &cut, points, attrs)
            .ok_or_else(|| internal("split face"))?;
        report.edges.push(e);
        report.faces.extend([f1, f2]);
    }
    report.faces.retain(|f| net.face(*f).is_some());
    Ok(report)
}
