//! One JSON object per decoded packet, as `fires decode` prints them: a stable, line-oriented form of the link
//! that other tools (and people) can read without knowing the wire format.

use fires_protocol::{Decoded, DecoderStats, Frame};
use serde::Serialize;

/// A decoded packet as one JSON line, tagged by `kind`.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PacketLine {
    /// A sensor packet: raw counts, as on the wire.
    Sensor {
        /// Packet counter (u8, wraps).
        counter: u8,
        /// Accelerometer x, y, z counts.
        accel: [i16; 3],
        /// Gyroscope x, y, z counts.
        gyro: [i16; 3],
        /// Magnetometer x, y, z counts.
        mag: [i16; 3],
        /// Sensor packets missing directly before this one.
        lost_before: u8,
        /// Stream offset one past the packet's last byte.
        end_offset: u64,
    },
    /// A status packet.
    Status {
        /// Status sequence number.
        sequence: u8,
        /// Counter of the latest sensor packet at the time of this status.
        sensor_counter: u8,
        /// Device time of that sample, microseconds.
        device_time_us: u32,
        /// The four mode buttons, button 1 first.
        buttons: [bool; 4],
        /// Streaming flag.
        streaming: bool,
        /// IR LEDs on.
        ir_leds_on: bool,
        /// Low-battery flag.
        low_battery: bool,
        /// Host connected flag.
        connected: bool,
        /// Raw sensor-health bits.
        health: u8,
        /// Why the packet was sent.
        reason: String,
        /// Battery voltage, millivolts.
        battery_mv: u16,
        /// Packets dropped on the pen since power-on.
        dropped_packets: u32,
        /// Firmware version "major.minor".
        firmware: String,
        /// Wire protocol version.
        protocol_version: u8,
        /// Stream offset one past the packet's last byte.
        end_offset: u64,
    },
}

impl From<&Decoded> for PacketLine {
    fn from(d: &Decoded) -> Self {
        match d.frame {
            Frame::Sensor(p) => PacketLine::Sensor {
                counter: p.counter,
                accel: p.accel,
                gyro: p.gyro,
                mag: p.mag,
                lost_before: d.lost_before,
                end_offset: d.end_offset,
            },
            Frame::Status(s) => {
                use fires_protocol::StateFlags as F;
                PacketLine::Status {
                    sequence: s.sequence,
                    sensor_counter: s.sensor_counter,
                    device_time_us: s.device_time_us,
                    buttons: s.buttons.states(),
                    streaming: s.flags.has(F::STREAMING),
                    ir_leds_on: s.flags.has(F::IR_LEDS_ON),
                    low_battery: s.flags.has(F::LOW_BATTERY),
                    connected: s.flags.has(F::CONNECTED),
                    health: s.health.0,
                    reason: reason_name(s.reason),
                    battery_mv: s.battery_mv,
                    dropped_packets: s.dropped_packets,
                    firmware: format!("{}.{}", s.firmware_version.0, s.firmware_version.1),
                    protocol_version: s.protocol_version,
                    end_offset: d.end_offset,
                }
            }
        }
    }
}

fn reason_name(r: fires_protocol::StatusReason) -> String {
    use fires_protocol::StatusReason as R;
    match r {
        R::Periodic => "periodic".into(),
        R::ButtonChange => "button_change".into(),
        R::ButtonRepeat(n) => format!("button_repeat_{n}"),
        R::Requested => "requested".into(),
        R::Boot => "boot".into(),
        R::Unknown(b) => format!("unknown_{b}"),
    }
}

/// The last line of `fires decode`: the bytes read and the decoder's counters, tagged `kind: "summary"`.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename = "summary")]
pub struct SummaryLine {
    /// Bytes read and the decoder's counters (the `link` block of `report.json` too).
    #[serde(flatten)]
    pub link: fires_record::report::LinkSummary,
}

impl SummaryLine {
    /// Builds the summary from the decoder's counters and the number of bytes read.
    pub fn new(bytes: u64, stats: DecoderStats) -> Self {
        SummaryLine {
            link: fires_record::report::LinkSummary { bytes, stats },
        }
    }
}
