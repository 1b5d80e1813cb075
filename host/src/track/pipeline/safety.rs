//! Labelling safety: the tracker's checks of an identification beyond the identifier's own, from
//! what only the tracker knows (the prior's age, the pen's recent motion, the images), and its
//! memory of the labels it accepted (the continuity prior of the next frames, FIRES thesis,
//! §4.1.2, and the poses and blob labels that time alignment uses).

use super::align::{PairPoints, TimeAlignment};
use super::TrackerConfig;
use crate::stereo::{CameraId, Candidate, StereoRig};
use crate::track::identify::Identification;
use crate::track::pen::LED_COUNT;
use crate::track::tip::{TipEstimate, TipEstimator};
use nalgebra::Vector3;

/// Everything one pair's checks look at, borrowed from the tracker.
pub(super) struct PairView<'a> {
    /// The rig.
    pub(super) rig: &'a StereoRig,
    /// Camera histories and pose predictions.
    pub(super) align: &'a TimeAlignment,
    /// The pair's (aligned) points.
    pub(super) points: &'a PairPoints,
    /// The pair's stereo candidates.
    pub(super) candidates: &'a [Candidate],
    /// The tip estimator (pattern centroids).
    pub(super) tip: &'a TipEstimator,
    /// The pair's time, left clock, nanoseconds.
    pub(super) t: u64,
}

/// Which labelling-safety check refused a labelling.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum Unsafe {
    /// Two LEDs with a stale prior or not where the recent motion predicts them.
    TwoLedsUnconfirmed,
    /// The LED images of the labelled pen lie too close together in an image.
    PenImagesOverlap,
    /// Another blob lies next to a labelled blob (a crowded image).
    BlobNotIsolated,
}

/// Two LED images must lie this many times the sum of their blobs' radii apart: spots whose
/// thresholded discs touch merge into one blob, and a blob grown by motion blur or a neighbour's
/// faint tail is up to this much wider than its disc.
pub(super) const MERGE_MARGIN: f64 = 1.2;

/// Accepted labels and the checks a new labelling must pass.
#[derive(Debug, Clone)]
pub(super) struct LabelGuard {
    led_offsets: [f64; LED_COUNT],
    min_image_separation_px: f64,
    continuity_ns: u64,
    /// Time and positions of the LEDs labelled last.
    previous_leds: (u64, [Option<Vector3<f64>>; LED_COUNT]),
    /// Time of the last labelled frame and the fastest LED speed since the one before (m/s),
    /// when both were within `continuity_ns` and shared an LED.
    measured_speed: Option<(u64, f64)>,
}

impl LabelGuard {
    /// No labels yet.
    pub(super) fn new(config: &TrackerConfig) -> Self {
        Self {
            led_offsets: config.pen.led_offsets,
            min_image_separation_px: config.min_image_separation_px,
            continuity_ns: config.continuity_ns,
            previous_leds: (0, [None; LED_COUNT]),
            measured_speed: None,
        }
    }

    /// The fastest LED speed the last two labelled frames measured (m/s), if the last one is
    /// within `continuity_ns` of `t`.
    pub(super) fn recent_speed(&self, t: u64) -> Option<f64> {
        let (t_prev, v) = self.measured_speed?;
        (t.saturating_sub(t_prev) <= self.continuity_ns).then_some(v)
    }

    /// The LEDs labelled last, if within `continuity_ns` of `t`.
    pub(super) fn recent_leds(&self, t: u64) -> Option<&[Option<Vector3<f64>>; LED_COUNT]> {
        let (t_prev, leds) = &self.previous_leds;
        (t.saturating_sub(*t_prev) <= self.continuity_ns).then_some(leds)
    }

    /// True when the labelling may be reported. Two LEDs are one distance: with only a stale
    /// direction to check it, a wrong stereo pair at that distance would pass; and a pair
    /// shifted by one LED in one image (LED images a few pixels apart when the pen points at a
    /// camera or turns fast) also fits. So two LEDs need the fused direction and temporal
    /// continuity (FIRES thesis, §4.1.2), i.e. must sit where the pen's recent motion predicts
    /// them. Any labelling needs well separated LED images and isolated labelled blobs.
    #[cfg(test)]
    pub(super) fn is_safe(
        &self,
        pair: &PairView<'_>,
        id: &Identification,
        vision: &TipEstimate,
        stale_prior: bool,
    ) -> bool {
        self.check(pair, id, vision, stale_prior).is_none()
    }

