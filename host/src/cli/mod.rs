//! The `fires` subcommands, one module each.

pub mod decode;
