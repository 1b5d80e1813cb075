//! The pen's axis from its labelled LEDs, shared by identification ([`super::identify`]) and the
//! tip ([`super::tip`]): the end-to-end direction that fixes the sign, the least-squares
//! (principal) axis of three or four LEDs (the "least squares line" of eq. 4.13, FIRES thesis,
//! §4.1.2), and the points' largest distance from that line.

use super::pen::LED_COUNT;
use nalgebra::{Matrix3, Vector3};

/// Unit direction from the highest-numbered labelled LED to the lowest (towards the tip).
pub fn labelled_direction(pts: &[Option<Vector3<f64>>; LED_COUNT]) -> Option<Vector3<f64>> {
    let front = pts.iter().flatten().next()?;
    let back = pts.iter().rev().flatten().next()?;
    (front - back).try_normalize(1e-12)
}

/// Unit principal axis (direction of the least-squares line) of the points about `centroid`,
/// by power iteration on the 3x3 scatter matrix started from the labelled end-to-end direction
/// (converges in a few steps because nearly collinear points have a dominant eigenvalue).
pub fn principal_axis(
    pts: &[Option<Vector3<f64>>; LED_COUNT],
    centroid: &Vector3<f64>,
) -> Option<Vector3<f64>> {
    let mut scatter = Matrix3::zeros();
    for p in pts.iter().flatten() {
        let d = p - centroid;
        scatter += d * d.transpose();
    }
    let mut v = labelled_direction(pts)?;
    for _ in 0..8 {
        v = (scatter * v).try_normalize(1e-300)?;
    }
    Some(v)
}

/// Maximum distance of the labelled points from their least-squares line (0 for two points).
pub fn line_residual(pts: &[Option<Vector3<f64>>; LED_COUNT]) -> f64 {
    let n = pts.iter().flatten().count();
    if n < 3 {
        return 0.0;
    }
    let centroid = pts.iter().flatten().sum::<Vector3<f64>>() / n as f64;
    let Some(axis) = principal_axis(pts, &centroid) else {
        return f64::INFINITY;
    };
    pts.iter()
        .flatten()
        .map(|p| {
            let d = p - centroid;
            (d - axis * d.dot(&axis)).norm()
        })
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn direction_points_from_the_back_led_to_the_front_one() {
        let pts = [
            None,
            Some(Vector3::new(1.0, 2.0, 3.0)),
            None,
            Some(Vector3::new(1.0, 2.0, 5.0)),
        ];
        let d = labelled_direction(&pts).unwrap();
        assert!((d - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-15);
        assert!(labelled_direction(&[Some(Vector3::x()), None, None, None]).is_none());
        assert!(labelled_direction(&[Some(Vector3::x()); LED_COUNT]).is_none());
    }

    #[test]
    fn principal_axis_of_collinear_points_is_their_line() {
        let u = Vector3::new(0.3, -0.4, 0.5).normalize();
        let o = Vector3::new(0.1, 0.2, 0.8);
        let pts = [0.0, 0.07, 0.11, 0.16].map(|s| Some(o - u * s));
        let c = pts.iter().flatten().sum::<Vector3<f64>>() / 4.0;
        let axis = principal_axis(&pts, &c).unwrap();
        // Same sign as the labelled direction (towards LED 1).
        assert!((axis - u).norm() < 1e-12, "{axis}");
        assert!(line_residual(&pts) < 1e-15);
    }

    #[test]
    fn line_residual_is_the_largest_offset_from_the_fit() {
        // Three points on x, the middle one lifted by h: the line shifts by h/3 towards it, so
        // the middle point is 2h/3 from it (the axis stays along x by symmetry).
        let h = 0.003;
        let pts = [
            Some(Vector3::new(0.0, 0.0, 1.0)),
            Some(Vector3::new(0.05, h, 1.0)),
            Some(Vector3::new(0.1, 0.0, 1.0)),
            None,
        ];
        assert!((line_residual(&pts) - 2.0 * h / 3.0).abs() < 1e-9);
        let two = [pts[0], pts[1], None, None];
        assert_eq!(line_residual(&two), 0.0);
    }
}
