//! Vibration and beep patterns, queued so that they never block streaming.
//!
//! [`FeedbackQueue::push`] never waits: a cue that does not fit is refused and counted. The application's
//! feedback task calls [`FeedbackQueue::poll`] at [`FeedbackQueue::next_change`] and sets the motor PWM and the
//! speaker tone from the returned [`Output`]. Motor and speaker have separate queues and run concurrently.
//! Durations are capped at [`MAX_STEP_MS`] so a corrupt or hostile command cannot keep the motor on.

use embassy_time::{Duration, Instant};
use heapless::Deque;

/// Longest single step, ms.
pub const MAX_STEP_MS: u16 = 5_000;
/// Steps each queue holds.
pub const QUEUE_LEN: usize = 16;

/// One step of a pattern.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Cue {
    /// Motor on for `ms`.
    Vibrate {
        /// Duration, ms.
        ms: u16,
    },
    /// Motor off for `ms` (a gap between two vibrations).
    MotorPause {
        /// Duration, ms.
        ms: u16,
    },
    /// Tone of `hz` for `ms` (`hz` 0 = silence).
    Tone {
        /// Frequency, Hz.
        hz: u16,
        /// Duration, ms.
        ms: u16,
    },
}

/// Power-on: two short rising beeps.
pub const BOOT: &[Cue] = &[
    Cue::Tone { hz: 1800, ms: 80 },
    Cue::Tone { hz: 0, ms: 40 },
    Cue::Tone { hz: 2400, ms: 80 },
];
/// A host connected: one short buzz.
pub const CONNECTED: &[Cue] = &[Cue::Vibrate { ms: 120 }];
/// The link dropped: two short buzzes.
pub const DISCONNECTED: &[Cue] = &[
    Cue::Vibrate { ms: 80 },
    Cue::MotorPause { ms: 80 },
    Cue::Vibrate { ms: 80 },
];
/// Turning off: one falling beep and a long buzz.
pub const POWER_OFF: &[Cue] = &[Cue::Tone { hz: 1200, ms: 300 }, Cue::Vibrate { ms: 300 }];

/// What the actuators should do now.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Output {
    /// Motor on.
    pub motor: bool,
    /// Speaker tone, Hz (None = silent).
    pub tone_hz: Option<u16>,
}

#[derive(Clone, Copy, Debug)]
struct Step {
    /// Motor: 1 = on, 0 = off. Speaker: frequency (0 = silent).
    level: u16,
    ms: u16,
}

#[derive(Debug)]
struct Channel {
    queue: Deque<Step, QUEUE_LEN>,
    current: Option<(Step, Instant)>,
}

impl Channel {
    const fn new() -> Self {
        Channel {
            queue: Deque::new(),
            current: None,
        }
    }

    /// Advances to the step active at `now`; returns its level.
    fn poll(&mut self, now: Instant) -> u16 {
        loop {
            match self.current {
                Some((step, end)) if now < end => return step.level,
                Some((_, end)) => {
                    // chain steps back to back from the previous end, not from `now`
                    self.current = self
                        .queue
                        .pop_front()
                        .map(|s| (s, end + Duration::from_millis(u64::from(s.ms))));
                }
                None => match self.queue.pop_front() {
                    Some(s) => {
                        self.current = Some((s, now + Duration::from_millis(u64::from(s.ms))));
                    }
                    None => return 0,
                },
            }
        }
    }

    fn end(&self) -> Option<Instant> {
        self.current.map(|(_, e)| e)
    }
}

/// The two actuator queues.
#[derive(Debug)]
pub struct FeedbackQueue {
    motor: Channel,
    speaker: Channel,
    refused: u32,
}

impl Default for FeedbackQueue {
    fn default() -> Self {
        Self::new()
    }
}

impl FeedbackQueue {
    /// Empty queues.
    pub const fn new() -> Self {
        FeedbackQueue {
            motor: Channel::new(),
            speaker: Channel::new(),
            refused: 0,
        }
    }

    /// Queues one cue; false (and counted) when its queue is full. Zero-length cues are ignored.
    pub fn push(&mut self, cue: Cue) -> bool {
        let (ch, step) = match cue {
            Cue::Vibrate { ms } => (&mut self.motor, Step { level: 1, ms }),
            Cue::MotorPause { ms } => (&mut self.motor, Step { level: 0, ms }),
            Cue::Tone { hz, ms } => (&mut self.speaker, Step { level: hz, ms }),
        };
        let step = Step {
            ms: step.ms.min(MAX_STEP_MS),
            ..step
        };
        if step.ms == 0 {
            return true;
        }
        if ch.queue.push_back(step).is_err() {
            self.refused = self.refused.wrapping_add(1);
            return false;
        }
        true
    }

    /// Queues a whole pattern (cue by cue; cues that do not fit are dropped). Returns whether all fitted.
    pub fn push_pattern(&mut self, cues: &[Cue]) -> bool {
        let mut all = true;
        for &c in cues {
            all &= self.push(c);
        }
        all
    }

    /// Cues refused since power-on.
    pub fn refused(&self) -> u32 {
        self.refused
    }

    /// Advances both queues to `now` and returns what the actuators should do.
    pub fn poll(&mut self, now: Instant) -> Output {
        let motor = self.motor.poll(now) != 0;
        let hz = self.speaker.poll(now);
        Output {
            motor,
            tone_hz: (hz != 0).then_some(hz),
        }
    }

    /// When the output next changes (None: both idle; poll again after the next push).
    pub fn next_change(&self) -> Option<Instant> {
        match (self.motor.end(), self.speaker.end()) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(ms: u64) -> Instant {
        Instant::from_millis(ms)
    }

    #[test]
    fn motor_and_speaker_run_concurrently_and_in_order() {
        let mut q = FeedbackQueue::new();
        assert!(q.push_pattern(DISCONNECTED));
        assert!(q.push(Cue::Tone { hz: 440, ms: 100 }));
        assert_eq!(
            q.poll(t(0)),
            Output {
                motor: true,
                tone_hz: Some(440)
            }
        );
        assert_eq!(q.next_change(), Some(t(80)));
        assert_eq!(
            q.poll(t(80)),
            Output {
                motor: false,
                tone_hz: Some(440)
            }
        );
        assert_eq!(q.poll(t(100)).tone_hz, None);
        assert!(q.poll(t(160)).motor);
        assert!(!q.poll(t(240)).motor);
        assert_eq!(q.next_change(), None);
    }

    #[test]
    fn never_blocks_refuses_when_full_and_caps_durations() {
        let mut q = FeedbackQueue::new();
        for _ in 0..QUEUE_LEN {
            assert!(q.push(Cue::Vibrate { ms: 60_000 }));
        }
        assert!(!q.push(Cue::Vibrate { ms: 10 }));
        assert_eq!(q.refused(), 1);
        q.poll(t(0));
        assert_eq!(q.next_change(), Some(t(u64::from(MAX_STEP_MS))));
        assert!(q.push(Cue::Tone { hz: 1000, ms: 0 })); // ignored
        assert_eq!(q.poll(t(1)).tone_hz, None);
    }
}
