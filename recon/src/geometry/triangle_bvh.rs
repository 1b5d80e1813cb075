//! A bounding-volume hierarchy over triangles for exact closest-point queries (point-to-mesh distance).
//!
//! Axis-aligned boxes, built top-down by splitting each node's triangles at the median centroid along the
//! longest axis of their centroids' box (Wald, Boulos and Shirley, *Ray tracing deformable scenes using dynamic
//! bounding volume hierarchies*, 2007, §3, the median variant), up to [`LEAF_SIZE`] triangles per leaf. A query
//! descends nearer child first and skips every box farther than the best distance found (branch and bound),
//! so the answer is the exact minimum over all triangles ([`super::closest_point_on_triangle`]).

use super::{closest_point_on_triangle, Vec3};

/// Largest number of triangles in a leaf.
pub const LEAF_SIZE: usize = 4;

#[derive(Clone, Debug)]
struct Node {
    lo: Vec3,
    hi: Vec3,
    /// Leaf: first index into `order`; inner: index of the first child (the second follows it).
    first: usize,
    /// Triangles of a leaf; 0 for an inner node.
    count: usize,
}

/// The answer of [`TriangleBvh::closest`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosestHit {
    /// Distance from the query point.
    pub distance: f64,
    /// The closest point.
    pub point: Vec3,
    /// Index of its triangle (in the order given to [`TriangleBvh::new`]).
    pub triangle: usize,
}

/// Bounding-volume hierarchy over a triangle soup (module docs).
#[derive(Clone, Debug)]
pub struct TriangleBvh {
    tris: Vec<[Vec3; 3]>,
    order: Vec<usize>,
    nodes: Vec<Node>,
}

fn min3(a: Vec3, b: Vec3) -> Vec3 {
    Vec3::new(a.x.min(b.x), a.y.min(b.y), a.z.min(b.z))
}

fn max3(a: Vec3, b: Vec3) -> Vec3 {
    Vec3::new(a.x.max(b.x), a.y.max(b.y), a.z.max(b.z))
}

/// Squared distance from `p` to the box `[lo, hi]` (0 inside).
fn box_distance2(p: Vec3, lo: Vec3, hi: Vec3) -> f64 {
    let d = |x: f64, l: f64, h: f64| (l - x).max(0.0).max(x - h);
    let (dx, dy, dz) = (d(p.x, lo.x, hi.x), d(p.y, lo.y, hi.y), d(p.z, lo.z, hi.z));
    dx * dx + dy * dy + dz * dz
}

impl TriangleBvh {
    /// Builds the hierarchy over `triangles` (corner positions). Triangles with a non-finite corner are left out.
    pub fn new(triangles: Vec<[Vec3; 3]>) -> Self {
        let order: Vec<usize> = (0..triangles.len())
            .filter(|&i| triangles[i].iter().all(|p| p.is_finite()))
            .collect();
        let mut bvh = TriangleBvh {
            tris: triangles,
            order,
            nodes: Vec::new(),
        };
        if !bvh.order.is_empty() {
            bvh.nodes.push(Node {
                lo: Vec3::ZERO,
                hi: Vec3::ZERO,
                first: 0,
                count: 0,
            });
            let n = bvh.order.len();
            bvh.build(0, 0, n);
        }
        bvh
    }

    /// Builds it over the triangles `[i, j, k]` of vertex indices into `points` (indices out of range are left
    /// out).
    pub fn from_indexed(points: &[Vec3], triangles: &[[usize; 3]]) -> Self {
        Self::new(
            triangles
                .iter()
                .filter(|t| t.iter().all(|&i| i < points.len()))
                .map(|t| [points[t[0]], points[t[1]], points[t[2]]])
                .collect(),
        )
    }

    /// Number of triangles indexed.
    pub fn len(&self) -> usize {
        self.order.len()
    }

    /// Whether no triangle is indexed.
    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    fn build(&mut self, node: usize, start: usize, end: usize) {
        let inf = Vec3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
        let (mut lo, mut hi) = (inf, -inf);
        let (mut clo, mut chi) = (lo, hi);
        for &t in &self.order[start..end] {
            let [a, b, c] = self.tris[t];
            lo = min3(lo, min3(a, min3(b, c)));
            hi = max3(hi, max3(a, max3(b, c)));
            let m = (a + b + c) / 3.0;
            clo = min3(clo, m);
            chi = max3(chi, m);
        }
        self.nodes[node].lo = lo;
        self.nodes[node].hi = hi;
        let n = end - start;
        let ext = chi - clo;
        if n <= LEAF_SIZE || !(ext.x > 0.0 || ext.y > 0.0 || ext.z > 0.0) {
            self.nodes[node].first = start;
            self.nodes[node].count = n;
            return;
        }
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        let mid = start + n / 2;
        let tris = &self.tris;
        let key = |t: &usize| {
            let [a, b, c] = tris[*t];
            a[axis] + b[axis] + c[axis]
        };
        self.order[start..end].select_nth_unstable_by(n / 2, |x, y| key(x).total_cmp(&key(y)));
        let left = self.nodes.len();
        for _ in 0..2 {
            self.nodes.push(Node {
                lo: Vec3::ZERO,
                hi: Vec3::ZERO,
                first: 0,
                count: 0,
            });
        }
        self.nodes[node].first = left;
        self.build(left, start, mid);
        self.build(left + 1, mid, end);
    }

    /// The closest point of all triangles to `p` (None if the hierarchy is empty or `p` is not finite).
    pub fn closest(&self, p: Vec3) -> Option<ClosestHit> {
        if self.nodes.is_empty() || !p.is_finite() {
            return None;
        }
        let mut best: Option<(f64, Vec3, usize)> = None;
        let mut stack = vec![(box_distance2(p, self.nodes[0].lo, self.nodes[0].hi), 0usize)];
        while let Some((d2, ni)) = stack.pop() {
            if best.is_some_and(|b| d2 >= b.0) {
                continue;
            }
            let node = &self.nodes[ni];
            if node.count > 0 {
                for &t in &self.order[node.first..node.first + node.count] {
                    let [a, b, c] = self.tris[t];
                    let q = closest_point_on_triangle(p, a, b, c);
                    let e2 = (q - p).norm_squared();
                    if best.is_none_or(|b| e2 < b.0) {
                        best = Some((e2, q, t));
                    }
                }
            } else {
                let (l, r) = (node.first, node.first + 1);
                let dl = box_distance2(p, self.nodes[l].lo, self.nodes[l].hi);
                let dr = box_distance2(p, self.nodes[r].lo, self.nodes[r].hi);
                // Nearer child popped first.
                if dl <= dr {
                    stack.push((dr, r));
                    stack.push((dl, l));
                } else {
                    stack.push((dl, l));
                    stack.push((dr, r));
                }
            }
        }
        best.map(|(d2, point, triangle)| ClosestHit {
            distance: d2.sqrt(),
            point,
            triangle,
        })
    }
}