    /// The first check of [`Self::is_safe`] that the labelling fails, None when it is safe.
    pub(super) fn check(
        &self,
        pair: &PairView<'_>,
        id: &Identification,
        vision: &TipEstimate,
        stale_prior: bool,
    ) -> Option<Unsafe> {
        // A pen-line labelling of two stereo LEDs located a third by its clear spot
        // (`pipeline/pen_line.rs`): three LEDs at the pen's spacing identify it.
        let pen_line_three = id.from_pen_line && id.located() >= 3;
        if id.count() < 3
            && id.located() < LED_COUNT
            && !pen_line_three
            && (stale_prior || !self.labels_match_prediction(pair, id))
        {
            return Some(Unsafe::TwoLedsUnconfirmed);
        }
        // A completed or pen-line labelling checked its own LEDs' separation blob by blob
        // (`merged.rs`, `pen_line.rs`).
        if id.completed == 0 && !id.from_pen_line && !self.pen_images_separated(pair, vision, id) {
            return Some(Unsafe::PenImagesOverlap);
        }
        (!self.labelled_blobs_isolated(pair, id)).then_some(Unsafe::BlobNotIsolated)
    }

    /// True when no other blob lies within `min_image_separation_px` of a labelled blob, in
    /// either camera's frame.
    pub(super) fn labelled_blobs_isolated(&self, pair: &PairView<'_>, id: &Identification) -> bool {
        let min2 = self.min_image_separation_px.powi(2);
        let isolated = |cam: usize, b: usize| {
            let Some(frame) = pair.align.current(cam) else {
                return true;
            };
            let Some(p) = frame.blobs.get(b) else {
                return true;
            };
            frame
                .blobs
                .iter()
                .enumerate()
                .all(|(j, q)| j == b || (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) >= min2)
        };
        id.assignment
            .iter()
            .flatten()
            .filter_map(|&c| pair.candidates.get(c))
            .all(|c| isolated(0, c.left) && isolated(1, c.right))
    }

    /// True when every labelled LED's image lies far enough from the images of the pen's other
    /// three LEDs (the labelled pen's model, unlabelled LEDs included) in both cameras that the
    /// spots cannot have merged into one blob ([`Self::merged_leds`] finds none).
    pub(super) fn pen_images_separated(
        &self,
        pair: &PairView<'_>,
        pen: &TipEstimate,
        id: &Identification,
    ) -> bool {
        self.merged_leds(pair, pen, id)
            .is_some_and(|m| m.iter().all(|&merged| !merged))
    }

    /// The labelled LEDs whose image, in either camera, lies within reach of another LED's image
    /// (labelled or not, from the labelled pen's model): closer than `min_image_separation_px`,
    /// or than [`MERGE_MARGIN`] times the sum of the two LEDs' blob radii in that camera (an
    /// unlabelled LED's taken as the largest labelled one's, so a spot nearer the camera is not
    /// underestimated). Two bright spots whose thresholded discs touch are detected as one blob
    /// half-way between them, which would be labelled as one of the two LEDs; a labelled blob
    /// that is such a merge is itself wide, so its own radius flags it. Two labelled LEDs with
    /// blobs of their own in that camera were resolved there, not merged, and only the
    /// `min_image_separation_px` floor applies between them. None when the pen model is unknown.
    pub(super) fn merged_leds(
        &self,
        pair: &PairView<'_>,
        pen: &TipEstimate,
        id: &Identification,
    ) -> Option<[bool; LED_COUNT]> {
        let c = pair.tip.pattern_centroid(pen.pattern)?;
        let leds = self
            .led_offsets
            .map(|l| pen.centroid + pen.direction * (c - l));
        let mut merged = [false; LED_COUNT];
        for camera in [CameraId::Left, CameraId::Right] {
            let cam = usize::from(camera == CameraId::Right);
            // Each labelled LED's blob in this camera, and its radius.
            let blob: [Option<usize>; LED_COUNT] = std::array::from_fn(|k| {
                let c = pair.candidates.get(id.assignment[k]?)?;
                Some(if cam == 0 { c.left } else { c.right })
            });
            let radius: [Option<f64>; LED_COUNT] =
                std::array::from_fn(|k| pair.align.current(cam)?.radii.get(blob[k]?).copied());
            let resolved =
                |k: usize, j: usize| blob[k].is_some() && blob[j].is_some() && blob[k] != blob[j];
            let largest = radius.iter().flatten().copied().fold(0.0, f64::max);
            let px: Vec<Option<[f64; 2]>> = leds
                .iter()
                .map(|p| pair.rig.project(camera, p).ok())
                .collect();
            for (k, flag) in merged.iter_mut().enumerate() {
                if id.assignment[k].is_none() {
                    continue;
                }
                let Some(a) = px[k] else {
                    *flag = true;
                    continue;
                };
                let r_k = radius[k].unwrap_or(largest);
                let near = px.iter().enumerate().any(|(j, b)| {
                    let merge = MERGE_MARGIN * (r_k + radius[j].unwrap_or(largest));
                    let min = if resolved(k, j) {
                        self.min_image_separation_px
                    } else {
                        self.min_image_separation_px.max(merge)
                    };
                    j != k && b.is_some_and(|b| (a[0] - b[0]).hypot(a[1] - b[1]) < min)
                });
                *flag |= near;
            }
        }
        Some(merged)
    }

