//! Status packets: once per second, immediately on any button change (repeated [`BUTTON_REPEATS`] later), on
//! the host's request, and once at boot.
//!
//! A status packet goes through the same [`FrameSink`] as the sensor packets, after whatever was queued before
//! it, and carries the counter (and device time) of the latest sensor packet *sent* ([`Framer`]); its sequence
//! number advances by one per status packet built, whether or not the sink took it.

use embassy_time::{Duration, Instant};
use fires_protocol::{
    Buttons, Health, StateFlags, StatusPacket, StatusReason, BUTTON_REPEAT_AFTER_US,
    PROTOCOL_VERSION,
};

use crate::board::FIRMWARE_VERSION;
use crate::sampler::{FrameSink, Framer};

/// Period of the periodic status packet.
pub const STATUS_PERIOD: Duration = Duration::from_secs(1);

/// When a button change is told again, after the change ([`StatusReason::ButtonRepeat`],
/// [`fires_protocol::BUTTON_REPEAT_AFTER_US`]): a lost change packet then costs nothing, not up to a
/// periodic report's second of the stroke (hardware-docs/protocol.md §1.2).
pub const BUTTON_REPEATS: [Duration; 2] = [
    Duration::from_micros(BUTTON_REPEAT_AFTER_US[0] as u64),
    Duration::from_micros(BUTTON_REPEAT_AFTER_US[1] as u64),
];

/// Device state a status packet reports.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StatusInputs {
    /// Debounced buttons.
    pub buttons: Buttons,
    /// Mode flags.
    pub flags: StateFlags,
    /// Sensor health.
    pub health: Health,
    /// Battery voltage, mV (0 = not measured).
    pub battery_mv: u16,
}

/// Builds and schedules status packets.
#[derive(Clone, Debug)]
pub struct StatusReporter {
    sequence: u8,
    next_periodic: Instant,
    refused: u32,
    /// When the latest button change was sent, and how many of its repeats went out.
    repeat: Option<(Instant, usize)>,
}

impl StatusReporter {
    /// A reporter whose first periodic packet is due one period after `now`.
    pub fn new(now: Instant) -> Self {
        StatusReporter {
            sequence: 0,
            next_periodic: now + STATUS_PERIOD,
            refused: 0,
            repeat: None,
        }
    }

    /// When the next repeat of the latest button change is due, if one is.
    pub fn next_repeat(&self) -> Option<Instant> {
        let (at, sent) = self.repeat.as_ref()?;
        BUTTON_REPEATS.get(*sent).map(|&d| *at + d)
    }

    /// Whether a repeat of the latest button change is due.
    pub fn repeat_due(&self, now: Instant) -> bool {
        self.next_repeat().is_some_and(|t| now >= t)
    }

    /// Sends the due repeat of the latest button change (a status packet of the current state with
    /// [`StatusReason::ButtonRepeat`]); `false` if none is due or the sink refused it.
    pub fn send_repeat(
        &mut self,
        inputs: &StatusInputs,
        framer: &Framer,
        now: Instant,
        sink: &mut impl FrameSink,
    ) -> bool {
        if !self.repeat_due(now) {
            return false;
        }
        let Some((_, sent)) = self.repeat.as_mut() else {
            return false;
        };
        let n = *sent as u8;
        *sent += 1;
        let p = self.build(
            StatusReason::ButtonRepeat(n),
            inputs,
            framer,
            now.as_micros() as u32,
        );
        let ok = sink.try_send(&p.encode());
        if !ok {
            self.refused = self.refused.wrapping_add(1);
        }
        ok
    }

    /// Whether the periodic packet is due.
    pub fn periodic_due(&self, now: Instant) -> bool {
        now >= self.next_periodic
    }

    /// When the next periodic packet is due.
    pub fn next_periodic(&self) -> Instant {
        self.next_periodic
    }

    /// Status packets the sink refused.
    pub fn refused(&self) -> u32 {
        self.refused
    }

    /// Moves the periodic schedule on by one period without sending (no host is listening). Never schedules
    /// into the past, so a stalled pen does not send a burst afterwards.
    pub fn skip_periodic(&mut self, now: Instant) {
        self.next_periodic += STATUS_PERIOD;
        if self.next_periodic <= now {
            self.next_periodic = now + STATUS_PERIOD;
        }
    }

    /// Builds the next status packet (consuming a sequence number).
    pub fn build(
        &mut self,
        reason: StatusReason,
        inputs: &StatusInputs,
        framer: &Framer,
        now_us: u32,
    ) -> StatusPacket {
        let seq = self.sequence;
        self.sequence = seq.wrapping_add(1);
        StatusPacket {
            sequence: seq,
            sensor_counter: framer.last_sent_counter(),
            device_time_us: framer.last_sent_time_us().unwrap_or(now_us),
            buttons: inputs.buttons,
            flags: inputs.flags,
            health: inputs.health,
            reason,
            battery_mv: inputs.battery_mv,
            dropped_packets: framer.dropped(),
            firmware_version: FIRMWARE_VERSION,
            protocol_version: PROTOCOL_VERSION,
        }
    }

