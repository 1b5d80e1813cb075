//! The pen's mode controller: host commands, link events, buttons and the power policy in one state machine.
//!
//! | input                          | effect                                                               |
//! |--------------------------------|----------------------------------------------------------------------|
//! | `=` (start)                    | IDLE -> STREAMING, IR LEDs on                                        |
//! | `:` (stop)                     | STREAMING -> IDLE, IR LEDs off                                       |
//! | vibrate / beep                 | queued on the [`FeedbackQueue`] (never blocks)                       |
//! | IR LEDs on/off                 | switches the LEDs in any state (e.g. for camera calibration)         |
//! | status request                 | a status packet now ([`StatusReason::Requested`])                    |
//! | link connected                 | short buzz                                                           |
//! | link dropped                   | STREAMING -> IDLE, IR LEDs off, two buzzes                           |
//! | button change                  | a status packet now ([`StatusReason::ButtonChange`]), repeated 30 ms and 100 ms later |
//! | power button held 5 s          | turn off (any state)                                                 |
//! | 2 min in IDLE without activity | turn off                                                             |
//! | battery critical               | turn off (any state)                                                 |
//!
//! Commands, button changes and link events all count as activity for the auto-off timer. Commands only arrive
//! while a host is connected (the UART carries SPP data only then); `=` is nevertheless refused while not
//! connected, so a stray byte in command mode cannot start the stream.

use embassy_time::Instant;
use fires_protocol::{Command, StateFlags, StatusReason};

use crate::buttons::{ButtonEvents, POWER_BUTTON};
use crate::feedback::{self, Cue, FeedbackQueue};
use crate::iwrap::LinkChange;
use crate::power::{AutoOff, PowerOffReason};
use crate::status_led::LedState;

/// Operating mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Mode {
    /// Initialising sensors and radio.
    Starting,
    /// On, not streaming.
    Idle,
    /// Sampling and streaming sensor packets.
    Streaming,
    /// Turning off (terminal).
    Off(PowerOffReason),
}

/// What the application must do after an input.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Effects {
    /// Send a status packet now, for this reason.
    pub status: Option<StatusReason>,
    /// Turn off (play [`feedback::POWER_OFF`], then release the power latch).
    pub power_off: Option<PowerOffReason>,
}

/// The controller.
#[derive(Debug)]
pub struct Controller {
    mode: Mode,
    mode_since: Instant,
    connected: bool,
    ir_leds: bool,
    radio_ok: bool,
    sensors_ok: bool,
    auto_off: AutoOff,
}

impl Controller {
    /// Power-on at `now`: [`Mode::Starting`].
    pub fn new(now: Instant) -> Self {
        Controller {
            mode: Mode::Starting,
            mode_since: now,
            connected: false,
            ir_leds: false,
            radio_ok: true,
            sensors_ok: true,
            auto_off: AutoOff::new(now),
        }
    }

    fn set_mode(&mut self, mode: Mode, now: Instant) {
        if mode != self.mode {
            self.mode = mode;
            self.mode_since = now;
        }
    }

    /// Initialisation finished: IDLE. `sensors_ok`/`radio_ok` select the fault LED patterns.
    pub fn startup_done(&mut self, sensors_ok: bool, radio_ok: bool, now: Instant) {
        self.sensors_ok = sensors_ok;
        self.radio_ok = radio_ok;
        self.auto_off.activity(now);
        if self.mode == Mode::Starting {
            self.set_mode(Mode::Idle, now);
        }
    }

    /// Current mode.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// Whether sensor packets are to be sent.
    pub fn streaming(&self) -> bool {
        self.mode == Mode::Streaming && self.connected
    }

    /// Whether the IR LEDs are to be on.
    pub fn ir_leds(&self) -> bool {
        self.ir_leds
    }

    /// Whether a host is connected.
    pub fn connected(&self) -> bool {
        self.connected
    }

    /// State flags for the status packet.
    pub fn flags(&self) -> StateFlags {
        let mut f = 0;
        if self.streaming() {
            f |= StateFlags::STREAMING;
        }
        if self.ir_leds {
            f |= StateFlags::IR_LEDS_ON;
        }
        if self.connected {
            f |= StateFlags::CONNECTED;
        }
        StateFlags(f)
    }

    /// What the status LED shows, and since when.
    pub fn led(&self) -> (LedState, Instant) {
        let s = match self.mode {
            Mode::Starting => LedState::Starting,
            Mode::Off(_) => LedState::ShuttingDown,
            _ if !self.sensors_ok => LedState::SensorFault,
            _ if !self.radio_ok => LedState::RadioFault,
            Mode::Idle => LedState::Idle,
            Mode::Streaming => LedState::Streaming,
        };
        (s, self.mode_since)
    }

