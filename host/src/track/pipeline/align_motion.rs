//! How the pen's motion moves its blobs, for the time alignment (`pipeline/align.rs`): the turn
//! the gyro measures, the acceleration the IMU measures, and the rigid pen's translation that
//! the LEDs with measured velocities share with one that has none.

use super::{KeptFrame, TimeAlignment, IMU_MOVE_MIN_INTERVAL_NS};
use crate::stereo::{CameraId, StereoRig};
use crate::track::pen::LED_COUNT;
use nalgebra::Vector3;

impl TimeAlignment {
    /// The image displacement of LED `k`'s blob in `frame` that the tip's measured acceleration
    /// adds to moving it from `t1` by `s` (ns) at its mean velocity since `t0` (`mv = (t0, t1,
    /// s)`, [`AccelHistory::move_part`](super::AccelHistory::move_part)), less the constant-acceleration move of the image
    /// acceleration those samples give over the blob's three frames (`frames`, ns); through the
    /// projection at the frame's pen guess. None without a guess or samples covering them, and
    /// for cameras faster than [`IMU_MOVE_MIN_INTERVAL_NS`].
    pub(super) fn imu_move_px(
        &self,
        rig: &StereoRig,
        camera: CameraId,
        frame: &KeptFrame,
        k: usize,
        (t0, t1, s): (f64, f64, f64),
        frames: (f64, f64, f64),
    ) -> Option<[f64; 2]> {
        let g = frame.guess?;
        if t1 - t0 < IMU_MOVE_MIN_INTERVAL_NS {
            return None;
        }
        let dv = self
            .accel
            .mean_velocity_change(frames.0, frames.1, frames.2)?;
        let seen = dv / (0.5 * (frames.2 - frames.0) * 1e-9);
        let m = self.accel.move_part(t0, t1, s)? - seen * (0.5 * s * (t1 - t0 + s) * 1e-18);
        let pen = &self.options.pen;
        let led = g.tip - g.direction() * (pen.led_offsets[k] + pen.tip_offset);
        let (a, b) = (
            rig.project(camera, &led).ok()?,
            rig.project(camera, &(led + m)).ok()?,
        );
        Some([b[0] - a[0], b[1] - a[1]])
    }

    /// The image motion of LED `k` in `frame` (of `camera`) from `t0` to `t1` (ns) that the pen's
    /// turn about its tip causes: the frame's guess turned by the gyro's rates, the tip held where
    /// vision last saw it. None without a guess or gyro samples covering the times.
    pub(super) fn turn_px(
        &self,
        rig: &StereoRig,
        camera: CameraId,
        frame: &KeptFrame,
        k: usize,
        t0: f64,
        t1: f64,
    ) -> Option<[f64; 2]> {
        let g = frame.guess?;
        let pen = &self.options.pen;
        let lever = pen.led_offsets[k] + pen.tip_offset;
        let at = |tt: f64| {
            let r = self.gyro.rotation(frame.t_ns as f64, tt)?;
            let d = g.orientation * r * Vector3::x();
            rig.project(camera, &(g.tip - d * lever)).ok()
        };
        let (a, b) = (at(t0)?, at(t1)?);
        Some([b[0] - a[0], b[1] - a[1]])
    }
}

/// The image velocity of the pen's translation that one LED's blobs measured: the motion the
/// pen's turn does not explain ([`TimeAlignment::alignment`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct MeasuredTranslation {
    /// The LED (index 0 = LED 1).
    pub(super) led: usize,
    /// Image velocity, pixels per nanosecond.
    pub(super) velocity: [f64; 2],
    /// The error of moving the LED's blob with it, pixels.
    pub(super) error_px: f64,
}

/// The image velocity (px/ns) of the pen's translation at LED `k` from the LEDs that measured
/// theirs: a least-squares line in the LEDs' axial offsets through two or more (a translation's
/// image velocity changes smoothly with depth along the pen), their one velocity otherwise;
/// None without any.
pub(super) fn rigid_translation(
    measured: &[MeasuredTranslation],
    offsets: &[f64; LED_COUNT],
    k: usize,
) -> Option<[f64; 2]> {
    if measured.is_empty() {
        return None;
    }
    let n = measured.len() as f64;
    let s_mean = measured.iter().map(|m| offsets[m.led]).sum::<f64>() / n;
    let var: f64 = measured
        .iter()
        .map(|m| (offsets[m.led] - s_mean).powi(2))
        .sum();
    Some(std::array::from_fn(|axis| {
        let v_mean = measured.iter().map(|m| m.velocity[axis]).sum::<f64>() / n;
        if var <= 1e-12 {
            return v_mean;
        }
        let cov: f64 = measured
            .iter()
            .map(|m| (offsets[m.led] - s_mean) * (m.velocity[axis] - v_mean))
            .sum();
        v_mean + cov / var * (offsets[k] - s_mean)
    }))
}
