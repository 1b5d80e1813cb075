//! Boundary loops, shared by mesh closure, border gluing and skinning: the nearest boundary point to a
//! drawn point, and the loop through a boundary edge traced in the *closing* direction (the direction a
//! new face on the open side traverses it, opposite to the one face already there).

use super::crossings::nearest_point_on;
use super::{End, ToolError};
use crate::network::geom::P3;
use crate::network::mesh::{EdgeUse, Network};
use crate::network::{EdgeId, VertexId};

/// A point on a boundary edge.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BorderPoint {
    pub(crate) edge: EdgeId,
    pub(crate) seg: usize,
    pub(crate) t: f64,
    pub(crate) point: P3,
    pub(crate) distance: f64,
}

/// Whether `e` is a boundary edge (used by exactly one face).
pub(crate) fn is_border(net: &Network, e: EdgeId) -> bool {
    net.edge(e).is_some_and(|x| x.faces.len() == 1)
}

/// The boundary point nearest to `p` within `radius` metres.
pub(crate) fn nearest_border(net: &Network, p: P3, radius: f64) -> Option<BorderPoint> {
    nearest_point_on(net, p, radius, |e| is_border(net, e)).map(|h| BorderPoint {
        edge: h.edge,
        seg: h.seg,
        t: h.t,
        point: h.point,
        distance: h.distance,
    })
}

/// The boundary point nearest to the `end` of a drawn curve, or the typed refusal.
pub(crate) fn border_end(
    net: &Network,
    p: P3,
    end: End,
    radius: f64,
) -> Result<BorderPoint, ToolError> {
    nearest_border(net, p, radius).ok_or_else(|| {
        let distance = nearest_border(net, p, f64::INFINITY).map_or(f64::INFINITY, |b| b.distance);
        ToolError::NotOnBoundary {
            end,
            distance_mm: distance * 1e3,
            limit_mm: radius * 1e3,
        }
    })
}

/// The closing-direction use of boundary edge `e` (opposite to its one face's use).
pub(crate) fn closing_use(net: &Network, e: EdgeId) -> Option<EdgeUse> {
    let ed = net.edge(e)?;
    let [f] = ed.faces[..] else { return None };
    let u = net.face(f)?.uses.iter().find(|u| u.edge == e)?;
    Some(EdgeUse {
        edge: e,
        reversed: !u.reversed,
    })
}

/// The boundary loop through boundary edge `e`, in the closing direction, starting with `e`. Refused
/// when a vertex of the loop has more than one way on (a pinched boundary: two loops touch there).
pub(crate) fn border_loop(net: &Network, e: EdgeId) -> Result<Vec<EdgeUse>, ToolError> {
    let first = closing_use(net, e).ok_or(ToolError::NotABoundaryEdge { edge: e })?;
    let mut out = vec![first];
    let mut used = std::collections::HashSet::from([e]);
    loop {
        let last = out[out.len() - 1];
        let v = net
            .use_end(last)
            .ok_or(ToolError::NotABoundaryEdge { edge: last.edge })?;
        let mut next: Option<EdgeUse> = None;
        let mut count = 0;
        let mut edges = net.vertex(v).map(|x| x.edges.clone()).unwrap_or_default();
        edges.sort_unstable();
        edges.dedup();
        for c in edges {
            let Some(u) = closing_use(net, c) else {
                continue;
            };
            if net.use_start(u) == Some(v) && (c != last.edge || is_self_loop(net, c)) {
                count += 1;
                next = Some(u);
            }
        }
        let Some(u) = next else {
            return Err(ToolError::NotABoundaryEdge { edge: last.edge });
        };
        if count > 1 {
            return Err(ToolError::PinchedBoundary { vertex: v });
        }
        if u.edge == e {
            return Ok(out);
        }
        if !used.insert(u.edge) {
            return Err(ToolError::PinchedBoundary { vertex: v });
        }
        out.push(u);
    }
}

fn is_self_loop(net: &Network, e: EdgeId) -> bool {
    net.edge(e).is_some_and(|x| x.from == x.to)
}

/// The vertices a loop passes through, in order (the start of each use).
pub(crate) fn loop_vertices(net: &Network, uses: &[EdgeUse]) -> Vec<VertexId> {
    uses.iter().filter_map(|u| net.use_start(*u)).collect()
}