    /// True when the predicted LED images (constant-velocity pen motion) put every labelled blob
    /// nearest its own LED's predicted image, in both cameras (the other camera's blobs moved to
    /// the pair's time); false without a prediction.
    pub(super) fn labels_match_prediction(&self, pair: &PairView<'_>, id: &Identification) -> bool {
        let cands = pair.candidates;
        for camera in [CameraId::Left, CameraId::Right] {
            let blobs = pair.points.pixels(camera);
            let Some(px) = pair.align.predicted_images(pair.rig, camera, pair.t) else {
                return false;
            };
            for (k, c) in id.assignment.iter().enumerate() {
                let Some(c) = c.and_then(|c| cands.get(c)) else {
                    continue;
                };
                let blob = if camera == CameraId::Left {
                    c.left
                } else {
                    c.right
                };
                let Some(b) = blobs.get(blob) else { continue };
                let d2 = |p: &[f64; 2]| (p[0] - b[0]).powi(2) + (p[1] - b[1]).powi(2);
                let nearest = (0..LED_COUNT).min_by(|&i, &j| d2(&px[i]).total_cmp(&d2(&px[j])));
                if nearest != Some(k) {
                    return false;
                }
            }
        }
        true
    }

    /// Keeps a labelled frame for the next frames: the LEDs for continuity, the whole pen for
    /// predicting LED images, and each camera's blob labels for time alignment.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn remember(
        &mut self,
        align: &mut TimeAlignment,
        tip: &TipEstimator,
        candidates: &[Candidate],
        this: usize,
        t: u64,
        id: &Identification,
        estimate: &TipEstimate,
    ) {
        let (t0, prev) = self.previous_leds;
        self.measured_speed = (t > t0 && t - t0 <= self.continuity_ns)
            .then(|| {
                let dt = (t - t0) as f64 * 1e-9;
                prev.iter()
                    .zip(&id.points)
                    .filter_map(|(a, b)| Some((b.as_ref()? - a.as_ref()?).norm() / dt))
                    .reduce(f64::max)
            })
            .flatten()
            .map(|v| (t, v));
        self.previous_leds = (t, id.points);
        if let Some(c) = tip.pattern_centroid(estimate.pattern) {
            let l = self.led_offsets;
            let all = l.map(|lk| estimate.centroid + estimate.direction * (c - lk));
            align.remember_pose(t, all);
        }
        let side = |left: bool| {
            id.assignment.map(|a| {
                a.map(|k| {
                    if left {
                        candidates[k].left
                    } else {
                        candidates[k].right
                    }
                })
            })
        };
        // A pen-ray labelling's crowded camera has no LED images of its own.
        let labels = |left: bool| match id.from_pen_ray {
            Some(c) if (c == CameraId::Left) == left => [None; LED_COUNT],
            _ => side(left),
        };
        align.label(this, labels(this == 0), labels(this != 0));
    }
}

#[cfg(test)]
mod tests {
    use super::super::align::AlignOptions;
    use super::*;
    use crate::track::identify::Resolution;
    use crate::track::pen::PenGeometry;

    fn rig() -> StereoRig {
        StereoRig::parallel(1024, 768, 45f64.to_radians(), 0.25)
    }

    /// The thesis pen with LED 1 at `led1`, pointing along `dir` (towards the tip).
    fn pen(led1: Vector3<f64>, dir: Vector3<f64>) -> [Vector3<f64>; LED_COUNT] {
        PenGeometry::thesis().led_offsets.map(|l| led1 - dir * l)
    }

    fn labelled(n: usize) -> Identification {
        labelled_leds(std::array::from_fn(|k| k < n))
    }

