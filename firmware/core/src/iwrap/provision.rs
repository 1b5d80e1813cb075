//! Provisioning of the WT12 at every boot, as a sans-IO state machine, plus the link monitor used afterwards.
//!
//! The sequence (hardware-docs/wt12.md explains each command):
//! 1. **Probe** the module's baud rate: at each of [`PROBE_BAUDS`] send `AT` and wait for `OK`. Garbage (the
//!    module answers at another rate) or silence moves on to the next rate.
//! 2. **Configure**: each command of [`commands`] is sent followed by `AT`. iWRAP prints nothing for a successful
//!    `SET`, `SYNTAX ERROR` for a rejected one, and `OK` for `AT`; so an `OK` proves the command went through and
//!    the link to the module is intact. `SET CONTROL BAUD` switches the module's rate at once: the MCU follows
//!    before the `AT`.
//! 3. **Reset** the module (`RESET`) so the profile settings take effect, and wait for `READY.` at the final rate.
//!
//! Every failure (timeout, garbage, `SYNTAX ERROR`, `ERROR`, an unexpected `READY.`) backs off exponentially
//! ([`backoff`]), pulses the module's reset line every other failure, re-probes the rate (a failed `SET CONTROL
//! BAUD` leaves it unknown) and retries the same command. After [`MAX_FAILURES`] failures in a row the provisioner
//! gives up with [`ProvisionError`].

use embassy_time::{Duration, Instant};
use heapless::{Deque, String};

use super::parser::Event;

/// Baud rates tried in order: FIRES's own (an already provisioned module), the iWRAP factory default, and the
/// rate some older firmware ships with.
pub const PROBE_BAUDS: [u32; 3] = [fires_protocol::LINK_BAUD, 115_200, 9_600];
/// Time to wait for `OK` after `AT` while probing.
pub const PROBE_TIMEOUT: Duration = Duration::from_millis(300);
/// Time to wait for the reply to a command.
pub const COMMAND_TIMEOUT: Duration = Duration::from_millis(800);
/// Time to wait for `READY.` after `RESET`.
pub const RESET_TIMEOUT: Duration = Duration::from_secs(5);
/// Consecutive failures before giving up.
pub const MAX_FAILURES: u8 = 6;

/// Back-off before retry number `failures` (1-based): 200 ms, 400 ms, ... capped at 3.2 s.
pub fn backoff(failures: u8) -> Duration {
    let exp = u32::from(failures.saturating_sub(1).min(4));
    Duration::from_millis(200 << exp)
}

/// What the pen's module must be set to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Config {
    /// Bluetooth friendly name.
    pub name: &'static str,
    /// Pairing PIN.
    pub pin: &'static str,
    /// Final UART rate.
    pub baud: u32,
}

impl Config {
    /// The FIRES pen: name "FIRES-Pen", PIN 1234, 230400 baud.
    pub const FIRES: Config = Config {
        name: "FIRES-Pen",
        pin: "1234",
        baud: fires_protocol::LINK_BAUD,
    };
}

/// Longest command line sent.
pub const MAX_COMMAND: usize = 48;
/// A line to send, CR LF included.
pub type Line = String<MAX_COMMAND>;

/// Number of configuration commands.
pub const COMMAND_COUNT: usize = 7;

/// Builds configuration command `index` (0..[`COMMAND_COUNT`]) without its line end.
pub fn commands(config: &Config, index: usize) -> Line {
    use core::fmt::Write;
    let mut s = Line::new();
    // Every line fits MAX_COMMAND for names up to 24 bytes; a longer name is cut by the capacity error.
    let _ = match index {
        0 => write!(s, "SET BT NAME {}", config.name),
        1 => write!(s, "SET BT AUTH * {}", config.pin),
        2 => write!(s, "SET BT PAGEMODE 3 2000 1"),
        3 => write!(s, "SET PROFILE SPP {}", config.name),
        4 => write!(s, "SET CONTROL ESCAPE - 40 1"),
        5 => write!(s, "SET CONTROL CONFIG 4000"),
        _ => write!(s, "SET CONTROL BAUD {},8n1", config.baud),
    };
    s
}

/// Index of the baud-rate command in [`commands`].
const BAUD_COMMAND: usize = COMMAND_COUNT - 1;

