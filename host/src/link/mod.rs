//! The pen link: decoding the byte stream the pen sends (hardware-docs/protocol.md).

pub mod packet_json;

pub use packet_json::{PacketLine, SummaryLine};
