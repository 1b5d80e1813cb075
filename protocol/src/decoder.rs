//! Byte-at-a-time stream decoder for the pen -> host link (hardware-docs/protocol.md).
//!
//! The link is a serial byte stream with no framing beyond the packets' own sync pairs, so the decoder must find
//! frame boundaries, survive garbage, lost and corrupted bytes, and never report a frame the pen did not send.
//!
//! **Acceptance rule** (hardware-docs/protocol.md §1.4). A candidate is 22 bytes starting with a sync pair whose
//! XOR checksum is zero.
//! 1. *Lock.* After a skipped byte the decoder is unlocked; an unlocked candidate is emitted only when the candidate
//!    directly after it is valid too **and continues it** (see below). Lock therefore needs two consecutive valid
//!    frames, so random bytes yield a frame with probability about 2^-58 per byte.
//! 2. *Release.* A locked candidate (the one directly before it was accepted) is emitted as soon as the two bytes
//!    after it are a sync pair. If garbage follows instead, it is emitted when it continues the candidate before
//!    it and shows no sign of a lost byte: a frame that lost a byte and still passed the 8-bit checksum (1 in 256)
//!    has the next frame's `0x20` as its last byte, so its last byte is `0x20` and the byte after it a second
//!    sync byte (the next sync pair one byte early). Otherwise it is dropped.
//!
//! *Continuation* is what the pen guarantees of two frames sent back to back (hardware-docs/protocol.md):
//! sensor -> sensor: counter + 1; sensor -> status: the status's `sensor_counter` equals the sensor counter;
//! status -> sensor: counter = `sensor_counter` + 1; status -> status: sequence + 1. Requiring it when lock is
//! acquired stops a window of garbage that ends exactly at a real frame boundary (a sync pair inside a corrupted
//! payload, say) from being confirmed by the real frame after it; requiring it for a release before garbage stops a
//! window of garbage that starts right after a frame. A pair that is not continuous (the pen dropped a packet
//! between them) only delays lock by one frame, and holds back a frame that garbage follows.
//!
//! What this guarantees, and the false-frame bounds (the price of not dropping every frame that garbage follows),
//! are listed in hardware-docs/protocol.md §1.4. The latency: a frame in lock is released at most two bytes (87 µs
//! at 230 400 baud) after its end; the first frame after a loss of lock
//! waits for the whole next frame. [`StreamDecoder::finish`] releases a locked last frame at the end of a stream.
//! An intact frame that has garbage on both sides is indistinguishable from garbage and is dropped (it then shows
//! up in `lost`).
//!
//! **Limit.** The guarantees hold for one fault per frame. The thesis's XOR checksum is blind to a permutation of
//! a frame's bytes, so a frame that loses a byte and then gains a garbage byte of the same value before its end
//! passes; only a stronger checksum (a future protocol version) could catch that double fault.
//!
//! **Counters.** `bytes_skipped` counts every consumed byte that is not part of an emitted or duplicate frame, so
//! after `finish`, `bytes_in = 22 * (sensor_frames + status_frames + duplicates) + bytes_skipped`.
//! `checksum_errors` counts 22-byte candidates with a sync pair and a wrong checksum (garbage that happens to
//! contain a sync pair counts too). `lost` sums the sensor-counter gaps between consecutive emitted sensor frames
//! (modulo 256: 256 lost packets in a row are invisible). A frame byte-identical to the previous emitted frame of
//! its kind (a radio retransmission) is a `duplicate` and is not emitted.

use crate::checksum::xor;
use crate::frame::{is_sync1, Frame};
use crate::sensor::SENSOR_SYNC1;
use crate::{FRAME_LEN, SYNC0};

/// Running totals of what the decoder has seen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct DecoderStats {
    /// Sensor frames emitted.
    pub sensor_frames: u64,
    /// Status frames emitted.
    pub status_frames: u64,
    /// Candidates with a sync pair whose checksum failed.
    pub checksum_errors: u64,
    /// Bytes consumed that belong to no emitted or duplicate frame.
    pub bytes_skipped: u64,
    /// Sensor packets missing between emitted sensor frames (counter gaps, modulo 256).
    pub lost: u64,
    /// Frames identical to the previous one of their kind, dropped.
    pub duplicates: u64,
}

/// One emitted frame and where it sat in the stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Decoded {
    /// The frame.
    pub frame: Frame,
    /// Stream offset one past the frame's last byte (bytes consumed since the decoder was created).
    pub end_offset: u64,
    /// Sensor packets missing directly before this one (0 for status frames).
    pub lost_before: u8,
}

/// A valid candidate waiting for confirmation.
#[derive(Clone, Copy)]
enum Held {
    None,
    /// Locked; released when the next two bytes are a sync pair, or, when garbage follows, if it continues the
    /// candidate before it (`StreamDecoder::held_continues`) and shows no sign of a lost byte.
    AwaitSync([u8; FRAME_LEN], u64),
    /// Not locked; released when the next whole frame is valid.
    AwaitNext([u8; FRAME_LEN], u64),
}

