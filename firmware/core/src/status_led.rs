//! Status LED patterns (thesis App. B for start-up, IDLE and streaming; the rest are FIRES choices).
//!
//! | pen state                 | LED                                         |
//! |---------------------------|---------------------------------------------|
//! | start-up                  | green blinking, 200 ms on / 200 ms off      |
//! | IDLE                      | green steady                                |
//! | streaming                 | green slow blink, 500 ms on / 500 ms off    |
//! | radio not provisioned     | yellow steady (pen works, nobody can connect) |
//! | sensor fault              | red blinking, 250 ms on / 250 ms off        |
//! | turning off               | red steady                                  |
//!
//! The pattern is a pure function of the state and the time since the state was entered.

use embassy_time::{Duration, Instant};

/// Colour shown by the red/green (yellow = both) LED.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Color {
    /// Dark.
    Off,
    /// Red die.
    Red,
    /// Green die.
    Green,
    /// Yellow die (or red and green together on a bicolour part).
    Yellow,
}

/// What the LED shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LedState {
    /// Initialising.
    Starting,
    /// IDLE.
    Idle,
    /// Streaming.
    Streaming,
    /// The WT12 could not be provisioned.
    RadioFault,
    /// A sensor failed its identity check or self-test.
    SensorFault,
    /// Turning off.
    ShuttingDown,
}

/// One blink pattern: colour, on time, off time (`off` zero = steady).
fn pattern(state: LedState) -> (Color, u64, u64) {
    match state {
        LedState::Starting => (Color::Green, 200, 200),
        LedState::Idle => (Color::Green, 1, 0),
        LedState::Streaming => (Color::Green, 500, 500),
        LedState::RadioFault => (Color::Yellow, 1, 0),
        LedState::SensorFault => (Color::Red, 250, 250),
        LedState::ShuttingDown => (Color::Red, 1, 0),
    }
}

/// Colour at `now` for a state entered at `since`, and when it next changes (`None`: steady).
pub fn color_at(state: LedState, since: Instant, now: Instant) -> (Color, Option<Instant>) {
    let (color, on, off) = pattern(state);
    if off == 0 {
        return (color, None);
    }
    let period = on + off;
    let elapsed = now.saturating_duration_since(since).as_millis();
    let phase = elapsed % period;
    let start = now - Duration::from_millis(phase);
    if phase < on {
        (color, Some(start + Duration::from_millis(on)))
    } else {
        (Color::Off, Some(start + Duration::from_millis(period)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(state: LedState, ms: u64) -> (Color, Option<Instant>) {
        color_at(
            state,
            Instant::from_millis(1000),
            Instant::from_millis(1000 + ms),
        )
    }

    #[test]
    fn thesis_patterns() {
        assert_eq!(at(LedState::Idle, 12345), (Color::Green, None));
        assert_eq!(
            at(LedState::Starting, 0),
            (Color::Green, Some(Instant::from_millis(1200)))
        );
        assert_eq!(
            at(LedState::Starting, 250),
            (Color::Off, Some(Instant::from_millis(1400)))
        );
        assert_eq!(at(LedState::Streaming, 499).0, Color::Green);
        assert_eq!(
            at(LedState::Streaming, 500),
            (Color::Off, Some(Instant::from_millis(2000)))
        );
        assert_eq!(at(LedState::Streaming, 1000).0, Color::Green);
        assert_eq!(at(LedState::SensorFault, 260).0, Color::Off);
        assert_eq!(at(LedState::RadioFault, 7).0, Color::Yellow);
        assert_eq!(at(LedState::ShuttingDown, 7).0, Color::Red);
    }
}
