//! Timing the pen's packets on the host clock. Sensor packets carry no timestamp, only an 8-bit counter, and the
//! pen samples at a fixed rate, so packet `k` was sampled at `t_k = a + k·T`: the counter is unwrapped with the
//! arrival times, and the anchor `a` is the lower envelope of `arrival_k − k·T` (the radio only adds latency,
//! so the earliest-arriving packet is the best anchor). Button changes come from status packets, timed at the
//! sensor sample they name. [`crate::replay::imu_stream`] does this over a whole recording (the envelope of the
//! full session); [`LiveImuTimer`] does it packet by packet for live tracking (the envelope so far).

use fires_protocol::{DecoderStats, Frame, StreamDecoder, FRAME_LEN};
use fires_record::LinkChunk;

use crate::track::fusion::{ImuSample, ImuScale};

/// A pen button state change at a host time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ButtonChange {
    /// Host time of the change, nanoseconds.
    pub t_ns: u64,
    /// Buttons pressed (bit i = button i+1).
    pub buttons: u8,
}

/// Unwraps an 8-bit counter into a sample index: the index congruent to `counter` modulo 256 closest to
/// the guess from the previous packet's index and arrival time (survives outages longer than 256 packets).
pub(crate) fn unwrap_counter(
    prev: Option<(i64, u64)>,
    counter: u8,
    arrival_ns: u64,
    period_ns: f64,
) -> i64 {
    let Some((k0, t0)) = prev else {
        return i64::from(counter);
    };
    let guess = k0 as f64 + (arrival_ns as f64 - t0 as f64) / period_ns;
    let base = guess.round() as i64;
    let offset = (i64::from(counter) - base).rem_euclid(256);
    let k = if offset > 128 {
        base + offset - 256
    } else {
        base + offset
    };
    k.max(k0 + 1)
}

/// How many samples before the last decoded sensor packet the status's named counter lies: 0 normally,
/// negative when the sensor packet the status names was lost on the link (the status then names a later
/// counter than any decoded one; read modulo 256 that was a gap of 255, which put a pen-up 2.5 s early,
/// before its own pen-down, and lost the stroke).
pub(crate) fn prev_counter_gap(prev: Option<(i64, u64)>, sensor_counter: u8) -> i8 {
    match prev {
        Some((k, _)) => (k.rem_euclid(256) as u8).wrapping_sub(sensor_counter) as i8,
        None => 0,
    }
}

/// Samples between a button change and the status packet that reports it: 0 for the change packet,
/// the repeat's delay for a repeat (hardware-docs/protocol.md §1.2), 0 when unknown (a periodic report of
/// a change whose packets were all lost).
pub(crate) fn change_age_samples(reason: fires_protocol::StatusReason, period_ns: f64) -> i64 {
    reason
        .button_change_age_us()
        .map_or(0, |us| (f64::from(us) * 1e3 / period_ns).round() as i64)
}

/// A timed event from the link.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimedLinkEvent {
    /// An IMU sample in SI units.
    Imu(ImuSample),
    /// The buttons changed.
    Button(ButtonChange),
}

/// Packet-by-packet decoding and timing of a live link.
pub struct LiveImuTimer {
    decoder: StreamDecoder,
    scale: ImuScale,
    period_ns: f64,
    ns_per_byte: f64,
    packet_ns: f64,
    bytes: u64,
    /// (stream offset one past the chunk, host time) of the latest chunks.
    recent: std::collections::VecDeque<(u64, u64)>,
    prev: Option<(i64, u64)>,
    anchor: f64,
    last_t_ns: Option<u64>,
    buttons: Option<u8>,
}

impl LiveImuTimer {
    /// A timer for a link at `baud` carrying `sample_rate_hz` sensor packets per second.
    pub fn new(baud: u32, sample_rate_hz: u32, scale: ImuScale) -> Self {
        let ns_per_byte = 10.0e9 / f64::from(baud.max(1));
        LiveImuTimer {
            decoder: StreamDecoder::new(),
            scale,
            period_ns: 1e9 / f64::from(sample_rate_hz.max(1)),
            ns_per_byte,
            packet_ns: FRAME_LEN as f64 * ns_per_byte,
            bytes: 0,
            recent: std::collections::VecDeque::new(),
            prev: None,
            anchor: f64::INFINITY,
            last_t_ns: None,
            buttons: None,
        }
    }

