//! The 22-byte sensor packet of the FIRES smart-pen (FIRES thesis, App. B; hardware-docs/protocol.md).
//!
//! | bytes  | field                                   |
//! |--------|-----------------------------------------|
//! | 0, 1   | sync `0x20 0x0A`                        |
//! | 2      | packet counter, u8, +1 per packet, wraps |
//! | 3..=8  | accelerometer x, y, z (i16 LE)          |
//! | 9..=14 | gyroscope x, y, z (i16 LE)              |
//! | 15..=20| magnetometer x, y, z (i16 LE)           |
//! | 21     | XOR of bytes 0..=20                     |
//!
//! The thesis leaves the byte order open; FIRES fixes little-endian (hardware-docs/protocol.md). Values are raw sensor
//! counts: the physical scale belongs to the board description ([`crate::ScaleFactors`]), not to the packet.

use crate::checksum::xor;
use crate::{FRAME_LEN, SYNC0};

/// Second sync byte of a sensor packet.
pub const SENSOR_SYNC1: u8 = 0x0A;

/// One IMU sample as the pen sends it: raw counts of the three 3-axis sensors, all taken at the same tick.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SensorPacket {
    /// Packet counter, incremented by one per packet sent, modulo 256.
    pub counter: u8,
    /// Accelerometer x, y, z in raw counts.
    pub accel: [i16; 3],
    /// Gyroscope x, y, z in raw counts.
    pub gyro: [i16; 3],
    /// Magnetometer x, y, z in raw counts.
    pub mag: [i16; 3],
}

impl SensorPacket {
    /// Serialises the packet into its 22 wire bytes, checksum included.
    pub fn encode(&self) -> [u8; FRAME_LEN] {
        let mut out = [0u8; FRAME_LEN];
        out[0] = SYNC0;
        out[1] = SENSOR_SYNC1;
        out[2] = self.counter;
        let axes = self.accel.iter().chain(&self.gyro).chain(&self.mag);
        for (i, v) in axes.enumerate() {
            out[3 + 2 * i..5 + 2 * i].copy_from_slice(&v.to_le_bytes());
        }
        out[21] = xor(&out[..21]);
        out
    }

    /// Reads the fields of a frame whose sync and checksum were already checked.
    pub(crate) fn from_checked(raw: &[u8; FRAME_LEN]) -> Self {
        let axis = |i: usize| i16::from_le_bytes([raw[3 + 2 * i], raw[4 + 2 * i]]);
        SensorPacket {
            counter: raw[2],
            accel: [axis(0), axis(1), axis(2)],
            gyro: [axis(3), axis(4), axis(5)],
            mag: [axis(6), axis(7), axis(8)],
        }
    }
}
