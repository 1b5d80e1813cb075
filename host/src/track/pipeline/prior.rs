//! The fused pen direction and what it gives the tracker (FIRES thesis, §4.1.4: the inertial
//! orientation fused with the vision axis): the direction prior of identification with its
//! expected error, the fused axis for the tip, and the world reference the filter works in,
//! configured or estimated online and accepted here ([`DirectionPrior::accept_world_fit`]).
//! Frames: docs/architecture.md §2.

use super::TrackerConfig;
use crate::stereo::Candidate;
use crate::track::fusion::{
    DirectionFilter, FusionKind, ImuSample, MagCalibrator, MagOffset, OrientationFilter,
    ThesisKalman, WorldEstimator, WorldFit, WorldReference,
};
use crate::track::identify::{Identification, Resolution};
use nalgebra::{UnitQuaternion, Vector3};

/// The direction filter the tracker runs.
enum Filter {
    Thesis(Box<ThesisKalman>),
    Orientation(Box<OrientationFilter>),
}

impl Filter {
    fn get(&self) -> &dyn DirectionFilter {
        match self {
            Filter::Thesis(f) => f.as_ref(),
            Filter::Orientation(f) => f.as_ref(),
        }
    }

    fn get_mut(&mut self) -> &mut dyn DirectionFilter {
        match self {
            Filter::Thesis(f) => f.as_mut(),
            Filter::Orientation(f) => f.as_mut(),
        }
    }
}

/// What the prior needs from the configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
struct PriorOptions {
    /// Expected error of a vision-corrected direction, radians.
    prior_sigma: f64,
    /// The fused direction counts as vision-corrected for this long, nanoseconds.
    fused_fresh_ns: u64,
    /// Growth of the expected error after that, radians per second...
    stale_prior_growth: f64,
    /// ...up to this, radians (0: no stale prior).
    stale_prior_max: f64,
}

/// How long a stale prior keeps vetoing labellings, seconds (see [`DirectionPrior::prior`]).
const STALE_PRIOR_TIMEOUT_S: f64 = 1.0;

/// Direction filter, magnetometer calibration and world reference of one tracker.
pub(super) struct DirectionPrior {
    options: PriorOptions,
    filter: Filter,
    /// The world reference in use: configured, or estimated (then `world_fit` is set).
    world: Option<WorldReference>,
    world_estimator: Option<WorldEstimator>,
    world_fit: Option<(u64, WorldFit)>,
    mag: MagCalibrator,
    last_vision_ns: Option<u64>,
}

impl DirectionPrior {
    /// The configured filter in the configured world frame, or (no world configured) in the
    /// default frame with an online world estimator.
    pub(super) fn new(config: &TrackerConfig) -> Self {
        // Until a reference is known the filters run in the default frame on the IMU alone.
        let initial_world = config.world.unwrap_or_default();
        let filter = match config.fusion {
            FusionKind::ThesisKalman => Filter::Thesis(Box::new(ThesisKalman::new(
                config.thesis_kalman,
                initial_world,
            ))),
            FusionKind::Orientation => Filter::Orientation(Box::new(OrientationFilter::new(
                config.orientation,
                initial_world,
            ))),
        };
        let world_estimator = config
            .world
            .is_none()
            .then(|| WorldEstimator::new(config.world_estimate, config.orientation));
        Self {
            options: PriorOptions {
                prior_sigma: config.identify.prior_sigma,
                fused_fresh_ns: config.fused_fresh_ns,
                stale_prior_growth: config.stale_prior_growth,
                stale_prior_max: config.stale_prior_max,
            },
            filter,
            world: config.world,
            world_estimator,
            world_fit: None,
            mag: MagCalibrator::new(config.mag_calibration),
            last_vision_ns: None,
        }
    }

    /// The world reference in use (configured or estimated), None while still being estimated.
    pub(super) fn world(&self) -> Option<&WorldReference> {
        self.world.as_ref()
    }

    /// The latest online world estimate with the time it was accepted, nanoseconds.
    pub(super) fn world_fit(&self) -> Option<&(u64, WorldFit)> {
        self.world_fit.as_ref()
    }