    /// Decodes one chunk of link bytes (read at `chunk.host_time_ns`) and appends its timed events. Sample
    /// times never go backwards, even when a faster packet lowers the anchor.
    pub fn feed(&mut self, chunk: &LinkChunk, out: &mut Vec<TimedLinkEvent>) {
        self.bytes += chunk.bytes.len() as u64;
        let mut frames = Vec::new();
        self.decoder
            .feed(&chunk.bytes, |d| frames.push((d.frame, d.end_offset)));
        self.recent.push_back((self.bytes, chunk.host_time_ns));
        if self.recent.len() > 64 {
            self.recent.pop_front();
        }
        for (frame, end) in frames {
            // Timed by the chunk that delivered the frame's last byte (the decoder releases a frame only
            // when the next one begins, often in a later chunk), less the serial time of the bytes after it.
            let (chunk_end, chunk_ns) = self
                .recent
                .iter()
                .find(|(e, _)| *e >= end)
                .copied()
                .unwrap_or((self.bytes, chunk.host_time_ns));
            let after = chunk_end.saturating_sub(end);
            let arrival = chunk_ns.saturating_sub((after as f64 * self.ns_per_byte) as u64);
            self.time_frame(frame, arrival, out);
        }
    }

    /// Releases the frame the decoder still holds (the end of the session), timed at `host_time_ns`.
    pub fn finish(&mut self, host_time_ns: u64, out: &mut Vec<TimedLinkEvent>) {
        if let Some(d) = self.decoder.finish() {
            self.time_frame(d.frame, host_time_ns, out);
        }
    }

    fn time_frame(&mut self, frame: Frame, arrival: u64, out: &mut Vec<TimedLinkEvent>) {
        match frame {
            Frame::Sensor(p) => {
                let k = unwrap_counter(self.prev, p.counter, arrival, self.period_ns);
                self.prev = Some((k, arrival));
                let envelope = arrival as f64 - k as f64 * self.period_ns - self.packet_ns;
                self.anchor = self.anchor.min(envelope);
                let t = match self.last_t_ns {
                    Some(last) => self.grid_time(k).max(last + 1),
                    None => self.grid_time(k),
                };
                self.last_t_ns = Some(t);
                out.push(TimedLinkEvent::Imu(
                    self.scale.to_si(t, p.accel, p.gyro, p.mag),
                ));
            }
            Frame::Status(s) => {
                if self.buttons == Some(s.buttons.0) {
                    return;
                }
                self.buttons = Some(s.buttons.0);
                let t_ns = match self.prev {
                    Some((k, _)) => {
                        let gap = i64::from(prev_counter_gap(self.prev, s.sensor_counter));
                        let age = change_age_samples(s.reason, self.period_ns);
                        self.grid_time(k - gap - age)
                            .min(self.last_t_ns.unwrap_or(u64::MAX))
                    }
                    None => arrival,
                };
                out.push(TimedLinkEvent::Button(ButtonChange {
                    t_ns,
                    buttons: s.buttons.0,
                }));
            }
        }
    }

    /// The decoder's counters so far.
    pub fn stats(&self) -> DecoderStats {
        self.decoder.stats()
    }

