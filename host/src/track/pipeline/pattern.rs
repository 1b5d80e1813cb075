//! One camera's LED labels from the pen's inertial direction, for frames no recent vision pose
//! predicts (after a loss longer than `TrackerConfig::continuity_ns`).
//!
//! Without the LEDs' identities in consecutive frames of a camera, its blobs cannot be moved to
//! the other camera's exposure time ([`super::align`]), and the stereo pairs of two cameras
//! exposed a third of a frame apart miss their epipolar gates: on the 15 Hz Minoru rig a pen
//! drawn at 0.2-0.4 m/s moves 5-10 px between the two exposures, and once a loss outlived the
//! last pose's prediction, pair after pair was refused for want of correspondences (fires-v2
//! seed 4: 78 of the 131 refused pairs in strokes, and losses of 0.3-1 s).
//!
//! The orientation filter still knows the pen's direction through such a loss (gyro, gravity and
//! the magnetometer do not need the cameras), and the pen is still about where vision last saw
//! it. Placed there along that direction, the four LEDs project to a pattern whose *shape* the
//! direction fixes: the image direction of the pen and the ratios of its LED spacings (70:40:50 mm
//! on the FIRES pen, FIRES thesis §4.1.2, foreshortened by perspective). Its position and size in
//! the image depend on where the pen has moved since, which is not known. So the pattern is
//! matched up to a 2-D similarity close to a translation: every pair of LEDs is mapped onto every
//! pair of blobs, the map is accepted only when it turns the pattern by at most the direction's
//! uncertainty and scales it by at most the depth's, and the LEDs whose mapped images then lie on
//! a blob of their own are its inliers. The labelling with the most inliers (at least three) is
//! the frame's when no different labelling has as many.
//!
//! The spacings' differences (70, 40, 50, 110, 90, 160 mm) are all distinct, so no shift along the
//! pen maps two LEDs onto two others; the scale bound excludes the scaled twins (LEDs 2-4 at
//! 40:50 are LEDs 1, 2 and 4 at 70:90 scaled by 1.78), and the direction's sign the mirror image.
//! The labels give the camera's image velocities, and the stereo pair they align is identified
//! as every other; only a pair the identifier refuses as ambiguous (or for a strayed fused
//! direction) is labelled by both frames' labels (`pipeline/frame_labels.rs`), and the labelling
//! safety checks it as every other.

use nalgebra::{UnitQuaternion, Vector3};

use crate::stereo::{CameraId, StereoRig};
use crate::track::pen::LED_COUNT;

/// How far a pattern may be turned and scaled onto the blobs, and how close a mapped LED must lie
/// to its blob.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct PatternOptions {
    /// Largest turn of the pattern in the image, radians.
    pub(super) max_turn_rad: f64,
    /// Scale range of the pattern (the depth's uncertainty over the pen's distance).
    pub(super) scale: (f64, f64),
    /// A mapped LED's blob lies within this fraction of the smallest mapped LED spacing.
    pub(super) gate_fraction: f64,
    /// ... and within at least this many pixels.
    pub(super) min_gate_px: f64,
    /// Pairs of predicted LED images closer than this give no map (their direction is noise),
    /// pixels.
    pub(super) min_pair_px: f64,
}

impl PatternOptions {
    /// The defaults: a turn of 12 degrees (the direction prior's few degrees, and the perspective
    /// change of a pen moved a few centimetres), a scale of 0.8-1.25 (the pen 0.55 m away and up to
    /// 0.1-0.14 m nearer or farther), a gate of a tenth of the smallest spacing (at least 1.5 px).
    pub(super) const DEFAULT: Self = Self {
        max_turn_rad: 12.0 * std::f64::consts::PI / 180.0,
        scale: (0.8, 1.25),
        gate_fraction: 0.1,
        min_gate_px: 1.5,
        min_pair_px: 8.0,
    };
}

