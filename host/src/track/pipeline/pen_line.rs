//! Pen-line stereo: a labelling for the pairs in which the pen points nearly at one camera, so
//! that its LED spots crowd into fewer blobs there, while the other camera sees them apart.
//!
//! A merged blob lies on no LED's epipolar line, so point-to-point stereo finds one LED or none
//! (webcam seed 3, the last stroke: the left camera sees LED 1, LEDs 2+3 as one blob and LED 4;
//! the right camera LEDs 2, 3 and 4, LED 1 hidden by the hand; one stereo candidate for 0.7 s).
//! Every blob of the crowded camera still lies on the pen's image line there: a single spot on
//! its LED, a merged one at the centroid of collinear spots; a streak of merged spots lies along
//! it (its second moments' principal axis, when the pen's image is one blob). That line and the
//! crowded camera's centre span a plane that holds the pen, and each LED seen apart in the other
//! camera lies where its viewing ray meets that plane. The pen is then the intersection of the two cameras' pen
//! planes, and the LEDs are told apart by their distances along it (FIRES thesis, §4.1.2), as
//! point stereo does. The labelling is accepted only when:
//!
//! * the two pen planes meet at a clear angle and every LED's ray meets the crowded camera's
//!   plane at a clear angle (the point along the ray is well conditioned);
//! * at least three LEDs have separate spots in the clear camera, at the pen's distances along
//!   the line, and every blob on the pen's image there is one of them;
//! * in the crowded camera every LED is imaged, by a spot of its own or inside a blob that covers
//!   at least two neighbours and is centred on their segment (at least one such merge), and every
//!   blob on the pen's image is one of these; only an end LED that the clear camera sees may be
//!   hidden there (by the hand), and has no stereo pair;
//! * or, in a second pass run only when the first finds nothing, the crowded camera images just
//!   two LEDs, each by a spot of its own, and misses the others, a run at one end of the pen
//!   (webcam seeds 6, 8 and 9 at a stroke's start: the LEDs' emission cones turned away, one
//!   camera sees LEDs 1-3 and the other LEDs 1-2); the clear camera's third spot tells which LEDs
//!   they are, and the labelling is one of two stereo LEDs and a third located by its clear spot
//!   on the fitted pen ([`Identification::completed`]). About a compact blob's ray there is no
//!   such pass (two spots give the plane);
//! * or, in a third pass, the crowded camera shows one blob alone, the own spot of an end LED,
//!   and misses the others (webcam seeds 8, 12 and 15: one camera sees LEDs 1-3, the other LED 1
//!   alone, the rest too dim): the plane is found about that spot's ray (`pipeline/pen_ray.rs`),
//!   the other LEDs are located by their clear spots on the fitted pen, and their points give
//!   the pen's axis (the tip, at LED 1, is the fit's). One spot checks little of the pen, so this
//!   pass needs the fused direction and a narrower cone about it (`SINGLE_PRIOR_MIN_COS`), and
//!   no other blob in the crowded camera (one could be an LED this labelling calls hidden);
//! * the pen points the way the fused direction does, while the tracker has that prior (after a
//!   loss longer than the prior's timeout, the geometry alone decides, as in identification: an
//!   uncorrected inertial direction may have drifted beyond any bound);
//! * no other labelling (other camera crowded, other LEDs, the mirrored pen, other blobs) passes.
//!
//! The LEDs' points are the clear camera's rays met with the crowded camera's pen plane, then
//! moved to the pen's line fitted to every spot and merged blob of both images (an LED hidden in
//! the crowded camera by its clear spot alone), which also gives
//! their covariance (`pipeline/pen_fit.rs`; a labelling the fit cannot explain is dropped). When
//! the crowded camera's pen is one compact blob (pointing straight at it), the plane is found
//! about that blob's ray (`pipeline/pen_ray.rs`). The tracker adds the points as stereo
//! candidates (the crowded camera's blob being each LED's own or covering blob) and marks the
//! labelling [`Identification::from_pen_line`], which its merge checks and the clock-offset
//! estimate leave out (a covering blob is not its LEDs' image).