/// Something the driver must do, in order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Action {
    /// Reconfigure the MCU's UART to this rate (and forget any partial line).
    SetBaud(u32),
    /// Send these bytes.
    Send(Line),
    /// Pulse the module's hardware reset line.
    ResetModule,
}

/// Why provisioning gave up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ProvisionError {
    /// The module never answered `AT` at any rate.
    NoResponse,
    /// The module kept rejecting or not confirming configuration command `step`.
    CommandFailed {
        /// Index into [`commands`].
        step: u8,
    },
    /// The module did not come back with `READY.` after `RESET`.
    NoReadyAfterReset,
}

/// Where the provisioner is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Phase {
    /// Probing rate `PROBE_BAUDS[index]`.
    Probe {
        /// Index into [`PROBE_BAUDS`].
        index: u8,
    },
    /// Waiting for the `OK` after command `step`.
    Command {
        /// Index into [`commands`].
        step: u8,
    },
    /// Waiting for `READY.` after `RESET`.
    Resetting,
    /// Waiting out a back-off.
    Backoff,
    /// Done: the module runs at the configured rate.
    Done,
    /// Gave up.
    Failed(ProvisionError),
}

/// The provisioning state machine. Feed it parser events and time; drain its actions.
#[derive(Debug)]
pub struct Provisioner {
    config: Config,
    phase: Phase,
    deadline: Instant,
    /// Command to continue with once the rate is known again.
    resume_step: u8,
    failures: u8,
    total_failures: u32,
    baud: u32,
    actions: Deque<Action, 4>,
}

impl Provisioner {
    /// Starts probing at `now`.
    pub fn new(config: Config, now: Instant) -> Self {
        let mut p = Provisioner {
            config,
            phase: Phase::Backoff,
            deadline: now,
            resume_step: 0,
            failures: 0,
            total_failures: 0,
            baud: PROBE_BAUDS[0],
            actions: Deque::new(),
        };
        p.enter_probe(0, now);
        p
    }

    /// Current phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// The UART rate the MCU should be using now.
    pub fn baud(&self) -> u32 {
        self.baud
    }

    /// Failures since the start (including recovered ones).
    pub fn total_failures(&self) -> u32 {
        self.total_failures
    }

    /// The next thing to do, if any.
    pub fn next_action(&mut self) -> Option<Action> {
        self.actions.pop_front()
    }

    /// `Some(Ok(baud))` when done, `Some(Err(..))` when failed, `None` while working.
    pub fn result(&self) -> Option<Result<u32, ProvisionError>> {
        match self.phase {
            Phase::Done => Some(Ok(self.baud)),
            Phase::Failed(e) => Some(Err(e)),
            _ => None,
        }
    }

    /// When [`Provisioner::on_time`] must be called if nothing arrives before.
    pub fn deadline(&self) -> Option<Instant> {
        self.result().is_none().then_some(self.deadline)
    }

    fn push(&mut self, a: Action) {
        // The queue never holds more than 3 actions between drains.
        let _ = self.actions.push_back(a);
    }

    fn send(&mut self, text: &str) {
        let mut l = Line::new();
        let _ = l.push_str(text);
        let _ = l.push_str("\r\n");
        self.push(Action::Send(l));
    }

    fn enter_probe(&mut self, index: u8, now: Instant) {
        self.phase = Phase::Probe { index };
        self.baud = PROBE_BAUDS[usize::from(index)];
        self.push(Action::SetBaud(self.baud));
        // The leading CR LF ends any half-typed line in the module so that AT stands on its own.
        let mut l = Line::new();
        let _ = l.push_str("\r\nAT\r\n");
        self.push(Action::Send(l));
        self.deadline = now + PROBE_TIMEOUT;
    }

    fn enter_command(&mut self, step: u8, now: Instant) {
        if usize::from(step) >= COMMAND_COUNT {
            self.phase = Phase::Resetting;
            self.send("RESET");
            self.deadline = now + RESET_TIMEOUT;
            return;
        }
        self.phase = Phase::Command { step };
        let cmd = commands(&self.config, usize::from(step));
        self.send(&cmd);
        if usize::from(step) == BAUD_COMMAND {
            self.baud = self.config.baud;
            self.push(Action::SetBaud(self.baud));
        }
        self.send("AT");
        self.deadline = now + COMMAND_TIMEOUT;
    }

