//! What a salvaging reader skipped: torn last records, corrupt records, lost files and frame images
//! (`docs/recording.md`, section "Damaged recordings").
//!
//! A [`crate::RecordingReader`] opened with [`crate::RecordingReader::open_salvaging`] keeps one
//! [`DamageLog`]; every read replaces the entry of the stream or frame it read, so reading a stream twice
//! does not count its damage twice. [`DamageLog::summary`] turns the log into the [`Damage`] written to
//! `report.json` as `damaged`.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Damage found in one record stream (`link.bin` or a `.jsonl` file).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct StreamDamage {
    /// The last record was cut short (`(byte offset of its start, bytes dropped)`).
    pub torn: Option<(u64, u64)>,
    /// Corrupt records skipped inside the stream: where (`"line 7"`, `"byte offset 1200"`) and why.
    pub skipped: Vec<(String, String)>,
    /// Reading stopped at a corrupt record the reader could not resync past: `(byte offset, bytes not read,
    /// why)`.
    pub stopped: Option<(u64, u64, String)>,
}

impl StreamDamage {
    /// Whether nothing was skipped.
    pub fn is_clean(&self) -> bool {
        self.torn.is_none() && self.skipped.is_empty() && self.stopped.is_none()
    }
}

/// Why a frame's image was not used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameLoss {
    /// The image file does not exist.
    Missing,
    /// The image file exists but cannot be read or is not a valid image of the calibrated size.
    Unreadable,
}

/// Everything a salvaging reader skipped so far, keyed so that re-reading replaces instead of adding.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct DamageLog {
    /// Per stream (path relative to the recording, `/`-separated).
    pub streams: BTreeMap<String, StreamDamage>,
    /// Per frame `(camera, index)`: the image file (relative path), why it was lost and the detail.
    pub frames: BTreeMap<(u8, u64), (String, FrameLoss, String)>,
    /// Whole files (relative path) read as absent or empty because they are missing or do not parse.
    pub lost_files: BTreeMap<String, String>,
}

/// Summary of a [`DamageLog`] (`report.json` -> `damaged`).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Damage {
    /// Per stream: bytes of its torn last record that were dropped.
    pub torn_bytes: BTreeMap<String, u64>,
    /// Per stream: corrupt records skipped inside the stream (the reader resynced after each).
    pub skipped_records: BTreeMap<String, u64>,
    /// Per stream: bytes after a corrupt record the reader could not resync past (not read).
    pub unread_bytes: BTreeMap<String, u64>,
    /// Files read as absent or empty, with the reason.
    pub lost_files: BTreeMap<String, String>,
    /// Frames skipped because their image file is missing.
    pub frames_missing: u64,
    /// Frames skipped because their image file cannot be read or decoded.
    pub frames_unreadable: u64,
    /// One human-readable line per kind of damage found (empty for an intact recording).
    pub warnings: Vec<String>,
}

impl Damage {
    /// Whether the recording read without damage.
    pub fn is_clean(&self) -> bool {
        self.warnings.is_empty()
    }
}

/// At most this many examples are named in one warning line.
const EXAMPLES: usize = 3;

fn list(items: Vec<String>) -> String {
    let n = items.len();
    let mut s = items
        .into_iter()
        .take(EXAMPLES)
        .collect::<Vec<_>>()
        .join(", ");
    if n > EXAMPLES {
        s.push_str(&format!(", and {} more", n - EXAMPLES));
    }
    s
}

fn plural(n: u64, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

impl DamageLog {
    /// Records the outcome of reading stream `name` (replacing any earlier entry; a clean read removes it).
    pub fn set_stream(&mut self, name: &str, damage: StreamDamage) {
        if damage.is_clean() {
            self.streams.remove(name);
        } else {
            self.streams.insert(name.to_string(), damage);
        }
    }

    /// Records that file `name` was read as absent (or clears it when it read fine).
    pub fn set_lost_file(&mut self, name: &str, reason: Option<String>) {
        match reason {
            Some(r) => self.lost_files.insert(name.to_string(), r),
            None => self.lost_files.remove(name),
        };
    }

    /// Records that a frame's image was lost (or clears it when it read fine).
    pub fn set_frame(&mut self, key: (u8, u64), loss: Option<(String, FrameLoss, String)>) {
        match loss {
            Some(l) => self.frames.insert(key, l),
            None => self.frames.remove(&key),
        };
    }

    /// The counts and one warning line per kind of damage.
    pub fn summary(&self) -> Damage {
        let mut d = Damage::default();
        let (mut torn, mut skipped, mut stopped) = (Vec::new(), Vec::new(), Vec::new());
        for (name, s) in &self.streams {
            if let Some((offset, bytes)) = s.torn {
                d.torn_bytes.insert(name.clone(), bytes);
                torn.push(format!(
                    "{name} ({} at byte offset {offset})",
                    plural(bytes, "byte", "bytes")
                ));
            }
            if let Some((at, why)) = s.skipped.first() {
                d.skipped_records
                    .insert(name.clone(), s.skipped.len() as u64);
                skipped.push(format!(
                    "{name}: {} (first at {at}: {why})",
                    s.skipped.len()
                ));
            }
            if let Some((offset, bytes, why)) = &s.stopped {
                d.unread_bytes.insert(name.clone(), *bytes);
                stopped.push(format!(
                    "{name} at byte offset {offset} ({why}; {} not read)",
                    plural(*bytes, "byte", "bytes")
                ));
            }
        }
        if !torn.is_empty() {
            d.warnings
                .push(format!("torn last record dropped: {}", list(torn)));
        }
        if !skipped.is_empty() {
            d.warnings
                .push(format!("corrupt records skipped: {}", list(skipped)));
        }
        if !stopped.is_empty() {
            d.warnings.push(format!(
                "reading stopped at a corrupt record, what came before is kept: {}",
                list(stopped)
            ));
        }
        if !self.lost_files.is_empty() {
            d.lost_files = self.lost_files.clone();
            let items = self
                .lost_files
                .iter()
                .map(|(f, why)| format!("{f} ({why})"))
                .collect();
            d.warnings.push(format!(
                "files missing or unreadable, read as absent: {}",
                list(items)
            ));
        }
        for (loss, what) in [
            (FrameLoss::Missing, "missing"),
            (FrameLoss::Unreadable, "unreadable"),
        ] {
            let items: Vec<String> = self
                .frames
                .values()
                .filter(|(_, l, _)| *l == loss)
                .map(|(file, _, why)| match loss {
                    FrameLoss::Missing => file.clone(),
                    FrameLoss::Unreadable => format!("{file} ({why})"),
                })
                .collect();
            let n = items.len() as u64;
            match loss {
                FrameLoss::Missing => d.frames_missing = n,
                FrameLoss::Unreadable => d.frames_unreadable = n,
            }
            if n > 0 {
                d.warnings.push(format!(
                    "{} {what}, {} skipped: {}",
                    plural(n, "frame image", "frame images"),
                    if n == 1 { "its frame" } else { "their frames" },
                    list(items)
                ));
            }
        }
        d
    }
}
