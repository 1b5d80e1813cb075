//! The 22-byte status packet: everything the thesis packet lacks (buttons, device time, battery, health,
//! versions), in a frame of the same size with its own sync pair `0x20 0x0B` (hardware-docs/protocol.md), so a decoder
//! that only knows sensor packets skips it as garbage and a new one reads it.
//!
//! | bytes   | field                                                                         |
//! |---------|-------------------------------------------------------------------------------|
//! | 0, 1    | sync `0x20 0x0B`                                                              |
//! | 2       | status sequence number, u8, +1 per status packet, wraps                       |
//! | 3       | counter of the latest sensor packet sent (255 before the first; ties `device_time_us` to it) |
//! | 4..=7   | device time of that sample, microseconds, u32 LE (wraps after ~71.6 min)      |
//! | 8       | buttons: bit i = button i+1 pressed (bits 4..=7 zero)                         |
//! | 9       | state flags ([`StateFlags`])                                                  |
//! | 10      | sensor health ([`Health`])                                                    |
//! | 11      | why this packet was sent ([`StatusReason`])                                   |
//! | 12, 13  | battery voltage, millivolts, u16 LE (0 = not measured)                        |
//! | 14..=17 | sensor packets dropped on the pen since power-on (backpressure), u32 LE       |
//! | 18, 19  | firmware version major, minor                                                 |
//! | 20      | protocol version ([`crate::PROTOCOL_VERSION`])                                |
//! | 21      | XOR of bytes 0..=20                                                           |

use crate::checksum::xor;
use crate::{FRAME_LEN, SYNC0};

/// Second sync byte of a status packet.
pub const STATUS_SYNC1: u8 = 0x0B;

/// Pressed state of the pen's four mode buttons (bit i = button i+1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Buttons(pub u8);

impl Buttons {
    /// Whether button `index` (0..=3) is pressed; false for any other index.
    pub fn pressed(self, index: u8) -> bool {
        index < 4 && self.0 & (1 << index) != 0
    }
    /// The four states, button 1 first.
    pub fn states(self) -> [bool; 4] {
        [0, 1, 2, 3].map(|i| self.pressed(i))
    }
    /// Builds the bit field from four states, button 1 first.
    pub fn from_states(states: [bool; 4]) -> Self {
        Buttons(
            states
                .iter()
                .enumerate()
                .fold(0, |acc, (i, &s)| acc | (u8::from(s) << i)),
        )
    }
}

/// Device state flags (byte 9).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct StateFlags(pub u8);

impl StateFlags {
    /// Bit 0: sensor packets are being streamed (after `=`).
    pub const STREAMING: u8 = 1 << 0;
    /// Bit 1: the four IR LEDs are on.
    pub const IR_LEDS_ON: u8 = 1 << 1;
    /// Bit 2: the battery is low (the pen will turn itself off soon).
    pub const LOW_BATTERY: u8 = 1 << 2;
    /// Bit 3: a Bluetooth host is connected.
    pub const CONNECTED: u8 = 1 << 3;

    /// Whether all bits of `mask` are set.
    pub fn has(self, mask: u8) -> bool {
        self.0 & mask == mask
    }
}

/// Sensor health bits (byte 10): bits 0..=2 say the accelerometer, gyroscope and magnetometer answered their
/// identity check; bits 3..=5 say each passed its power-on self-test; bit 6 says a sensor read failed since the
/// last status packet.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Health(pub u8);

impl Health {
    /// Accelerometer identified.
    pub const ACCEL_OK: u8 = 1 << 0;
    /// Gyroscope identified.
    pub const GYRO_OK: u8 = 1 << 1;
    /// Magnetometer identified.
    pub const MAG_OK: u8 = 1 << 2;
    /// Accelerometer self-test passed.
    pub const ACCEL_SELF_TEST: u8 = 1 << 3;
    /// Gyroscope self-test passed.
    pub const GYRO_SELF_TEST: u8 = 1 << 4;
    /// Magnetometer self-test passed (the MAG3110 has none; the firmware sets it after a plausibility check).
    pub const MAG_SELF_TEST: u8 = 1 << 5;
    /// A sensor read failed since the previous status packet.
    pub const READ_ERROR: u8 = 1 << 6;
    /// Every sensor identified and self-tested, no read error.
    pub const ALL_GOOD: u8 = 0b0011_1111;

    /// Whether all bits of `mask` are set.
    pub fn has(self, mask: u8) -> bool {
        self.0 & mask == mask
    }
}

/// How long after a button change its repeats are sent, microseconds ([`StatusReason::ButtonRepeat`]).
pub const BUTTON_REPEAT_AFTER_US: [u32; 2] = [30_000, 100_000];