use super::pen_fit::fit_pen_line;
use super::pen_image::{explained_leds, frame};
use super::pen_mono::mono_labellings;
use super::pen_ray::ray_labellings;
use super::safety::PairView;
use super::{Tracker, TrackerConfig};
use crate::stereo::correspond::covariance;
use crate::stereo::{CameraId, Candidate, StereoRig};
use crate::track::identify::{Identification, Resolution};
use crate::track::pen::LED_COUNT;
use crate::vision::principal_axis;
use nalgebra::{Matrix3, Vector3};

/// What the pen-line labelling needs from the configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct LineOptions {
    /// The pen's LED offsets along its axis, metres.
    pub(super) led_offsets: [f64; LED_COUNT],
    /// Largest mismatch of an LED's position along the pen from the pen's spacing, metres.
    pub(super) tolerance: f64,
    /// Largest distance of a blob from the pen's image line, or of an LED's image from its own
    /// blob, pixels.
    pub(super) gate_px: f64,
    /// Smallest sine of the angle between the two pen planes, and between a clear-camera ray and
    /// the crowded camera's pen plane.
    pub(super) min_sine: f64,
    /// The pen must point within this cosine of the fused direction.
    pub(super) prior_min_cos: f64,
    /// Standard deviation of a spot's centroid, pixels (the pen-ray fit's covariance).
    pub(super) pixel_sigma: f64,
    /// Try the clear camera's own pose when no plane labels the pen (`pipeline/pen_mono.rs`).
    /// Off in the tracker: on webcam seeds 1-7 it recovers seed 3's boundary stroke (coverage
    /// 0.862 -> 0.984) but its fitted points can lie mm off (seed 3's worst RMS 0.68 -> 1.04 mm,
    /// seed 4's 0.91 -> 1.11 mm); see the measurements in `pipeline/pen_mono.rs`.
    pub(super) mono_start: bool,
    /// Some(n): the crowded camera images exactly `n` LEDs, each by a spot of its own, and misses
    /// the others, a run at one end of the pen (`crowded_image_explained`): [`label_pen_line`]'s
    /// later passes.
    pub(super) own_spots: Option<usize>,
}

impl LineOptions {
    /// The tracker's pen, identification tolerance, epipolar gate and prior cone.
    pub(super) fn from_config(config: &TrackerConfig) -> Self {
        Self {
            led_offsets: config.pen.led_offsets,
            tolerance: config.identify.tolerance,
            gate_px: config.correspondence.max_epipolar_px,
            min_sine: MIN_SINE,
            prior_min_cos: config.identify.prior_min_cos,
            pixel_sigma: config.correspondence.pixel_sigma,
            mono_start: false,
            own_spots: None,
        }
    }
}

/// A labelling along the pen's line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct LineLabelling {
    /// The camera whose LED spots merged.
    pub(super) crowded: CameraId,
    /// Per LED seen apart in the clear camera: its blob there, its (own or covering) blob in the
    /// crowded camera, and its point.
    pub(super) leds: [Option<LineLed>; LED_COUNT],
    /// RMS mismatch of the LEDs' positions along the pen from its spacing, metres.
    pub(super) mismatch: f64,
    /// Found about a compact blob's ray (`pipeline/pen_ray.rs`), not on a measured pen plane.
    pub(super) from_ray: bool,
}

/// One LED of a [`LineLabelling`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct LineLed {
    /// Its blob in the clear camera.
    pub(super) clear_blob: usize,
    /// Its own blob, or the blob covering it, in the crowded camera; None where it is hidden there
    /// (by the hand, or too dim: the end of the pen that the crowded camera sees least).
    pub(super) crowded_blob: Option<usize>,
    /// The clear camera's ray met with the crowded camera's pen plane, world frame, metres.
    pub(super) point: Vector3<f64>,
    /// The point's covariance once the pen's line was fitted to the images
    /// (`pipeline/pen_fit.rs`), m²; None before (the tracker then treats the point as a stereo
    /// pair's).
    pub(super) covariance: Option<Matrix3<f64>>,
}

