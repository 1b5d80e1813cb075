//! Online estimate of the world reference (gravity "up" and the magnetic field in the left-camera
//! frame) from the session itself, so no rig-to-gravity calibration is needed (the FIRES thesis, §4.1.4,
//! leaves this camera-to-world alignment to calibration; see also [`super`]).
//!
//! An IMU-only copy of the orientation filter runs in an arbitrary Earth frame `E` (the default
//! [`WorldReference`]): its gravity and magnetic-heading corrections make `E` a fixed frame, up to
//! the magnetometer's errors. Every frame whose labels the geometry alone settled gives a pair
//! (vision axis `d_i` in the camera frame `C`, IMU axis `e_i = q_E(t_i) x̂`) with `d_i = R e_i`
//! for the constant rotation `R = C ← E`. `R` is Wahba's problem, solved by SVD of the attitude
//! profile matrix `B = Σ d_i e_iᵀ` (Markley 1988), with outliers (mislabelled frames, hand
//! accelerations) removed in a few reweighting rounds. The estimate is accepted once the
//! worst-determined rotation axis, from the information matrix `Σ (I - d_i d_iᵀ) / σ²`, is known
//! to `target_sigma` *and* the pen axes spread about that rotation axis by `min_spread`: pen axes
//! inside a narrow cone leave the rotation about the cone's axis poorly determined, and the
//! magnetometer's orientation-dependent errors, which are not white, would be amplified into it.
//! Then `up_C = R up_E`, `m_C = R m_E`.

use super::imu::{ImuSample, WorldReference};
use super::orientation::{OrientationConfig, OrientationFilter};
use super::DirectionFilter;
use nalgebra::{Matrix3, Rotation3, SymmetricEigen, UnitQuaternion, Vector3};

/// When pairs are taken and when the estimate is good enough.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WorldEstimateConfig {
    /// Pairs are ignored until the IMU-only filter has run this long (its start-up), nanoseconds.
    pub settle_ns: u64,
    /// At most one pair per this interval (consecutive frames carry correlated IMU errors),
    /// nanoseconds.
    pub min_interval_ns: u64,
    /// Fewest inlier pairs for an estimate.
    pub min_pairs: usize,
    /// Required standard deviation of the worst-determined rotation axis, radians.
    pub target_sigma: f64,
    /// Smallest spread of the pen axes about the worst-determined rotation axis (RMS sine of
    /// their angle to it). The IMU-only frame's errors are not white (the magnetometer's heading
    /// error follows the pen's orientation), and a fit amplifies them by the inverse of this
    /// spread, which the statistical test alone does not see.
    pub min_spread: f64,
    /// Pairs whose residual angle exceeds this after a fit are outliers, radians.
    pub outlier_angle: f64,
    /// Smallest inlier fraction for an estimate (protects against a fit to mislabelled frames).
    pub min_inlier_fraction: f64,
    /// Pairs kept; beyond this every other pair is dropped (the oldest half thinned).
    pub max_pairs: usize,
    /// New pairs between two fits.
    pub refit_every: usize,
}

impl Default for WorldEstimateConfig {
    fn default() -> Self {
        Self {
            settle_ns: 1_500_000_000,
            min_interval_ns: 50_000_000,
            min_pairs: 20,
            target_sigma: 1.5f64.to_radians(),
            min_spread: 0.2,
            outlier_angle: 15f64.to_radians(),
            min_inlier_fraction: 0.8,
            max_pairs: 4000,
            refit_every: 10,
        }
    }
}

/// One accepted estimate of the world reference.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WorldFit {
    /// Camera-from-Earth rotation `R` (Earth = the IMU-only filter's frame) as a unit
    /// quaternion `[w, x, y, z]`.
    pub camera_from_earth: [f64; 4],
    /// `up` and magnetic field in the camera frame.
    pub reference: WorldReference,
    /// Inlier pairs used.
    pub pairs: usize,
    /// All pairs considered.
    pub candidates: usize,
    /// RMS residual angle of the inliers, radians.
    pub residual_rms: f64,
    /// Standard deviation of the worst-determined rotation axis, radians.
    pub worst_axis_sigma: f64,
    /// Spread of the pen axes about that rotation axis (RMS sine).
    pub spread: f64,
}

impl WorldFit {
    /// `R` as a rotation.
    pub fn rotation(&self) -> UnitQuaternion<f64> {
        let [w, x, y, z] = self.camera_from_earth;
        UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(w, x, y, z))
    }
}

/// One (camera axis, Earth axis) observation.
#[derive(Debug, Clone, Copy)]
struct AxisPair {
    camera: Vector3<f64>,
    earth: Vector3<f64>,
}

