//! Writes a recording directory.
//!
//! Crash safety (docs/recording.md, "Damaged recordings"): by default every record is handed to the operating
//! system as one `write` as soon as it is appended, so a killed process leaves files that end at a record
//! boundary (or, at worst, in one torn record that a salvaging reader drops); and the data is forced to disk
//! ([`File::sync_data`]) at most [`WriterOptions::sync_interval`] after it was written, so a power cut loses
//! about that much. Image files are written whole before the frame line that names them.

use crate::error::RecordError;
use crate::image::{EncodedImage, GrayImage, ImageEncoder};
use crate::meta::Meta;
use crate::truth::{ExposureTruth, ImuTruth, PacketTruth, StrokeTruth, WorldTruth};
use crate::{camera_dir_name, CameraFrame, LinkChunk};
use serde::Serialize;
use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// How eagerly a [`RecordingWriter`] makes its records durable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WriterOptions {
    /// Hand every record to the operating system when it is appended (survives a killed process).
    pub flush_each_record: bool,
    /// Force written data to disk when this much time has passed since the last time (survives a power cut up
    /// to about this long before it); `None`: only [`RecordingWriter::finish`] does.
    pub sync_interval: Option<Duration>,
    /// Store frame images Zstandard-compressed (`{index:06}.pgm.zst`) rather than as plain PGM.
    pub compress_images: bool,
}

impl Default for WriterOptions {
    /// Flush every record, sync every second.
    fn default() -> Self {
        WriterOptions {
            flush_each_record: true,
            sync_interval: Some(Duration::from_secs(1)),
            compress_images: false,
        }
    }
}

impl WriterOptions {
    /// Buffered writing with no syncing until [`RecordingWriter::finish`]: fastest, for files that can be
    /// regenerated (a killed writer loses up to the buffer size of every stream).
    pub fn buffered() -> Self {
        WriterOptions {
            flush_each_record: false,
            sync_interval: None,
            compress_images: false,
        }
    }
}

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
    fn sync(&mut self) -> Result<(), RecordError> {
        self.flush()?;
        self.w
            .get_ref()
            .sync_data()
            .map_err(|e| RecordError::io(&self.path, e))
    }
}

/// Makes a directory's entries (files created in it) durable; a no-op where directories cannot be opened.
fn sync_dir(dir: &Path) -> Result<(), RecordError> {
    #[cfg(unix)]
    {
        File::open(dir)
            .and_then(|d| d.sync_all())
            .map_err(|e| RecordError::io(dir, e))?;
    }
    #[cfg(not(unix))]
    let _ = dir;
    Ok(())
}

/// Writes a recording into a directory (created if missing; files it writes are replaced).
pub struct RecordingWriter {
    dir: PathBuf,
    options: WriterOptions,
    link: Out,
    frames: Vec<Option<Out>>,
    imu: Option<Out>,
    exposures: Option<Out>,
    packets: Option<Out>,
    /// Image files written since the last sync (still to be synced), with their paths.
    unsynced_images: Vec<(PathBuf, File)>,
    /// Directories that gained entries since the last sync.
    unsynced_dirs: Vec<PathBuf>,
    last_sync: Instant,
    /// Encodes frame images (one compression context for the whole recording).
    encoder: ImageEncoder,
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
    /// Crash-safe defaults ([`WriterOptions::default`]).
    pub fn create(dir: &Path, meta: &Meta) -> Result<Self, RecordError> {
        Self::create_with(dir, meta, WriterOptions::default())
    }

    /// As [`RecordingWriter::create`], with the given durability options. `meta` must pass
    /// [`Meta::validate`]: a recording the reader would refuse is not written.
    pub fn create_with(
        dir: &Path,
        meta: &Meta,
        options: WriterOptions,
    ) -> Result<Self, RecordError> {
        meta.validate()
            .map_err(|problem| RecordError::InvalidMeta {
                path: dir.join("meta.json"),
                problem,
            })?;
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
        let mut unsynced_dirs = vec![dir.to_path_buf()];
        for cam in &meta.cameras {
            let cdir = dir.join(camera_dir_name(cam.id));
            fs::create_dir_all(&cdir).map_err(|e| RecordError::io(&cdir, e))?;
            frames[cam.id as usize] = Some(Out::create(cdir.join("frames.jsonl"))?);
            unsynced_dirs.push(cdir);
        }
        let (mut imu, mut exposures, mut packets) = (None, None, None);
        if meta.has_truth {
            let tdir = dir.join("truth");
            fs::create_dir_all(&tdir).map_err(|e| RecordError::io(&tdir, e))?;
            imu = Some(Out::create(tdir.join("imu.jsonl"))?);
            exposures = Some(Out::create(tdir.join("exposures.jsonl"))?);
            packets = Some(Out::create(tdir.join("packets.jsonl"))?);
            unsynced_dirs.push(tdir);
        }
        let mut w = RecordingWriter {
            dir: dir.to_path_buf(),
            options,
            link,
            frames,
            imu,
            exposures,
            packets,
            unsynced_images: Vec::new(),
            unsynced_dirs,
            last_sync: Instant::now(),
            encoder: ImageEncoder::new(options.compress_images)
                .map_err(|e| RecordError::io(dir, e))?,
        };
        if options.sync_interval.is_some() {
            // meta.json and the empty streams exist on disk before the first record.
            let meta_path = dir.join("meta.json");
            File::open(&meta_path)
                .and_then(|f| f.sync_all())
                .map_err(|e| RecordError::io(&meta_path, e))?;
            w.sync()?;
        }
        Ok(w)
    }

