//! The `fires` subcommands, one module each.

pub mod bench;
pub mod calibrate;
pub mod coat;
pub mod decode;
pub mod demo;
pub mod denoise;
pub mod edit;
pub mod pivot;
pub mod replay;
pub mod sim;
pub mod track;
pub mod transplant;
