//! Byte-at-a-time parser of what the WT12's iWRAP firmware prints: command replies and events.
//!
//! Lines end in `\r`, `\n` or both; empty lines are skipped. A line is classified by its first word (after any
//! stray `=` or `:` the host sent just before the module printed it, which happens when the link drops while the
//! host is talking). Bytes outside printable ASCII mean the UART runs at a different rate than the module (or
//! noise): the parser reports [`Event::Garbage`] at the first such byte of a line and ignores the rest of it, so
//! the provisioner can move on to the next baud rate without waiting for a line end that may never come.

use heapless::Vec;

/// Longest line kept; longer lines are reported as garbage.
pub const MAX_LINE: usize = 96;

/// One reply or event of the module.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event {
    /// `READY.`: the module finished booting (or left data mode after an escape).
    Ready,
    /// `OK` (or `OK.`): the reply to `AT`, and to commands when OK replies are enabled.
    Ok,
    /// `SYNTAX ERROR`: the module did not understand the command.
    SyntaxError,
    /// `ERROR ...`: a command failed.
    Error,
    /// `RING {link} {address} {channel} RFCOMM`: a host opened the SPP link; the module is now in data mode.
    Ring {
        /// Link id.
        link: u8,
    },
    /// `CONNECT {link} RFCOMM {channel}`: an outgoing call connected; data mode.
    Connect {
        /// Link id.
        link: u8,
    },
    /// `NO CARRIER {link} ERROR {code} ...`: the link closed or dropped; back in command mode.
    NoCarrier {
        /// Link id.
        link: u8,
    },
    /// `PAIR {address} {key}`: a host paired.
    Pair,
    /// `WRAP THOR AI ...`: the boot banner.
    Banner,
    /// Any other printable line (a `SET` listing, an echo, an event FIRES does not use).
    Other,
    /// Non-printable bytes or an overlong line: wrong baud rate or noise.
    Garbage,
}

/// The parser.
#[derive(Clone, Debug, Default)]
pub struct LineParser {
    line: Vec<u8, MAX_LINE>,
    /// The current line already produced a [`Event::Garbage`].
    spoiled: bool,
}

impl LineParser {
    /// An empty parser.
    pub const fn new() -> Self {
        LineParser {
            line: Vec::new(),
            spoiled: false,
        }
    }

    /// Forgets a partial line (after a baud rate change).
    pub fn reset(&mut self) {
        self.line.clear();
        self.spoiled = false;
    }

    /// Feeds one byte; returns an event when a line ends or garbage starts.
    pub fn push(&mut self, byte: u8) -> Option<Event> {
        match byte {
            b'\r' | b'\n' => {
                let spoiled = self.spoiled;
                self.spoiled = false;
                if spoiled || self.line.is_empty() {
                    self.line.clear();
                    return None;
                }
                let ev = classify(&self.line);
                self.line.clear();
                Some(ev)
            }
            _ if self.spoiled => None,
            0x20..=0x7E | b'\t' => {
                if self.line.push(byte).is_err() {
                    self.spoil()
                } else {
                    None
                }
            }
            _ => self.spoil(),
        }
    }

    fn spoil(&mut self) -> Option<Event> {
        self.spoiled = true;
        self.line.clear();
        Some(Event::Garbage)
    }
}

/// First number after the first word (the link id of RING / CONNECT / NO CARRIER).
fn link_id(rest: &[u8]) -> u8 {
    rest.split(|&b| b == b' ')
        .find(|w| !w.is_empty())
        .and_then(|w| core::str::from_utf8(w).ok())
        .and_then(|s| s.parse().ok())
        .unwrap_or(0)
}

/// Classifies a complete printable line.
pub fn classify(line: &[u8]) -> Event {
    let start = line
        .iter()
        .position(|b| !matches!(b, b'=' | b':' | b' ' | b'\t'))
        .unwrap_or(line.len());
    let l = &line[start..];
    let trimmed = l.trim_ascii_end();
    if trimmed == b"OK" || trimmed == b"OK." {
        Event::Ok
    } else if trimmed.starts_with(b"READY.") {
        Event::Ready
    } else if trimmed.starts_with(b"SYNTAX ERROR") {
        Event::SyntaxError
    } else if let Some(rest) = trimmed.strip_prefix(b"NO CARRIER") {
        Event::NoCarrier {
            link: link_id(rest),
        }
    } else if let Some(rest) = trimmed.strip_prefix(b"RING ") {
        Event::Ring {
            link: link_id(rest),
        }
    } else if let Some(rest) = trimmed.strip_prefix(b"CONNECT ") {
        Event::Connect {
            link: link_id(rest),
        }
    } else if trimmed.starts_with(b"ERROR") {
        Event::Error
    } else if trimmed.starts_with(b"PAIR ") {
        Event::Pair
    } else if trimmed.starts_with(b"WRAP ") {
        Event::Banner
    } else {
        Event::Other
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec::Vec as StdVec;

    fn parse(bytes: &[u8]) -> StdVec<Event> {
        let mut p = LineParser::new();
        bytes.iter().filter_map(|&b| p.push(b)).collect()
    }

    #[test]
    fn boot_transcript() {
        let t = b"\r\nWRAP THOR AI (4.1.0 build 384)\r\nCopyright (c) 2003-2010 Bluegiga Technologies Inc.\r\nREADY.\r\n";
        assert_eq!(parse(t), [Event::Banner, Event::Other, Event::Ready]);
    }

    #[test]
    fn replies_and_events() {
        let t = b"OK\r\nSYNTAX ERROR\r\nRING 0 00:07:80:12:34:56 1 RFCOMM\r\nNO CARRIER 0 ERROR 0 \r\nCONNECT 1 RFCOMM 1\nPAIR 00:07:80:12:34:56 0011\r\nERROR 0x0191\r\nOK.\r\n";
        assert_eq!(
            parse(t),
            [
                Event::Ok,
                Event::SyntaxError,
                Event::Ring { link: 0 },
                Event::NoCarrier { link: 0 },
                Event::Connect { link: 1 },
                Event::Pair,
                Event::Error,
                Event::Ok
            ]
        );
    }

    #[test]
    fn host_bytes_before_an_event_do_not_hide_it() {
        // The host sent "=" and a ':' just before the link dropped.
        assert_eq!(
            parse(b"=:NO CARRIER 0 ERROR 113 HCI_ERROR_OETC_USER\r\n"),
            [Event::NoCarrier { link: 0 }]
        );
    }

    #[test]
    fn wrong_baud_is_garbage_at_once_and_once_per_line() {
        // What 115200-baud "OK\r\n" looks like sampled at 230400: high-bit and zero bytes, no line end.
        let ev = parse(&[0x80, 0xF8, 0x00, 0xFE, 0x86]);
        assert_eq!(ev, [Event::Garbage]);
        // after a line end the parser recovers
        assert_eq!(parse(b"\xF0\xF0\r\nOK\r\n"), [Event::Garbage, Event::Ok]);
    }

    #[test]
    fn overlong_line_is_garbage() {
        let long = [b'A'; MAX_LINE + 10];
        let mut p = LineParser::new();
        let ev: StdVec<Event> = long.iter().filter_map(|&b| p.push(b)).collect();
        assert_eq!(ev, [Event::Garbage]);
        assert_eq!(p.push(b'\n'), None);
        assert_eq!(p.push(b'O'), None);
        assert_eq!(p.push(b'K'), None);
        assert_eq!(p.push(b'\r'), Some(Event::Ok));
    }
}
