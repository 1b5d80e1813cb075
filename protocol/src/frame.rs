//! A checked 22-byte frame: either packet kind, parsed from wire bytes.

use crate::checksum::xor;
use crate::sensor::{SensorPacket, SENSOR_SYNC1};
use crate::status::{StatusPacket, STATUS_SYNC1};
use crate::{FRAME_LEN, SYNC0};

/// A decoded frame of either kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Frame {
    /// An IMU sample.
    Sensor(SensorPacket),
    /// A device status report.
    Status(StatusPacket),
}

/// Why 22 bytes are not a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameError {
    /// Bytes 0 and 1 are not a known sync pair.
    BadSync,
    /// Byte 21 is not the XOR of bytes 0..=20.
    BadChecksum,
}

impl core::fmt::Display for FrameError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            FrameError::BadSync => f.write_str("bytes 0 and 1 are not a known sync pair"),
            FrameError::BadChecksum => f.write_str("checksum (byte 21) does not match"),
        }
    }
}

/// Whether `b` is the second byte of a known sync pair.
#[inline]
pub fn is_sync1(b: u8) -> bool {
    b == SENSOR_SYNC1 || b == STATUS_SYNC1
}

impl Frame {
    /// Parses one frame, checking sync and checksum.
    pub fn parse(raw: &[u8; FRAME_LEN]) -> Result<Frame, FrameError> {
        if raw[0] != SYNC0 || !is_sync1(raw[1]) {
            return Err(FrameError::BadSync);
        }
        if xor(raw) != 0 {
            return Err(FrameError::BadChecksum);
        }
        Ok(Frame::from_checked(raw))
    }

    /// Builds the frame from bytes whose sync and checksum are known good.
    pub(crate) fn from_checked(raw: &[u8; FRAME_LEN]) -> Frame {
        if raw[1] == SENSOR_SYNC1 {
            Frame::Sensor(SensorPacket::from_checked(raw))
        } else {
            Frame::Status(StatusPacket::from_checked(raw))
        }
    }

    /// Serialises the frame into its 22 wire bytes.
    pub fn encode(&self) -> [u8; FRAME_LEN] {
        match self {
            Frame::Sensor(p) => p.encode(),
            Frame::Status(p) => p.encode(),
        }
    }
}
