//! Triangle quantities: area, normal, interior angles, cotangents.
//!
//! Near-degenerate triangles: cotangents are computed as `cos/sin` with the sine clamped
//! from below (see [`cot_of_angle_between`]), so a zero-area triangle gives a large but
//! finite weight instead of an infinity or NaN.

use super::Vec3;

/// Smallest `|a × b|` relative to `|a||b|` used when forming a cotangent (≈ an angle of
/// 1e-8 rad). Below it the cotangent is clamped to ±1e8.
const MIN_RELATIVE_SINE: f64 = 1e-8;

/// Unnormalised normal `(b − a) × (c − a)`; its length is twice the area.
pub fn triangle_normal(a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    (b - a).cross(c - a)
}

/// Area of triangle `abc`.
pub fn triangle_area(a: Vec3, b: Vec3, c: Vec3) -> f64 {
    0.5 * triangle_normal(a, b, c).norm()
}

/// Cotangent of the angle between `u` and `v` (`u·v / |u × v|`), with the sine clamped
/// from below to `1e-8 |u||v|` so degenerate corners give a finite value.
pub fn cot_of_angle_between(u: Vec3, v: Vec3) -> f64 {
    let cos = u.dot(v);
    let sin = u.cross(v).norm();
    let floor = MIN_RELATIVE_SINE * (u.norm() * v.norm());
    if floor == 0.0 {
        return 0.0;
    }
    cos / sin.max(floor)
}

/// True when a corner's sine is below the cotangent clamp of [`cot_of_angle_between`]
/// (`|u × v| < 1e-8 |u||v|`) or two corners coincide: a zero-area triangle whose
/// clamped cotangents no longer form a positive semidefinite element matrix.
pub fn is_degenerate_triangle(a: Vec3, b: Vec3, c: Vec3) -> bool {
    let twice_area = triangle_normal(a, b, c).norm();
    let (ab, bc, ca) = ((b - a).norm(), (c - b).norm(), (a - c).norm());
    let widest = (ab * ca).max(ab * bc).max(bc * ca);
    ab == 0.0 || bc == 0.0 || ca == 0.0 || twice_area < MIN_RELATIVE_SINE * widest
}

/// Interior angles at `a`, `b` and `c` (radians), computed with `atan2` for accuracy on
/// thin triangles. A corner with a zero-length edge gets angle 0.
pub fn triangle_angles(a: Vec3, b: Vec3, c: Vec3) -> [f64; 3] {
    let angle = |p: Vec3, q: Vec3, r: Vec3| {
        let u = q - p;
        let v = r - p;
        u.cross(v).norm().atan2(u.dot(v))
    };
    [angle(a, b, c), angle(b, c, a), angle(c, a, b)]
}