    /// Builds a status packet and offers it to `sink`; a periodic packet also schedules the next one (never in
    /// the past, so a stalled pen does not send a burst). Returns whether the sink took it.
    pub fn send(
        &mut self,
        reason: StatusReason,
        inputs: &StatusInputs,
        framer: &Framer,
        now: Instant,
        sink: &mut impl FrameSink,
    ) -> bool {
        if reason == StatusReason::Periodic {
            self.skip_periodic(now);
        }
        let p = self.build(reason, inputs, framer, now.as_micros() as u32);
        if reason == StatusReason::ButtonChange {
            self.repeat = Some((now, 0));
        }
        let ok = sink.try_send(&p.encode());
        if !ok {
            self.refused = self.refused.wrapping_add(1);
        }
        ok
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::sampler::ImuSample;
    use fires_protocol::{Frame, FRAME_LEN};
    use std::vec::Vec;

    struct All(Vec<[u8; FRAME_LEN]>);
    impl FrameSink for All {
        fn try_send(&mut self, f: &[u8; FRAME_LEN]) -> bool {
            self.0.push(*f);
            true
        }
    }

    #[test]
    fn a_button_change_is_repeated_twice() {
        let t0 = Instant::from_millis(5_000);
        let mut r = StatusReporter::new(t0);
        let mut f = Framer::new();
        let mut sink = All(Vec::new());
        let inputs = StatusInputs {
            buttons: Buttons(1),
            ..Default::default()
        };
        assert!(!r.repeat_due(t0) && r.next_repeat().is_none());
        r.send(StatusReason::ButtonChange, &inputs, &f, t0, &mut sink);
        assert_eq!(r.next_repeat(), Some(t0 + BUTTON_REPEATS[0]));
        let early = t0 + Duration::from_millis(29);
        assert!(!r.send_repeat(&inputs, &f, early, &mut sink));
        // A sample in between: the repeat names it, keeping the continuation rule.
        f.sensor(&ImuSample::default(), 1234, &mut sink);
        assert!(r.send_repeat(&inputs, &f, t0 + Duration::from_millis(30), &mut sink));
        assert_eq!(r.next_repeat(), Some(t0 + BUTTON_REPEATS[1]));
        assert!(r.send_repeat(&inputs, &f, t0 + Duration::from_millis(150), &mut sink));
        assert!(r.next_repeat().is_none());
        assert!(!r.send_repeat(&inputs, &f, t0 + Duration::from_secs(5), &mut sink));
        let statuses: Vec<StatusPacket> = sink
            .0
            .iter()
            .filter_map(|b| match Frame::parse(b) {
                Ok(Frame::Status(s)) => Some(s),
                _ => None,
            })
            .collect();
        let reasons: Vec<StatusReason> = statuses.iter().map(|s| s.reason).collect();
        assert_eq!(
            reasons,
            [
                StatusReason::ButtonChange,
                StatusReason::ButtonRepeat(0),
                StatusReason::ButtonRepeat(1)
            ]
        );
        assert_eq!(statuses[1].sensor_counter, 0);
        assert_eq!(statuses[1].device_time_us, 1234);
        assert!(statuses.iter().all(|s| s.buttons == Buttons(1)));
        // A newer change replaces the pending repeats.
        let later = t0 + Duration::from_secs(6);
        r.send(StatusReason::ButtonChange, &inputs, &f, later, &mut sink);
        assert_eq!(r.next_repeat(), Some(later + BUTTON_REPEATS[0]));
    }

    #[test]
    fn carries_latest_sent_counter_and_schedules() {
        let t0 = Instant::from_millis(5_000);
        let mut r = StatusReporter::new(t0);
        let mut f = Framer::new();
        let mut sink = All(Vec::new());
        let inputs = StatusInputs {
            buttons: Buttons(0b0001),
            ..Default::default()
        };
        assert!(!r.periodic_due(t0 + Duration::from_millis(999)));
        assert!(r.periodic_due(t0 + STATUS_PERIOD));
        // before any sensor packet: counter 255, device time = now
        r.send(StatusReason::Boot, &inputs, &f, t0, &mut sink);
        f.sensor(&ImuSample::default(), 1234, &mut sink);
        r.send(
            StatusReason::Periodic,
            &inputs,
            &f,
            t0 + STATUS_PERIOD,
            &mut sink,
        );
        assert_eq!(r.next_periodic(), t0 + STATUS_PERIOD * 2);
        let frames: Vec<Frame> = sink.0.iter().map(|b| Frame::parse(b).unwrap()).collect();
        let Frame::Status(s0) = frames[0] else {
            panic!()
        };
        let Frame::Status(s1) = frames[2] else {
            panic!()
        };
        assert_eq!((s0.sequence, s0.sensor_counter), (0, 255));
        assert_eq!(s0.device_time_us, 5_000_000);
        assert_eq!(s0.reason, StatusReason::Boot);
        assert_eq!((s1.sequence, s1.sensor_counter), (1, 0));
        assert_eq!(s1.device_time_us, 1234);
        assert_eq!(s1.buttons, Buttons(1));
        assert_eq!(s1.protocol_version, PROTOCOL_VERSION);
        // a late periodic packet does not cause a burst
        r.send(
            StatusReason::Periodic,
            &inputs,
            &f,
            t0 + STATUS_PERIOD * 10,
            &mut sink,
        );
        assert_eq!(r.next_periodic(), t0 + STATUS_PERIOD * 11);
    }
}