impl Tracker {
    /// The labelling of a pair whose LED spots crowd in one camera, when the pen's image lines
    /// in the two cameras locate it uniquely (`pipeline/pen_line.rs`): tried where identification
    /// refused for want of stereo candidates (not for a conflict) or the safety refused fewer than
    /// three LEDs for crowded images. Adds the labelled LEDs' candidates to the pair's.
    pub(super) fn complete_pen_line(&mut self, t: u64) -> Option<Identification> {
        // The fused direction, also while it is stale (the identifier's prior); None after the
        // prior's timeout.
        let direction = self.direction.prior(t).map(|(d, _)| d);
        self.direction.world()?;
        let options = LineOptions::from_config(&self.config);
        let found = label_pen_line(&self.pair_view(t), &options, direction.as_ref())?;
        let sigma = self.config.correspondence.pixel_sigma;
        let pixel_sigma = [
            sigma / self.rig.left.focal_px(),
            sigma / self.rig.right.focal_px(),
        ];
        let mut assignment = [None; LED_COUNT];
        let mut points = [None; LED_COUNT];
        let mut completed = 0u8;
        let stereo = found
            .leds
            .iter()
            .flatten()
            .filter(|l| l.crowded_blob.is_some())
            .count();
        for (k, led) in found.leds.iter().enumerate() {
            let Some(led) = led else { continue };
            // An LED only the clear camera sees has no stereo pair; its spot was fitted. With one
            // stereo LED, the fitted pen's other LEDs give the axis (the tip, at LED 1, is the
            // fit's); one candidate gives no axis variance (`prior::direction_variance`), so the
            // orientation filter takes that axis with its configured vision gain.
            let Some(crowded_blob) = led.crowded_blob else {
                completed |= 1 << k;
                if stereo == 1 {
                    points[k] = Some(led.point);
                }
                continue;
            };
            let (left, right) = match found.crowded {
                CameraId::Left => (crowded_blob, led.clear_blob),
                CameraId::Right => (led.clear_blob, crowded_blob),
            };
            // The crowded camera's image point is where the LED projects on its pen line.
            let to_normal = |camera: CameraId| {
                let q = match camera {
                    CameraId::Left => led.point,
                    CameraId::Right => self.rig.to_right(&led.point),
                };
                [q.x / q.z, q.y / q.z]
            };
            let ml = to_normal(CameraId::Left);
            let mr = to_normal(CameraId::Right);
            let mut cand = Candidate::at(left, right, led.point);
            if let Some(c) = led.covariance {
                cand.covariance = c;
            } else if sigma > 0.0 {
                cand.covariance = covariance(&self.triangulator, ml, mr, &led.point, pixel_sigma);
            }
            assignment[k] = Some(self.correspondences.candidates.len());
            points[k] = Some(led.point);
            self.correspondences.candidates.push(cand);
        }
        let count = points.iter().flatten().count();
        let fit = (-(found.mismatch / options.tolerance).powi(2)).exp();
        // A pen imaged as one blob labels it for every LED (a merge, as a plane's labelling
        // does); about a ray among several blobs the LEDs may sit one blob off.
        let mut crowded_blobs = found.leds.iter().flatten().filter_map(|l| l.crowded_blob);
        let first_blob = crowded_blobs.next();
        let one_blob = crowded_blobs.all(|b| Some(b) == first_blob);
        Some(Identification {
            assignment,
            points,
            distance_rms: found.mismatch,
            confidence: fit * (count as f64 / LED_COUNT as f64).sqrt(),
            resolution: Resolution::Geometry,
            interference: 0,
            completed,
            from_pen_line: true,
            from_pen_ray: (found.from_ray && !one_blob).then_some(found.crowded),
        })
    }
}

/// Smallest sine of the angles that condition the pen line (about 8.6 degrees).
const MIN_SINE: f64 = 0.15;

