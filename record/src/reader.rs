//! Reads a recording directory.

use crate::damage::{Damage, DamageLog, FrameLoss, StreamDamage};
use crate::error::RecordError;
use crate::image::GrayImage;
use crate::meta::{Meta, FORMAT_MAJOR, FORMAT_NAME};
use crate::salvage::{scan_jsonl, scan_link, LinkProblem};
use crate::truth::{ExposureTruth, ImuTruth, PacketTruth, StrokeTruth, WorldTruth};
use crate::{camera_dir_name, CameraFrame, LinkChunk, MAX_LINK_RECORD};
use serde::de::DeserializeOwned;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, PoisonError};

/// An open recording: the metadata is read and checked; streams are read on demand.
///
/// A reader opened with [`RecordingReader::open`] is strict: any damage is an error. One opened with
/// [`RecordingReader::open_salvaging`] keeps what is whole (torn last records dropped, corrupt records skipped,
/// missing or unreadable frame images reported as [`FrameImage::Lost`]) and logs what it skipped; see
/// [`RecordingReader::damage`]. Clones share the log.
#[derive(Clone, Debug)]
pub struct RecordingReader {
    dir: PathBuf,
    meta: Meta,
    salvage: Option<Arc<Mutex<DamageLog>>>,
}

/// The image of one frame, as a salvaging reader sees it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FrameImage {
    /// The frame names no image (a blob camera).
    NoImage,
    /// The image.
    Image(GrayImage),
    /// The frame names an image that is missing or unreadable (logged; only a salvaging reader returns this).
    Lost,
}

/// Most pixels a compressed frame may hold when its camera has no calibration (a 16-megapixel sensor).
const MAX_IMAGE_PIXELS: usize = 1 << 24;

fn read_file(path: &Path) -> Result<Vec<u8>, RecordError> {
    fs::read(path).map_err(|e| RecordError::io(path, e))
}

fn read_json<T: DeserializeOwned>(path: &Path) -> Result<T, RecordError> {
    parse_json(&read_file(path)?, path)
}

fn read_jsonl<T: DeserializeOwned>(path: &Path) -> Result<Vec<T>, RecordError> {
    parse_jsonl(&read_file(path)?, path)
}

/// Parses a whole-file JSON document (`meta.json`, `truth/strokes.json`, `truth/world.json`); `path` names the
/// source in errors.
pub fn parse_json<T: DeserializeOwned>(bytes: &[u8], path: &Path) -> Result<T, RecordError> {
    serde_json::from_slice(bytes).map_err(|e| RecordError::Json {
        path: path.to_path_buf(),
        line: e.line(),
        cause: e,
    })
}

fn plain_image_name(name: &str) -> bool {
    !name.is_empty() && !name.contains(['/', '\\']) && name != "." && name != ".."
}

/// Parses a JSON-lines file (one value per line, blank lines ignored: `frames.jsonl`, `truth/*.jsonl`); `path`
/// names the source in errors.
pub fn parse_jsonl<T: DeserializeOwned>(bytes: &[u8], path: &Path) -> Result<Vec<T>, RecordError> {
    let mut out = Vec::new();
    for (i, line) in bytes.split(|&b| b == b'\n').enumerate() {
        if line.iter().all(u8::is_ascii_whitespace) {
            continue;
        }
        let v = serde_json::from_slice(line).map_err(|e| RecordError::Json {
            path: path.to_path_buf(),
            line: i + 1,
            cause: e,
        })?;
        out.push(v);
    }
    Ok(out)
}

/// Parses `meta.json` bytes, checks the format name and major version and validates the calibration and pen
/// (docs/recording.md, "Validation"); `path` names the source in errors.
pub fn parse_meta(bytes: &[u8], path: &Path) -> Result<Meta, RecordError> {
    let meta: Meta = parse_json(bytes, path)?;
    check_version(&meta, path)?;
    meta.validate().map_err(|e| RecordError::InvalidMeta {
        path: path.to_path_buf(),
        problem: e,
    })?;
    Ok(meta)
}

