//! The metadata the recording tests write: a small two-camera rig, the default pen, and the given streams.

use fires_record::*;

/// A rig of two `width` x `height` cameras `baseline_m` apart, the default pen, and one camera stream per
/// entry of `streams` (ids 0, 1, ...), seeded with `seed`.
pub fn test_meta(
    (width, height): (u32, u32),
    baseline_m: f64,
    streams: &[FrameContent],
    seed: Option<u64>,
    has_truth: bool,
) -> Meta {
    let cam = CalibratedCamera {
        intrinsics: CameraModel::from_hfov(width, height, 1.0),
        extrinsics: Extrinsics::IDENTITY,
    };
    let mut right = cam;
    right.extrinsics.translation_m = [-baseline_m, 0.0, 0.0];
    Meta::new(
        Source {
            kind: "test".into(),
            scenario: None,
            seed,
            generator: None,
        },
        RigCalibration {
            cameras: vec![cam, right],
        },
        PenGeometry::fires_default(),
        streams
            .iter()
            .enumerate()
            .map(|(id, &provides)| CameraStream::global(id as u8, provides, 15.0))
            .collect(),
        has_truth,
    )
}
