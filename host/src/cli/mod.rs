//! The `fires` subcommands, one module each.

pub mod bench;
pub mod decode;
pub mod sim;