    /// Host time of sample `k` on the current anchor.
    fn grid_time(&self, k: i64) -> u64 {
        (self.anchor + k as f64 * self.period_ns).max(0.0) as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fires_protocol::{Buttons, SensorPacket, StatusPacket, StatusReason};

    fn packet(k: u64) -> [u8; 22] {
        SensorPacket {
            counter: k as u8,
            ..Default::default()
        }
        .encode()
    }

    #[test]
    fn live_timing_settles_on_the_offline_grid() {
        let period = 10_000_000u64;
        let jitter = [3_000_000u64, 0, 7_000_000, 1_000_000, 4_000_000];
        let chunks: Vec<LinkChunk> = (0..600u64)
            .map(|k| LinkChunk {
                host_time_ns: 1_000_000_000 + k * period + 2_000_000 + jitter[(k % 5) as usize],
                bytes: packet(k).to_vec(),
            })
            .collect();
        let offline =
            crate::replay::imu_stream::imu_stream(&chunks, 230_400, 100, &ImuScale::default());
        let mut timer = LiveImuTimer::new(230_400, 100, ImuScale::default());
        let mut out = Vec::new();
        for c in &chunks {
            timer.feed(c, &mut out);
        }
        timer.finish(chunks.last().map_or(0, |c| c.host_time_ns), &mut out);
        let live: Vec<u64> = out
            .iter()
            .filter_map(|e| match e {
                TimedLinkEvent::Imu(s) => Some(s.t_ns),
                TimedLinkEvent::Button(_) => None,
            })
            .collect();
        assert_eq!(live.len(), 600);
        assert!(live.windows(2).all(|w| w[1] > w[0]));
        // After the fastest packet (the second) every time equals the offline one (to rounding).
        for (l, o) in live.iter().zip(&offline.samples).skip(1) {
            assert!(l.abs_diff(o.t_ns) <= 1_000, "{l} vs {}", o.t_ns);
        }
        assert!(live[0] - offline.samples[0].t_ns <= 3_000_000);
    }

    #[test]
    fn a_change_naming_a_lost_sample_or_told_by_a_repeat_lands_on_its_sample() {
        // Counters wrap at 256: packet 300 (counter 44) is lost and the pen-up status right after
        // packet 299 names it; the pen-down was told only by its first repeat, 3 samples late.
        let mut timer = LiveImuTimer::new(230_400, 100, ImuScale::default());
        let mut out = Vec::new();
        let status = |k: u64, seq: u8, pressed: bool, reason| {
            StatusPacket {
                sensor_counter: k as u8,
                sequence: seq,
                buttons: Buttons(u8::from(pressed)),
                reason,
                ..Default::default()
            }
            .encode()
        };
        for k in 0..320u64 {
            let mut bytes = if k == 300 {
                Vec::new()
            } else {
                packet(k).to_vec()
            };
            if k == 253 {
                bytes.extend(status(k, 1, true, StatusReason::ButtonRepeat(0)));
            }
            if k == 300 {
                bytes.extend(status(k, 2, false, StatusReason::ButtonChange));
            }
            timer.feed(
                &LinkChunk {
                    host_time_ns: k * 10_000_000 + 5_000_000,
                    bytes,
                },
                &mut out,
            );
        }
        let samples: Vec<u64> = out
            .iter()
            .filter_map(|e| match e {
                TimedLinkEvent::Imu(s) => Some(s.t_ns),
                TimedLinkEvent::Button(_) => None,
            })
            .collect();
        let changes: Vec<(u8, u64)> = out
            .iter()
            .filter_map(|e| match e {
                TimedLinkEvent::Button(b) => Some((b.buttons, b.t_ns)),
                TimedLinkEvent::Imu(_) => None,
            })
            .collect();
        assert_eq!(changes.len(), 2, "{changes:?}");
        // The live grid still settles (its anchor moves by less than half a period here).
        let near = |t: u64, s: u64| t.abs_diff(s) < 5_000_000;
        assert_eq!(changes[0].0, 1);
        assert!(near(changes[0].1, samples[250]), "{changes:?}");
        // Sample 300 was lost: the change is at the latest sample, 299 (live times never run ahead of
        // the samples), not 2.55 s before it.
        assert_eq!(changes[1].0, 0);
        assert!(near(changes[1].1, samples[299]), "{changes:?}");
    }

    #[test]
    fn live_button_changes_are_reported_once_at_the_named_sample() {
        let mut timer = LiveImuTimer::new(230_400, 100, ImuScale::default());
        let mut out = Vec::new();
        for k in 0..20u64 {
            let mut bytes = packet(k).to_vec();
            // Every state is sent twice (as the pen repeats status packets); changes are reported once.
            let pressed = (9..14).contains(&k);
            for _ in 0..2 {
                bytes.extend(
                    StatusPacket {
                        sensor_counter: k as u8,
                        sequence: (2 * k) as u8,
                        buttons: Buttons(u8::from(pressed)),
                        ..Default::default()
                    }
                    .encode(),
                );
            }
            timer.feed(
                &LinkChunk {
                    host_time_ns: k * 10_000_000 + 5_000_000,
                    bytes,
                },
                &mut out,
            );
        }
        let times: Vec<(u64, u64)> = out
            .iter()
            .enumerate()
            .filter_map(|(i, e)| match e {
                TimedLinkEvent::Button(b) => Some((i as u64, b.t_ns)),
                TimedLinkEvent::Imu(_) => None,
            })
            .collect();
        let presses: Vec<u8> = out
            .iter()
            .filter_map(|e| match e {
                TimedLinkEvent::Button(b) => Some(b.buttons),
                TimedLinkEvent::Imu(_) => None,
            })
            .collect();
        assert_eq!(presses, vec![0, 1, 0]);
        let sample_time = |k: usize| match out
            .iter()
            .filter(|e| matches!(e, TimedLinkEvent::Imu(_)))
            .nth(k)
        {
            Some(TimedLinkEvent::Imu(s)) => s.t_ns,
            _ => panic!("no sample {k}"),
        };
        assert_eq!(times[1].1, sample_time(9));
        assert_eq!(times[2].1, sample_time(14));
    }
}