/// The pen must point within this cosine (15 degrees) of the fused direction when the crowded
/// camera images one LED alone. The pen's plane about that spot's ray is free, and a wrong
/// labelling of the clear spots (LEDs 2-4 taken for 1-3, LED 1 hidden in both cameras) meets
/// the pen's spacing only on a plane that tilts the pen out of the true direction (stress seed
/// 14: a tip 167 mm off, within the identification's 26-degree cone). A margin beside the
/// spot-alone check of `unique_plane`, which by itself removed every wrong label measured
/// (webcam 1-26, fires-v1 1-4, stress 13-30; this cone changed none of them); the orientation
/// filter's heading reference is good to about 10 degrees after a loss.
const SINGLE_PRIOR_MIN_COS: f64 = 0.966;

/// The unique labelling along the pen's line, with the pen pointing within
/// `options.prior_min_cos` of `direction` (towards the tip) when there is one, or None (none, or
/// several).
pub(super) fn label_pen_line(
    pair: &PairView<'_>,
    options: &LineOptions,
    direction: Option<&Vector3<f64>>,
) -> Option<LineLabelling> {
    // The images as they are first, then with LEDs missing at one end of the crowded camera's
    // pen: a labelling that sees more of the pen is the likelier one, and where it exists the
    // second pass adds nothing (nor a rival).
    let mut found = unique_plane(pair, options, direction)?;
    if found.is_none() {
        let two = LineOptions {
            own_spots: Some(2),
            ..*options
        };
        found = unique_plane(pair, &two, direction)?;
    }
    // Then one end LED's own spot alone in the crowded camera (the module doc's third pass).
    if found.is_none() && direction.is_some() {
        let one = LineOptions {
            own_spots: Some(1),
            prior_min_cos: options.prior_min_cos.max(SINGLE_PRIOR_MIN_COS),
            ..*options
        };
        found = unique_plane(pair, &one, direction)?;
    }
    // No plane labels the pen: the clear camera's spots alone may (`pipeline/pen_mono.rs`).
    if found.is_none() && options.mono_start {
        found = unique_mono(pair, options, direction)?;
    }
    // Only the unique labelling is fitted: a rival that the fit would reject still makes the
    // pair ambiguous.
    fit_pen_line(pair, options, found?)
}

/// The one labelling of the pair along a pen plane of either camera's (see the module doc):
/// Some(None) when there is none, None when there are several.
fn unique_plane(
    pair: &PairView<'_>,
    options: &LineOptions,
    direction: Option<&Vector3<f64>>,
) -> Option<Option<LineLabelling>> {
    let mut found: Option<LineLabelling> = None;
    for crowded in [CameraId::Left, CameraId::Right] {
        let clear = other(crowded);
        let (norm_c, norm_k) = (normals(pair, crowded), normals(pair, clear));
        if norm_k.len() < 3 || norm_c.is_empty() {
            continue;
        }
        // One own spot spans no plane: only the planes about its ray. Any other blob of the
        // crowded camera may be an LED this labelling calls hidden (webcam seed 17: LED 1 hidden
        // on the right, LEDs 2-4 there, one of them taken for LED 1; without this check 7 of 53
        // recordings took 1-9 wrong labels): the spot must be alone.
        let single = options.own_spots == Some(1);
        if single && norm_c.len() != 1 {
            continue;
        }
        let gate_c = options.gate_px / pair.rig.camera(crowded).focal_px();
        let gate_k = options.gate_px / pair.rig.camera(clear).focal_px();
        // The crowded camera's candidate pen planes: through two or more collinear blobs, or
        // along one streak's axis; about the ray of a compact blob, the planes of
        // `pipeline/pen_ray.rs`.
        let streaks: Vec<Option<(Vector3<f64>, Vector3<f64>)>> = (0..norm_c.len())
            .map(|n| streak_plane(pair, crowded, n))
            .collect();
        let planes_c: Vec<(Vector3<f64>, Vector3<f64>)> = if single {
            Vec::new()
        } else {
            collinear_sets(norm_c, gate_c, 2)
                .into_iter()
                .filter_map(|set| pen_plane(pair.rig, crowded, norm_c, set))
                .chain(streaks.iter().flatten().copied())
                .collect()
        };
        let sets_k = collinear_sets(norm_k, gate_k, 3);
        for set_k in &sets_k {
            let mut all = Vec::new();
            for plane_c in &planes_c {
                all.extend(labellings(
                    pair, options, crowded, plane_c, set_k, direction,
                ));
            }
            // About a compact blob's ray (the pen pointing at the crowded camera, or one LED's
            // own spot), not where two spots give the plane.
            if options.own_spots != Some(2) {
                // A lone streak whose axis plane labels nothing is scanned too: its axis may be
                // the exposure's smear more than the pen (the pen swinging through a camera's
                // view), while its centroid still lies on the pen's image line.
                let lone_streak = norm_c.len() == 1 && all.is_empty();
                for n in (0..norm_c.len()).filter(|&n| streaks[n].is_none() || lone_streak) {
                    let found =
                        ray_labellings(pair, options, crowded, n, *set_k, direction).ok()?;
                    // One own spot images its LED alone: the fit takes it as that LED's.
                    all.extend(found.into_iter().map(|l| LineLabelling {
                        from_ray: l.from_ray && !single,
                        ..l
                    }));
                }
            }
            for l in all {
                if !keep_unique(&mut found, l) {
                    return None;
                }
            }
        }
    }
    Some(found)
}

