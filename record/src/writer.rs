//! Writes a recording directory.

use crate::error::RecordError;
use crate::image::GrayImage;
use crate::meta::Meta;
use crate::truth::{ExposureTruth, ImuTruth, PacketTruth, StrokeTruth, WorldTruth};
use crate::{camera_dir_name, image_file_name, CameraFrame, LinkChunk};
use serde::Serialize;
use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// A buffered file with its path, for error messages.
struct Out {
    path: PathBuf,
    w: BufWriter<File>,
}

impl Out {
    fn create(path: PathBuf) -> Result<Self, RecordError> {
        let f = File::create(&path).map_err(|e| RecordError::io(&path, e))?;
        Ok(Out {
            w: BufWriter::with_capacity(1 << 16, f),
            path,
        })
    }
    fn write(&mut self, bytes: &[u8]) -> Result<(), RecordError> {
        self.w
            .write_all(bytes)
            .map_err(|e| RecordError::io(&self.path, e))
    }
    fn json_line<T: Serialize>(&mut self, value: &T) -> Result<(), RecordError> {
        let mut line = serde_json::to_vec(value).map_err(|e| RecordError::Json {
            path: self.path.clone(),
            line: 0,
            cause: e,
        })?;
        line.push(b'\n');
        self.write(&line)
    }
    fn flush(&mut self) -> Result<(), RecordError> {
        self.w.flush().map_err(|e| RecordError::io(&self.path, e))
    }
}

/// Writes a recording into a directory (created if missing; files it writes are replaced).
pub struct RecordingWriter {
    dir: PathBuf,
    link: Out,
    frames: Vec<Option<Out>>,
    imu: Option<Out>,
    exposures: Option<Out>,
    packets: Option<Out>,
}

fn write_json_file<T: Serialize>(path: PathBuf, value: &T) -> Result<(), RecordError> {
    let mut text = serde_json::to_vec_pretty(value).map_err(|e| RecordError::Json {
        path: path.clone(),
        line: 0,
        cause: e,
    })?;
    text.push(b'\n');
    fs::write(&path, text).map_err(|e| RecordError::io(&path, e))
}

impl RecordingWriter {
    /// Creates the directory and writes `meta.json`; camera directories are created for every stream in `meta`.
    pub fn create(dir: &Path, meta: &Meta) -> Result<Self, RecordError> {
        fs::create_dir_all(dir).map_err(|e| RecordError::io(dir, e))?;
        write_json_file(dir.join("meta.json"), meta)?;
        let link = Out::create(dir.join("link.bin"))?;
        let max_id = meta
            .cameras
            .iter()
            .map(|c| c.id as usize + 1)
            .max()
            .unwrap_or(0);
        let mut frames: Vec<Option<Out>> = (0..max_id).map(|_| None).collect();
        for cam in &meta.cameras {
            let cdir = dir.join(camera_dir_name(cam.id));
            fs::create_dir_all(&cdir).map_err(|e| RecordError::io(&cdir, e))?;
            frames[cam.id as usize] = Some(Out::create(cdir.join("frames.jsonl"))?);
        }
        let (mut imu, mut exposures, mut packets) = (None, None, None);
        if meta.has_truth {
            let tdir = dir.join("truth");
            fs::create_dir_all(&tdir).map_err(|e| RecordError::io(&tdir, e))?;
            imu = Some(Out::create(tdir.join("imu.jsonl"))?);
            exposures = Some(Out::create(tdir.join("exposures.jsonl"))?);
            packets = Some(Out::create(tdir.join("packets.jsonl"))?);
        }
        Ok(RecordingWriter {
            dir: dir.to_path_buf(),
            link,
            frames,
            imu,
            exposures,
            packets,
        })
    }

    /// The recording directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Appends one link record.
    pub fn write_link_chunk(&mut self, chunk: &LinkChunk) -> Result<(), RecordError> {
        let len = u32::try_from(chunk.bytes.len())
            .ok()
            .filter(|&l| l <= crate::MAX_LINK_RECORD)
            .ok_or_else(|| RecordError::LinkRecordTooLong {
                path: self.link.path.clone(),
                offset: 0,
                len: u32::MAX,
                limit: crate::MAX_LINK_RECORD,
            })?;
        self.link.write(&chunk.host_time_ns.to_le_bytes())?;
        self.link.write(&len.to_le_bytes())?;
        self.link.write(&chunk.bytes)
    }

    /// Appends one frame; if `image` is given it is written as `cam{N}/{index:06}.pgm` and `frame.image` is set
    /// to that name.
    pub fn write_frame(
        &mut self,
        frame: &CameraFrame,
        image: Option<&GrayImage>,
    ) -> Result<(), RecordError> {
        let cam = frame.camera;
        let out = self
            .frames
            .get_mut(cam as usize)
            .and_then(Option::as_mut)
            .ok_or(RecordError::UnknownCamera { camera: cam })?;
        match image {
            Some(img) => {
                let name = image_file_name(frame.index);
                let path = self.dir.join(camera_dir_name(cam)).join(&name);
                fs::write(&path, img.to_pgm()).map_err(|e| RecordError::io(&path, e))?;
                let mut f = frame.clone();
                f.image = Some(name);
                out.json_line(&f)
            }
            None => out.json_line(frame),
        }
    }

    fn truth_out(slot: &mut Option<Out>) -> Result<&mut Out, RecordError> {
        slot.as_mut().ok_or_else(|| {
            RecordError::io(
                "truth/",
                std::io::Error::other("meta.has_truth is false: no ground truth may be written"),
            )
        })
    }

    /// Appends ground truth for one IMU sample.
    pub fn write_imu_truth(&mut self, t: &ImuTruth) -> Result<(), RecordError> {
        Self::truth_out(&mut self.imu)?.json_line(t)
    }

    /// Appends ground truth for one exposure.
    pub fn write_exposure_truth(&mut self, t: &ExposureTruth) -> Result<(), RecordError> {
        Self::truth_out(&mut self.exposures)?.json_line(t)
    }

    /// Appends ground truth for one produced packet.
    pub fn write_packet_truth(&mut self, t: &PacketTruth) -> Result<(), RecordError> {
        Self::truth_out(&mut self.packets)?.json_line(t)
    }

    /// Writes `truth/strokes.json`.
    pub fn write_strokes(&mut self, strokes: &[StrokeTruth]) -> Result<(), RecordError> {
        Self::truth_out(&mut self.imu)?;
        write_json_file(self.dir.join("truth").join("strokes.json"), &strokes)
    }

    /// Writes `truth/world.json`.
    pub fn write_world_truth(&mut self, world: &WorldTruth) -> Result<(), RecordError> {
        Self::truth_out(&mut self.imu)?;
        write_json_file(self.dir.join("truth").join("world.json"), world)
    }

    /// Flushes every file.
    pub fn finish(mut self) -> Result<(), RecordError> {
        self.link.flush()?;
        for out in self.frames.iter_mut().flatten() {
            out.flush()?;
        }
        for out in [&mut self.imu, &mut self.exposures, &mut self.packets]
            .into_iter()
            .flatten()
        {
            out.flush()?;
        }
        Ok(())
    }
}