    /// The magnetometer's hard-iron offset, once calibrated.
    pub(super) fn mag_offset(&self) -> Option<&MagOffset> {
        self.mag.offset()
    }

    /// The sample with the magnetometer's hard-iron offset removed (once known); a newly
    /// accepted offset restarts the world estimate, whose Earth frame takes its heading from
    /// the magnetometer.
    pub(super) fn calibrated_mag(&mut self, sample: &ImuSample) -> ImuSample {
        let raw = Vector3::from(sample.mag);
        if self.mag.push(&raw).is_some() {
            if let Some(e) = &mut self.world_estimator {
                e.restart();
            }
        }
        match self.mag.offset() {
            Some(o) => ImuSample {
                mag: o.correct(&raw).into(),
                ..*sample
            },
            None => *sample,
        }
    }

    /// Feeds one (calibrated) IMU sample to the world estimator and the filter.
    pub(super) fn imu(&mut self, sample: &ImuSample) {
        if let Some(e) = &mut self.world_estimator {
            e.imu(sample);
        }
        self.filter.get_mut().imu(sample);
    }

    /// The filter's orientation at `t_ns`, once it is expressed in the camera frame.
    pub(super) fn orientation_at(&self, t_ns: u64) -> Option<UnitQuaternion<f64>> {
        self.world?;
        self.filter.get().orientation_at(t_ns)
    }

    /// The filter's pen direction at `t_ns`, once it is expressed in the camera frame.
    pub(super) fn direction_at(&self, t_ns: u64) -> Option<Vector3<f64>> {
        self.world?;
        self.filter.get().direction_at(t_ns)
    }

    /// Offers a labelled frame's vision axis to the world estimate. Only labels the geometry
    /// settled may calibrate the world: a prior from an uncalibrated filter could confirm its
    /// own error. Mirrored three-LED labellings that slipped through the distance test are
    /// outliers of the fit. Returns the new reference when a fit was accepted.
    pub(super) fn observe_labelled(
        &mut self,
        t: u64,
        id: &Identification,
        direction: &Vector3<f64>,
    ) -> Option<WorldReference> {
        if id.resolution == Resolution::Geometry && id.count() >= 3 {
            let fit = self
                .world_estimator
                .as_mut()
                .and_then(|e| e.vision(t, direction));
            if let Some(fit) = fit {
                self.accept_world_fit(t, fit);
                return Some(fit.reference);
            }
        }
        None
    }

    /// Takes a new online world estimate: the first one moves the filter into the camera frame
    /// (`R` applied to its state); later ones refine the reference only.
    pub(super) fn accept_world_fit(&mut self, t_ns: u64, fit: WorldFit) {
        let r = if self.world.is_none() {
            fit.rotation()
        } else {
            UnitQuaternion::identity()
        };
        self.filter.get_mut().rebase(&r, fit.reference);
        self.world = Some(fit.reference);
        let first = self.world_fit.map_or(t_ns, |(t, _)| t);
        self.world_fit = Some((first, fit));
    }

    /// Corrects the filter with a vision axis (variance per perpendicular axis, rad^2), once the
    /// world reference is known.
    pub(super) fn correct(&mut self, t: u64, direction: &Vector3<f64>, variance: Option<f64>) {
        if self.world.is_some() {
            self.filter.get_mut().vision(t, direction, variance);
        }
    }

    /// Records that a vision sample was produced at `t` (the fused direction is fresh from now).
    pub(super) fn mark_vision(&mut self, t: u64) {
        self.last_vision_ns = Some(t);
    }

