//! Host -> pen commands.
//!
//! The thesis defines two single-byte commands (FIRES thesis, App. B): `=` (0x3D) starts streaming,
//! `:` (0x3A) stops it. They stay exactly so. Every further command is an **extended frame** of printable ASCII:
//!
//! ```text
//! '!'  opcode  payload-as-hex  crc8-as-hex  '\r'
//! ```
//!
//! - `'!'` (0x21) opens a frame; the opcode is one uppercase letter; each payload byte and the CRC are two
//!   uppercase hex digits (`0-9`, `A-F`); `'\r'` (0x0D) closes it. The payload length is fixed by the opcode.
//! - The CRC is CRC-8/SMBUS over the opcode byte followed by the raw (not hex) payload bytes.
//! - No frame byte is `=` or `:`, so a frame whose start was lost can never be read as start/stop; the iWRAP
//!   escape character `+` never occurs either.
//! - A lost byte shifts the terminator into the hex field (`'\r'` is not hex) and a corrupted digit changes at most
//!   4 bits, which the CRC always detects; so a damaged frame is dropped and never becomes another command.
//! - A `=` or `:` inside a frame aborts the frame and is executed: it cannot belong to a frame, so it must be a real
//!   command sent after a frame whose tail was lost. A `'!'` inside a frame restarts the frame.
//!
//! | command        | bytes                                  | payload                          |
//! |----------------|----------------------------------------|----------------------------------|
//! | start          | `=`                                    |                                  |
//! | stop           | `:`                                    |                                  |
//! | vibrate        | `!V` hhhh cc `\r` (9 bytes)            | duration ms, u16 big-endian      |
//! | beep           | `!B` hhhh hhhh cc `\r` (13 bytes)      | frequency Hz, duration ms (u16 BE each) |
//! | IR LEDs        | `!L` hh cc `\r` (7 bytes)              | 0 = off, 1 = on                  |
//! | status request | `!S` cc `\r` (5 bytes)                 |                                  |
//!
//! Payload integers are big-endian so the hex reads naturally (`!V01F4..` is 500 ms).

use crate::checksum::crc8;

/// Byte of the thesis's start-streaming command.
pub const START_BYTE: u8 = b'=';
/// Byte of the thesis's stop-streaming command.
pub const STOP_BYTE: u8 = b':';
/// First byte of an extended command frame.
pub const FRAME_START: u8 = b'!';
/// Last byte of an extended command frame.
pub const FRAME_END: u8 = b'\r';
/// Longest encoded command, in bytes.
pub const MAX_COMMAND_LEN: usize = 13;

/// A command from the host to the pen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Command {
    /// Start sampling and streaming sensor packets (`=`).
    Start,
    /// Stop streaming (`:`).
    Stop,
    /// Run the vibration motor.
    Vibrate {
        /// Duration in milliseconds.
        duration_ms: u16,
    },
    /// Sound the speaker.
    Beep {
        /// Tone frequency in hertz.
        frequency_hz: u16,
        /// Duration in milliseconds.
        duration_ms: u16,
    },
    /// Switch the four IR LEDs on or off.
    IrLeds {
        /// True to switch them on.
        on: bool,
    },
    /// Ask for a status packet now.
    RequestStatus,
}

/// Opcode letters of the extended commands.
mod opcode {
    pub const VIBRATE: u8 = b'V';
    pub const BEEP: u8 = b'B';
    pub const IR_LEDS: u8 = b'L';
    pub const STATUS: u8 = b'S';
}

/// Payload length in raw bytes of an extended opcode, or `None` for an unknown opcode.
fn payload_len(op: u8) -> Option<usize> {
    match op {
        opcode::VIBRATE => Some(2),
        opcode::BEEP => Some(4),
        opcode::IR_LEDS => Some(1),
        opcode::STATUS => Some(0),
        _ => None,
    }
}

const HEX: &[u8; 16] = b"0123456789ABCDEF";

fn hex_value(c: u8) -> Option<u8> {
    match c {
        b'0'..=b'9' => Some(c - b'0'),
        b'A'..=b'F' => Some(c - b'A' + 10),
        _ => None,
    }
}

/// A command in its wire form (at most [`MAX_COMMAND_LEN`] bytes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EncodedCommand {
    bytes: [u8; MAX_COMMAND_LEN],
    len: usize,
}

impl EncodedCommand {
    /// The bytes to send.
    pub fn as_bytes(&self) -> &[u8] {
        &self.bytes[..self.len]
    }

    fn push(&mut self, b: u8) {
        self.bytes[self.len] = b;
        self.len += 1;
    }

    fn push_hex(&mut self, b: u8) {
        self.push(HEX[usize::from(b >> 4)]);
        self.push(HEX[usize::from(b & 0x0F)]);
    }
}