impl Default for PatternOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Where the pen is believed to be for a frame: the last vision tip and the inertial direction
/// towards the tip at the frame's time, world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct PenGuess {
    /// Tip position, metres.
    pub(super) tip: Vector3<f64>,
    /// The pen's orientation (world from pen; its x axis points towards the tip).
    pub(super) orientation: UnitQuaternion<f64>,
}

impl PenGuess {
    /// Unit pen direction towards the tip.
    pub(super) fn direction(&self) -> Vector3<f64> {
        self.orientation * Vector3::x()
    }

    /// The LEDs' images in `camera` with the pen's axial LED offsets and tip offset (LED `k` lies
    /// `offsets[k] + tip_offset` behind the tip), or None when one does not project.
    pub(super) fn images(
        &self,
        rig: &StereoRig,
        camera: CameraId,
        offsets: &[f64; LED_COUNT],
        tip_offset: f64,
    ) -> Option<[[f64; 2]; LED_COUNT]> {
        let (mut out, direction) = ([[0.0; 2]; LED_COUNT], self.direction());
        for (o, &l) in out.iter_mut().zip(offsets) {
            let p = self.tip - direction * (l + tip_offset);
            *o = rig.project(camera, &p).ok()?;
        }
        Some(out)
    }
}

/// The blob of each LED when the predicted pattern `leds` maps onto `blobs` in exactly one best
/// way with at least three inliers (see the module doc); None otherwise.
pub(super) fn label_by_pattern(
    leds: &[[f64; 2]; LED_COUNT],
    blobs: &[[f64; 2]],
    options: &PatternOptions,
) -> Option<[Option<usize>; LED_COUNT]> {
    let mut best: Option<([Option<usize>; LED_COUNT], usize, f64)> = None;
    let mut tied = false;
    for a in 0..LED_COUNT {
        for b in a + 1..LED_COUNT {
            let d = sub(leds[b], leds[a]);
            let len = d[0].hypot(d[1]);
            if len < options.min_pair_px {
                continue;
            }
            for (i, &bi) in blobs.iter().enumerate() {
                for (j, &bj) in blobs.iter().enumerate() {
                    if i == j {
                        continue;
                    }
                    let e = sub(bj, bi);
                    // The similarity z -> bi + r (z - leds[a]) with r = e / d (complex ratio).
                    let den = d[0] * d[0] + d[1] * d[1];
                    let r = [
                        (e[0] * d[0] + e[1] * d[1]) / den,
                        (e[1] * d[0] - e[0] * d[1]) / den,
                    ];
                    let scale = r[0].hypot(r[1]);
                    let turn = r[1].atan2(r[0]).abs();
                    if turn > options.max_turn_rad
                        || scale < options.scale.0
                        || scale > options.scale.1
                    {
                        continue;
                    }
                    let mapped: [[f64; 2]; LED_COUNT] = std::array::from_fn(|k| {
                        let z = sub(leds[k], leds[a]);
                        [
                            bi[0] + r[0] * z[0] - r[1] * z[1],
                            bi[1] + r[1] * z[0] + r[0] * z[1],
                        ]
                    });
                    let Some((labels, n, residual)) = inliers(&mapped, blobs, options) else {
                        continue;
                    };
                    match &mut best {
                        Some((l, bn, br)) if n == *bn && labels == *l => *br = br.min(residual),
                        Some((_, bn, _)) if n == *bn => tied = true,
                        Some((_, bn, _)) if n < *bn => {}
                        _ => {
                            tied = false;
                            best = Some((labels, n, residual));
                        }
                    }
                }
            }
        }
    }
    let (labels, n, _) = best?;
    (n >= 3 && !tied).then_some(labels)
}

