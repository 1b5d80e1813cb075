//! Frame capture for live tracking: a [`FrameSource`] hands out 8-bit grey frames stamped with the host time
//! taken at capture. Cameras come through nokhwa behind the `camera` feature (module `camera`); [`RecordedFrames`]
//! plays a recording's images back at their nominal rate (tests and dry runs without hardware).

#[cfg(feature = "camera")]
pub mod camera;

use std::time::{Duration, Instant};

use fires_record::{GrayImage, RecordingReader};

use crate::clock::HostClock;

/// One captured frame.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CapturedFrame {
    /// Host time of the capture, nanoseconds ([`HostClock`]).
    pub t_ns: u64,
    /// The frame as 8-bit grey.
    pub image: GrayImage,
}

/// A capture failure (the device could not be opened or stopped delivering).
#[derive(Debug, thiserror::Error)]
#[error("camera {device}: {message}")]
pub struct CaptureError {
    /// The device as the user named it.
    pub device: String,
    /// What went wrong.
    pub message: String,
}

/// Something that delivers frames one at a time (a camera, or a recording played back). A source lives on the
/// capture thread that opened it (cameras need not be `Send`); see [`SourceOpener`].
pub trait FrameSource {
    /// Waits for the next frame and stamps it with `clock`; `Ok(None)` when the source has no more frames.
    fn next_frame(&mut self, clock: &HostClock) -> Result<Option<CapturedFrame>, CaptureError>;
}

/// A recording's images of one camera, delivered at the stream's nominal rate, or on the recorded exposure
/// schedule ([`RecordedFrames::on_schedule`]) so that two cameras keep their recorded offset.
pub struct RecordedFrames {
    images: std::vec::IntoIter<(u64, GrayImage)>,
    period: Duration,
    next_at: Option<Instant>,
    schedule: Option<(Instant, u64)>,
}

impl RecordedFrames {
    /// Loads every image of `camera` (frames without an image are skipped).
    pub fn from_recording(reader: &RecordingReader, camera: u8) -> Result<Self, CaptureError> {
        let err = |e: &dyn std::fmt::Display| CaptureError {
            device: format!("{} cam{camera}", reader.dir().display()),
            message: e.to_string(),
        };
        let rate = reader
            .meta()
            .cameras
            .iter()
            .find(|c| c.id == camera)
            .map_or(30.0, |c| c.nominal_rate_hz);
        let mut images = Vec::new();
        for f in reader.frames(camera).map_err(|e| err(&e))? {
            if let Some(img) = reader.image(&f).map_err(|e| err(&e))? {
                images.push((f.exposure_time_ns, img));
            }
        }
        Ok(RecordedFrames {
            images: images.into_iter(),
            period: Duration::from_secs_f64(1.0 / rate.max(1.0)),
            next_at: None,
            schedule: None,
        })
    }

    /// Delivers each frame at `start` plus its recorded exposure time minus `epoch_ns` (frames before the
    /// epoch at once), instead of at the nominal rate from the first call.
    pub fn on_schedule(mut self, start: Instant, epoch_ns: u64) -> Self {
        self.schedule = Some((start, epoch_ns));
        self
    }
}

impl FrameSource for RecordedFrames {
    fn next_frame(&mut self, clock: &HostClock) -> Result<Option<CapturedFrame>, CaptureError> {
        let Some((exposure_ns, image)) = self.images.next() else {
            return Ok(None);
        };
        let now = Instant::now();
        let at = match self.schedule {
            Some((start, epoch)) => start + Duration::from_nanos(exposure_ns.saturating_sub(epoch)),
            None => self.next_at.unwrap_or(now),
        };
        if at > now {
            std::thread::sleep(at - now);
        }
        self.next_at = Some(at + self.period);
        Ok(Some(CapturedFrame {
            t_ns: clock.now_ns(),
            image,
        }))
    }
}

/// Opens a frame source on the capture thread that will read it.
pub type SourceOpener = Box<dyn FnOnce() -> Result<Box<dyn FrameSource>, CaptureError> + Send>;