    fn off(&mut self, reason: PowerOffReason, now: Instant) -> Effects {
        if matches!(self.mode, Mode::Off(_)) {
            return Effects::default();
        }
        self.ir_leds = false;
        self.set_mode(Mode::Off(reason), now);
        Effects {
            status: None,
            power_off: Some(reason),
        }
    }

    /// A command from the host.
    pub fn on_command(
        &mut self,
        cmd: Command,
        feedback: &mut FeedbackQueue,
        now: Instant,
    ) -> Effects {
        if matches!(self.mode, Mode::Off(_)) {
            return Effects::default();
        }
        self.auto_off.activity(now);
        let mut fx = Effects::default();
        match cmd {
            Command::Start => {
                if self.connected && self.mode == Mode::Idle {
                    self.ir_leds = true;
                    self.set_mode(Mode::Streaming, now);
                }
            }
            Command::Stop => {
                if self.mode == Mode::Streaming {
                    self.ir_leds = false;
                    self.set_mode(Mode::Idle, now);
                }
            }
            Command::Vibrate { duration_ms } => {
                feedback.push(Cue::Vibrate { ms: duration_ms });
            }
            Command::Beep {
                frequency_hz,
                duration_ms,
            } => {
                feedback.push(Cue::Tone {
                    hz: frequency_hz,
                    ms: duration_ms,
                });
            }
            Command::IrLeds { on } => self.ir_leds = on,
            Command::RequestStatus => fx.status = Some(StatusReason::Requested),
        }
        fx
    }

    /// The SPP link came up or went down.
    pub fn on_link(&mut self, change: LinkChange, feedback: &mut FeedbackQueue, now: Instant) {
        self.auto_off.activity(now);
        match change {
            LinkChange::Connected => {
                self.connected = true;
                feedback.push_pattern(feedback::CONNECTED);
            }
            LinkChange::Disconnected => {
                self.connected = false;
                if self.mode == Mode::Streaming {
                    self.ir_leds = false;
                    self.set_mode(Mode::Idle, now);
                }
                feedback.push_pattern(feedback::DISCONNECTED);
            }
        }
    }

    /// Debounced button events.
    pub fn on_buttons(&mut self, ev: ButtonEvents, now: Instant) -> Effects {
        let mut fx = Effects::default();
        if ev.changed.is_some() {
            self.auto_off.activity(now);
            fx.status = Some(StatusReason::ButtonChange);
        }
        if ev.long_press == Some(POWER_BUTTON) {
            let off = self.off(PowerOffReason::LongPress, now);
            fx.power_off = off.power_off;
        }
        fx
    }

    /// The battery monitor says the cell is nearly empty: turn off (any state).
    pub fn on_battery_critical(&mut self, now: Instant) -> Effects {
        self.off(PowerOffReason::LowBattery, now)
    }

    /// Time passes: the IDLE auto-off.
    pub fn poll(&mut self, now: Instant) -> Effects {
        let idle = self.mode == Mode::Idle;
        if self.auto_off.expired(idle, now) && idle {
            return self.off(PowerOffReason::IdleTimeout, now);
        }
        Effects::default()
    }