    /// The filter's pen direction as an identification prior, with its expected error: the
    /// configured `prior_sigma` while vision corrected it within `fused_fresh_ns`, then growing
    /// by `stale_prior_growth` per second up to `stale_prior_max`. Without it a three-LED pen
    /// that lost the track could never be relabelled (its mirror image fits the distances).
    /// None until the world reference is known, and until vision has corrected the filter once: an
    /// inertial direction never corrected carries the magnetometer's uncalibrated heading error, which
    /// can exceed any stale bound, and a prior that refused every labelling would never be corrected.
    pub(super) fn prior(&self, t: u64) -> Option<(Vector3<f64>, f64)> {
        let d = self.direction_at(t)?;
        let base = self.options.prior_sigma;
        let age = t.saturating_sub(self.last_vision_ns?);

        if age <= self.options.fused_fresh_ns {
            return Some((d, base));
        }
        if self.options.stale_prior_max <= 0.0 {
            return None;
        }
        let stale_s = (age - self.options.fused_fresh_ns) as f64 * 1e-9;
        if stale_s > STALE_PRIOR_TIMEOUT_S {
            // Refused this long, the inertial direction may have drifted beyond any bound (the
            // magnetometer's heading before its hard iron is calibrated); identification falls
            // back to the geometry alone, which refuses what it cannot tell apart, until vision
            // corrects the filter again. Otherwise a wrong prior would refuse vision for ever.
            return None;
        }
        let sigma =
            (base + self.options.stale_prior_growth * stale_s).min(self.options.stale_prior_max);
        Some((d, sigma.max(base)))
    }

    /// The fused direction while vision corrected it within `fused_fresh_ns`, else None.
    pub(super) fn fused(&self, t: u64) -> Option<Vector3<f64>> {
        let fresh = self
            .last_vision_ns
            .is_some_and(|tv| t.saturating_sub(tv) <= self.options.fused_fresh_ns);
        if fresh {
            self.direction_at(t)
        } else {
            None
        }
    }
}

