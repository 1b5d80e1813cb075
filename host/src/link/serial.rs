//! The pen's serial port (the WT12's SPP link, e.g. `/dev/rfcomm0`): reads raw bytes with host timestamps and
//! survives the device disappearing and coming back (Bluetooth out of range, pen switched off, cable pulled).
//!
//! Bytes already read are never lost: a disconnect is reported as an event between chunks, and the link reopens
//! the same path with exponential back-off. The link does not decode; feed its chunks to
//! [`fires_protocol::StreamDecoder`] (which resynchronises after the gap) or write them to a recording.

use std::io::{self, Read, Write};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use fires_protocol::{Command, LINK_BAUD};
use serialport::SerialPort;

use crate::clock::HostClock;

/// How to open and keep the port.
#[derive(Clone, Debug)]
pub struct SerialConfig {
    /// Device path (a stable name such as a udev symlink survives re-enumeration best).
    pub path: PathBuf,
    /// Baud rate; the pen's link runs at 230 400 (8N1).
    pub baud: u32,
    /// How long one read waits for bytes before reporting [`LinkEvent::Idle`].
    pub read_timeout: Duration,
    /// First wait before reopening after a disconnect; doubles up to `max_backoff`.
    pub min_backoff: Duration,
    /// Longest wait between reopen attempts.
    pub max_backoff: Duration,
}

impl SerialConfig {
    /// The pen's settings for `path`.
    pub fn pen(path: impl Into<PathBuf>) -> Self {
        SerialConfig {
            path: path.into(),
            baud: LINK_BAUD,
            read_timeout: Duration::from_millis(50),
            min_backoff: Duration::from_millis(50),
            max_backoff: Duration::from_secs(2),
        }
    }
}

/// Errors of the serial link.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// The port could not be opened at all.
    #[error("cannot open serial port {path}: {source}")]
    Open {
        /// The device path.
        path: PathBuf,
        /// What the OS said.
        source: serialport::Error,
    },
    /// A command could not be sent (the link is down).
    #[error("cannot send to the pen: {0}")]
    Send(io::Error),
}

/// What one call to [`SerialLink::poll`] saw.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LinkEvent {
    /// `len` bytes were read into the buffer, stamped with the host time of the read.
    Bytes {
        /// Host time when the read returned, nanoseconds.
        host_time_ns: u64,
        /// Number of bytes at the start of the buffer.
        len: usize,
    },
    /// Nothing arrived within the read timeout.
    Idle,
    /// The device went away; the link will try to reopen it.
    Disconnected {
        /// Host time of the disconnect, nanoseconds.
        host_time_ns: u64,
        /// What the OS said.
        reason: String,
    },
    /// The device is back (a reopen succeeded).
    Reconnected {
        /// Host time of the reconnect, nanoseconds.
        host_time_ns: u64,
    },
}

/// A pen serial link that reconnects by itself.
pub struct SerialLink {
    cfg: SerialConfig,
    clock: HostClock,
    port: Option<Box<dyn SerialPort>>,
    backoff: Duration,
    next_attempt: Instant,
}

impl SerialLink {
    /// Opens the port; a device that is not there at start is an error (a clear one, for the user).
    pub fn open(cfg: SerialConfig, clock: HostClock) -> Result<Self, LinkError> {
        let port = open_port(&cfg).map_err(|source| LinkError::Open {
            path: cfg.path.clone(),
            source,
        })?;
        Ok(SerialLink {
            backoff: cfg.min_backoff,
            cfg,
            clock,
            port: Some(port),
            next_attempt: Instant::now(),
        })
    }

    /// Whether the port is currently open.
    pub fn is_connected(&self) -> bool {
        self.port.is_some()
    }

    /// Reads what is available into `buf`, or reports a disconnect, a reconnect or nothing.
    pub fn poll(&mut self, buf: &mut [u8]) -> LinkEvent {
        let Some(port) = self.port.as_mut() else {
            return self.try_reconnect();
        };
        match port.read(buf) {
            Ok(0) => self.disconnect("end of file".into()),
            Ok(len) => LinkEvent::Bytes {
                host_time_ns: self.clock.now_ns(),
                len,
            },
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::TimedOut | io::ErrorKind::Interrupted
                ) =>
            {
                LinkEvent::Idle
            }
            Err(e) => self.disconnect(e.to_string()),
        }
    }

    /// Sends a command to the pen.
    pub fn send(&mut self, command: Command) -> Result<(), LinkError> {
        let port = self.port.as_mut().ok_or_else(|| {
            LinkError::Send(io::Error::new(
                io::ErrorKind::NotConnected,
                "pen disconnected",
            ))
        })?;
        port.write_all(command.encode().as_bytes())
            .and_then(|()| port.flush())
            .map_err(LinkError::Send)
    }

    fn disconnect(&mut self, reason: String) -> LinkEvent {
        self.port = None;
        self.backoff = self.cfg.min_backoff;
        self.next_attempt = Instant::now() + self.backoff;
        LinkEvent::Disconnected {
            host_time_ns: self.clock.now_ns(),
            reason,
        }
    }

    fn try_reconnect(&mut self) -> LinkEvent {
        let now = Instant::now();
        if now < self.next_attempt {
            std::thread::sleep((self.next_attempt - now).min(self.cfg.read_timeout));
            return LinkEvent::Idle;
        }
        match open_port(&self.cfg) {
            Ok(port) => {
                self.port = Some(port);
                LinkEvent::Reconnected {
                    host_time_ns: self.clock.now_ns(),
                }
            }
            Err(_) => {
                self.backoff = (self.backoff * 2).min(self.cfg.max_backoff);
                self.next_attempt = Instant::now() + self.backoff;
                LinkEvent::Idle
            }
        }
    }
}

fn open_port(cfg: &SerialConfig) -> serialport::Result<Box<dyn SerialPort>> {
    serialport::new(cfg.path.to_string_lossy(), cfg.baud)
        .data_bits(serialport::DataBits::Eight)
        .parity(serialport::Parity::None)
        .stop_bits(serialport::StopBits::One)
        .flow_control(serialport::FlowControl::None)
        .timeout(cfg.read_timeout)
        .open()
}
