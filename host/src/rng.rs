//! A small seedable random generator for this crate's synthetic tests and benches (SplitMix64, Steele et al.,
//! "Fast splittable pseudorandom number generators", 2014, with Box-Muller Gaussians): deterministic across
//! platforms, so a seed names the same data everywhere.

use nalgebra::{UnitQuaternion, Vector3};

/// SplitMix64 pseudo-random generator (deterministic, no dependencies).
#[derive(Debug, Clone)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `[a, b)`.
    pub fn uniform(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.unit()
    }

    /// Standard normal sample (Box-Muller).
    pub fn gaussian(&mut self) -> f64 {
        let u1 = self.unit().max(1e-300);
        let u2 = self.unit();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// Uniformly distributed unit vector.
    pub fn unit_vector(&mut self) -> Vector3<f64> {
        loop {
            let v = Vector3::new(self.gaussian(), self.gaussian(), self.gaussian());
            let n = v.norm();
            if n > 1e-6 {
                return v / n;
            }
        }
    }

    /// Uniformly distributed rotation.
    pub fn rotation(&mut self) -> UnitQuaternion<f64> {
        UnitQuaternion::from_scaled_axis(
            self.unit_vector() * self.uniform(0.0, std::f64::consts::PI),
        )
    }
}
