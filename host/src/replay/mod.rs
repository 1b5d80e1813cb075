//! Replay: one pipeline from a recording (simulated or of real hardware) to strokes, per-frame tracks and a
//! report (docs/architecture.md §1, §4). Live tracking feeds the same [`crate::session::Session`]; replaying the same
//! recording twice gives identical output, since nothing here reads a clock.
//!
//! Stages: link bytes -> [`imu_stream`] (decode, sample times, buttons) -> camera frames (blob lists, or 8-bit
//! images through [`crate::vision::BlobDetector`] with the tracker's predicted window) -> tracker (stereo,
//! identification, tip, fusion) -> strokes (button-delimited, display filter, B-spline
//! post-processing) -> [`report`] against ground truth when the recording has it.

pub mod bar;
pub mod display;
pub mod floor;
pub mod imu_stream;
pub mod plot;
pub mod plot_text;
pub mod refusals;
pub mod report;
pub(crate) mod retrack;
pub mod run;
pub mod strokes_vs_truth;

pub use run::{replay, ReplayConfig, ReplayError, ReplayOutput, WorldSource};
