//! The half pairing of skinning (FIRES thesis §5.2.4): two spines cut each closed profile into two
//! halves; consecutive profiles must join half to matching half. For each half,
//! `d = (p_start + p_end)/2 − p_middle` (normalised; `p_middle` is the half's arc-length midpoint) points
//! from the half's bulge back to its chord; the pairing of the largest dot product among the four wins
//! and the complementary halves pair with each other. This assumes consecutive profile planes meet at a
//! dihedral angle below 90°, as the thesis does. The skinning tool that builds the faces is `skin.rs`.

use super::ToolError;
use crate::network::geom::{arc_lengths, dot, lerp, P3};

/// The normalised `d` of one half-profile.
pub fn half_direction(half: &[P3]) -> Result<P3, ToolError> {
    if half.len() < 2 {
        return Err(ToolError::BadCurve(
            "a half-profile needs at least 2 points".into(),
        ));
    }
    let arc = arc_lengths(half);
    let mid_s = arc[arc.len() - 1] / 2.0;
    let k = arc.partition_point(|&s| s < mid_s).clamp(1, half.len() - 1);
    let span = arc[k] - arc[k - 1];
    let t = if span > 0.0 {
        (mid_s - arc[k - 1]) / span
    } else {
        0.0
    };
    let m = lerp(half[k - 1], half[k], t);
    let (a, b) = (half[0], half[half.len() - 1]);
    let d = [
        (a[0] + b[0]) / 2.0 - m[0],
        (a[1] + b[1]) / 2.0 - m[1],
        (a[2] + b[2]) / 2.0 - m[2],
    ];
    let n = dot(d, d).sqrt();
    if n.is_nan() || n <= 0.0 {
        return Err(ToolError::BadCurve(
            "a half-profile is straight: no direction".into(),
        ));
    }
    Ok([d[0] / n, d[1] / n, d[2] / n])
}

/// Whether half 0 of profile `i` goes with half 0 of profile `j` (`true`) or with half 1 (`false`).
pub fn pair_halves(i: [&[P3]; 2], j: [&[P3]; 2]) -> Result<bool, ToolError> {
    let (a0, a1) = (half_direction(i[0])?, half_direction(i[1])?);
    let (b0, b1) = (half_direction(j[0])?, half_direction(j[1])?);
    let straight = dot(a0, b0).max(dot(a1, b1));
    let crossed = dot(a0, b1).max(dot(a1, b0));
    Ok(straight >= crossed)
}