/// Parses a camera's `frames.jsonl` bytes and checks that every image name is a plain file name; `path` names
/// the source in errors.
pub fn parse_frames(bytes: &[u8], path: &Path) -> Result<Vec<CameraFrame>, RecordError> {
    let frames: Vec<CameraFrame> = parse_jsonl(bytes, path)?;
    for (i, f) in frames.iter().enumerate() {
        if let Some(name) = &f.image {
            if !plain_image_name(name) {
                return Err(RecordError::BadImageName {
                    path: path.to_path_buf(),
                    line: i + 1,
                    name: name.clone(),
                });
            }
        }
    }
    Ok(frames)
}

/// Parses `link.bin` bytes strictly: the first record that is not whole is an error; `path` names the source.
pub fn parse_link(bytes: &[u8], path: &Path) -> Result<Vec<LinkChunk>, RecordError> {
    let scan = scan_link(bytes);
    match scan.first_problem {
        None => Ok(scan.chunks),
        Some((offset, problem)) => Err(link_error(path, offset, problem)),
    }
}

fn link_error(path: &Path, offset: u64, problem: LinkProblem) -> RecordError {
    let path = path.to_path_buf();
    match problem {
        LinkProblem::Truncated => RecordError::LinkTruncated { path, offset },
        LinkProblem::TooLong(len) => RecordError::LinkRecordTooLong {
            path,
            offset,
            len,
            limit: MAX_LINK_RECORD,
        },
        LinkProblem::BadTime {
            time_ns,
            previous_ns,
        } => RecordError::LinkTimeOutOfOrder {
            path,
            offset,
            time_ns,
            previous_ns,
        },
    }
}

/// Checks `format` and `format_version` of a metadata record.
pub fn check_version(meta: &Meta, path: &Path) -> Result<(), RecordError> {
    if meta.format != FORMAT_NAME {
        return Err(RecordError::NotARecording {
            path: path.to_path_buf(),
            found: meta.format.clone(),
        });
    }
    let major = meta
        .format_version
        .split_once('.')
        .filter(|(_, minor)| !minor.is_empty() && minor.bytes().all(|b| b.is_ascii_digit()))
        .and_then(|(major, _)| major.parse::<u32>().ok());
    if major != Some(FORMAT_MAJOR) {
        return Err(RecordError::UnsupportedVersion {
            path: path.to_path_buf(),
            found: meta.format_version.clone(),
            supported_major: FORMAT_MAJOR,
        });
    }
    Ok(())
}

impl RecordingReader {
    /// Opens a recording strictly: reads `meta.json`, checks its format name and major version and validates
    /// the calibration and pen geometry ([`Meta::validate`]); every later read fails on any damage.
    pub fn open(dir: &Path) -> Result<Self, RecordError> {
        let path = dir.join("meta.json");
        let meta = parse_meta(&read_file(&path)?, &path)?;
        Ok(RecordingReader {
            dir: dir.to_path_buf(),
            meta,
            salvage: None,
        })
    }

    /// Opens a recording like [`RecordingReader::open`] (a bad `meta.json` is still an error), but later reads
    /// keep what is whole and log the rest instead of failing (docs/recording.md, "Damaged recordings").
    pub fn open_salvaging(dir: &Path) -> Result<Self, RecordError> {
        let mut r = Self::open(dir)?;
        r.salvage = Some(Arc::new(Mutex::new(DamageLog::default())));
        Ok(r)
    }

    /// Whether this reader salvages damaged streams instead of failing.
    pub fn is_salvaging(&self) -> bool {
        self.salvage.is_some()
    }

    /// What the reads so far skipped (always clean for a strict reader).
    pub fn damage(&self) -> Damage {
        self.salvage.as_ref().map_or_else(Damage::default, |log| {
            log.lock().unwrap_or_else(PoisonError::into_inner).summary()
        })
    }

    fn log(&self, f: impl FnOnce(&mut DamageLog)) {
        if let Some(log) = &self.salvage {
            f(&mut log.lock().unwrap_or_else(PoisonError::into_inner));
        }
    }

