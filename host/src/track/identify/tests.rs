//! Whole-identifier tests: random pens, visibility patterns, interference and priors.

use super::*;
use crate::stereo::Candidate;
use crate::track::pen::{PenGeometry, LED_COUNT};
use crate::track::synth::{PenPose, SplitMix64};
use nalgebra::Vector3;

fn candidates(points: &[Vector3<f64>]) -> Vec<Candidate> {
    points
        .iter()
        .enumerate()
        .map(|(i, p)| Candidate::at(i, i, *p))
        .collect()
}

/// Scene: visible LEDs (by mask) + spurious points, with per-point 3D noise; returns the
/// candidates and, for each candidate, its true LED (or None for interference).
fn scene(
    rng: &mut SplitMix64,
    mask: u8,
    spurious: usize,
    noise: f64,
) -> (Vec<Candidate>, Vec<Option<usize>>, PenPose) {
    let pen = PenGeometry::thesis();
    let pose = PenPose::random(rng, 0.4, 1.2, 1.2);
    let leds = pen.led_positions(&pose.led1, &pose.rotation);
    let mut pts = Vec::new();
    let mut truth = Vec::new();
    for (i, p) in leds.iter().enumerate() {
        if mask & (1 << i) != 0 {
            // Gaussian noise, clipped to +-2 mm per point: labels must stay exact up to that error.
            let n = Vector3::new(rng.gaussian(), rng.gaussian(), rng.gaussian()) * noise;
            pts.push(p + n.cap_magnitude(0.002));
            truth.push(Some(i));
        }
    }
    while truth.len() < mask.count_ones() as usize + spurious {
        let s = pose.led1
            + Vector3::new(
                rng.uniform(-0.2, 0.2),
                rng.uniform(-0.2, 0.2),
                rng.uniform(-0.2, 0.2),
            );
        // A point within ~2 cm of where an LED should be (distance tolerance plus line residual)
        // is geometrically indistinguishable from that LED: it is not "interference".
        if leds.iter().any(|l| (l - s).norm() < 0.02) {
            continue;
        }
        pts.push(s);
        truth.push(None);
    }
    // Shuffle so the order carries no information.
    for k in (1..pts.len()).rev() {
        let j = (rng.next_u64() % (k as u64 + 1)) as usize;
        pts.swap(k, j);
        truth.swap(k, j);
    }
    (candidates(&pts), truth, pose)
}

fn wrong_labels(id: &Identification, truth: &[Option<usize>]) -> usize {
    id.assignment
        .iter()
        .enumerate()
        .filter(|(led, a)| a.is_some_and(|k| truth[k] != Some(*led)))
        .count()
}

#[test]
fn every_subset_is_labelled_with_a_direction_prior() {
    let mut rng = SplitMix64::new(7);
    let mut id = Identifier::new(PenGeometry::thesis(), IdentifyConfig::default()).unwrap();
    for mask in 1u8..16 {
        if mask.count_ones() < 2 {
            continue;
        }
        for _ in 0..200 {
            let (c, truth, pose) = scene(&mut rng, mask, 0, 0.0007);
            let prior = IdentifyPrior {
                direction: Some(pose.direction()),
                previous: continuity_for_triples(mask, &pose),
                ..Default::default()
            };
            let r = id.identify(&c, &prior).unwrap();
            assert_eq!(r.mask(), mask);
            assert_eq!(wrong_labels(&r, &truth), 0);
        }
    }
}

/// Previous LED positions (continuity) for three-LED masks, whose twin triples need them.
fn continuity_for_triples(mask: u8, pose: &PenPose) -> [Option<Vector3<f64>>; LED_COUNT] {
    if mask.count_ones() == 3 {
        PenGeometry::thesis()
            .led_positions(&pose.led1, &pose.rotation)
            .map(Some)
    } else {
        [None; LED_COUNT]
    }
}

/// LEDs 1-3 seen where LEDs 2-4 were a frame ago: the distances fit 1-3 exactly, but the
/// labels would trade places between frames, so the frame is refused; with the previous
/// frame agreeing, it is labelled.
#[test]
fn labels_that_trade_places_between_frames_are_refused() {
    let mut rng = SplitMix64::new(8);
    let pen = PenGeometry::thesis();
    let mut id = Identifier::new(pen, IdentifyConfig::default()).unwrap();
    let pose = PenPose::random(&mut rng, 0.5, 0.7, 0.3);
    let leds = pen.led_positions(&pose.led1, &pose.rotation);
    let c = candidates(&leds[..3]);
    let agreeing = IdentifyPrior {
        previous: [Some(leds[0]), Some(leds[1]), Some(leds[2]), None],
        ..Default::default()
    };
    let r = id.identify(&c, &agreeing).expect("labelled");
    assert_eq!(r.assignment, [Some(0), Some(1), Some(2), None]);
    let shifted = IdentifyPrior {
        previous: [None, Some(leds[0]), Some(leds[1]), Some(leds[2])],
        ..Default::default()
    };
    assert_eq!(id.identify(&c, &shifted), Err(IdentifyError::Ambiguous));
}

