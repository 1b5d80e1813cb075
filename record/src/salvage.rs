//! Record-stream parsers that keep what is whole: `link.bin` records and `.jsonl` lines
//! (`docs/recording.md`, section "Damaged recordings").
//!
//! `.jsonl` lines delimit themselves, so a corrupt line is skipped and reading goes on at the next one.
//! `link.bin` has no sync marker or checksum; a record is taken as corrupt when its header is impossible (a
//! length above [`MAX_LINK_RECORD`] or a time before the previous record's), and the parser resyncs at the
//! first later offset from which [`RESYNC_RECORDS`] plausible records follow (or fewer that end exactly at the
//! end of the file); there "plausible" also means at most [`MAX_LINK_GAP_NS`] after the previous record. When
//! no such offset exists it stops there. A corrupt header that still looks possible (a small length and a
//! later time) cannot be told from a real one and is taken as it is.

use crate::damage::StreamDamage;
use crate::{LinkChunk, MAX_LINK_RECORD};
use serde::de::DeserializeOwned;

/// Largest accepted step between the times of consecutive `link.bin` records, nanoseconds (one day).
pub const MAX_LINK_GAP_NS: u64 = 86_400_000_000_000;

/// Plausible records that must follow a resync offset (fewer when they end exactly at the end of the file).
pub const RESYNC_RECORDS: usize = 4;

/// Bytes of a `link.bin` record header.
const HEADER: usize = 12;

/// Why a `link.bin` record was not taken.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LinkProblem {
    /// The file ends inside the record.
    Truncated,
    /// The record declares more than [`MAX_LINK_RECORD`] bytes.
    TooLong(u32),
    /// The record's time is before the previous record's (or, while resyncing, implausibly far after it).
    BadTime {
        /// The record's time, nanoseconds.
        time_ns: u64,
        /// The previous record's time, nanoseconds.
        previous_ns: u64,
    },
}

impl std::fmt::Display for LinkProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LinkProblem::Truncated => write!(f, "the file ends inside the record"),
            LinkProblem::TooLong(len) => {
                write!(f, "record declares {len} bytes (limit {MAX_LINK_RECORD})")
            }
            LinkProblem::BadTime {
                time_ns,
                previous_ns,
            } => write!(
                f,
                "record time {time_ns} ns does not follow the previous record's {previous_ns} ns"
            ),
        }
    }
}

enum Rec {
    Whole { time_ns: u64, end: usize },
    Bad(LinkProblem),
}

/// The record at `pos`; `max_gap_ns` bounds the step from `previous_ns` (only while resyncing).
fn record_at(bytes: &[u8], pos: usize, previous_ns: Option<u64>, max_gap_ns: u64) -> Rec {
    let Some(head) = bytes.get(pos..pos.saturating_add(HEADER)) else {
        return Rec::Bad(LinkProblem::Truncated);
    };
    let mut t = [0u8; 8];
    t.copy_from_slice(&head[..8]);
    let mut l = [0u8; 4];
    l.copy_from_slice(&head[8..12]);
    let (time_ns, len) = (u64::from_le_bytes(t), u32::from_le_bytes(l));
    if len > MAX_LINK_RECORD {
        return Rec::Bad(LinkProblem::TooLong(len));
    }
    if let Some(p) = previous_ns {
        if time_ns < p || time_ns - p > max_gap_ns {
            return Rec::Bad(LinkProblem::BadTime {
                time_ns,
                previous_ns: p,
            });
        }
    }
    let end = pos + HEADER + len as usize;
    if end > bytes.len() {
        return Rec::Bad(LinkProblem::Truncated);
    }
    Rec::Whole { time_ns, end }
}

/// Whether plausible records start at `pos`: [`RESYNC_RECORDS`] of them, or at least one ending exactly at
/// the end of the file, or at least two followed by a torn last record.
fn chain_starts_at(bytes: &[u8], mut pos: usize, mut previous_ns: Option<u64>) -> bool {
    let mut whole = 0;
    loop {
        if pos == bytes.len() {
            return whole >= 1;
        }
        match record_at(bytes, pos, previous_ns, MAX_LINK_GAP_NS) {
            Rec::Whole { time_ns, end } => {
                whole += 1;
                if whole >= RESYNC_RECORDS {
                    return true;
                }
                previous_ns = Some(time_ns);
                pos = end;
            }
            Rec::Bad(LinkProblem::Truncated) => return whole >= 2,
            Rec::Bad(_) => return false,
        }
    }
}

/// `link.bin` parsed as far as it is whole.
#[derive(Clone, Debug, Default)]
pub struct LinkScan {
    /// The records taken, in file order.
    pub chunks: Vec<LinkChunk>,
    /// What was skipped.
    pub damage: StreamDamage,
    /// The first problem met (byte offset of the record's start, problem), for strict readers.
    pub first_problem: Option<(u64, LinkProblem)>,
}

/// Parses `link.bin` bytes, skipping or dropping what is not whole (see the module documentation).
pub fn scan_link(bytes: &[u8]) -> LinkScan {
    let mut out = LinkScan::default();
    let (mut pos, mut previous_ns) = (0usize, None);
    while pos < bytes.len() {
        match record_at(bytes, pos, previous_ns, u64::MAX) {
            Rec::Whole { time_ns, end } => {
                out.chunks.push(LinkChunk {
                    host_time_ns: time_ns,
                    bytes: bytes[pos + HEADER..end].to_vec(),
                });
                previous_ns = Some(time_ns);
                pos = end;
            }
            Rec::Bad(problem) => {
                out.first_problem
                    .get_or_insert((pos as u64, problem.clone()));
                let resync =
                    (pos + 1..bytes.len()).find(|&q| chain_starts_at(bytes, q, previous_ns));
                if let Some(q) = resync {
                    out.damage.skipped.push((
                        format!("byte offset {pos}"),
                        format!("{problem}; resynced at byte offset {q}"),
                    ));
                    pos = q;
                    continue;
                }
                let rest = (bytes.len() - pos) as u64;
                match problem {
                    LinkProblem::Truncated => out.damage.torn = Some((pos as u64, rest)),
                    other => out.damage.stopped = Some((pos as u64, rest, other.to_string())),
                }
                break;
            }
        }
    }
    out
}

/// Parses a `.jsonl` file line by line: a line that does not parse (or fails `check`) is skipped, except an
/// unterminated last line, which is a torn last record. Blank lines are ignored.
pub fn scan_jsonl<T: DeserializeOwned>(
    bytes: &[u8],
    check: impl Fn(&T) -> Result<(), String>,
) -> (Vec<T>, StreamDamage) {
    let mut out = Vec::new();
    let mut damage = StreamDamage::default();
    let terminated = bytes.last() == Some(&b'\n');
    let lines: Vec<&[u8]> = bytes.split(|&b| b == b'\n').collect();
    let mut offset = 0usize;
    for (i, line) in lines.iter().enumerate() {
        let start = offset;
        offset += line.len() + 1;
        if line.iter().all(u8::is_ascii_whitespace) {
            continue;
        }
        let parsed = serde_json::from_slice::<T>(line)
            .map_err(|e| e.to_string())
            .and_then(|v| check(&v).map(|()| v));
        match parsed {
            Ok(v) => out.push(v),
            Err(_) if i + 1 == lines.len() && !terminated => {
                damage.torn = Some((start as u64, line.len() as u64));
            }
            Err(why) => damage.skipped.push((format!("line {}", i + 1), why)),
        }
    }
    (out, damage)
}
