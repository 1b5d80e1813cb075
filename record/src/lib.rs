//! FIRES recordings (docs/architecture.md §4; the format is specified in `docs/recording.md`).
//!
//! A recording is a directory:
//! - `meta.json`: [`Meta`] (format version, rig calibration, pen geometry, board scale factors, camera streams);
//! - `link.bin`: the raw pen -> host bytes as received, records `[u64 LE host_time_ns][u32 LE len][len bytes]`;
//! - `cam{N}/frames.jsonl`: one [`CameraFrame`] per line; images (if any) as `cam{N}/{index:06}.pgm`,
//!   or Zstandard-compressed as `cam{N}/{index:06}.pgm.zst`;
//! - `truth/` (simulated recordings only): `imu.jsonl`, `exposures.jsonl`, `packets.jsonl`, `strokes.json`,
//!   `world.json`.
//!
//! [`RecordingWriter`] and [`RecordingReader`] are the only code that touches these files; the simulator, the
//! tracker and the CLI all go through them. Nothing here panics on malformed input: every failure is a
//! [`RecordError`] naming the file and the line or byte offset. [`RecordingReader::open_salvaging`] reads a
//! damaged recording (a writer killed mid-record, a lost frame image) as far as it is whole and reports what
//! it skipped as a [`Damage`].

pub mod damage;
pub mod error;
pub mod image;
pub mod meta;
pub mod reader;
pub mod report;
pub mod salvage;
pub mod strokes;
pub mod truth;
pub mod validate;
pub mod writer;

pub use damage::{Damage, DamageLog};
pub use error::RecordError;
pub use image::{EncodedImage, GrayImage, ImageEncoder};
pub use meta::{
    CalibratedCamera, CameraModel, CameraStream, Extrinsics, FrameContent, LinkInfo, Meta,
    PenGeometry, RigCalibration, Source, UndistortError, FORMAT_MAJOR, FORMAT_NAME, FORMAT_VERSION,
};
pub use reader::{FrameImage, RecordingReader};
pub use report::{
    NetworkReport, ReplayReport, Report, SurfaceReport, REPORT_FORMAT, REPORT_VERSION,
};
pub use strokes::{
    Stroke, StrokePiece, StrokePoint, StrokesError, StrokesFile, STROKES_FORMAT, STROKES_VERSION,
};
pub use truth::{
    ExposureTruth, ImuTruth, Interval, LedTruth, ObjectTruth, PacketFate, PacketTruth, PoseTruth,
    SceneTruth, StrokeKind, StrokeTruth, TargetTruth, Visibility, WorldTruth,
};
pub use validate::{MetaProblem, MIN_BASELINE_M};
pub use writer::{RecordingWriter, WriterOptions};

use serde::{Deserialize, Serialize};

/// Bytes received from the link in one read, with the host time of the read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LinkChunk {
    /// Host monotonic time at which the bytes were received, nanoseconds.
    pub host_time_ns: u64,
    /// The bytes, exactly as received.
    pub bytes: Vec<u8>,
}

/// Largest `link.bin` record the reader accepts (a sanity limit against corrupt length fields).
pub const MAX_LINK_RECORD: u32 = 1 << 24;

/// One bright spot reported by a camera (or a blob detector).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Blob {
    /// Centroid x, pixels (pixel centres at integers).
    pub x: f64,
    /// Centroid y, pixels.
    pub y: f64,
    /// Area in pixels (Wii-like cameras report a coarse size).
    pub area: f64,
    /// Brightness, 0..=255 (peak or mean, device dependent).
    pub intensity: f64,
}

/// One exposure of one camera (one line of `cam{N}/frames.jsonl`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CameraFrame {
    /// Camera id.
    pub camera: u8,
    /// Frame index, +1 per exposure from 0.
    pub index: u64,
    /// Reported mid-exposure time, host monotonic clock, nanoseconds.
    pub exposure_time_ns: u64,
    /// Blob list, for cameras that report blobs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blobs: Option<Vec<Blob>>,
    /// Image file name inside `cam{N}/`, for cameras that deliver images.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image: Option<String>,
}

/// File name of frame `index`'s image.
pub fn image_file_name(index: u64) -> String {
    format!("{index:06}.pgm")
}

/// File name of frame `index`'s image stored compressed (a PGM inside a Zstandard frame; `zstd -d` restores it).
pub fn compressed_image_file_name(index: u64) -> String {
    format!("{index:06}.pgm{}", image::ZSTD_SUFFIX)
}

/// Directory name of camera `id`.
pub fn camera_dir_name(id: u8) -> String {
    format!("cam{id}")
}
