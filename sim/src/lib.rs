//! FIRES deterministic simulator: the smart-pen (LED geometry and emission cone), its motion drawing a curve
//! network over a target object, the IMU and its packets, the 230400-baud radio link, and two unsynchronised
//! cameras; output is a recording (`fires-record`) of exactly what the devices deliver plus ground truth.
//!
//! Entry point: [`run_scenario`]. Scenarios: [`SCENARIOS`]. Each model lives in its own module.

pub mod camera;
pub mod imu;
pub mod link;
pub mod motion;
pub mod objects;
pub mod pen;
pub mod rng;
pub mod scenario;
pub mod session;

pub use scenario::{scenario, Scenario, SCENARIOS};
pub use session::{run, run_scenario, true_strokes, SimOptions, SimSummary, HOST_ORIGIN_NS};

/// Errors of the simulator.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// No scenario of that name; the message lists the names of [`SCENARIOS`].
    #[error("unknown scenario {0:?} (known: {known})", known = scenario::scenario_names())]
    UnknownScenario(String),
    /// Duration not positive and finite (or longer than a day).
    #[error("bad duration {0} s: must be positive, finite and at most 86400")]
    BadDuration(f64),
    /// Writing the recording failed.
    #[error(transparent)]
    Record(#[from] fires_record::RecordError),
    /// A frame image could not be encoded (the compressor could not allocate).
    #[error("encoding image {index} of camera {camera}: {cause}")]
    Encode {
        /// Camera index.
        camera: usize,
        /// Frame index.
        index: u64,
        /// What failed.
        cause: std::io::Error,
    },
}
