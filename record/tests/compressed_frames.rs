//! Zstandard-compressed frame images (`.pgm.zst`): exact round trip, a real size gain on a dark sensor-noise
//! frame, typed errors for damaged files, and no decompression beyond the calibrated size.

mod common;

use common::test_meta;
use fires_record::*;
use std::fs;
use std::path::Path;

const W: u32 = 64;
const H: u32 = 48;

/// A dark frame with one-DN noise on a fraction of the pixels and one bright spot, as an IR webcam sees it.
fn dark_frame() -> GrayImage {
    let mut img = GrayImage::new(W, H);
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    for (i, p) in img.data.iter_mut().enumerate() {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        *p = match state % 40 {
            0 => 1,
            1 => 3,
            _ => 2,
        };
        let (x, y) = ((i as u32 % W) as f64, (i as u32 / W) as f64);
        let d2 = (x - 20.0).powi(2) + (y - 30.0).powi(2);
        *p = p.saturating_add((300.0 * (-d2 / 8.0).exp()).min(250.0) as u8);
    }
    img
}

fn write(dir: &Path, compress: bool, img: &GrayImage) -> CameraFrame {
    let meta = test_meta((W, H), 0.1, &[FrameContent::Images], None, false);
    let options = WriterOptions {
        compress_images: compress,
        ..WriterOptions::buffered()
    };
    let mut w = RecordingWriter::create_with(dir, &meta, options).unwrap();
    let frame = CameraFrame {
        camera: 0,
        index: 7,
        exposure_time_ns: 1_000,
        blobs: None,
        image: None,
    };
    w.write_frame(&frame, Some(img)).unwrap();
    w.finish().unwrap();
    RecordingReader::open(dir).unwrap().frames(0).unwrap()[0].clone()
}

#[test]
fn compressed_frames_read_back_exactly_and_are_smaller() {
    let img = dark_frame();
    let plain_dir = tempfile::tempdir().unwrap();
    let zst_dir = tempfile::tempdir().unwrap();
    let plain = write(plain_dir.path(), false, &img);
    let zst = write(zst_dir.path(), true, &img);
    assert_eq!(plain.image.as_deref(), Some("000007.pgm"));
    assert_eq!(zst.image.as_deref(), Some("000007.pgm.zst"));
    let r = RecordingReader::open(zst_dir.path()).unwrap();
    assert_eq!(r.image(&zst).unwrap(), Some(img.clone()));
    let size = |d: &Path, f: &CameraFrame| {
        fs::metadata(d.join("cam0").join(f.image.as_ref().unwrap()))
            .unwrap()
            .len()
    };
    let (p, z) = (size(plain_dir.path(), &plain), size(zst_dir.path(), &zst));
    assert!(z * 3 < p, "compressed {z} bytes against {p} plain");
    // The bytes are a standard Zstandard frame holding the plain PGM.
    let stored = fs::read(zst_dir.path().join("cam0/000007.pgm.zst")).unwrap();
    assert_eq!(zstd::decode_all(stored.as_slice()).unwrap(), img.to_pgm());
}

#[test]
fn a_damaged_compressed_frame_is_a_typed_error_or_a_counted_loss() {
    let img = dark_frame();
    let dir = tempfile::tempdir().unwrap();
    let frame = write(dir.path(), true, &img);
    let path = dir.path().join("cam0/000007.pgm.zst");
    let bytes = fs::read(&path).unwrap();
    fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
    let strict = RecordingReader::open(dir.path()).unwrap();
    match strict.image(&frame) {
        Err(RecordError::BadImage { path: p, reason }) => {
            assert_eq!(p, path);
            assert!(reason.contains("Zstandard"), "{reason}");
        }
        other => panic!("expected BadImage, got {other:?}"),
    }
    let salvaging = RecordingReader::open_salvaging(dir.path()).unwrap();
    assert!(matches!(
        salvaging.frame_image(&frame),
        Ok(FrameImage::Lost)
    ));
    assert_eq!(salvaging.damage().frames_unreadable, 1);
}

#[test]
fn a_compressed_frame_larger_than_the_calibration_is_not_decompressed() {
    let dir = tempfile::tempdir().unwrap();
    let frame = write(dir.path(), true, &dark_frame());
    // A valid Zstandard frame of a 4096 x 4096 PGM: 16 MB once decompressed, a few KB stored.
    let huge = GrayImage::new(4096, 4096);
    fs::write(
        dir.path().join("cam0/000007.pgm.zst"),
        huge.to_pgm_zst().unwrap(),
    )
    .unwrap();
    let r = RecordingReader::open(dir.path()).unwrap();
    assert!(matches!(r.image(&frame), Err(RecordError::BadImage { .. })));
}
