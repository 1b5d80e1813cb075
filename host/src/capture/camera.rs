//! Cameras through nokhwa (V4L2 on Linux): the highest frame rate the device offers, each frame decoded to RGB
//! and converted to 8-bit grey (Rec. 601 luma), stamped with the host time right after the frame arrived.

use nokhwa::pixel_format::LumaFormat;
use nokhwa::utils::{CameraIndex, RequestedFormat, RequestedFormatType};
use nokhwa::Camera;

use super::{CaptureError, CapturedFrame, FrameSource};
use crate::clock::HostClock;
use fires_record::GrayImage;

/// One open camera.
pub struct NokhwaCamera {
    device: String,
    camera: Camera,
}

/// `/dev/video2` or `2` -> camera index 2; anything else is passed as a string.
fn index_of(device: &str) -> CameraIndex {
    let digits = device.trim_start_matches("/dev/video");
    match digits.parse::<u32>() {
        Ok(i) => CameraIndex::Index(i),
        Err(_) => CameraIndex::String(device.to_string()),
    }
}

impl NokhwaCamera {
    /// Opens `device` (`/dev/videoN` or `N`) and starts streaming.
    pub fn open(device: &str) -> Result<Self, CaptureError> {
        let err = |e: &dyn std::fmt::Display| CaptureError {
            device: device.to_string(),
            message: e.to_string(),
        };
        if device.starts_with('/') && !std::path::Path::new(device).exists() {
            return Err(err(&"no such device"));
        }
        let format =
            RequestedFormat::new::<LumaFormat>(RequestedFormatType::AbsoluteHighestFrameRate);
        let mut camera = Camera::new(index_of(device), format).map_err(|e| err(&e))?;
        camera.open_stream().map_err(|e| err(&e))?;
        Ok(NokhwaCamera {
            device: device.to_string(),
            camera,
        })
    }
}

impl FrameSource for NokhwaCamera {
    fn next_frame(&mut self, clock: &HostClock) -> Result<Option<CapturedFrame>, CaptureError> {
        let err = |e: &dyn std::fmt::Display| CaptureError {
            device: self.device.clone(),
            message: e.to_string(),
        };
        let buffer = self.camera.frame().map_err(|e| err(&e))?;
        let t_ns = clock.now_ns();
        let luma = buffer.decode_image::<LumaFormat>().map_err(|e| err(&e))?;
        let (width, height) = (luma.width(), luma.height());
        Ok(Some(CapturedFrame {
            t_ns,
            image: GrayImage {
                width,
                height,
                data: luma.into_raw(),
            },
        }))
    }
}

impl Drop for NokhwaCamera {
    fn drop(&mut self) {
        let _ = self.camera.stop_stream();
    }
}