    fn fail(&mut self, error: ProvisionError, now: Instant) {
        self.failures += 1;
        self.total_failures += 1;
        if self.failures >= MAX_FAILURES {
            self.phase = Phase::Failed(error);
            return;
        }
        if self.failures % 2 == 0 {
            self.push(Action::ResetModule);
        }
        self.phase = Phase::Backoff;
        self.deadline = now + backoff(self.failures);
    }

    /// Handles one parser event.
    pub fn on_event(&mut self, event: Event, now: Instant) {
        match (self.phase, event) {
            (Phase::Probe { .. }, Event::Ok) => {
                let step = self.resume_step;
                self.enter_command(step, now);
            }
            (Phase::Probe { index }, Event::Garbage) => self.next_probe(index, now),
            (Phase::Command { step }, Event::Ok) => {
                self.failures = 0;
                self.resume_step = step + 1;
                self.enter_command(step + 1, now);
            }
            (
                Phase::Command { step },
                Event::SyntaxError | Event::Error | Event::Garbage | Event::Ready,
            ) => self.fail(ProvisionError::CommandFailed { step }, now),
            (Phase::Resetting, Event::Ready) => {
                self.failures = 0;
                self.phase = Phase::Done;
            }
            (Phase::Resetting, Event::Garbage) => self.fail(ProvisionError::NoReadyAfterReset, now),
            _ => {}
        }
    }

    fn next_probe(&mut self, index: u8, now: Instant) {
        if usize::from(index) + 1 < PROBE_BAUDS.len() {
            self.enter_probe(index + 1, now);
        } else {
            self.fail(ProvisionError::NoResponse, now);
        }
    }

    /// Handles the passage of time (call at or after [`Provisioner::deadline`]).
    pub fn on_time(&mut self, now: Instant) {
        if now < self.deadline {
            return;
        }
        match self.phase {
            Phase::Probe { index } => self.next_probe(index, now),
            Phase::Command { step } => self.fail(ProvisionError::CommandFailed { step }, now),
            Phase::Resetting => self.fail(ProvisionError::NoReadyAfterReset, now),
            Phase::Backoff => {
                if self.resume_step as usize >= COMMAND_COUNT {
                    // RESET was sent with the module at the final rate; retry it directly.
                    self.enter_command(self.resume_step, now);
                } else {
                    self.enter_probe(0, now);
                }
            }
            Phase::Done | Phase::Failed(_) => {}
        }
    }
}

/// Link state change reported by [`LinkMonitor`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LinkChange {
    /// A host connected: the UART now carries the SPP data.
    Connected,
    /// The link closed or dropped: the module is back in command mode.
    Disconnected,
}

/// Tracks the SPP link from iWRAP events after provisioning.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinkMonitor {
    connected: bool,
}

impl LinkMonitor {
    /// Not connected.
    pub const fn new() -> Self {
        LinkMonitor { connected: false }
    }

    /// Whether a host is connected.
    pub fn connected(&self) -> bool {
        self.connected
    }