    /// When [`Controller::poll`] next has something to do.
    pub fn next_deadline(&self) -> Instant {
        self.auto_off.deadline()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::buttons::ButtonEvents;
    use embassy_time::Duration;
    use fires_protocol::{Buttons, CommandParser};

    fn t(ms: u64) -> Instant {
        Instant::from_millis(ms)
    }

    fn ready() -> (Controller, FeedbackQueue) {
        let mut c = Controller::new(t(0));
        assert_eq!(c.led().0, LedState::Starting);
        c.startup_done(true, true, t(1500));
        assert_eq!(c.mode(), Mode::Idle);
        assert_eq!(c.led().0, LedState::Idle);
        (c, FeedbackQueue::new())
    }

    #[test]
    fn start_stop_over_the_wire() {
        let (mut c, mut fb) = ready();
        let mut parser = CommandParser::new();
        // '=' before any host is connected is refused
        let cmd = parser.push(b'=').unwrap();
        c.on_command(cmd, &mut fb, t(1600));
        assert!(!c.streaming());
        c.on_link(LinkChange::Connected, &mut fb, t(2000));
        assert!(fb.poll(t(2000)).motor, "connect buzz");
        c.on_command(parser.push(b'=').unwrap(), &mut fb, t(2100));
        assert!(c.streaming() && c.ir_leds());
        assert_eq!(c.led().0, LedState::Streaming);
        let f = c.flags();
        assert!(f.has(StateFlags::STREAMING | StateFlags::IR_LEDS_ON | StateFlags::CONNECTED));
        c.on_command(parser.push(b':').unwrap(), &mut fb, t(3000));
        assert!(!c.streaming() && !c.ir_leds());
        assert_eq!(c.mode(), Mode::Idle);
    }

    #[test]
    fn extended_commands() {
        let (mut c, mut fb) = ready();
        c.on_link(LinkChange::Connected, &mut fb, t(2000));
        fb.poll(t(2000));
        fb.poll(t(3000)); // connect buzz over
        let mut parser = CommandParser::new();
        let mut run = |c: &mut Controller, fb: &mut FeedbackQueue, cmd: Command| {
            let bytes = cmd.encode();
            let mut fx = Effects::default();
            for &b in bytes.as_bytes() {
                if let Some(parsed) = parser.push(b) {
                    fx = c.on_command(parsed, fb, t(3000));
                }
            }
            fx
        };
        run(&mut c, &mut fb, Command::Vibrate { duration_ms: 500 });
        run(
            &mut c,
            &mut fb,
            Command::Beep {
                frequency_hz: 2000,
                duration_ms: 100,
            },
        );
        let out = fb.poll(t(3000));
        assert!(out.motor);
        assert_eq!(out.tone_hz, Some(2000));
        run(&mut c, &mut fb, Command::IrLeds { on: true });
        assert!(c.ir_leds() && !c.streaming());
        let fx = run(&mut c, &mut fb, Command::RequestStatus);
        assert_eq!(fx.status, Some(StatusReason::Requested));
    }

    #[test]
    fn link_drop_mid_stream_returns_to_idle() {
        let (mut c, mut fb) = ready();
        c.on_link(LinkChange::Connected, &mut fb, t(2000));
        c.on_command(Command::Start, &mut fb, t(2100));
        c.on_link(LinkChange::Disconnected, &mut fb, t(9000));
        assert_eq!(c.mode(), Mode::Idle);
        assert!(!c.streaming() && !c.ir_leds() && !c.connected());
    }

    #[test]
    fn buttons_report_and_long_press_turns_off() {
        let (mut c, _) = ready();
        let fx = c.on_buttons(
            ButtonEvents {
                changed: Some(Buttons(0b10)),
                long_press: None,
            },
            t(5000),
        );
        assert_eq!(fx.status, Some(StatusReason::ButtonChange));
        // long press of a non-power button does nothing
        let fx = c.on_buttons(
            ButtonEvents {
                changed: None,
                long_press: Some(1),
            },
            t(10_000),
        );
        assert_eq!(fx.power_off, None);
        let fx = c.on_buttons(
            ButtonEvents {
                changed: None,
                long_press: Some(POWER_BUTTON),
            },
            t(11_000),
        );
        assert_eq!(fx.power_off, Some(PowerOffReason::LongPress));
        assert_eq!(c.led().0, LedState::ShuttingDown);
        assert_eq!(c.mode(), Mode::Off(PowerOffReason::LongPress));
    }

    #[test]
    fn idle_auto_off_after_two_minutes_but_not_while_streaming() {
        let (mut c, mut fb) = ready();
        let two_min = Duration::from_secs(120);
        assert_eq!(c.next_deadline(), t(1500) + two_min);
        assert_eq!(c.poll(t(1499) + two_min).power_off, None);
        c.on_link(LinkChange::Connected, &mut fb, t(60_000));
        c.on_command(Command::Start, &mut fb, t(61_000));
        assert_eq!(c.poll(t(1_000_000)).power_off, None, "streaming");
        c.on_command(Command::Stop, &mut fb, t(1_000_000));
        assert_eq!(
            c.poll(t(1_000_000) + two_min - Duration::from_millis(1))
                .power_off,
            None
        );
        assert_eq!(
            c.poll(t(1_000_000) + two_min).power_off,
            Some(PowerOffReason::IdleTimeout)
        );
        // only once
        assert_eq!(c.poll(t(2_000_000)).power_off, None);
    }

    #[test]
    fn critical_battery_turns_off_even_while_streaming() {
        let (mut c, mut fb) = ready();
        c.on_link(LinkChange::Connected, &mut fb, t(2000));
        c.on_command(Command::Start, &mut fb, t(2100));
        let fx = c.on_battery_critical(t(3000));
        assert_eq!(fx.power_off, Some(PowerOffReason::LowBattery));
        assert!(!c.streaming() && !c.ir_leds());
    }

    #[test]
    fn fault_leds() {
        let mut c = Controller::new(t(0));
        c.startup_done(false, true, t(10));
        assert_eq!(c.led().0, LedState::SensorFault);
        let mut c = Controller::new(t(0));
        c.startup_done(true, false, t(10));
        assert_eq!(c.led().0, LedState::RadioFault);
    }
}