/// Why the pen sent a status packet (byte 11).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum StatusReason {
    /// The once-per-second report.
    #[default]
    Periodic,
    /// A button changed state.
    ButtonChange,
    /// The host asked with the status-request command.
    Requested,
    /// The first packet after power-on or reset.
    Boot,
    /// The latest button change told again, [`BUTTON_REPEAT_AFTER_US`]`[n]` after it (`n` = 0, 1; wire
    /// values 4, 5), so that one lost change packet neither delays a stroke to the next periodic report nor
    /// loses it (hardware-docs/protocol.md §1.2). Bytes 3–7 are the latest sample's, as in every status
    /// packet; the change happened that long before it.
    ButtonRepeat(u8),
    /// A value this decoder does not know (sent by a newer firmware).
    Unknown(u8),
}

impl StatusReason {
    /// How long before this packet's sample the buttons it reports changed, microseconds: 0 for a
    /// button change, the repeat's delay for a repeat, `None` for other reasons.
    pub fn button_change_age_us(self) -> Option<u32> {
        match self {
            StatusReason::ButtonChange => Some(0),
            StatusReason::ButtonRepeat(n) => BUTTON_REPEAT_AFTER_US.get(usize::from(n)).copied(),
            _ => None,
        }
    }

    /// The wire value.
    pub fn to_byte(self) -> u8 {
        match self {
            StatusReason::Periodic => 0,
            StatusReason::ButtonChange => 1,
            StatusReason::Requested => 2,
            StatusReason::Boot => 3,
            StatusReason::ButtonRepeat(n) => 4 + n.min(1),
            StatusReason::Unknown(b) => b,
        }
    }
    /// Reads the wire value; unknown values are kept, not rejected.
    pub fn from_byte(b: u8) -> Self {
        match b {
            0 => StatusReason::Periodic,
            1 => StatusReason::ButtonChange,
            2 => StatusReason::Requested,
            3 => StatusReason::Boot,
            4 => StatusReason::ButtonRepeat(0),
            5 => StatusReason::ButtonRepeat(1),
            other => StatusReason::Unknown(other),
        }
    }
}

/// Device state the pen reports once per second and on every button change.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct StatusPacket {
    /// Status sequence number, +1 per status packet, modulo 256.
    pub sequence: u8,
    /// Counter of the latest sensor packet sent before this status (255 before the first one).
    pub sensor_counter: u8,
    /// Device time of that sample in microseconds (wrapping u32).
    pub device_time_us: u32,
    /// Mode buttons.
    pub buttons: Buttons,
    /// Device state flags.
    pub flags: StateFlags,
    /// Sensor health.
    pub health: Health,
    /// Why the packet was sent.
    pub reason: StatusReason,
    /// Battery voltage in millivolts (0 = not measured).
    pub battery_mv: u16,
    /// Sensor packets dropped on the pen since power-on.
    pub dropped_packets: u32,
    /// Firmware version (major, minor).
    pub firmware_version: (u8, u8),
    /// Wire protocol version.
    pub protocol_version: u8,
}

impl StatusPacket {
    /// Serialises the packet into its 22 wire bytes, checksum included.
    pub fn encode(&self) -> [u8; FRAME_LEN] {
        let mut out = [0u8; FRAME_LEN];
        out[0] = SYNC0;
        out[1] = STATUS_SYNC1;
        out[2] = self.sequence;
        out[3] = self.sensor_counter;
        out[4..8].copy_from_slice(&self.device_time_us.to_le_bytes());
        out[8] = self.buttons.0;
        out[9] = self.flags.0;
        out[10] = self.health.0;
        out[11] = self.reason.to_byte();
        out[12..14].copy_from_slice(&self.battery_mv.to_le_bytes());
        out[14..18].copy_from_slice(&self.dropped_packets.to_le_bytes());
        out[18] = self.firmware_version.0;
        out[19] = self.firmware_version.1;
        out[20] = self.protocol_version;
        out[21] = xor(&out[..21]);
        out
    }

    /// Reads the fields of a frame whose sync and checksum were already checked.
    pub(crate) fn from_checked(raw: &[u8; FRAME_LEN]) -> Self {
        StatusPacket {
            sequence: raw[2],
            sensor_counter: raw[3],
            device_time_us: u32::from_le_bytes([raw[4], raw[5], raw[6], raw[7]]),
            buttons: Buttons(raw[8]),
            flags: StateFlags(raw[9]),
            health: Health(raw[10]),
            reason: StatusReason::from_byte(raw[11]),
            battery_mv: u16::from_le_bytes([raw[12], raw[13]]),
            dropped_packets: u32::from_le_bytes([raw[14], raw[15], raw[16], raw[17]]),
            firmware_version: (raw[18], raw[19]),
            protocol_version: raw[20],
        }
    }
}
