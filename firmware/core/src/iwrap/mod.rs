//! The Bluegiga WT12 running iWRAP: reply/event parser ([`parser`]), provisioning state machine and link monitor
//! ([`provision`]), and [`provision_module`], the async driver that runs the state machine over a UART.

pub mod parser;
pub mod provision;

use embassy_time::{with_deadline, Instant};
use fires_protocol::{Command, CommandParser};

pub use parser::{Event, LineParser};
pub use provision::{Action, Config, LinkChange, LinkMonitor, ProvisionError, Provisioner};

/// The MCU side of the module's UART, plus its reset line.
#[allow(async_fn_in_trait)] // single-threaded embedded executors: no Send bound needed
pub trait ModemPort {
    /// Write error.
    type Error;
    /// Sends all bytes.
    async fn write_all(&mut self, bytes: &[u8]) -> Result<(), Self::Error>;
    /// Waits for at least one byte and returns how many were stored. A receive error (framing, noise: what a
    /// wrong baud rate produces) is returned as `Err`, which the driver treats as garbage.
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error>;
    /// Reconfigures the UART rate.
    fn set_baud(&mut self, baud: u32);
    /// Pulses the module's reset line and returns when it is released.
    async fn reset_module(&mut self);
}

/// Runs [`Provisioner`] over `port` until it finishes. Returns the final baud rate.
pub async fn provision_module<P: ModemPort>(
    port: &mut P,
    config: Config,
) -> Result<u32, ProvisionError> {
    let mut prov = Provisioner::new(config, Instant::now());
    let mut parser = LineParser::new();
    let mut buf = [0u8; 32];
    loop {
        while let Some(action) = prov.next_action() {
            match action {
                Action::SetBaud(b) => {
                    port.set_baud(b);
                    parser.reset();
                }
                Action::Send(line) => {
                    if port.write_all(line.as_bytes()).await.is_err() {
                        prov.on_event(Event::Garbage, Instant::now());
                    }
                }
                Action::ResetModule => port.reset_module().await,
            }
        }
        if let Some(result) = prov.result() {
            return result;
        }
        let Some(deadline) = prov.deadline() else {
            continue;
        };
        match with_deadline(deadline, port.read(&mut buf)).await {
            Ok(Ok(n)) => {
                for &b in &buf[..n] {
                    if let Some(ev) = parser.push(b) {
                        prov.on_event(ev, Instant::now());
                    }
                }
            }
            Ok(Err(_)) => prov.on_event(Event::Garbage, Instant::now()),
            Err(_) => prov.on_time(Instant::now()),
        }
    }
}

/// Splits the module's UART output after provisioning into link events and host commands.
///
/// Every byte goes to the iWRAP line parser (so `NO CARRIER` is seen even while the link carries data); bytes
/// received while connected also go to the host command parser. Bytes received in command mode are never
/// commands: module text such as the `:` of a Bluetooth address in `RING 0 00:07:80:..` must not stop the pen.
#[derive(Debug, Default)]
pub struct RxRouter {
    lines: LineParser,
    link: LinkMonitor,
    commands: CommandParser,
}

impl RxRouter {
    /// Not connected.
    pub const fn new() -> Self {
        RxRouter {
            lines: LineParser::new(),
            link: LinkMonitor::new(),
            commands: CommandParser::new(),
        }
    }

    /// Whether a host is connected.
    pub fn connected(&self) -> bool {
        self.link.connected()
    }

    /// Host command parser totals.
    pub fn command_stats(&self) -> fires_protocol::CommandStats {
        self.commands.stats()
    }

    /// Feeds one received byte.
    pub fn push(&mut self, byte: u8) -> (Option<LinkChange>, Option<Command>) {
        let cmd = if self.link.connected() {
            self.commands.push(byte)
        } else {
            None
        };
        let change = self.lines.push(byte).and_then(|ev| self.link.on_event(ev));
        if change == Some(LinkChange::Connected) {
            self.commands = CommandParser::new();
        }
        (change, cmd)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec::Vec;

    #[test]
    fn connect_stream_and_drop_mid_stream() {
        let mut r = RxRouter::new();
        let mut transcript: Vec<u8> = Vec::new();
        transcript.extend_from_slice(b"PAIR 00:1A:7D:DA:71:13 6b8e5a1c\r\n"); // colons: not commands
        transcript.extend_from_slice(b"RING 0 00:1a:7d:da:71:13 1 RFCOMM\r\n");
        transcript.extend_from_slice(b"=");
        transcript.extend_from_slice(Command::Vibrate { duration_ms: 300 }.encode().as_bytes());
        transcript.extend_from_slice(b"=NO CARRIER 0 ERROR 0 \r\n"); // link lost mid-stream
        transcript.extend_from_slice(b":"); // command mode again: ignored
        let mut changes = Vec::new();
        let mut cmds = Vec::new();
        for &b in &transcript {
            let (c, k) = r.push(b);
            changes.extend(c);
            cmds.extend(k);
        }
        assert_eq!(changes, [LinkChange::Connected, LinkChange::Disconnected]);
        assert_eq!(
            cmds,
            [
                Command::Start,
                Command::Vibrate { duration_ms: 300 },
                Command::Start
            ]
        );
        assert!(!r.connected());
    }
}
