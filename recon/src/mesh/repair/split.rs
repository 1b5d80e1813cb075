//! Non-manifold configurations, resolved by duplicating vertices so every vertex keeps a
//! single fan:
//! * a face that would give an edge a third face is added on its own copies of its
//!   vertices (what pmp-library's `SurfaceMeshIO::add_failed_faces` and OpenMesh's
//!   `ImporterT` do for faces `add_face` refuses);
//! * a vertex whose faces form several fans (a bow-tie) keeps its index for the first fan
//!   and gets one appended copy per further fan (CGAL's
//!   `duplicate_non_manifold_vertices`), so the file's vertex indices stay valid.

use super::{edge_key, EdgeKey, IndexMap, IndexSet};

/// Marks inactive every face (in file order) that would give one of its edges a third
/// active face. Returns how many were marked.
pub(super) fn deactivate_complex_edge_faces(faces: &[Vec<usize>], active: &mut [bool]) -> usize {
    let mut count: IndexMap<EdgeKey, u8> = IndexMap::default();
    count.reserve(faces.len() * 2);
    let mut marked = 0;
    for (fi, f) in faces.iter().enumerate() {
        if !active[fi] {
            continue;
        }
        let n = f.len();
        let complex = (0..n).any(|k| {
            count
                .get(&edge_key(f[k], f[(k + 1) % n]))
                .is_some_and(|&c| c >= 2)
        });
        if complex {
            active[fi] = false;
            marked += 1;
            continue;
        }
        for k in 0..n {
            *count.entry(edge_key(f[k], f[(k + 1) % n])).or_insert(0) += 1;
        }
    }
    marked
}

/// Union-find with path halving.
struct Dsu(Vec<usize>);

impl Dsu {
    fn find(&mut self, mut x: usize) -> usize {
        while self.0[x] != x {
            self.0[x] = self.0[self.0[x]];
            x = self.0[x];
        }
        x
    }
    fn union(&mut self, a: usize, b: usize) {
        let (a, b) = (self.find(a), self.find(b));
        if a != b {
            self.0[a.max(b)] = a.min(b);
        }
    }
}

/// Faces renumbered so that each vertex is one fan.
pub(super) struct Fans {
    /// Active faces with split vertex indices (inactive faces: empty).
    pub(super) faces: Vec<Vec<usize>>,
    /// Original index of every appended vertex (`n_points + k` copies `copies[k]`).
    pub(super) copies: Vec<usize>,
    /// Original vertices that were split.
    pub(super) split_vertices: usize,
}

/// Groups the corners of active faces at each vertex into fans (corners joined through
/// an edge shared by exactly two faces traversing it in opposite directions and not in
/// `cut`), and gives every fan after the first its own appended vertex.
pub(super) fn split_fans(
    faces: &[Vec<usize>],
    active: &[bool],
    n_points: usize,
    cut: &IndexSet<EdgeKey>,
) -> Fans {
    let mut start = Vec::with_capacity(faces.len() + 1);
    start.push(0);
    for (fi, f) in faces.iter().enumerate() {
        let len = if active[fi] { f.len() } else { 0 };
        start.push(start[fi] + len);
    }
    let n_corners = start[faces.len()];
    // Directed edge a→b ↦ corner of `a` in the face using it.
    let mut directed: IndexMap<(usize, usize), usize> = IndexMap::default();
    directed.reserve(n_corners);
    let mut twice: IndexSet<EdgeKey> = IndexSet::default();
    let mut corner_face = vec![0usize; n_corners];
    for (fi, f) in faces.iter().enumerate() {
        if !active[fi] {
            continue;
        }
        let n = f.len();
        corner_face[start[fi]..start[fi] + n].fill(fi);
        for k in 0..n {
            if directed
                .insert((f[k], f[(k + 1) % n]), start[fi] + k)
                .is_some()
            {
                twice.insert(edge_key(f[k], f[(k + 1) % n]));
            }
        }
    }
    let mut dsu = Dsu((0..n_corners).collect());
    let next_corner = |c: usize, fi: usize| {
        let n = start[fi + 1] - start[fi];
        start[fi] + (c - start[fi] + 1) % n
    };
    for (&(a, b), &ca) in &directed {
        let key = edge_key(a, b);
        if cut.contains(&key) || twice.contains(&key) {
            continue;
        }
        let Some(&cb) = directed.get(&(b, a)) else {
            continue;
        };
        // ca is a's corner in face F (edge a→b); cb is b's corner in face G (edge b→a).
        // a's corner in G is the one after cb; b's corner in F is the one after ca.
        let (fa, fb) = (corner_face[ca], corner_face[cb]);
        dsu.union(ca, next_corner(cb, fb));
        dsu.union(cb, next_corner(ca, fa));
    }
    let mut owner: IndexMap<usize, usize> = IndexMap::default();
    let mut first_class = vec![usize::MAX; n_points];
    let mut copies = Vec::new();
    let mut split = vec![false; n_points];
    let mut out = Vec::with_capacity(faces.len());
    for (fi, f) in faces.iter().enumerate() {
        if !active[fi] {
            out.push(Vec::new());
            continue;
        }
        let mut g = Vec::with_capacity(f.len());
        for (k, &v) in f.iter().enumerate() {
            let class = dsu.find(start[fi] + k);
            let id = if first_class[v] == usize::MAX || first_class[v] == class {
                first_class[v] = class;
                v
            } else {
                *owner.entry(class).or_insert_with(|| {
                    split[v] = true;
                    copies.push(v);
                    n_points + copies.len() - 1
                })
            };
            g.push(id);
        }
        out.push(g);
    }
    Fans {
        faces: out,
        copies,
        split_vertices: split.iter().filter(|&&s| s).count(),
    }
}

/// Active faces (after splitting) that reuse a directed edge of an earlier face.
pub(super) fn directed_conflicts(faces: &[Vec<usize>], active: &[bool]) -> Vec<usize> {
    let mut used: IndexSet<(usize, usize)> = IndexSet::default();
    let mut bad = Vec::new();
    for (fi, f) in faces.iter().enumerate() {
        if !active[fi] {
            continue;
        }
        let n = f.len();
        let edge = |k: usize| (f[k], f[(k + 1) % n]);
        if (0..n).any(|k| used.contains(&edge(k))) {
            bad.push(fi);
        } else {
            used.extend((0..n).map(edge));
        }
    }
    bad
}
