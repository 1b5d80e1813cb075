//! Reads a recording directory.

use crate::error::RecordError;
use crate::image::GrayImage;
use crate::meta::{Meta, FORMAT_MAJOR, FORMAT_NAME};
use crate::truth::{ExposureTruth, ImuTruth, PacketTruth, StrokeTruth, WorldTruth};
use crate::{camera_dir_name, CameraFrame, LinkChunk, MAX_LINK_RECORD};
use serde::de::DeserializeOwned;
use std::fs;
use std::path::{Path, PathBuf};

/// An open recording: the metadata is read and checked; streams are read on demand.
#[derive(Clone, Debug)]
pub struct RecordingReader {
    dir: PathBuf,
    meta: Meta,
}

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

/// Parses `meta.json` bytes and checks the format name and major version; `path` names the source in errors.
pub fn parse_meta(bytes: &[u8], path: &Path) -> Result<Meta, RecordError> {
    let meta: Meta = parse_json(bytes, path)?;
    check_version(&meta, path)?;
    Ok(meta)
}

/// Parses a camera's `frames.jsonl` bytes and checks that every image name is a plain file name; `path` names
/// the source in errors.
pub fn parse_frames(bytes: &[u8], path: &Path) -> Result<Vec<CameraFrame>, RecordError> {
    let frames: Vec<CameraFrame> = parse_jsonl(bytes, path)?;
    for (i, f) in frames.iter().enumerate() {
        if let Some(name) = &f.image {
            let plain =
                !name.is_empty() && !name.contains(['/', '\\']) && name != "." && name != "..";
            if !plain {
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

/// Parses `link.bin` bytes; `path` names the source in errors.
pub fn parse_link(bytes: &[u8], path: &Path) -> Result<Vec<LinkChunk>, RecordError> {
    let mut out = Vec::new();
    let mut pos = 0usize;
    while pos < bytes.len() {
        let truncated = || RecordError::LinkTruncated {
            path: path.to_path_buf(),
            offset: pos as u64,
        };
        let head = bytes.get(pos..pos + 12).ok_or_else(truncated)?;
        let mut t = [0u8; 8];
        t.copy_from_slice(&head[..8]);
        let mut l = [0u8; 4];
        l.copy_from_slice(&head[8..12]);
        let len = u32::from_le_bytes(l);
        if len > MAX_LINK_RECORD {
            return Err(RecordError::LinkRecordTooLong {
                path: path.to_path_buf(),
                offset: pos as u64,
                len,
                limit: MAX_LINK_RECORD,
            });
        }
        let body = bytes
            .get(pos + 12..pos + 12 + len as usize)
            .ok_or_else(truncated)?;
        out.push(LinkChunk {
            host_time_ns: u64::from_le_bytes(t),
            bytes: body.to_vec(),
        });
        pos += 12 + len as usize;
    }
    Ok(out)
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
    /// Opens a recording: reads `meta.json` and checks its format name and major version.
    pub fn open(dir: &Path) -> Result<Self, RecordError> {
        let path = dir.join("meta.json");
        let meta = parse_meta(&read_file(&path)?, &path)?;
        Ok(RecordingReader {
            dir: dir.to_path_buf(),
            meta,
        })
    }

    /// The recording directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The metadata.
    pub fn meta(&self) -> &Meta {
        &self.meta
    }

    /// All link records in file order.
    pub fn link_chunks(&self) -> Result<Vec<LinkChunk>, RecordError> {
        let path = self.dir.join("link.bin");
        parse_link(&read_file(&path)?, &path)
    }

    /// All frames of camera `camera`, in file order.
    pub fn frames(&self, camera: u8) -> Result<Vec<CameraFrame>, RecordError> {
        if !self.meta.cameras.iter().any(|c| c.id == camera) {
            return Err(RecordError::UnknownCamera { camera });
        }
        let path = self.dir.join(camera_dir_name(camera)).join("frames.jsonl");
        parse_frames(&read_file(&path)?, &path)
    }

    /// Reads the image of a frame (`None` if the frame has no image).
    pub fn image(&self, frame: &CameraFrame) -> Result<Option<GrayImage>, RecordError> {
        let Some(name) = &frame.image else {
            return Ok(None);
        };
        if name.contains(['/', '\\']) || name == ".." {
            return Err(RecordError::BadImageName {
                path: self.dir.join(camera_dir_name(frame.camera)),
                line: 0,
                name: name.clone(),
            });
        }
        let path = self.dir.join(camera_dir_name(frame.camera)).join(name);
        let img = GrayImage::from_pgm(&read_file(&path)?, &path)?;
        if let Some(cam) = self.meta.rig.cameras.get(frame.camera as usize) {
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

    /// Whether the recording has ground truth.
    pub fn has_truth(&self) -> bool {
        self.meta.has_truth
    }

    fn truth_path(&self, name: &str) -> Option<PathBuf> {
        self.meta
            .has_truth
            .then(|| self.dir.join("truth").join(name))
    }

    /// Ground truth at every IMU sample (`None` without ground truth).
    pub fn imu_truth(&self) -> Result<Option<Vec<ImuTruth>>, RecordError> {
        self.truth_path("imu.jsonl")
            .map(|p| read_jsonl(&p))
            .transpose()
    }

    /// Ground truth at every exposure of every camera.
    pub fn exposure_truth(&self) -> Result<Option<Vec<ExposureTruth>>, RecordError> {
        self.truth_path("exposures.jsonl")
            .map(|p| read_jsonl(&p))
            .transpose()
    }

    /// Every packet the pen produced and its fate.
    pub fn packet_truth(&self) -> Result<Option<Vec<PacketTruth>>, RecordError> {
        self.truth_path("packets.jsonl")
            .map(|p| read_jsonl(&p))
            .transpose()
    }

    /// Stroke segmentation.
    pub fn strokes(&self) -> Result<Option<Vec<StrokeTruth>>, RecordError> {
        self.truth_path("strokes.json")
            .map(|p| read_json(&p))
            .transpose()
    }

    /// Session-wide physical constants.
    pub fn world_truth(&self) -> Result<Option<WorldTruth>, RecordError> {
        self.truth_path("world.json")
            .map(|p| read_json(&p))
            .transpose()
    }
}
