//! Face cleaning before the halfedge build: index checks, repeated corners, degenerate
//! and duplicate faces, zero-area faces.

use super::{IndexSet, Repairs};
use crate::geometry::Vec3;
use crate::mesh::MeshError;

/// Faces that survived cleaning, with the file face each came from.
pub(super) struct CleanFaces {
    pub(super) faces: Vec<Vec<usize>>,
    pub(super) source: Vec<usize>,
}

/// Checks indices (an index out of range is the one fatal defect), collapses cyclically
/// repeated consecutive corners (`a b b c` → `a b c`), drops faces left with fewer than
/// three corners or with a vertex repeated elsewhere, and drops exact duplicates (same
/// cyclic vertex sequence in either direction; the first one is kept).
pub(super) fn clean_faces<'a>(
    n_points: usize,
    faces: impl Iterator<Item = &'a [usize]>,
    repairs: &mut Repairs,
) -> Result<CleanFaces, MeshError> {
    let mut out = CleanFaces {
        faces: Vec::new(),
        source: Vec::new(),
    };
    let mut seen: IndexSet<Vec<usize>> = IndexSet::default();
    let mut sorted = Vec::new();
    for (fi, face) in faces.enumerate() {
        if let Some(&index) = face.iter().find(|&&i| i >= n_points) {
            return Err(MeshError::VertexIndexOutOfRange {
                face: fi,
                index,
                n_vertices: n_points,
            });
        }
        let mut f: Vec<usize> = face.to_vec();
        f.dedup();
        while f.len() > 1 && f.first() == f.last() {
            f.pop();
        }
        if f.len() != face.len() {
            repairs.repeated_corners_collapsed += 1;
        }
        sorted.clear();
        sorted.extend_from_slice(&f);
        sorted.sort_unstable();
        let distinct = sorted.windows(2).all(|w| w[0] != w[1]);
        if f.len() < 3 || !distinct {
            repairs.degenerate_faces_removed += 1;
            continue;
        }
        if !seen.insert(canonical_cycle(&f)) {
            repairs.duplicate_faces_removed += 1;
            continue;
        }
        out.faces.push(f);
        out.source.push(fi);
    }
    Ok(out)
}

/// The cyclic sequence rotated to start at its smallest index, read in the direction
/// whose second element is smaller: equal for the same polygon in either orientation.
fn canonical_cycle(f: &[usize]) -> Vec<usize> {
    let n = f.len();
    let s = (0..n).min_by_key(|&k| f[k]).unwrap_or(0);
    let fwd = f[(s + 1) % n] < f[(s + n - 1) % n];
    (0..n)
        .map(|k| {
            if fwd {
                f[(s + k) % n]
            } else {
                f[(s + n - k) % n]
            }
        })
        .collect()
}

/// Relative area below which a face counts as zero-area: `2·|vector area| ≤ 1e-8 · ℓ²_max`
/// (ℓ_max its longest edge), the scale where cotangent weights get clamped.
pub const ZERO_AREA_RELATIVE: f64 = 1e-8;

/// True when a polygon's vector area vanishes relative to its longest edge squared (for a
/// triangle: a corner angle below ~1e-8 rad, or coincident corners).
pub fn is_zero_area_polygon(points: &[Vec3], face: &[usize]) -> bool {
    let n = face.len();
    if n < 3 {
        return true;
    }
    let p = |k: usize| points[face[k % n]];
    let mut area2 = Vec3::ZERO;
    let mut longest: f64 = 0.0;
    for k in 0..n {
        area2 += (p(k) - p(0)).cross(p(k + 1) - p(0));
        longest = longest.max((p(k + 1) - p(k)).norm_squared());
    }
    area2.norm() <= ZERO_AREA_RELATIVE * longest
}
