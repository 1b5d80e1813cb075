//! FIRES host library: everything between the pen's bytes and the strokes the reconstruction consumes
//! (architecture.md §1). The `fires` binary (src/main.rs) is a thin command-line layer over it.

pub mod calibrate;
pub mod capture;
pub mod clock;
pub mod link;
pub mod live;
pub mod replay;
pub mod session;
pub mod stereo;
pub mod stroke;
pub mod track;
pub mod vision;
