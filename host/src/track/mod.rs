//! Pen tracking after blob detection: LED identification (thesis §4.1.2), tip estimation
//! (eqs. 4.11-4.13), sensor fusion (§4.1.4) and the per-frame [`pipeline::Tracker`].

pub mod fusion;
pub mod identify;
pub mod pen;
pub mod pipeline;

#[cfg(test)]
mod stress_tests;
pub mod synth;
pub mod tip;

pub use identify::{Identification, Identifier, IdentifyConfig, IdentifyError, IdentifyPrior};
pub use pen::{PenGeometry, LED_COUNT};
pub use tip::{TipError, TipEstimate, TipEstimator};
