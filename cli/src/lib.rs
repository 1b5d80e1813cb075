//! The `fires` command-line tool over the FIRES crates: one module per command (`fires <command>`), and
//! [`output`] for the files several commands write. The binary (`src/main.rs`) parses the arguments and maps
//! an error to one line on standard error and exit code 2; the modules are public so that the end-to-end tests
//! can run a command in-process exactly as the binary does.

pub mod bench;
pub mod calibrate;
pub mod coat;
pub mod decode;
pub mod demo;
pub mod denoise;
pub mod edit;
pub mod mesh;
pub mod network;
pub mod output;
pub mod pipeline;
pub mod pivot;
pub mod recon;
pub mod replay;
pub mod sim;
pub mod track;
pub mod transplant;