/// Resynchronising decoder of the pen's byte stream; never allocates, never panics.
#[derive(Clone)]
pub struct StreamDecoder {
    buf: [u8; FRAME_LEN],
    len: usize,
    held: Held,
    /// The previous candidate ended exactly where `buf` starts.
    contiguous: bool,
    /// The previous candidate's header (meaningful while `contiguous`).
    prev: Header,
    /// A locked held frame continues the candidate before it.
    held_continues: bool,
    last_sensor: Option<[u8; FRAME_LEN]>,
    last_status: Option<[u8; FRAME_LEN]>,
    offset: u64,
    stats: DecoderStats,
}

impl Default for StreamDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl StreamDecoder {
    /// A decoder that has seen nothing.
    pub const fn new() -> Self {
        StreamDecoder {
            buf: [0; FRAME_LEN],
            len: 0,
            held: Held::None,
            contiguous: false,
            prev: Header([0; 3]),
            held_continues: false,
            last_sensor: None,
            last_status: None,
            offset: 0,
            stats: DecoderStats {
                sensor_frames: 0,
                status_frames: 0,
                checksum_errors: 0,
                bytes_skipped: 0,
                lost: 0,
                duplicates: 0,
            },
        }
    }

    /// Totals so far.
    pub fn stats(&self) -> DecoderStats {
        self.stats
    }

    /// Bytes consumed so far.
    pub fn bytes_in(&self) -> u64 {
        self.offset
    }

    /// Whether the decoder is locked (the last candidate was accepted and nothing was skipped since).
    pub fn is_locked(&self) -> bool {
        self.contiguous && matches!(self.held, Held::AwaitSync(..) | Held::None)
    }

    /// Feeds one byte; returns the frame it releases, if any (at most one per byte).
    #[inline]
    pub fn push(&mut self, byte: u8) -> Option<Decoded> {
        self.offset += 1;
        self.buf[self.len] = byte;
        self.len += 1;
        self.settle()
    }

    /// Feeds a slice, calling `sink` for every frame released. Same result as [`Self::push`] byte by byte;
    /// whole aligned frames take a fast path.
    pub fn feed(&mut self, bytes: &[u8], mut sink: impl FnMut(Decoded)) {
        let mut rest = bytes;
        while let Some((&first, tail)) = rest.split_first() {
            if self.len == 0 {
                if let Some(frame) = rest.first_chunk::<FRAME_LEN>() {
                    if self.take_aligned_frame(frame, &mut sink) {
                        rest = &rest[FRAME_LEN..];
                        continue;
                    }
                }
            }
            if let Some(d) = self.push(first) {
                sink(d);
            }
            rest = tail;
        }
    }

    /// With nothing buffered, consumes a whole valid frame at once, exactly as 22 pushes would.
    fn take_aligned_frame(
        &mut self,
        frame: &[u8; FRAME_LEN],
        sink: &mut impl FnMut(Decoded),
    ) -> bool {
        if frame[0] != SYNC0 || !is_sync1(frame[1]) || xor(frame) != 0 {
            return false;
        }
        self.offset += 2;
        if let Some(d) = self.release_on_sync() {
            sink(d);
        }
        self.offset += (FRAME_LEN - 2) as u64;
        self.buf = *frame;
        self.len = FRAME_LEN;
        if let Some(d) = self.accept_candidate() {
            sink(d);
        }
        true
    }

    /// Ends the stream: releases a locked last frame and counts the unfinished tail as skipped.
    pub fn finish(&mut self) -> Option<Decoded> {
        let out = match self.held {
            Held::AwaitSync(raw, end) => self.emit(raw, end),
            Held::AwaitNext(..) => {
                self.stats.bytes_skipped += FRAME_LEN as u64;
                None
            }
            Held::None => None,
        };
        self.held = Held::None;
        self.stats.bytes_skipped += self.len as u64;
        self.len = 0;
        self.contiguous = false;
        out
    }

    /// Advances the state machine over the buffered bytes after one byte was appended.
    fn settle(&mut self) -> Option<Decoded> {
        // At most one frame comes out per byte: a frame released because garbage follows it leaves nothing held,
        // and fewer than 22 bytes buffered, so neither a sync pair nor a candidate can release another.
        let mut out = None;
        loop {
            if self.len == 0 {
                return out;
            }
            if self.buf[0] != SYNC0 {
                let first = self.buf[0];
                if self.drop_front() {
                    out = self.garbage_after_held(first);
                }
                continue;
            }
            if self.len < 2 {
                return out;
            }
            if !is_sync1(self.buf[1]) {
                let first = self.buf[0];
                if self.drop_front() {
                    out = self.garbage_after_held(first);
                }
                continue;
            }
            if self.len == 2 {
                if out.is_some() {
                    return out;
                }
                return self.release_on_sync();
            }
            if self.len < FRAME_LEN {
                return out;
            }
            if xor(&self.buf) != 0 {
                self.stats.checksum_errors += 1;
                if self.drop_front() {
                    out = self.garbage_after_held(SYNC0);
                }
                continue;
            }
            if out.is_some() {
                return out;
            }
            return self.accept_candidate();
        }
    }

