//! FIRES host library: everything between the pen's bytes and the strokes the reconstruction consumes
//! (docs/architecture.md §1). The `fires` command-line tool is the `fires-cli` crate (`cli/`).

pub mod calibrate;
pub mod capture;
pub mod clock;
pub mod link;
pub mod live;
pub mod meta;
pub mod replay;
pub mod rng;
pub mod session;
pub mod stereo;
pub mod stroke;
pub mod track;
pub mod vision;