#[test]
fn two_leds_without_prior_are_refused_and_three_need_continuity() {
    let mut rng = SplitMix64::new(3);
    let mut id = Identifier::new(PenGeometry::thesis(), IdentifyConfig::default()).unwrap();
    let (c, _, _) = scene(&mut rng, 0b0101, 0, 0.0);
    assert_eq!(
        id.identify(&c, &IdentifyPrior::default()),
        Err(IdentifyError::Ambiguous)
    );
    // {1,2,4} (70:90) and {2,3,4} (40:50) are twins up to scale: without continuity a scale
    // error could swap them, so the frame is refused, even with the direction prior (twins
    // point the same way). ({1,2,3} vs {1,3,4} differ by more than the band here.)
    for mask in [0b1011u8, 0b1110] {
        let (c, truth, pose) = scene(&mut rng, mask, 0, 0.0);
        let direction = IdentifyPrior {
            direction: Some(pose.direction()),
            ..Default::default()
        };
        assert_eq!(id.identify(&c, &direction), Err(IdentifyError::Ambiguous));
        let continuity = IdentifyPrior {
            direction: None,
            previous: continuity_for_triples(mask, &pose),
            ..Default::default()
        };
        let r = id.identify(&c, &continuity).unwrap();
        assert_eq!((r.count(), wrong_labels(&r, &truth)), (3, 0));
    }
    // Continuity alone also resolves the two-LED case.
    let (c, truth, pose) = scene(&mut rng, 0b0011, 0, 0.0);
    let leds = PenGeometry::thesis().led_positions(&pose.led1, &pose.rotation);
    let prior = IdentifyPrior {
        direction: None,
        previous: leds.map(Some),
        ..Default::default()
    };
    let r = id.identify(&c, &prior).unwrap();
    assert_eq!(wrong_labels(&r, &truth), 0);
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(200))]
    /// Random pens, visibility patterns and spurious points: never a wrong label.
    #[test]
    fn random_pens_and_spurious_points_never_get_wrong_labels(seed in 0u64..u64::MAX, mask in 3u8..16, spurious in 0usize..4) {
        proptest::prop_assume!(mask.count_ones() >= 2);
        let mut rng = SplitMix64::new(seed);
        let mut id = Identifier::new(PenGeometry::thesis(), IdentifyConfig::default()).unwrap();
        let (c, truth, pose) = scene(&mut rng, mask, spurious, 0.0007);
        let prior = IdentifyPrior { direction: Some(pose.direction()), ..Default::default() };
        if let Ok(r) = id.identify(&c, &prior) {
            proptest::prop_assert_eq!(wrong_labels(&r, &truth), 0);
        }
    }
}

#[test]
fn interference_never_yields_a_wrong_label() {
    let mut rng = SplitMix64::new(11);
    let mut id = Identifier::new(PenGeometry::thesis(), IdentifyConfig::default()).unwrap();
    let (mut wrong, mut labelled, mut frames) = (0, 0, 0);
    for mask in [
        0b1111u8, 0b1110, 0b0111, 0b1011, 0b1101, 0b0011, 0b1100, 0b0110, 0b1001,
    ] {
        for spurious in 1..=3 {
            for _ in 0..400 {
                let (c, truth, pose) = scene(&mut rng, mask, spurious, 0.0007);
                let prior = IdentifyPrior {
                    direction: Some(pose.direction()),
                    previous: continuity_for_triples(mask, &pose),
                    ..Default::default()
                };
                frames += 1;
                if let Ok(r) = id.identify(&c, &prior) {
                    labelled += 1;
                    wrong += wrong_labels(&r, &truth);
                }
            }
        }
    }
    assert_eq!(wrong, 0);
    assert!(labelled as f64 > 0.9 * frames as f64, "{labelled}/{frames}");
}

/// A stereo pair stretched by a stale time alignment can make LEDs 1-3 look like LEDs 1, 3 and 4
/// (110 and 50 mm apart); the true LED 4's blob then lies on the pen's image line beyond the
/// labelled LED 4, 1.64 of the labelled LED 1-4 segment from LED 1 when the pen recedes (stress
/// seed 16). The image evidence looks that far along the line, so the labelling is refused; the
/// same points without that blob are labelled.
#[test]
fn a_blob_beyond_the_labelled_pen_refuses_a_shifted_labelling() {
    let rig = crate::stereo::StereoRig::parallel(1024, 768, 45f64.to_radians(), 0.25);
    let mut id = Identifier::new(PenGeometry::thesis(), IdentifyConfig::default())
        .unwrap()
        .with_rig(&rig, 0.5);
    // The pen across the view: the labelled LEDs 1, 3, 4 at 0, 110 and 160 mm along x, and the
    // unlabelled blob at 262 mm (1.64 x 160).
    let at = |s: f64| Vector3::new(-0.08 + s, 0.02, 0.7);
    let points = [at(0.0), at(0.110), at(0.160)];
    let norm = |p: &Vector3<f64>| {
        let q = [(p.x / p.z, p.y / p.z), ((p.x - 0.25) / p.z, p.y / p.z)];
        q.map(|(x, y)| [x, y])
    };
    let cands = candidates(&points);
    let mut left: Vec<[f64; 2]> = points.iter().map(|p| norm(p)[0]).collect();
    let mut right: Vec<[f64; 2]> = points.iter().map(|p| norm(p)[1]).collect();
    let prior = IdentifyPrior::default();
    let labelled = id
        .identify_with_images(&cands, &prior, &left, &right)
        .expect("labelled without the extra blob");
    assert_eq!(labelled.assignment, [Some(0), None, Some(1), Some(2)]);
    left.push(norm(&at(0.262))[0]);
    right.push(norm(&at(0.262))[1]);
    assert_eq!(
        id.identify_with_images(&cands, &prior, &left, &right),
        Err(IdentifyError::ContradictedByImage)
    );
}