    fn outs(&mut self) -> impl Iterator<Item = &mut Out> {
        std::iter::once(&mut self.link)
            .chain(self.frames.iter_mut().flatten())
            .chain(
                [&mut self.imu, &mut self.exposures, &mut self.packets]
                    .into_iter()
                    .flatten(),
            )
    }

    /// Forces everything written so far to disk: every stream, the images written since the last sync and
    /// the directory entries of new files.
    pub fn sync(&mut self) -> Result<(), RecordError> {
        for out in self.outs() {
            out.sync()?;
        }
        for (path, f) in self.unsynced_images.drain(..) {
            f.sync_data().map_err(|e| RecordError::io(&path, e))?;
        }
        for d in std::mem::take(&mut self.unsynced_dirs) {
            sync_dir(&d)?;
        }
        self.last_sync = Instant::now();
        Ok(())
    }

    /// Syncs when [`WriterOptions::sync_interval`] has passed since the last sync. Every append calls this;
    /// a caller that may go quiet for a while (a live session waiting for data) calls it on its idle ticks
    /// too, so the last records do not wait for the next one.
    pub fn sync_if_due(&mut self) -> Result<(), RecordError> {
        match self.options.sync_interval {
            Some(every) if self.last_sync.elapsed() >= every => self.sync(),
            _ => Ok(()),
        }
    }

    /// Ends one record appended to `which`: flushed (and synced when due) as the options say.
    fn end_record(&mut self, which: Stream) -> Result<(), RecordError> {
        if self.options.flush_each_record {
            let out = match which {
                Stream::Link => Some(&mut self.link),
                Stream::Frames(cam) => self.frames.get_mut(cam).and_then(Option::as_mut),
                Stream::Imu => self.imu.as_mut(),
                Stream::Exposures => self.exposures.as_mut(),
                Stream::Packets => self.packets.as_mut(),
            };
            if let Some(out) = out {
                out.flush()?;
            }
        }
        self.sync_if_due()
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
        // One buffer, so that a flushed record reaches the file in one write.
        let mut record = Vec::with_capacity(12 + chunk.bytes.len());
        record.extend_from_slice(&chunk.host_time_ns.to_le_bytes());
        record.extend_from_slice(&len.to_le_bytes());
        record.extend_from_slice(&chunk.bytes);
        self.link.write(&record)?;
        self.end_record(Stream::Link)
    }

    /// Appends one frame; if `image` is given it is written as `cam{N}/{index:06}.pgm` (`.pgm.zst` when
    /// [`WriterOptions::compress_images`]) and `frame.image` is set to that name.
    pub fn write_frame(
        &mut self,
        frame: &CameraFrame,
        image: Option<&GrayImage>,
    ) -> Result<(), RecordError> {
        let encoded = image
            .map(|img| self.encoder.encode(img))
            .transpose()
            .map_err(|e| RecordError::io(self.dir.join(camera_dir_name(frame.camera)), e))?;
        self.write_frame_encoded(frame, encoded.as_ref())
    }

    /// As [`RecordingWriter::write_frame`] with the image already encoded (so encoding can run on other
    /// threads); its own compression choice is kept.
    pub fn write_frame_encoded(
        &mut self,
        frame: &CameraFrame,
        image: Option<&EncodedImage>,
    ) -> Result<(), RecordError> {
        let cam = frame.camera;
        let out = self
            .frames
            .get_mut(cam as usize)
            .and_then(Option::as_mut)
            .ok_or(RecordError::UnknownCamera { camera: cam })?;
        match image {
            Some(img) => {
                let name = img.file_name(frame.index);
                let bytes = &img.bytes;
                let cdir = self.dir.join(camera_dir_name(cam));
                let path = cdir.join(&name);
                // The image is whole on the file system before the line naming it is written.
                let mut file = File::create(&path).map_err(|e| RecordError::io(&path, e))?;
                file.write_all(bytes)
                    .map_err(|e| RecordError::io(&path, e))?;
                let mut f = frame.clone();
                f.image = Some(name);
                out.json_line(&f)?;
                if self.options.sync_interval.is_some() {
                    self.unsynced_images.push((path, file));
                    if !self.unsynced_dirs.contains(&cdir) {
                        self.unsynced_dirs.push(cdir);
                    }
                }
            }
            None => out.json_line(frame)?,
        }
        self.end_record(Stream::Frames(cam as usize))
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
        Self::truth_out(&mut self.imu)?.json_line(t)?;
        self.end_record(Stream::Imu)
    }

    /// Appends ground truth for one exposure.
    pub fn write_exposure_truth(&mut self, t: &ExposureTruth) -> Result<(), RecordError> {
        Self::truth_out(&mut self.exposures)?.json_line(t)?;
        self.end_record(Stream::Exposures)
    }

    /// Appends ground truth for one produced packet.
    pub fn write_packet_truth(&mut self, t: &PacketTruth) -> Result<(), RecordError> {
        Self::truth_out(&mut self.packets)?.json_line(t)?;
        self.end_record(Stream::Packets)
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

    /// Flushes every file; with a [`WriterOptions::sync_interval`], also forces everything to disk.
    pub fn finish(mut self) -> Result<(), RecordError> {
        if self.options.sync_interval.is_some() {
            return self.sync();
        }
        for out in self.outs() {
            out.flush()?;
        }
        Ok(())
    }
}

/// The stream a record was appended to.
#[derive(Clone, Copy)]
enum Stream {
    Link,
    Frames(usize),
    Imu,
    Exposures,
    Packets,
}