    /// Handles one event; returns a change of state.
    pub fn on_event(&mut self, event: Event) -> Option<LinkChange> {
        match event {
            Event::Ring { .. } | Event::Connect { .. } if !self.connected => {
                self.connected = true;
                Some(LinkChange::Connected)
            }
            // A module that reboots (READY.) has lost the link too.
            Event::NoCarrier { .. } | Event::Ready if self.connected => {
                self.connected = false;
                Some(LinkChange::Disconnected)
            }
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::string::ToString;
    use std::vec::Vec;

    fn drain(p: &mut Provisioner) -> Vec<Action> {
        core::iter::from_fn(|| p.next_action()).collect()
    }

    fn sends(actions: &[Action]) -> Vec<std::string::String> {
        actions
            .iter()
            .filter_map(|a| match a {
                Action::Send(l) => Some(l.as_str().to_string()),
                _ => None,
            })
            .collect()
    }

    fn t(ms: u64) -> Instant {
        Instant::from_millis(ms)
    }

    #[test]
    fn command_list() {
        let c = Config::FIRES;
        let all: Vec<Line> = (0..COMMAND_COUNT).map(|i| commands(&c, i)).collect();
        assert_eq!(all[0].as_str(), "SET BT NAME FIRES-Pen");
        assert_eq!(all[1].as_str(), "SET BT AUTH * 1234");
        assert_eq!(all[3].as_str(), "SET PROFILE SPP FIRES-Pen");
        assert_eq!(all[6].as_str(), "SET CONTROL BAUD 230400,8n1");
    }

    #[test]
    fn happy_path_on_factory_module() {
        let mut p = Provisioner::new(Config::FIRES, t(0));
        let a = drain(&mut p);
        assert_eq!(a[0], Action::SetBaud(230_400));
        assert_eq!(sends(&a), ["\r\nAT\r\n"]);
        // factory module at 115200: silence at 230400 (or garbage)
        p.on_event(Event::Garbage, t(10));
        let a = drain(&mut p);
        assert_eq!(a[0], Action::SetBaud(115_200));
        p.on_event(Event::Ok, t(20));
        let mut now = 20;
        for step in 0..COMMAND_COUNT {
            let a = drain(&mut p);
            let s = sends(&a);
            assert_eq!(s[0], std::format!("{}\r\n", commands(&Config::FIRES, step)));
            assert_eq!(s[1], "AT\r\n");
            if step == COMMAND_COUNT - 1 {
                // the MCU follows the module to the new rate before AT
                assert_eq!(a[1], Action::SetBaud(230_400));
            }
            now += 15;
            p.on_event(Event::Ok, t(now));
        }
        assert_eq!(sends(&drain(&mut p)), ["RESET\r\n"]);
        assert_eq!(p.phase(), Phase::Resetting);
        p.on_event(Event::Banner, t(now + 100));
        p.on_event(Event::Ready, t(now + 200));
        assert_eq!(p.result(), Some(Ok(230_400)));
        assert_eq!(p.deadline(), None);
    }

    #[test]
    fn syntax_error_backs_off_and_retries_same_command() {
        let mut p = Provisioner::new(Config::FIRES, t(0));
        drain(&mut p);
        p.on_event(Event::Ok, t(5)); // already at 230400
        drain(&mut p);
        p.on_event(Event::Ok, t(10)); // NAME ok
        drain(&mut p);
        p.on_event(Event::SyntaxError, t(20)); // AUTH rejected
        assert_eq!(p.phase(), Phase::Backoff);
        assert_eq!(p.deadline(), Some(t(20) + backoff(1)));
        p.on_time(t(19) + backoff(1)); // too early: nothing
        assert_eq!(p.phase(), Phase::Backoff);
        p.on_time(t(20) + backoff(1));
        assert_eq!(p.phase(), Phase::Probe { index: 0 });
        drain(&mut p);
        p.on_event(Event::Ok, t(500));
        let s = sends(&drain(&mut p));
        assert_eq!(s[0], "SET BT AUTH * 1234\r\n");
        assert_eq!(p.total_failures(), 1);
    }

    #[test]
    fn silent_module_gives_up_with_growing_backoff_and_resets() {
        let mut p = Provisioner::new(Config::FIRES, t(0));
        let mut resets = 0;
        let mut backoffs = Vec::new();
        let mut now = t(0);
        for _ in 0..200 {
            for a in drain(&mut p) {
                if a == Action::ResetModule {
                    resets += 1;
                }
            }
            let Some(d) = p.deadline() else { break };
            if p.phase() == Phase::Backoff {
                backoffs.push(d - now);
            }
            now = d;
            p.on_time(now);
        }
        assert_eq!(p.result(), Some(Err(ProvisionError::NoResponse)));
        assert_eq!(
            backoffs,
            (1..MAX_FAILURES).map(backoff).collect::<Vec<_>>(),
            "exponential back-off"
        );
        assert_eq!(resets, (MAX_FAILURES as usize - 1) / 2);
        assert_eq!(backoff(1), Duration::from_millis(200));
        assert_eq!(backoff(9), Duration::from_millis(3200));
    }

    #[test]
    fn link_monitor_connect_and_drop() {
        let mut m = LinkMonitor::new();
        assert_eq!(m.on_event(Event::Ok), None);
        assert_eq!(
            m.on_event(Event::Ring { link: 0 }),
            Some(LinkChange::Connected)
        );
        assert!(m.connected());
        assert_eq!(m.on_event(Event::Connect { link: 0 }), None);
        assert_eq!(
            m.on_event(Event::NoCarrier { link: 0 }),
            Some(LinkChange::Disconnected)
        );
        assert_eq!(m.on_event(Event::NoCarrier { link: 0 }), None);
        m.on_event(Event::Ring { link: 0 });
        assert_eq!(m.on_event(Event::Ready), Some(LinkChange::Disconnected));
    }
}
