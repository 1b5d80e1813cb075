//! The Bluegiga WT12 running iWRAP: reply/event parser ([`parser`]), provisioning state machine and link monitor
//! ([`provision`]), and [`provision_module`], the async driver that runs the state machine over a UART.

pub mod parser;
pub mod provision;

use embassy_time::{with_deadline, Instant};

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