/// The one labelling that the clear camera's pose alone gives (`pipeline/pen_mono.rs`): Some(None)
/// when there is none, None when there are several.
fn unique_mono(
    pair: &PairView<'_>,
    options: &LineOptions,
    direction: Option<&Vector3<f64>>,
) -> Option<Option<LineLabelling>> {
    let mut found: Option<LineLabelling> = None;
    for crowded in [CameraId::Left, CameraId::Right] {
        let clear = other(crowded);
        let (norm_c, norm_k) = (normals(pair, crowded), normals(pair, clear));
        if norm_k.len() < 3 || norm_c.is_empty() {
            continue;
        }
        let gate_k = options.gate_px / pair.rig.camera(clear).focal_px();
        for set_k in collinear_sets(norm_k, gate_k, 3) {
            for l in mono_labellings(pair, options, crowded, set_k, direction) {
                if !keep_unique(&mut found, l) {
                    return None;
                }
            }
        }
    }
    Some(found)
}

pub(super) fn other(camera: CameraId) -> CameraId {
    match camera {
        CameraId::Left => CameraId::Right,
        CameraId::Right => CameraId::Left,
    }
}

pub(super) fn normals<'a>(pair: &PairView<'a>, camera: CameraId) -> &'a [[f64; 2]] {
    match camera {
        CameraId::Left => &pair.points.left_norm,
        CameraId::Right => &pair.points.right_norm,
    }
}

/// Same crowded camera and the same clear-camera blob for every LED.
pub(super) fn same_labels(a: &LineLabelling, b: &LineLabelling) -> bool {
    a.crowded == b.crowded
        && a.leds
            .iter()
            .zip(&b.leds)
            .all(|(x, y)| x.map(|x| x.clear_blob) == y.map(|y| y.clear_blob))
}

/// The sets of at least `min` points (bit masks) that lie within `gate` of a line through two of
/// them, each set once.
fn collinear_sets(points: &[[f64; 2]], gate: f64, min: usize) -> Vec<u32> {
    let n = points.len().min(16);
    let mut sets = Vec::new();
    for i in 0..n {
        for j in (i + 1)..n {
            let (a, b) = (points[i], points[j]);
            let len = (b[0] - a[0]).hypot(b[1] - a[1]);
            if len.is_nan() || len <= 0.0 {
                continue;
            }
            let set = (0..n)
                .filter(|&m| {
                    let p = points[m];
                    ((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])).abs() / len
                        <= gate
                })
                .fold(0u32, |s, m| s | (1 << m));
            if set.count_ones() as usize >= min && !sets.contains(&set) {
                sets.push(set);
            }
        }
    }
    sets
}

