//! `detail_error`: the as-rigid-as-possible energy of an edited mesh against its rest
//! shape over a vertex set, normalised (Sorkine & Alexa 2007, *As-Rigid-As-Possible
//! Surface Modeling*, Eq. 3, with the per-cell optimal rotation of §2.1):
//!
//! `Σᵢ min_{Rᵢ} Σⱼ wᵢⱼ ‖(x′ᵢ − x′ⱼ) − Rᵢ(xᵢ − xⱼ)‖² / Σᵢ Σⱼ wᵢⱼ ‖xᵢ − xⱼ‖²`
//!
//! over the vertices `i` of the set and their 1-ring neighbours `j`, with cotangent
//! weights `wᵢⱼ = ½(cot α + cot β)` of the rest mesh clamped at 0. Zero for any rigid
//! motion; scale-free.

use nalgebra::Matrix3;

use super::similarity::{polar_rotation, to_na};
use super::EditError;
use crate::geometry::Vec3;
use crate::mesh::SurfaceMesh;
use crate::operators::cotan_matrix;

/// Normalised ARAP energy of `deformed` (positions per vertex of `rest`) over `vertices`
/// (`None`: all vertices).
pub fn detail_error(
    rest: &SurfaceMesh,
    deformed: &[Vec3],
    vertices: Option<&[usize]>,
) -> Result<f64, EditError> {
    let n = rest.vertices_size();
    if deformed.len() != n {
        return Err(EditError::Mismatch(format!(
            "{} deformed positions for {n} vertices",
            deformed.len()
        )));
    }
    let c = cotan_matrix(rest)?;
    let all: Vec<usize>;
    let set = match vertices {
        Some(v) => v,
        None => {
            all = (0..n).collect();
            &all
        }
    };
    let x = rest.positions();
    let (mut num, mut den) = (0.0, 0.0);
    let cr = c.as_ref();
    for &i in set {
        if i >= n {
            return Err(EditError::InvalidVertex { index: i, n });
        }
        let rows = cr.row_idx_of_col_raw(i);
        let vals = cr.val_of_col(i);
        let mut s = Matrix3::<f64>::zeros();
        let mut cell = Vec::with_capacity(rows.len());
        for (&j, &w) in rows.iter().zip(vals) {
            if j == i || w <= 0.0 {
                continue;
            }
            let e = x[i] - x[j];
            let e2 = deformed[i] - deformed[j];
            s += to_na(e2) * to_na(e).transpose() * w;
            cell.push((w, e, e2));
            den += w * e.norm_squared();
        }
        let (r, _) = polar_rotation(&s);
        for (w, e, e2) in cell {
            let d = to_na(e2) - r * to_na(e);
            num += w * d.norm_squared();
        }
    }
    Ok(if den > 0.0 { num / den } else { 0.0 })
}
