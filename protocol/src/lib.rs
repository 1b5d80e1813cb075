//! FIRES smart-pen wire format, shared by the pen firmware and the host (hardware-docs/protocol.md,
//! hardware-docs/protocol.md).
//!
//! - [`SensorPacket`]: the thesis's 22-byte IMU packet (FIRES thesis, App. B), little-endian.
//! - [`StatusPacket`]: buttons, device time, battery, health and versions in a 22-byte frame with its own sync.
//! - [`Command`] / [`CommandParser`]: host -> pen commands, `=` and `:` as the thesis plus CRC-framed extensions.
//! - [`StreamDecoder`]: byte-at-a-time resynchronising decoder of the pen -> host stream.
//!
//! `no_std`, no allocation, no panics on any input.
#![no_std]

pub mod checksum;
pub mod command;
pub mod decoder;
pub mod frame;
pub mod scale;
pub mod sensor;
pub mod status;

pub use command::{Command, CommandParser, CommandStats, EncodedCommand};
pub use decoder::{Decoded, DecoderStats, StreamDecoder};
pub use frame::{Frame, FrameError};
pub use scale::ScaleFactors;
pub use sensor::SensorPacket;
pub use status::{Buttons, Health, StateFlags, StatusPacket, StatusReason, BUTTON_REPEAT_AFTER_US};

/// Length of every pen -> host frame, in bytes.
pub const FRAME_LEN: usize = 22;
/// First sync byte of every pen -> host frame.
pub const SYNC0: u8 = 0x20;
/// Version of this wire protocol, sent in every status packet.
pub const PROTOCOL_VERSION: u8 = 1;
/// Nominal sensor packet rate of the pen, in hertz.
pub const SAMPLE_RATE_HZ: u32 = 100;
/// Serial link rate between the pen's MCU and its Bluetooth module (8N1).
pub const LINK_BAUD: u32 = 230_400;