    /// A sync pair follows the held frame directly: a locked frame is released.
    fn release_on_sync(&mut self) -> Option<Decoded> {
        if let Held::AwaitSync(raw, end) = self.held {
            self.held = Held::None;
            return self.emit(raw, end);
        }
        None
    }

    /// `buf` holds a valid candidate.
    fn accept_candidate(&mut self) -> Option<Decoded> {
        let raw = self.buf;
        self.len = 0;
        let end = self.offset;
        let after_previous = self.contiguous;
        self.contiguous = true;
        let prev = core::mem::replace(&mut self.prev, Header::of(&raw));
        match self.held {
            Held::AwaitNext(first, first_end) => {
                if Header::of(&first).continued_by(&raw) {
                    self.held = Held::AwaitSync(raw, end);
                    self.held_continues = true;
                    self.emit(first, first_end)
                } else {
                    self.stats.bytes_skipped += FRAME_LEN as u64;
                    self.held = Held::AwaitNext(raw, end);
                    None
                }
            }
            _ => {
                if after_previous {
                    self.held = Held::AwaitSync(raw, end);
                    self.held_continues = prev.continued_by(&raw);
                } else {
                    self.held = Held::AwaitNext(raw, end);
                }
                None
            }
        }
    }

    /// Drops the first buffered byte; returns whether a frame is held, which garbage now follows.
    #[inline]
    fn drop_front(&mut self) -> bool {
        self.buf.copy_within(1..self.len, 0);
        self.len -= 1;
        self.stats.bytes_skipped += 1;
        self.contiguous = false;
        !matches!(self.held, Held::None)
    }

    /// Rule 3 when garbage follows the held frame. `first` is the dropped byte: for a locked frame, the one right
    /// after it (a locked frame is held only while `buf` starts right after it). A locked frame that continues the
    /// frame before it and shows no sign of a lost byte is released; any other held frame is dropped. A frame that
    /// lost a byte and passed the checksum with the next frame's 0x20 ends in 0x20 and is followed by that frame's
    /// second sync byte: the next sync pair one byte early.
    #[cold]
    fn garbage_after_held(&mut self, first: u8) -> Option<Decoded> {
        match core::mem::replace(&mut self.held, Held::None) {
            Held::AwaitSync(raw, end)
                if self.held_continues && !(raw[FRAME_LEN - 1] == SYNC0 && is_sync1(first)) =>
            {
                self.emit(raw, end)
            }
            _ => {
                self.stats.bytes_skipped += FRAME_LEN as u64;
                None
            }
        }
    }

    /// Releases a confirmed frame, updating counters.
    fn emit(&mut self, raw: [u8; FRAME_LEN], end_offset: u64) -> Option<Decoded> {
        let frame = Frame::from_checked(&raw);
        let mut lost_before = 0;
        match frame {
            Frame::Sensor(_) => {
                if let Some(prev) = self.last_sensor {
                    if prev == raw {
                        self.stats.duplicates += 1;
                        return None;
                    }
                    lost_before = raw[2].wrapping_sub(prev[2]).wrapping_sub(1);
                }
                self.last_sensor = Some(raw);
                self.stats.lost += u64::from(lost_before);
                self.stats.sensor_frames += 1;
            }
            Frame::Status(_) => {
                if self.last_status == Some(raw) {
                    self.stats.duplicates += 1;
                    return None;
                }
                self.last_status = Some(raw);
                self.stats.status_frames += 1;
            }
        }
        Some(Decoded {
            frame,
            end_offset,
            lost_before,
        })
    }
}

/// The bytes of a frame that continuation looks at: kind (byte 1), counter or sequence (2), sensor counter (3).
#[derive(Clone, Copy)]
struct Header([u8; 3]);

impl Header {
    fn of(raw: &[u8; FRAME_LEN]) -> Header {
        Header([raw[1], raw[2], raw[3]])
    }

    /// Whether frame `b`, received directly after this one, is what the pen sends next (see the module docs).
    #[inline]
    fn continued_by(self, b: &[u8; FRAME_LEN]) -> bool {
        let [kind, count, sensor_count] = self.0;
        match (kind == SENSOR_SYNC1, b[1] == SENSOR_SYNC1) {
            (true, true) => b[2] == count.wrapping_add(1),
            (true, false) => b[3] == count,
            (false, true) => b[2] == sensor_count.wrapping_add(1),
            (false, false) => b[2] == count.wrapping_add(1),
        }
    }
}
