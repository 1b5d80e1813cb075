//! Consistent face orientation per connected component (breadth-first flipping across
//! manifold edges, as in Botsch et al., *Polygon Mesh Processing*, §1.4 / the
//! `orient_polygon_soup` step of CGAL), with non-orientable components detected.

use std::collections::VecDeque;

use super::{edge_key, edge_uses, EdgeKey, IndexSet};

/// Result of [`orient_faces`].
pub(super) struct Orientation {
    /// Faces whose vertex order was reversed.
    pub(super) flipped: usize,
    /// Components where a cycle of faces cannot be oriented consistently.
    pub(super) non_orientable: usize,
    /// Edges joining two faces that still traverse them the same way (the cuts that make
    /// a non-orientable component orientable).
    pub(super) cut: IndexSet<EdgeKey>,
}

/// Reverses faces so that every edge shared by two active faces is traversed in opposite
/// directions where possible. In each component the orientation that flips fewer faces
/// is kept (majority of the file's faces). Inactive faces are left alone.
pub(super) fn orient_faces(faces: &mut [Vec<usize>], active: &[bool]) -> Orientation {
    let uses = edge_uses(faces, active);
    // Adjacency through edges with exactly two active faces: (neighbour, same_direction).
    // Built in face and corner order so the traversal (and any cut) is deterministic.
    let mut adj: Vec<Vec<(usize, bool, EdgeKey)>> = vec![Vec::new(); faces.len()];
    for (fi, f) in faces.iter().enumerate() {
        if !active[fi] {
            continue;
        }
        let n = f.len();
        for k in 0..n {
            let key = edge_key(f[k], f[(k + 1) % n]);
            if let Some(u) = uses.get(&key).filter(|u| u.n == 2) {
                let other = if u.face[0] == fi {
                    u.face[1]
                } else {
                    u.face[0]
                };
                adj[fi].push((other, u.fwd[0] == u.fwd[1], key));
            }
        }
    }
    let mut flip: Vec<Option<bool>> = vec![None; faces.len()];
    let mut out = Orientation {
        flipped: 0,
        non_orientable: 0,
        cut: IndexSet::default(),
    };
    let mut queue = VecDeque::new();
    let mut component = Vec::new();
    for seed in 0..faces.len() {
        if !active[seed] || flip[seed].is_some() {
            continue;
        }
        flip[seed] = Some(false);
        queue.push_back(seed);
        component.clear();
        let mut orientable = true;
        while let Some(f) = queue.pop_front() {
            component.push(f);
            let ff = flip[f].unwrap_or(false);
            for &(g, same, key) in &adj[f] {
                // Consistent when the two traversals are opposite after flipping.
                let want = ff ^ same;
                match flip[g] {
                    None => {
                        flip[g] = Some(want);
                        queue.push_back(g);
                    }
                    Some(fg) if fg != want => {
                        orientable = false;
                        out.cut.insert(key);
                    }
                    Some(_) => {}
                }
            }
        }
        if !orientable {
            out.non_orientable += 1;
        }
        let n_flip = component.iter().filter(|&&f| flip[f] == Some(true)).count();
        let invert = 2 * n_flip > component.len();
        for &f in &component {
            if flip[f].unwrap_or(false) != invert {
                faces[f].reverse();
                out.flipped += 1;
            }
        }
    }
    out
}