    /// The recording directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The metadata.
    pub fn meta(&self) -> &Meta {
        &self.meta
    }

    /// Reads a whole file; when salvaging, a file that cannot be read is logged as lost and gives `None`.
    fn read_or_lose(&self, rel: &str) -> Result<Option<Vec<u8>>, RecordError> {
        let path = self.dir.join(rel);
        match fs::read(&path) {
            Ok(b) => {
                self.log(|l| l.set_lost_file(rel, None));
                Ok(Some(b))
            }
            Err(e) if self.is_salvaging() => {
                self.log(|l| l.set_lost_file(rel, Some(e.to_string())));
                Ok(None)
            }
            Err(e) => Err(RecordError::io(path, e)),
        }
    }

    /// A `.jsonl` stream: strict, or salvaged (`None` when the file is lost).
    fn jsonl<T: DeserializeOwned>(
        &self,
        rel: &str,
        check: impl Fn(&T) -> Result<(), String>,
    ) -> Result<Option<Vec<T>>, RecordError> {
        if !self.is_salvaging() {
            return read_jsonl(&self.dir.join(rel)).map(Some);
        }
        let Some(bytes) = self.read_or_lose(rel)? else {
            self.log(|l| l.set_stream(rel, StreamDamage::default()));
            return Ok(None);
        };
        let (v, damage) = scan_jsonl(&bytes, check);
        self.log(|l| l.set_stream(rel, damage));
        Ok(Some(v))
    }

    /// A whole-file JSON document: strict, or salvaged (`None` when the file is missing or does not parse).
    fn json<T: DeserializeOwned>(&self, rel: &str) -> Result<Option<T>, RecordError> {
        let path = self.dir.join(rel);
        if !self.is_salvaging() {
            return read_json(&path).map(Some);
        }
        let Some(bytes) = self.read_or_lose(rel)? else {
            return Ok(None);
        };
        match serde_json::from_slice(&bytes) {
            Ok(v) => Ok(Some(v)),
            Err(e) => {
                self.log(|l| l.set_lost_file(rel, Some(e.to_string())));
                Ok(None)
            }
        }
    }

    /// All link records in file order (when salvaging: the whole ones; a lost `link.bin` reads as empty).
    pub fn link_chunks(&self) -> Result<Vec<LinkChunk>, RecordError> {
        let path = self.dir.join("link.bin");
        if !self.is_salvaging() {
            return parse_link(&read_file(&path)?, &path);
        }
        let Some(bytes) = self.read_or_lose("link.bin")? else {
            return Ok(Vec::new());
        };
        let scan = scan_link(&bytes);
        self.log(|l| l.set_stream("link.bin", scan.damage));
        Ok(scan.chunks)
    }

    /// All frames of camera `camera`, in file order (when salvaging: the lines that parse; a lost
    /// `frames.jsonl` reads as empty).
    pub fn frames(&self, camera: u8) -> Result<Vec<CameraFrame>, RecordError> {
        if !self.meta.cameras.iter().any(|c| c.id == camera) {
            return Err(RecordError::UnknownCamera { camera });
        }
        let rel = format!("{}/frames.jsonl", camera_dir_name(camera));
        if self.is_salvaging() {
            let check = |f: &CameraFrame| match &f.image {
                Some(name) if !plain_image_name(name) => {
                    Err(format!("image name {name:?} must be a plain file name"))
                }
                _ => Ok(()),
            };
            return Ok(self.jsonl(&rel, check)?.unwrap_or_default());
        }
        let path = self.dir.join(&rel);
        parse_frames(&read_file(&path)?, &path)
    }