/// The LEDs of a mapped pattern that have a blob of their own within the gate: labels, count and
/// summed distance; None when a blob would image two LEDs or a gate holds two blobs.
fn inliers(
    mapped: &[[f64; 2]; LED_COUNT],
    blobs: &[[f64; 2]],
    options: &PatternOptions,
) -> Option<([Option<usize>; LED_COUNT], usize, f64)> {
    let mut spacing = f64::INFINITY;
    for (k, p) in mapped.iter().enumerate() {
        for q in &mapped[k + 1..] {
            spacing = spacing.min((p[0] - q[0]).hypot(p[1] - q[1]));
        }
    }
    let gate = (options.gate_fraction * spacing).max(options.min_gate_px);
    let mut labels = [None; LED_COUNT];
    let (mut n, mut residual) = (0, 0.0);
    for (k, p) in mapped.iter().enumerate() {
        let mut near = blobs
            .iter()
            .enumerate()
            .map(|(i, b)| (i, (b[0] - p[0]).hypot(b[1] - p[1])))
            .filter(|&(_, d)| d <= gate);
        let Some((i, d)) = near.next() else { continue };
        if near.next().is_some() || labels.contains(&Some(i)) {
            return None;
        }
        labels[k] = Some(i);
        n += 1;
        residual += d;
    }
    Some((labels, n, residual))
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The FIRES pen's LED images, `px_per_mm` apart per millimetre along `angle` from `origin`.
    fn pattern(origin: [f64; 2], angle: f64, px_per_mm: f64) -> [[f64; 2]; LED_COUNT] {
        let offsets = [0.0, 70.0, 110.0, 160.0];
        let (s, c) = angle.sin_cos();
        offsets.map(|l| [origin[0] + c * l * px_per_mm, origin[1] + s * l * px_per_mm])
    }

    #[test]
    fn a_shifted_pattern_labels_its_blobs_in_any_order() {
        let leds = pattern([100.0, 200.0], 0.3, 0.5);
        // Seen 25 px away, 5 degrees turned, 8% larger, blobs shuffled, a reflection added.
        let seen = pattern([130.0, 190.0], 0.3 + 5f64.to_radians(), 0.54);
        let blobs = vec![seen[2], [400.0, 50.0], seen[0], seen[3], seen[1]];
        let labels = label_by_pattern(&leds, &blobs, &PatternOptions::default());
        assert_eq!(labels, Some([Some(2), Some(4), Some(0), Some(3)]));
    }

    #[test]
    fn three_leds_with_the_first_hidden_are_labelled() {
        let leds = pattern([100.0, 200.0], -1.0, 0.4);
        let seen = pattern([90.0, 215.0], -1.0, 0.42);
        let blobs = vec![seen[3], seen[1], seen[2]];
        let labels = label_by_pattern(&leds, &blobs, &PatternOptions::default());
        assert_eq!(labels, Some([None, Some(1), Some(2), Some(0)]));
    }

    #[test]
    fn the_scaled_twin_and_the_mirror_image_are_not_taken() {
        let leds = pattern([100.0, 200.0], 0.0, 0.5);
        // LEDs 2-4 at the predicted size: LEDs 1, 2 and 4 would need the pen 1.78 times farther.
        let seen = pattern([95.0, 203.0], 0.0, 0.5);
        let blobs = vec![seen[1], seen[2], seen[3]];
        assert_eq!(
            label_by_pattern(&leds, &blobs, &PatternOptions::default()),
            Some([None, Some(0), Some(1), Some(2)])
        );
        // The pen turned end for end: its pattern runs the other way.
        let mirrored = pattern([180.0, 200.0], std::f64::consts::PI, 0.5);
        assert_eq!(
            label_by_pattern(&leds, &mirrored, &PatternOptions::default()),
            None
        );
    }

    #[test]
    fn two_blobs_or_a_gate_with_two_blobs_give_nothing() {
        let leds = pattern([100.0, 200.0], 0.0, 0.5);
        let seen = pattern([100.0, 200.0], 0.0, 0.5);
        assert_eq!(
            label_by_pattern(&leds, &seen[..2], &PatternOptions::default()),
            None
        );
        // A second blob 1 px from LED 3's image: which one is the LED is not known.
        let blobs = vec![
            seen[0],
            seen[1],
            seen[2],
            [seen[2][0] + 1.0, seen[2][1]],
            seen[3],
        ];
        assert_eq!(
            label_by_pattern(&leds, &blobs, &PatternOptions::default()),
            None
        );
    }
}