/// IMU-only filter plus the axis pairs and the latest fit.
#[derive(Debug, Clone)]
pub struct WorldEstimator {
    config: WorldEstimateConfig,
    earth: WorldReference,
    imu_only: OrientationFilter,
    first_imu_ns: Option<u64>,
    last_pair_ns: Option<u64>,
    pairs: Vec<AxisPair>,
    since_fit: usize,
    fit: Option<WorldFit>,
}

impl WorldEstimator {
    /// An estimator whose IMU-only filter runs with `filter` gains in the default Earth frame.
    pub fn new(config: WorldEstimateConfig, filter: OrientationConfig) -> Self {
        let earth = WorldReference::default();
        Self {
            config,
            earth,
            imu_only: OrientationFilter::new(filter, earth),
            first_imu_ns: None,
            last_pair_ns: None,
            pairs: Vec::new(),
            since_fit: 0,
            fit: None,
        }
    }

    /// Starts the pairs and the IMU-only filter afresh (e.g. once the magnetometer is
    /// calibrated, the Earth frame's heading changes); the latest fit is kept.
    pub fn restart(&mut self) {
        self.imu_only = OrientationFilter::new(self.imu_only.config, self.earth);
        self.first_imu_ns = None;
        self.last_pair_ns = None;
        self.pairs.clear();
        self.since_fit = 0;
    }

    /// The IMU-only filter (Earth frame).
    pub fn imu_only(&self) -> &OrientationFilter {
        &self.imu_only
    }

    /// Feeds one IMU sample to the IMU-only filter.
    pub fn imu(&mut self, s: &ImuSample) {
        self.imu_only.imu(s);
        if self.imu_only.is_initialised() && self.first_imu_ns.is_none() {
            self.first_imu_ns = Some(s.t_ns);
        }
    }

    /// Offers the vision pen axis (unit, camera frame, towards the tip) of a frame labelled by
    /// geometry alone; returns a new fit when this pair completed one.
    pub fn vision(&mut self, t_ns: u64, axis: &Vector3<f64>) -> Option<WorldFit> {
        let settled = self
            .first_imu_ns
            .is_some_and(|t0| t_ns.saturating_sub(t0) >= self.config.settle_ns);
        let spaced = self
            .last_pair_ns
            .is_none_or(|t| t_ns.saturating_sub(t) >= self.config.min_interval_ns);
        let camera = axis.try_normalize(1e-9)?;
        if !(settled && spaced) {
            return None;
        }
        let earth = self.imu_only.direction_at(t_ns)?;
        self.last_pair_ns = Some(t_ns);
        self.pairs.push(AxisPair { camera, earth });
        if self.pairs.len() > self.config.max_pairs {
            let mut i = 0;
            self.pairs.retain(|_| {
                i += 1;
                i % 2 == 0
            });
        }
        self.since_fit += 1;
        if self.since_fit < self.config.refit_every || self.pairs.len() < self.config.min_pairs {
            return None;
        }
        self.since_fit = 0;
        let fit = solve(&self.pairs, &self.config, &self.earth)?;
        self.fit = Some(fit);
        Some(fit)
    }

    /// The latest accepted fit.
    pub fn fit(&self) -> Option<&WorldFit> {
        self.fit.as_ref()
    }

    /// Pairs collected so far.
    pub fn pair_count(&self) -> usize {
        self.pairs.len()
    }
}

/// Wahba's problem by SVD: the rotation `R` minimising `Σ w_i |d_i - R e_i|²`.
fn wahba(pairs: &[AxisPair], inlier: &[bool]) -> Option<Rotation3<f64>> {
    let b: Matrix3<f64> = pairs
        .iter()
        .zip(inlier)
        .filter(|(_, k)| **k)
        .map(|(p, _)| p.camera * p.earth.transpose())
        .sum();
    let svd = b.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let d = (u * v_t).determinant().signum();
    let r = u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * v_t;
    r.iter()
        .all(|x| x.is_finite())
        .then(|| Rotation3::from_matrix_unchecked(r))
}

fn residual(p: &AxisPair, r: &Rotation3<f64>) -> f64 {
    p.camera.angle(&(r * p.earth))
}

