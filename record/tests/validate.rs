//! `meta.json` that parses but describes an impossible rig or pen is refused on load, naming the field.

mod common;
use common::test_meta;
use fires_record::*;
use std::fs;

fn meta() -> Meta {
    test_meta((64, 48), 0.06, &[FrameContent::Blobs], None, false)
}

/// Writes a valid recording, then replaces `meta.json` with `edit(meta)` and opens it.
fn open_edited(edit: impl FnOnce(&mut Meta)) -> Result<RecordingReader, RecordError> {
    let dir = tempfile::tempdir().unwrap();
    RecordingWriter::create(dir.path(), &meta())
        .unwrap()
        .finish()
        .unwrap();
    let mut m = meta();
    edit(&mut m);
    // JSON cannot hold NaN or infinity: serde_json writes them as null, which does not parse as f64, so
    // non-finite values are checked through Meta::validate directly below.
    fs::write(
        dir.path().join("meta.json"),
        serde_json::to_vec_pretty(&m).unwrap(),
    )
    .unwrap();
    RecordingReader::open(dir.path())
}

fn problem(edit: impl FnOnce(&mut Meta)) -> String {
    let mut m = meta();
    edit(&mut m);
    m.validate().expect_err("invalid").to_string()
}

#[test]
fn valid_meta_opens() {
    assert!(meta().validate().is_ok());
    assert!(open_edited(|_| {}).is_ok());
}

#[test]
fn negative_focal_length_is_refused_naming_the_field() {
    let err = open_edited(|m| m.rig.cameras[1].intrinsics.fx = -1.0)
        .expect_err("negative fx")
        .to_string();
    assert!(
        err.ends_with(
            "meta.json: rig.cameras[1].intrinsics.fx = -1.0: focal length must be positive"
        ),
        "{err}"
    );
    assert!(problem(|m| m.rig.cameras[0].intrinsics.fy = 0.0)
        .starts_with("rig.cameras[0].intrinsics.fy = 0.0"));
    assert!(problem(|m| m.rig.cameras[0].intrinsics.fx = f64::NAN).contains("focal length"));
}

#[test]
fn zero_baseline_is_refused() {
    let err = open_edited(|m| m.rig.cameras[1].extrinsics.translation_m = [0.0; 3])
        .expect_err("zero baseline")
        .to_string();
    assert!(
        err.contains("rig.cameras[1].extrinsics.translation_m = [0.0, 0.0, 0.0]"),
        "{err}"
    );
    assert!(err.contains("at least 0.01 m"), "{err}");
    // Just below and just above the minimum.
    assert!(
        problem(|m| m.rig.cameras[1].extrinsics.translation_m = [-0.0099, 0.0, 0.0])
            .contains("baseline")
    );
    let mut ok = meta();
    ok.rig.cameras[1].extrinsics.translation_m = [-0.0101, 0.0, 0.0];
    assert!(ok.validate().is_ok());
}

#[test]
fn rotations_must_be_proper_and_orthonormal() {
    // A reflection: orthonormal, determinant -1.
    let refl = problem(|m| m.rig.cameras[1].extrinsics.rotation[2][2] = -1.0);
    assert!(
        refl.contains("rig.cameras[1].extrinsics.rotation") && refl.contains("determinant"),
        "{refl}"
    );
    // A scaled matrix.
    let scaled = problem(|m| m.rig.cameras[1].extrinsics.rotation[0][0] = 1.0 + 1e-5);
    assert!(scaled.contains("not a rotation"), "{scaled}");
    // Within the tolerance: a rotation by 0.3 rad about y written with 9 significant digits.
    let mut ok = meta();
    let (s, c) = (0.3f64.sin(), 0.3f64.cos());
    let r = |v: f64| (v * 1e9).round() / 1e9;
    ok.rig.cameras[1].extrinsics.rotation =
        [[r(c), 0.0, r(s)], [0.0, 1.0, 0.0], [r(-s), 0.0, r(c)]];
    assert!(ok.validate().is_ok(), "{:?}", ok.validate());
}

#[test]
fn distortion_pen_streams_and_link_are_checked() {
    assert!(problem(|m| m.rig.cameras[0].intrinsics.k2 = f64::INFINITY)
        .starts_with("rig.cameras[0].intrinsics.k2 = inf: distortion"));
    assert!(
        problem(|m| m.pen.led_positions_m[2] = 0.05).starts_with("pen.led_positions_m[2] = 0.05")
    );
    assert!(problem(|m| m.pen.led_positions_m[0] = 0.01).starts_with("pen.led_positions_m[0]"));
    assert!(problem(|m| m.pen.tip_offset_m = -0.02).starts_with("pen.tip_offset_m = -0.02"));
    assert!(
        problem(|m| m.pen.imu_position_m = Some([-0.1, f64::NAN, 0.0]))
            .starts_with("pen.imu_position_m[1] = NaN")
    );
    assert!(problem(|m| m.cameras[0].id = 2).starts_with("cameras[0].id = 2"));
    assert!(
        problem(|m| m.cameras[0].nominal_rate_hz = 0.0).starts_with("cameras[0].nominal_rate_hz")
    );
    assert!(problem(|m| m.link.sample_rate_hz = 0).starts_with("link.sample_rate_hz = 0"));
    // The writer refuses to write what the reader would refuse.
    let dir = tempfile::tempdir().unwrap();
    let mut m = meta();
    m.rig.cameras[1].intrinsics.fx = -1.0;
    assert!(matches!(
        RecordingWriter::create(dir.path(), &m),
        Err(RecordError::InvalidMeta { .. })
    ));
}

#[test]
fn frame_timing_noise_is_a_standard_deviation_below_a_quarter_period() {
    // test_meta's cameras run at their nominal rate; a quarter of their period is the limit.
    let period = 1.0 / meta().cameras[0].nominal_rate_hz;
    let ok = open_edited(|m| {
        m.cameras[0].exposure_jitter_s = 0.0;
        m.cameras[0].timestamp_noise_s = 0.2 * period;
    });
    assert!(ok.is_ok());
    assert!(problem(|m| m.cameras[0].timestamp_noise_s = -1e-3)
        .starts_with("cameras[0].timestamp_noise_s = -0.001"));
    assert!(
        problem(|m| m.cameras[0].exposure_jitter_s = 0.3 * period).contains("quarter frame period")
    );
    assert!(problem(|m| m.cameras[0].timestamp_noise_s = f64::NAN).contains("standard deviation"));
    // Absent in a 1.1 file written before the fields existed: 0, stamps used as they are.
    let json = serde_json::to_string(&meta()).unwrap();
    let older = json
        .replace(",\"exposure_jitter_s\":0.0", "")
        .replace(",\"timestamp_noise_s\":0.0", "");
    assert!(!older.contains("timestamp_noise_s"));
    let back: Meta = serde_json::from_str(&older).unwrap();
    assert_eq!(back, meta());
}