/// The plane through `camera`'s centre and the total-least-squares line of the normalised
/// points in `set`: (unit normal, a point on it), world frame.
pub(super) fn pen_plane(
    rig: &StereoRig,
    camera: CameraId,
    points: &[[f64; 2]],
    set: u32,
) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let members: Vec<[f64; 2]> = (0..points.len())
        .filter(|&m| set & (1 << m) != 0)
        .map(|m| points[m])
        .collect();
    let n = members.len() as f64;
    let mean = members
        .iter()
        .fold([0.0, 0.0], |s, p| [s[0] + p[0] / n, s[1] + p[1] / n]);
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in &members {
        let (dx, dy) = (p[0] - mean[0], p[1] - mean[1]);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    // The line's direction is the principal axis of the scatter.
    let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let dir = [angle.cos(), angle.sin()];
    let a = Vector3::new(mean[0], mean[1], 1.0);
    let b = Vector3::new(mean[0] + dir[0], mean[1] + dir[1], 1.0);
    let normal_cam = a.cross(&b).try_normalize(1e-12)?;
    Some(to_world(rig, camera, normal_cam))
}

/// Smallest elongation (ratio of principal standard deviations) of a blob whose axis is taken
/// for the pen's image line: a streak of at least two merged spots.
const STREAK_MIN_ELONGATION: f64 = 2.0;

/// The plane through `camera`'s centre and the axis of blob `n` when it is a streak (see
/// [`STREAK_MIN_ELONGATION`]): (unit normal, a point on it), world frame.
fn streak_plane(
    pair: &PairView<'_>,
    camera: CameraId,
    n: usize,
) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let shape = frame(pair, camera)?.shapes.get(n)?;
    let (axis, elongation) = principal_axis(shape);
    if elongation.is_nan() || elongation < STREAK_MIN_ELONGATION {
        return None;
    }
    let c = pair.points.pixels(camera).get(n)?;
    let model = pair.rig.camera(camera);
    let reach = 2.0;
    let a = model
        .undistort([c[0] - reach * axis[0], c[1] - reach * axis[1]])
        .ok()?;
    let b = model
        .undistort([c[0] + reach * axis[0], c[1] + reach * axis[1]])
        .ok()?;
    let normal_cam = Vector3::new(a[0], a[1], 1.0)
        .cross(&Vector3::new(b[0], b[1], 1.0))
        .try_normalize(1e-12)?;
    Some(to_world(pair.rig, camera, normal_cam))
}

/// A plane through `camera`'s centre with normal `normal_cam` in that camera's frame: (unit
/// normal, a point on it), world frame.
fn to_world(
    rig: &StereoRig,
    camera: CameraId,
    normal_cam: Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    match camera {
        CameraId::Left => (normal_cam, Vector3::zeros()),
        CameraId::Right => (
            rig.r_right_from_left.transpose() * normal_cam,
            rig.right_center(),
        ),
    }
}

/// The world-frame ray (origin, unit direction) of normalised point `m` of `camera`.
pub(super) fn ray(rig: &StereoRig, camera: CameraId, m: [f64; 2]) -> (Vector3<f64>, Vector3<f64>) {
    let d = Vector3::new(m[0], m[1], 1.0).normalize();
    match camera {
        CameraId::Left => (Vector3::zeros(), d),
        CameraId::Right => (rig.right_center(), rig.r_right_from_left.transpose() * d),
    }
}