impl Command {
    /// Encodes the command for the wire.
    pub fn encode(&self) -> EncodedCommand {
        let mut out = EncodedCommand {
            bytes: [0; MAX_COMMAND_LEN],
            len: 0,
        };
        let (op, payload, n): (u8, [u8; 4], usize) = match *self {
            Command::Start => {
                out.push(START_BYTE);
                return out;
            }
            Command::Stop => {
                out.push(STOP_BYTE);
                return out;
            }
            Command::Vibrate { duration_ms } => {
                let d = duration_ms.to_be_bytes();
                (opcode::VIBRATE, [d[0], d[1], 0, 0], 2)
            }
            Command::Beep {
                frequency_hz,
                duration_ms,
            } => {
                let f = frequency_hz.to_be_bytes();
                let d = duration_ms.to_be_bytes();
                (opcode::BEEP, [f[0], f[1], d[0], d[1]], 4)
            }
            Command::IrLeds { on } => (opcode::IR_LEDS, [u8::from(on), 0, 0, 0], 1),
            Command::RequestStatus => (opcode::STATUS, [0; 4], 0),
        };
        out.push(FRAME_START);
        out.push(op);
        for &b in &payload[..n] {
            out.push_hex(b);
        }
        out.push_hex(command_crc(op, &payload[..n]));
        out.push(FRAME_END);
        out
    }
}

/// CRC of an extended frame: over the opcode and the raw payload.
fn command_crc(op: u8, payload: &[u8]) -> u8 {
    let mut bytes = [0u8; 5];
    bytes[0] = op;
    bytes[1..=payload.len()].copy_from_slice(payload);
    crc8(&bytes[..=payload.len()])
}

/// Builds a command from an opcode and its checked payload.
fn command_from(op: u8, p: &[u8]) -> Option<Command> {
    Some(match op {
        opcode::VIBRATE => Command::Vibrate {
            duration_ms: u16::from_be_bytes([p[0], p[1]]),
        },
        opcode::BEEP => Command::Beep {
            frequency_hz: u16::from_be_bytes([p[0], p[1]]),
            duration_ms: u16::from_be_bytes([p[2], p[3]]),
        },
        opcode::IR_LEDS => match p[0] {
            0 => Command::IrLeds { on: false },
            1 => Command::IrLeds { on: true },
            _ => return None,
        },
        opcode::STATUS => Command::RequestStatus,
        _ => return None,
    })
}

/// Counters of the pen-side command parser.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CommandStats {
    /// Commands recognised.
    pub commands: u32,
    /// Extended frames dropped (bad digit, bad CRC, missing terminator, unknown opcode, bad payload).
    pub rejected_frames: u32,
    /// Bytes outside any frame that are not a command.
    pub ignored_bytes: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum ParseState {
    Idle,
    /// After `'!'`, waiting for the opcode.
    Opcode,
    /// Reading hex digits: opcode, payload bytes expected, digits read so far.
    Digits {
        op: u8,
        payload: usize,
        read: usize,
    },
    /// All digits read; waiting for the terminator.
    End {
        op: u8,
        payload: usize,
    },
}

/// Pen-side byte-at-a-time command parser; never allocates, never panics.
#[derive(Clone, Debug)]
pub struct CommandParser {
    state: ParseState,
    /// Raw bytes decoded from hex: payload then CRC.
    raw: [u8; 5],
    stats: CommandStats,
}

impl Default for CommandParser {
    fn default() -> Self {
        Self::new()
    }
}

impl CommandParser {
    /// A parser in the idle state.
    pub const fn new() -> Self {
        CommandParser {
            state: ParseState::Idle,
            raw: [0; 5],
            stats: CommandStats {
                commands: 0,
                rejected_frames: 0,
                ignored_bytes: 0,
            },
        }
    }

    /// Totals so far.
    pub fn stats(&self) -> CommandStats {
        self.stats
    }

    /// Feeds one received byte; returns a command when one is complete and intact.
    pub fn push(&mut self, byte: u8) -> Option<Command> {
        let in_frame = self.state != ParseState::Idle;
        let cmd = match byte {
            START_BYTE | STOP_BYTE => {
                if in_frame {
                    self.reject();
                }
                Some(if byte == START_BYTE {
                    Command::Start
                } else {
                    Command::Stop
                })
            }
            FRAME_START => {
                if in_frame {
                    self.stats.rejected_frames += 1;
                }
                self.state = ParseState::Opcode;
                None
            }
            _ => self.push_in_frame(byte),
        };
        if cmd.is_some() {
            self.stats.commands += 1;
        }
        cmd
    }

    fn reject(&mut self) {
        self.stats.rejected_frames += 1;
        self.state = ParseState::Idle;
    }

    fn push_in_frame(&mut self, byte: u8) -> Option<Command> {
        match self.state {
            ParseState::Idle => {
                self.stats.ignored_bytes += 1;
                None
            }
            ParseState::Opcode => {
                match payload_len(byte) {
                    Some(payload) => {
                        self.state = ParseState::Digits {
                            op: byte,
                            payload,
                            read: 0,
                        }
                    }
                    None => self.reject(),
                }
                None
            }
            ParseState::Digits { op, payload, read } => {
                let Some(v) = hex_value(byte) else {
                    self.reject();
                    return None;
                };
                let i = read / 2;
                self.raw[i] = if read % 2 == 0 {
                    v << 4
                } else {
                    self.raw[i] | v
                };
                let read = read + 1;
                self.state = if read == 2 * (payload + 1) {
                    ParseState::End { op, payload }
                } else {
                    ParseState::Digits { op, payload, read }
                };
                None
            }
            ParseState::End { op, payload } => {
                self.state = ParseState::Idle;
                let crc_ok =
                    byte == FRAME_END && command_crc(op, &self.raw[..payload]) == self.raw[payload];
                let cmd = if crc_ok {
                    command_from(op, &self.raw[..payload])
                } else {
                    None
                };
                if cmd.is_none() {
                    self.stats.rejected_frames += 1;
                }
                cmd
            }
        }
    }
}
