//! The `fires` subcommands, one module each.

pub mod bench;
pub mod calibrate;
pub mod decode;
pub mod demo;
pub mod mesh;
pub mod pivot;
pub mod replay;
pub mod sim;
pub mod track;
