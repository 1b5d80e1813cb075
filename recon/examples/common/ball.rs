//! A geodesic ball on an icosphere and its vertices' ring neighbourhoods, the systems the
//! solver examples factor.

use fires_recon::generate::icosphere;
use fires_recon::mesh::Vertex;

/// The 1-ring of each vertex (itself included, sorted) of the `roi` vertices nearest
/// vertex 0 of an icosphere with at least 1.25 × `roi` vertices, in local numbering.
pub fn ball_rings(roi: usize) -> Vec<Vec<usize>> {
    let mut level = 1;
    while 10 * 4usize.pow(level) + 2 < roi * 5 / 4 {
        level += 1;
    }
    let mesh = icosphere(level, 1.0);
    let seed = mesh.vertices().next().expect("icosphere has vertices");
    let d = fires_recon::operators::geodesic_dijkstra(&mesh, &[seed]).expect("connected");
    let mut order: Vec<usize> = mesh.vertices().map(|v| v.idx()).collect();
    order.sort_by(|&a, &b| d[a].total_cmp(&d[b]));
    let mut local = vec![usize::MAX; mesh.n_vertices()];
    for (l, &v) in order[..roi].iter().enumerate() {
        local[v] = l;
    }
    order[..roi]
        .iter()
        .map(|&v| {
            let mut r: Vec<usize> = mesh
                .vertex_vertices(Vertex::new(v))
                .map(|u| local[u.idx()])
                .filter(|&u| u != usize::MAX)
                .collect();
            r.push(local[v]);
            r.sort_unstable();
            r
        })
        .collect()
}

/// One more ring around every neighbourhood in `near`.
pub fn grow(ring: &[Vec<usize>], near: &[Vec<usize>]) -> Vec<Vec<usize>> {
    near.iter()
        .map(|r| {
            let mut s: Vec<usize> = r.iter().flat_map(|&u| ring[u].iter().copied()).collect();
            s.sort_unstable();
            s.dedup();
            s
        })
        .collect()
}
