//! The pen link: decoding the byte stream the pen sends (hardware-docs/protocol.md).

pub mod imu_timing;
pub mod packet_json;
pub mod serial;

pub use imu_timing::{ButtonChange, LiveImuTimer, TimedLinkEvent};
pub use packet_json::{PacketLine, SummaryLine};
pub use serial::{LinkError, LinkEvent, SerialConfig, SerialLink};
