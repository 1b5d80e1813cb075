//! Debounce and long-press detection for the four mode buttons.
//!
//! The application samples the raw pin levels (after an EXTI edge, then every [`POLL_PERIOD`] while anything is
//! pressed or unsettled) and feeds them to [`Debouncer::update`]. A level must hold for [`DEBOUNCE`] to count. A
//! button held for [`LONG_PRESS`] produces one long-press event; button 1 doubles as the power button, whose long
//! press turns the pen off. A button already pressed when the debouncer starts (the power button that was just
//! used to turn the pen on) is ignored until it is released, so holding it at power-on does not turn the pen off.

use embassy_time::{Duration, Instant};
use fires_protocol::Buttons;

/// Time a level must be stable to count.
pub const DEBOUNCE: Duration = Duration::from_millis(20);
/// Hold time of a long press (thesis App. B: about 5 s turns the pen off).
pub const LONG_PRESS: Duration = Duration::from_secs(5);
/// How often the application samples while a button is pressed or bouncing.
pub const POLL_PERIOD: Duration = Duration::from_millis(5);
/// Index of the power button.
pub const POWER_BUTTON: usize = 0;

/// What one update found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ButtonEvents {
    /// The debounced state changed to this.
    pub changed: Option<Buttons>,
    /// This button has just been held for [`LONG_PRESS`].
    pub long_press: Option<usize>,
}

/// Debouncer of the four buttons.
#[derive(Clone, Debug)]
pub struct Debouncer {
    stable: [bool; 4],
    candidate: [bool; 4],
    since: [Instant; 4],
    /// Long press already reported (or suppressed) for the current press.
    long_done: [bool; 4],
}

impl Debouncer {
    /// Starts with the levels read at power-on; buttons already held are ignored until released.
    pub fn new(raw: [bool; 4], now: Instant) -> Self {
        Debouncer {
            stable: [false; 4],
            candidate: raw,
            since: [now; 4],
            long_done: raw,
        }
    }

    /// Debounced state (a held-at-boot button reads released until it is released and pressed again).
    pub fn state(&self) -> Buttons {
        Buttons::from_states(self.stable)
    }

    /// Whether the application should keep polling (something pressed or not yet settled).
    pub fn busy(&self) -> bool {
        self.candidate.iter().any(|&c| c) || self.candidate != self.stable
    }

    /// Feeds the raw levels at `now`.
    pub fn update(&mut self, raw: [bool; 4], now: Instant) -> ButtonEvents {
        let mut ev = ButtonEvents::default();
        let mut changed = false;
        for (i, &level) in raw.iter().enumerate() {
            if level != self.candidate[i] {
                self.candidate[i] = level;
                self.since[i] = now;
                if !level {
                    // any release re-arms the long press
                    self.long_done[i] = false;
                }
            }
            let held = now.saturating_duration_since(self.since[i]);
            if self.candidate[i] != self.stable[i] && held >= DEBOUNCE {
                // a held-at-boot button never becomes "pressed" until a fresh press
                if !(self.candidate[i] && self.long_done[i]) {
                    self.stable[i] = self.candidate[i];
                    changed = true;
                }
            }
            if self.stable[i] && self.candidate[i] && !self.long_done[i] && held >= LONG_PRESS {
                self.long_done[i] = true;
                ev.long_press.get_or_insert(i);
            }
        }
        if changed {
            ev.changed = Some(self.state());
        }
        ev
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(ms: u64) -> Instant {
        Instant::from_millis(ms)
    }
    const NONE: [bool; 4] = [false; 4];
    const B1: [bool; 4] = [true, false, false, false];
    const B3: [bool; 4] = [false, false, true, false];

    #[test]
    fn bounces_are_filtered() {
        let mut d = Debouncer::new(NONE, t(0));
        assert_eq!(d.update(B3, t(100)).changed, None);
        assert_eq!(d.update(NONE, t(105)).changed, None); // bounce
        assert_eq!(d.update(B3, t(110)).changed, None);
        assert_eq!(d.update(B3, t(125)).changed, None); // 15 ms
        assert_eq!(d.update(B3, t(130)).changed, Some(Buttons(0b0100)));
        assert!(d.busy());
        assert_eq!(d.update(NONE, t(200)).changed, None);
        assert_eq!(d.update(NONE, t(220)).changed, Some(Buttons(0)));
        assert!(!d.busy());
    }

    #[test]
    fn long_press_once_per_press() {
        let mut d = Debouncer::new(NONE, t(0));
        d.update(B1, t(1000));
        d.update(B1, t(1020));
        assert_eq!(d.update(B1, t(5999)).long_press, None);
        assert_eq!(d.update(B1, t(6000)).long_press, Some(POWER_BUTTON));
        assert_eq!(d.update(B1, t(9000)).long_press, None);
        d.update(NONE, t(9100));
        d.update(NONE, t(9200));
        d.update(B1, t(10_000));
        assert_eq!(d.update(B1, t(15_000)).long_press, Some(0));
    }

    #[test]
    fn button_held_at_power_on_is_ignored_until_released() {
        let mut d = Debouncer::new(B1, t(0));
        assert_eq!(d.update(B1, t(30)).changed, None);
        assert_eq!(d.update(B1, t(6000)).long_press, None);
        assert_eq!(d.state(), Buttons(0));
        d.update(NONE, t(6100));
        d.update(NONE, t(6200));
        d.update(B1, t(7000));
        assert_eq!(d.update(B1, t(7020)).changed, Some(Buttons(1)));
    }
}
