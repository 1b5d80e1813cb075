//! Host time: monotonic nanoseconds since the session started (docs/architecture.md §2). Every measurement the host
//! takes is stamped with it as close to the source as possible.

use std::time::Instant;

/// A monotonic clock whose zero is the moment it was created.
#[derive(Clone, Copy, Debug)]
pub struct HostClock {
    epoch: Instant,
}

impl Default for HostClock {
    fn default() -> Self {
        Self::new()
    }
}

impl HostClock {
    /// A clock starting now.
    pub fn new() -> Self {
        HostClock {
            epoch: Instant::now(),
        }
    }

    /// Nanoseconds since the clock was created (saturates after 584 years).
    pub fn now_ns(&self) -> u64 {
        u64::try_from(self.epoch.elapsed().as_nanos()).unwrap_or(u64::MAX)
    }
}
