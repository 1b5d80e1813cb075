//! Power policy: IDLE auto-off after two minutes without activity (thesis App. B) and the long-press shutdown.
//!
//! The pen's supply is held on by the MCU (hardware-docs/board.md, power latch): pressing the power button
//! switches the regulator on through the latch's diode, firmware then holds `PWR_HOLD` high; releasing
//! `PWR_HOLD` turns the pen off. This module only decides *when*.

use embassy_time::{Duration, Instant};

/// IDLE time without activity after which the pen turns itself off.
pub const IDLE_TIMEOUT: Duration = Duration::from_secs(120);

/// Why the pen turns off.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PowerOffReason {
    /// Two minutes in IDLE without a button, command or link event.
    IdleTimeout,
    /// The power button was held for the long-press time.
    LongPress,
}

/// The IDLE auto-off timer.
#[derive(Clone, Copy, Debug)]
pub struct AutoOff {
    last_activity: Instant,
}

impl AutoOff {
    /// Starts counting at `now`.
    pub fn new(now: Instant) -> Self {
        AutoOff { last_activity: now }
    }

    /// Something happened: restart the count.
    pub fn activity(&mut self, now: Instant) {
        if now > self.last_activity {
            self.last_activity = now;
        }
    }

    /// When the pen turns off if it stays idle.
    pub fn deadline(&self) -> Instant {
        self.last_activity + IDLE_TIMEOUT
    }

    /// Whether the pen, idle (`idle` = not streaming), must turn off at `now`. Streaming restarts the count.
    pub fn expired(&mut self, idle: bool, now: Instant) -> bool {
        if !idle {
            self.activity(now);
            return false;
        }
        now >= self.deadline()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_minutes_of_idle() {
        let t0 = Instant::from_secs(10);
        let mut a = AutoOff::new(t0);
        assert!(!a.expired(true, t0 + Duration::from_secs(119)));
        a.activity(t0 + Duration::from_secs(60));
        assert!(!a.expired(true, t0 + Duration::from_secs(179)));
        assert!(a.expired(true, t0 + Duration::from_secs(180)));
        // streaming keeps it alive, and the count restarts when streaming stops
        assert!(!a.expired(false, t0 + Duration::from_secs(500)));
        assert!(!a.expired(true, t0 + Duration::from_secs(619)));
        assert!(a.expired(true, t0 + Duration::from_secs(620)));
    }
}