/// Variance (rad^2 per perpendicular axis) of the least-squares pen axis `v` from the labelled
/// candidates' covariances: `Σ (s_i - s̄)^2 σ⊥_i^2 / (Σ (s_i - s̄)^2)^2` with `s_i` the LEDs'
/// axial positions (`led_offsets`).
pub(super) fn direction_variance(
    led_offsets: &[f64; crate::track::pen::LED_COUNT],
    candidates: &[Candidate],
    id: &Identification,
    v: &Vector3<f64>,
) -> Option<f64> {
    let l = led_offsets;
    let labelled: Vec<(f64, &Candidate)> = id
        .assignment
        .iter()
        .enumerate()
        .filter_map(|(i, k)| k.map(|k| (l[i], &candidates[k])))
        .collect();
    let mean = labelled.iter().map(|(s, _)| s).sum::<f64>() / labelled.len() as f64;
    let sxx: f64 = labelled.iter().map(|(s, _)| (s - mean).powi(2)).sum();
    let num: f64 = labelled
        .iter()
        .map(|(s, c)| {
            (s - mean).powi(2) * 0.5 * (c.covariance.trace() - v.dot(&(c.covariance * v)))
        })
        .sum();
    let var = num / (sxx * sxx);
    (var.is_finite() && var > 0.0).then_some(var)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::pen::PenGeometry;

    fn imu(t_ns: u64) -> ImuSample {
        ImuSample {
            t_ns,
            accel: [0.0, 0.0, 9.81],
            gyro: [0.0; 3],
            mag: [0.0, 30.0, 20.0],
        }
    }

    fn known_world() -> TrackerConfig {
        TrackerConfig {
            world: Some(WorldReference::default()),
            ..TrackerConfig::default()
        }
    }

    /// Fresh: the configured sigma; then it grows at `stale_prior_growth` up to
    /// `stale_prior_max`, and there is none after the stale timeout or before the first vision;
    /// without a stale prior there is none once vision is old.
    #[test]
    fn the_prior_loosens_as_vision_ages() {
        let cfg = known_world();
        let mut p = DirectionPrior::new(&cfg);
        assert!(p.prior(0).is_none(), "no filter state yet");
        p.imu(&imu(1_000_000));
        let base = cfg.identify.prior_sigma;
        // Never corrected by vision: no prior (its heading error is unbounded).
        assert!(p.prior(2_000_000).is_none());
        assert!(p.fused(2_000_000).is_none());
        p.mark_vision(10_000_000);
        let fresh_end = 10_000_000 + cfg.fused_fresh_ns;
        assert_eq!(p.prior(fresh_end).unwrap().1, base);
        assert!(p.fused(fresh_end).is_some());
        assert!(p.fused(fresh_end + 1).is_none());
        let later = fresh_end + 200_000_000;
        let sigma = p.prior(later).unwrap().1;
        assert!((sigma - (base + cfg.stale_prior_growth * 0.2)).abs() < 1e-15);
        assert_eq!(
            p.prior(fresh_end + 900_000_000).unwrap().1,
            cfg.stale_prior_max
        );
        // Stale beyond the timeout: none, until vision corrects the filter again.
        assert!(p.prior(fresh_end + 1_100_000_000).is_none());
        p.mark_vision(fresh_end + 3_000_000_000);
        assert_eq!(p.prior(fresh_end + 3_000_000_000).unwrap().1, base);
        let mut none = DirectionPrior::new(&TrackerConfig {
            stale_prior_max: 0.0,
            ..known_world()
        });
        none.imu(&imu(1_000_000));
        none.mark_vision(10_000_000);
        assert!(none.prior(fresh_end).is_some());
        assert!(none.prior(later).is_none());
    }

    /// Without a world reference the filter runs but gives nothing; the first accepted fit
    /// rotates it into the camera frame and is remembered with its time, later fits only
    /// refine the reference.
    #[test]
    fn the_first_world_fit_moves_the_filter_into_the_camera_frame() {
        let mut p = DirectionPrior::new(&TrackerConfig::default());
        p.imu(&imu(1_000_000));
        assert!(p.world().is_none() && p.prior(2_000_000).is_none());
        let before = p.filter.get().direction_at(2_000_000).unwrap();
        let r = UnitQuaternion::from_euler_angles(0.3, -0.2, 1.1);
        let d = WorldReference::default();
        let reference = WorldReference {
            up: (r * d.up()).into(),
            magnetic: (r * d.magnetic()).into(),
            gravity: d.gravity,
        };
        let q = r.into_inner();
        let fit = WorldFit {
            camera_from_earth: [q.w, q.i, q.j, q.k],
            reference,
            pairs: 30,
            candidates: 30,
            residual_rms: 0.01,
            worst_axis_sigma: 0.01,
            spread: 0.5,
        };
        p.accept_world_fit(5, fit);
        let after = p.direction_at(2_000_000).unwrap();
        assert!((after - r * before).norm() < 1e-12);
        p.accept_world_fit(9, fit);
        assert!((p.direction_at(2_000_000).unwrap() - after).norm() < 1e-12);
        assert_eq!(p.world_fit().map(|f| f.0), Some(5));
        assert_eq!(p.world(), Some(&reference));
    }

    /// Equal isotropic covariances `σ² I`: each LED's perpendicular variance is `σ²`, so the
    /// axis variance is `σ² / Σ (s_i - s̄)^2`.
    #[test]
    fn direction_variance_of_isotropic_leds() {
        let l = PenGeometry::thesis().led_offsets;
        let sigma2 = 1e-6;
        let cands: Vec<Candidate> = (0..4)
            .map(|i| Candidate {
                covariance: nalgebra::Matrix3::identity() * sigma2,
                ..Candidate::at(i, i, Vector3::new(-l[i], 0.0, 1.0))
            })
            .collect();
        let id = Identification {
            assignment: [Some(0), None, Some(2), Some(3)],
            points: [None; 4],
            distance_rms: 0.0,
            confidence: 1.0,
            resolution: Resolution::Geometry,
            interference: 0,
            completed: 0,
            from_pen_line: false,
            from_pen_ray: None,
        };
        let s = [l[0], l[2], l[3]];
        let mean = s.iter().sum::<f64>() / 3.0;
        let sxx: f64 = s.iter().map(|x| (x - mean).powi(2)).sum();
        let var = direction_variance(&l, &cands, &id, &Vector3::x()).unwrap();
        assert!((var - sigma2 / sxx).abs() < 1e-12 * var);
        // No covariance: no variance.
        let bare: Vec<Candidate> = (0..4).map(|i| Candidate::at(i, i, Vector3::z())).collect();
        assert!(direction_variance(&l, &bare, &id, &Vector3::x()).is_none());
    }
}