    /// Reads the image of a frame (`None` if the frame has no image); a missing or bad image is an error, also
    /// when salvaging (see [`RecordingReader::frame_image`]).
    pub fn image(&self, frame: &CameraFrame) -> Result<Option<GrayImage>, RecordError> {
        let Some(name) = &frame.image else {
            return Ok(None);
        };
        if !plain_image_name(name) {
            return Err(RecordError::BadImageName {
                path: self.dir.join(camera_dir_name(frame.camera)),
                line: 0,
                name: name.clone(),
            });
        }
        let path = self.dir.join(camera_dir_name(frame.camera)).join(name);
        let calibrated = self.meta.rig.cameras.get(frame.camera as usize);
        let max_pixels = calibrated.map_or(MAX_IMAGE_PIXELS, |c| {
            c.intrinsics.width as usize * c.intrinsics.height as usize
        });
        let img = GrayImage::from_stored(&read_file(&path)?, &path, max_pixels)?;
        if let Some(cam) = calibrated {
            if (img.width, img.height) != (cam.intrinsics.width, cam.intrinsics.height) {
                return Err(RecordError::BadImage {
                    path,
                    reason: format!(
                        "{}x{} image, calibration says {}x{}",
                        img.width, img.height, cam.intrinsics.width, cam.intrinsics.height
                    ),
                });
            }
        }
        Ok(Some(img))
    }

    /// Reads the image of a frame. Strict: as [`RecordingReader::image`]. Salvaging: a missing or unreadable
    /// image is logged (counted as missing or unreadable) and returned as [`FrameImage::Lost`].
    pub fn frame_image(&self, frame: &CameraFrame) -> Result<FrameImage, RecordError> {
        let key = (frame.camera, frame.index);
        match self.image(frame) {
            Ok(img) => {
                self.log(|l| l.set_frame(key, None));
                Ok(img.map_or(FrameImage::NoImage, FrameImage::Image))
            }
            Err(e) if self.is_salvaging() => {
                let missing = matches!(&e, RecordError::Io { cause, .. }
                    if cause.kind() == std::io::ErrorKind::NotFound);
                let (loss, why) = if missing {
                    (FrameLoss::Missing, "missing".to_string())
                } else {
                    (FrameLoss::Unreadable, unreadable_reason(&e))
                };
                let file = format!(
                    "{}/{}",
                    camera_dir_name(frame.camera),
                    frame.image.as_deref().unwrap_or_default()
                );
                self.log(|l| l.set_frame(key, Some((file, loss, why))));
                Ok(FrameImage::Lost)
            }
            Err(e) => Err(e),
        }
    }

    /// Whether the recording has ground truth.
    pub fn has_truth(&self) -> bool {
        self.meta.has_truth
    }

    fn truth_jsonl<T: DeserializeOwned>(&self, name: &str) -> Result<Option<Vec<T>>, RecordError> {
        if !self.meta.has_truth {
            return Ok(None);
        }
        self.jsonl(&format!("truth/{name}"), |_| Ok(()))
    }

    fn truth_json<T: DeserializeOwned>(&self, name: &str) -> Result<Option<T>, RecordError> {
        if !self.meta.has_truth {
            return Ok(None);
        }
        self.json(&format!("truth/{name}"))
    }

    /// Ground truth at every IMU sample (`None` without ground truth, or when salvaging a lost file).
    pub fn imu_truth(&self) -> Result<Option<Vec<ImuTruth>>, RecordError> {
        self.truth_jsonl("imu.jsonl")
    }

    /// Ground truth at every exposure of every camera.
    pub fn exposure_truth(&self) -> Result<Option<Vec<ExposureTruth>>, RecordError> {
        self.truth_jsonl("exposures.jsonl")
    }

    /// Every packet the pen produced and its fate.
    pub fn packet_truth(&self) -> Result<Option<Vec<PacketTruth>>, RecordError> {
        self.truth_jsonl("packets.jsonl")
    }

    /// Stroke segmentation.
    pub fn strokes(&self) -> Result<Option<Vec<StrokeTruth>>, RecordError> {
        self.truth_json("strokes.json")
    }

    /// Session-wide physical constants.
    pub fn world_truth(&self) -> Result<Option<WorldTruth>, RecordError> {
        self.truth_json("world.json")
    }
}

/// The error's message without the path (the damage log names the file already).
fn unreadable_reason(e: &RecordError) -> String {
    match e {
        RecordError::Io { cause, .. } => cause.to_string(),
        RecordError::BadImage { reason, .. } => reason.clone(),
        other => other.to_string(),
    }
}