    /// LED k labelled with candidate k where `which[k]`.
    fn labelled_leds(which: [bool; LED_COUNT]) -> Identification {
        Identification {
            assignment: std::array::from_fn(|k| which[k].then_some(k)),
            points: [None; LED_COUNT],
            distance_rms: 0.0,
            confidence: 1.0,
            resolution: Resolution::Geometry,
            interference: 0,
            completed: 0,
            from_pen_line: false,
            from_pen_ray: None,
        }
    }

    /// A pen imaged in both cameras at `t`, with candidate k = LED k (blob k in both images).
    struct Scene {
        rig: StereoRig,
        align: TimeAlignment,
        points: PairPoints,
        candidates: Vec<Candidate>,
        tip: TipEstimator,
        leds: [Vector3<f64>; LED_COUNT],
    }

    impl Scene {
        fn new(leds: [Vector3<f64>; LED_COUNT]) -> Self {
            let rig = rig();
            let mut align = TimeAlignment::new(AlignOptions {
                time_align: false,
                ..super::super::align::tests::OPTIONS
            });
            for (cam, camera) in [CameraId::Left, CameraId::Right].into_iter().enumerate() {
                let blobs = leds
                    .iter()
                    .map(|p| rig.project(camera, p).unwrap())
                    .collect();
                align.push(cam, 1_000, blobs, Vec::new());
            }
            let mut points = PairPoints::default();
            align.prepare(&rig, 1, 1_000, &mut points);
            let candidates = (0..LED_COUNT)
                .map(|k| Candidate::at(k, k, leds[k]))
                .collect();
            let tip = TipEstimator::new(&PenGeometry::thesis());
            Self {
                rig,
                align,
                points,
                candidates,
                tip,
                leds,
            }
        }

        fn view(&self) -> PairView<'_> {
            PairView {
                rig: &self.rig,
                align: &self.align,
                points: &self.points,
                candidates: &self.candidates,
                tip: &self.tip,
                t: 1_000,
            }
        }