/// Every labelling of the clear camera's blobs in `set_k` along the pen line that the crowded
/// camera's pen plane `plane_c` (unit normal, a point) spans with them, that passes the checks
/// of the module doc.
pub(super) fn labellings(
    pair: &PairView<'_>,
    options: &LineOptions,
    crowded: CameraId,
    plane_c: &(Vector3<f64>, Vector3<f64>),
    set_k: &u32,
    direction: Option<&Vector3<f64>>,
) -> Vec<LineLabelling> {
    let clear = other(crowded);
    let norm_k = normals(pair, clear);
    let &(n_c, o_c) = plane_c;
    let Some((n_k, _)) = pen_plane(pair.rig, clear, norm_k, *set_k) else {
        return Vec::new();
    };
    let Some(u) = n_c.cross(&n_k).try_normalize(1e-12) else {
        return Vec::new();
    };
    if n_c.cross(&n_k).norm() < options.min_sine {
        return Vec::new();
    }
    // The clear camera's blobs on the crowded camera's pen plane, by position along the pen.
    let mut along: Vec<(f64, usize, Vector3<f64>)> = Vec::new();
    for m in (0..norm_k.len()).filter(|&m| set_k & (1 << m) != 0) {
        let (origin, d) = ray(pair.rig, clear, norm_k[m]);
        let sine = n_c.dot(&d);
        if sine.abs() < options.min_sine {
            return Vec::new();
        }
        let lambda = n_c.dot(&(o_c - origin)) / sine;
        let p = origin + d * lambda;
        if lambda <= 0.0 || p.z <= 0.0 || pair.rig.to_right(&p).z <= 0.0 {
            return Vec::new();
        }
        along.push((u.dot(&p), m, p));
    }
    along.sort_by(|a, b| a.0.total_cmp(&b.0));
    let count = along.len();
    if count > LED_COUNT {
        return Vec::new();
    }
    let offsets = &options.led_offsets;
    let mut out = Vec::new();
    // The LEDs in order along +u (`sign` +1: increasing offsets), as increasing index subsets.
    for sign in [1.0, -1.0] {
        for subset in 0u32..(1 << LED_COUNT) {
            if subset.count_ones() as usize != count {
                continue;
            }
            let mut order: Vec<usize> =
                (0..LED_COUNT).filter(|&k| subset & (1 << k) != 0).collect();
            if sign < 0.0 {
                order.reverse();
            }
            // Shift along the line that best puts each LED at its blob.
            let shift = along
                .iter()
                .zip(&order)
                .map(|(a, &k)| a.0 - sign * offsets[k])
                .sum::<f64>()
                / count as f64;
            let residuals: Vec<f64> = along
                .iter()
                .zip(&order)
                .map(|(a, &k)| a.0 - shift - sign * offsets[k])
                .collect();
            if residuals.iter().any(|r| r.abs() > options.tolerance) {
                continue;
            }
            // The pen points from its LEDs towards the tip, against increasing offsets.
            if direction.is_some_and(|d| d.dot(&(-sign * u)) < options.prior_min_cos * d.norm()) {
                continue;
            }
            let (s0, p0) = (along[0].0, along[0].2);
            let model: [Vector3<f64>; LED_COUNT] =
                std::array::from_fn(|k| p0 + u * (shift + sign * offsets[k] - s0));
            let mut clear_blob = [None; LED_COUNT];
            for (a, &k) in along.iter().zip(&order) {
                clear_blob[k] = Some(a.1);
            }
            let mut points = model;
            for (a, &k) in along.iter().zip(&order) {
                points[k] = a.2;
            }
            let Some(leds) = explained_leds(pair, options, crowded, &model, &clear_blob, &points)
            else {
                continue;
            };
            let mismatch = (residuals.iter().map(|r| r * r).sum::<f64>() / count as f64).sqrt();
            out.push(LineLabelling {
                crowded,
                leds,
                mismatch,
                from_ray: false,
            });
        }
    }
    out
}

/// Keeps `l` as the one labelling found so far: false when `found` holds another (the pair is
/// ambiguous).
fn keep_unique(found: &mut Option<LineLabelling>, l: LineLabelling) -> bool {
    match found {
        None => *found = Some(l),
        Some(f) if same_labels(f, &l) => {}
        Some(_) => return false,
    }
    true
}
