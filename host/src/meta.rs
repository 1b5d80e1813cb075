//! From a recording's metadata (docs/recording.md) to the tracker's types: the stereo rig, the pen, the IMU scale.
//! Replay and live tracking both start here.

use fires_record::Meta;
use nalgebra::{Matrix3, Vector3};

use crate::stereo::StereoRig;
use crate::track::frame_clock::FrameTiming;
use crate::track::fusion::ImuScale;
use crate::track::PenGeometry;

/// Why a recording's metadata cannot drive the tracker.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MetaError {
    /// The rig needs exactly two cameras.
    #[error("the rig has {0} camera(s); stereo tracking needs 2")]
    CameraCount(usize),
    /// The tracker is built for the four-LED pen.
    #[error("the pen has {0} LED(s); the tracker needs 4 (two-LED bars are measured separately)")]
    LedCount(usize),
    /// The pen's LED distances cannot be told apart by the identification.
    #[error("meta.json: pen.led_positions_m = {positions}: {reason}")]
    PenNotIdentifiable {
        /// The LED positions found.
        positions: String,
        /// What is wrong with them.
        reason: String,
    },
}

/// The stereo rig of a recording; camera 0 (left) defines the world frame.
pub fn stereo_rig(meta: &Meta) -> Result<StereoRig, MetaError> {
    let [left, right] = meta.rig.cameras.as_slice() else {
        return Err(MetaError::CameraCount(meta.rig.cameras.len()));
    };
    // Camera 0 may itself sit at a pose in the world; the tracker works in the left camera's frame.
    let (rl, tl) = (
        mat(&left.extrinsics.rotation),
        Vector3::from(left.extrinsics.translation_m),
    );
    let (rr, tr) = (
        mat(&right.extrinsics.rotation),
        Vector3::from(right.extrinsics.translation_m),
    );
    let r = rr * rl.transpose();
    let t = tr - r * tl;
    Ok(StereoRig::new(left.intrinsics, right.intrinsics, r, t))
}

/// The rolling-shutter delay of one pixel row of each camera (left, right), nanoseconds: the stream's
/// `readout_s` over its calibrated height (0 for a global shutter or a camera the metadata does not describe).
pub fn row_times_ns(meta: &Meta) -> [f64; 2] {
    std::array::from_fn(|i| {
        let stream = meta.cameras.iter().find(|c| usize::from(c.id) == i);
        let height = meta.rig.cameras.get(i).map_or(0, |c| c.intrinsics.height);
        stream.map_or(0.0, |s| s.row_period_s(height) * 1e9)
    })
}

/// How each camera's frames are timed (left, right), from the metadata's nominal rates and timing noise
/// (the default, stamps used as they are, for a camera the metadata does not describe).
pub fn frame_timings(meta: &Meta) -> [FrameTiming; 2] {
    std::array::from_fn(|i| {
        meta.cameras
            .iter()
            .find(|c| usize::from(c.id) == i)
            .map_or(FrameTiming::default(), |s| FrameTiming {
                period_ns: 1e9 / s.nominal_rate_hz,
                exposure_jitter_ns: s.exposure_jitter_s * 1e9,
                stamp_noise_ns: s.timestamp_noise_s * 1e9,
            })
    })
}

/// World -> left-camera transform of the recording (identity when camera 0 defines the world).
pub fn world_to_left(meta: &Meta) -> Option<(Matrix3<f64>, Vector3<f64>)> {
    let left = meta.rig.cameras.first()?;
    Some((
        mat(&left.extrinsics.rotation),
        Vector3::from(left.extrinsics.translation_m),
    ))
}

fn mat(r: &[[f64; 3]; 3]) -> Matrix3<f64> {
    Matrix3::from_row_slice(&[
        r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2],
    ])
}

/// The pen of a recording.
pub fn pen_geometry(meta: &Meta) -> Result<PenGeometry, MetaError> {
    let l = &meta.pen.led_positions_m;
    let [a, b, c, d] = l.as_slice() else {
        return Err(MetaError::LedCount(l.len()));
    };
    Ok(PenGeometry {
        led_offsets: [*a, *b, *c, *d],
        tip_offset: meta.pen.tip_offset_m,
    })
}

/// The pen of a recording, checked with [`PenGeometry::validate`] at the identification's distance tolerance
/// `tolerance` ([`crate::track::identify::IdentifyConfig::tolerance`]): no two of its six LED distances may be
/// closer than `2 * tolerance`.
pub fn checked_pen_geometry(meta: &Meta, tolerance: f64) -> Result<PenGeometry, MetaError> {
    let pen = pen_geometry(meta)?;
    pen.validate(tolerance)
        .map_err(|e| MetaError::PenNotIdentifiable {
            positions: format!("{:?}", meta.pen.led_positions_m),
            reason: format!(
                "{e} ({tolerance} m, the identification's distance tolerance): it could not tell them apart"
            ),
        })?;
    Ok(pen)
}

/// The tip's position relative to the accelerometer in the pen frame, metres (the tracker's
/// [`crate::track::pipeline::TrackerConfig::imu_to_tip`]), when the recording places the accelerometer.
pub fn imu_to_tip(meta: &Meta) -> Option<[f64; 3]> {
    meta.pen.imu_position_m.map(|p| p.map(|v| -v))
}

/// Count -> SI conversion from the board's scale factors (magnetometer in µT, the fusion's unit).
pub fn imu_scale(meta: &Meta) -> ImuScale {
    let s = &meta.scale_factors;
    ImuScale {
        accel_per_count: s.accel_mps2_per_count,
        gyro_per_count: s.gyro_radps_per_count,
        mag_per_count: s.mag_tesla_per_count * 1e6,
        ..ImuScale::default()
    }
}