        fn estimate(&self) -> TipEstimate {
            self.tip.estimate(&self.leds.map(Some)).unwrap()
        }
    }

    /// A pen across the view is safe; the same pen pointing at the left camera (LED images on top
    /// of one another) is not.
    #[test]
    fn overlapping_led_images_are_unsafe() {
        let guard = LabelGuard::new(&TrackerConfig::default());
        let across = Scene::new(pen(Vector3::new(0.05, 0.0, 0.7), Vector3::x()));
        assert!(guard.pen_images_separated(&across.view(), &across.estimate(), &labelled(4)));
        assert!(guard.is_safe(&across.view(), &labelled(4), &across.estimate(), true));
        let dir = Vector3::new(0.01, 0.0, -1.0).normalize();
        let at_camera = Scene::new(pen(Vector3::new(0.0, 0.0, 0.6), dir));
        assert!(!guard.pen_images_separated(
            &at_camera.view(),
            &at_camera.estimate(),
            &labelled(4)
        ));
    }

    /// An LED image closer to an unlabelled LED's than their blobs' discs (plus the margin) could
    /// be one merged blob: with LED 3 unlabelled and blob radii just under half the closest LED
    /// images' distance (LEDs 2 and 3) over the margin the labelling is safe, just over it is not.
    #[test]
    fn led_images_within_their_blobs_reach_are_unsafe() {
        let guard = LabelGuard::new(&TrackerConfig::default());
        let mut s = Scene::new(pen(Vector3::new(0.05, 0.0, 0.7), Vector3::x()));
        let closest = (0..2)
            .map(|cam| {
                let b = &s.align.current(cam).unwrap().blobs;
                (0..LED_COUNT - 1)
                    .map(|i| (b[i][0] - b[i + 1][0]).hypot(b[i][1] - b[i + 1][1]))
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(f64::INFINITY, f64::min);
        let reach = closest / (2.0 * MERGE_MARGIN);
        for (factor, safe) in [(0.95, true), (1.05, false)] {
            for cam in 0..2 {
                let blobs = s.align.current(cam).unwrap().blobs.clone();
                let radii = vec![reach * factor; blobs.len()];
                s.align.push(cam, 1_000, blobs, radii);
            }
            let leds_1_2_4 = labelled_leds([true, true, false, true]);
            assert_eq!(
                guard.pen_images_separated(&s.view(), &s.estimate(), &leds_1_2_4),
                safe,
                "radius {factor} x reach"
            );
        }
    }

    /// Two labelled LEDs with blobs of their own were resolved, not merged: LEDs 2 and 3, the
    /// closest pair, with blobs grown just over their reach and LED 1's spot five times wider
    /// (nearer the camera, brighter) are safe when all four are labelled; with LED 3 unlabelled
    /// its image could hide in LED 2's blob (its radius taken as the widest), grown or not.
    #[test]
    fn resolved_spots_are_not_merges() {
        let guard = LabelGuard::new(&TrackerConfig::default());
        let mut s = Scene::new(pen(Vector3::new(0.05, 0.0, 0.7), Vector3::x()));
        let gap = |b: &[[f64; 2]], i: usize, j: usize| (b[i][0] - b[j][0]).hypot(b[i][1] - b[j][1]);
        let blobs = [0, 1].map(|cam| s.align.current(cam).unwrap().blobs.clone());
        let closest = blobs
            .iter()
            .map(|b| gap(b, 1, 2))
            .fold(f64::INFINITY, f64::min);
        assert!(blobs.iter().all(|b| gap(b, 0, 1) > 1.6 * closest));
        let reach = closest / (2.0 * MERGE_MARGIN);
        for factor in [0.95, 1.05] {
            for (cam, b) in blobs.iter().enumerate() {
                let mut radii = vec![reach * factor; LED_COUNT];
                radii[0] = 0.8 * closest;
                assert!(MERGE_MARGIN * 2.0 * radii[0] > closest);
                s.align.push(cam, 1_000, b.clone(), radii);
            }
            let view = s.view();
            let all = guard.pen_images_separated(&view, &s.estimate(), &labelled(4));
            assert!(all, "radius {factor} x reach");
            let leds_1_2_4 = labelled_leds([true, true, false, true]);
            let without_3 = guard.pen_images_separated(&view, &s.estimate(), &leds_1_2_4);
            assert!(!without_3, "radius {factor} x reach");
        }
    }

    /// A stray blob next to a labelled one makes the labelling unsafe.
    #[test]
    fn a_blob_beside_a_labelled_one_is_unsafe() {
        let guard = LabelGuard::new(&TrackerConfig::default());
        let mut s = Scene::new(pen(Vector3::new(0.05, 0.0, 0.7), Vector3::x()));
        assert!(guard.labelled_blobs_isolated(&s.view(), &labelled(4)));
        let mut blobs = s.align.current(0).unwrap().blobs.clone();
        blobs.push([blobs[2][0] + 2.0, blobs[2][1] + 1.0]);
        let right = s.align.current(1).unwrap().blobs.clone();
        s.align.push(0, 1_000, blobs, Vec::new());
        s.align.push(1, 1_000, right, Vec::new());
        assert!(!guard.labelled_blobs_isolated(&s.view(), &labelled(4)));
        assert!(
            guard.labelled_blobs_isolated(&s.view(), &labelled(2)),
            "LED 3 not labelled"
        );
    }

    /// Two LEDs need a prediction that puts each labelled blob nearest its own LED, and a
    /// fresh prior; remembering a labelling provides the prediction.
    #[test]
    fn two_leds_need_a_matching_prediction() {
        let cfg = TrackerConfig::default();
        let mut guard = LabelGuard::new(&cfg);
        let mut s = Scene::new(pen(Vector3::new(0.05, 0.0, 0.7), Vector3::x()));
        let two = labelled(2);
        let vision = s.estimate();
        assert!(
            !guard.labels_match_prediction(&s.view(), &two),
            "no prediction yet"
        );
        assert!(!guard.is_safe(&s.view(), &two, &vision, false));
        let all = labelled(4);
        let (tip, cands) = (s.tip.clone(), s.candidates.clone());
        guard.remember(&mut s.align, &tip, &cands, 1, 1_000, &all, &vision);
        assert!(guard.recent_leds(1_000 + cfg.continuity_ns).is_some());
        assert!(guard.recent_leds(1_001 + cfg.continuity_ns).is_none());
        assert_eq!(
            s.align.current(0).unwrap().labels,
            [Some(0), Some(1), Some(2), Some(3)]
        );
        assert!(guard.labels_match_prediction(&s.view(), &two));
        assert!(guard.is_safe(&s.view(), &two, &vision, false));
        assert!(
            !guard.is_safe(&s.view(), &two, &vision, true),
            "stale prior"
        );
        // LEDs 1 and 2 labelled the other way round contradict the prediction.
        let swapped = Identification {
            assignment: [Some(1), Some(0), None, None],
            ..two
        };
        assert!(!guard.labels_match_prediction(&s.view(), &swapped));
    }
}