/// Robust fit (outlier rounds) and the acceptance test; None when not yet determined.
fn solve(
    pairs: &[AxisPair],
    config: &WorldEstimateConfig,
    earth: &WorldReference,
) -> Option<WorldFit> {
    let mut inlier = vec![true; pairs.len()];
    let mut r = wahba(pairs, &inlier)?;
    for _ in 0..4 {
        let next: Vec<bool> = pairs
            .iter()
            .map(|p| residual(p, &r) <= config.outlier_angle)
            .collect();
        if next == inlier {
            break;
        }
        inlier = next;
        if inlier.iter().filter(|k| **k).count() < config.min_pairs {
            return None;
        }
        r = wahba(pairs, &inlier)?;
    }
    let used: Vec<&AxisPair> = pairs
        .iter()
        .zip(&inlier)
        .filter_map(|(p, k)| k.then_some(p))
        .collect();
    let n = used.len();
    if n < config.min_pairs || (n as f64) < config.min_inlier_fraction * pairs.len() as f64 {
        return None;
    }
    let sum_sq: f64 = used.iter().map(|p| residual(p, &r).powi(2)).sum();
    let residual_rms = (sum_sq / n as f64).sqrt();
    // Per-axis variance of a direction residual (two perpendicular components), with a floor so
    // a perfect fit is not infinitely certain.
    let sigma2 = (sum_sq / (2.0 * n as f64)).max(1e-8);
    // Σ (I - d dᵀ): its smallest eigenvalue over n is the mean squared sine between the axes
    // and the worst-determined rotation axis.
    let scatter: Matrix3<f64> = used
        .iter()
        .map(|p| Matrix3::identity() - p.camera * p.camera.transpose())
        .sum();
    let lambda_min = SymmetricEigen::new(scatter).eigenvalues.min().max(0.0);
    let spread = (lambda_min / n as f64).sqrt();
    let worst_axis_sigma = if lambda_min > 0.0 {
        (sigma2 / lambda_min).sqrt()
    } else {
        f64::INFINITY
    };
    if worst_axis_sigma > config.target_sigma || spread < config.min_spread {
        return None;
    }
    let q = UnitQuaternion::from_rotation_matrix(&r);
    Some(WorldFit {
        camera_from_earth: [q.w, q.i, q.j, q.k],
        reference: WorldReference {
            up: (q * earth.up()).into(),
            magnetic: (q * Vector3::from(earth.magnetic)).into(),
            gravity: earth.gravity,
        },
        pairs: n,
        candidates: pairs.len(),
        residual_rms,
        worst_axis_sigma,
        spread,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::synth::{imu_sample, ImuNoise, PenMotion, SplitMix64};

    /// Drives the estimator with synthetic IMU data for a pen drawing in a camera frame rotated by
    /// `camera_from_world` away from the default; vision axes every 33 ms, a fraction `flipped`
    /// of them reversed (mislabelled frames).
    fn run(
        camera_from_world: UnitQuaternion<f64>,
        seconds: f64,
        flipped: f64,
        seed: u64,
    ) -> Option<WorldFit> {
        let world = WorldReference::default();
        let motion = PenMotion::drawing();
        let noise = ImuNoise::default();
        let mut rng = SplitMix64::new(seed);
        let mut est = WorldEstimator::new(WorldEstimateConfig::default(), Default::default());
        let mut fit = None;
        let steps = (seconds * 200.0) as u64;
        for k in 0..steps {
            let t_ns = k * 5_000_000;
            let s = imu_sample(&motion, t_ns, &world, &noise, &mut rng);
            est.imu(&s);
            if k % 7 == 0 {
                let pose = motion.pose(t_ns as f64 * 1e-9);
                let mut axis = camera_from_world * pose.direction();
                if rng.unit() < flipped {
                    axis = -axis;
                }
                if let Some(f) = est.vision(t_ns, &axis) {
                    fit = Some(f);
                }
            }
        }
        fit
    }

    #[test]
    fn recovers_a_tilted_camera_despite_mislabelled_frames() {
        let r = UnitQuaternion::from_euler_angles(0.4, -0.25, 1.9);
        let fit = run(r, 20.0, 0.05, 3).expect("estimate");
        let world = WorldReference::default();
        let up_err = Vector3::from(fit.reference.up).angle(&(r * world.up()));
        assert!(up_err < 1f64.to_radians(), "up error {up_err}");
        let mag_err = Vector3::from(fit.reference.magnetic).angle(&(r * world.magnetic()));
        assert!(mag_err < 2f64.to_radians(), "magnetic error {mag_err}");
        assert!(fit.worst_axis_sigma <= WorldEstimateConfig::default().target_sigma);
        assert!(fit.pairs < fit.candidates, "flipped frames are outliers");
    }

    #[test]
    fn a_pen_that_never_turns_gives_no_estimate() {
        // Vision axes all parallel: rotation about them is undetermined.
        let mut est = WorldEstimator::new(WorldEstimateConfig::default(), Default::default());
        let world = WorldReference::default();
        let still = [0.0, 0.0, 9.80665];
        for k in 0..4000u64 {
            let t_ns = k * 5_000_000;
            let mag = (Vector3::from(world.magnetic) * 47.0).into();
            est.imu(&ImuSample {
                t_ns,
                accel: still,
                gyro: [0.0; 3],
                mag,
            });
            if k % 7 == 0 {
                assert!(est.vision(t_ns, &Vector3::new(0.3, 0.2, 0.9)).is_none());
            }
        }
        assert!(est.fit().is_none());
        assert!(est.pair_count() > 100);
    }
}
