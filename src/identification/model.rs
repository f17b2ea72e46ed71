//! Synthetic-data helpers of the identification, and the augmented gear it fits: the gear model
//! itself lives in [`crate::model::recorded`] (one gear model for the dynamics and the
//! identification); its items are re-exported here under their identification names.

/// The augmented gear of the identification: [`crate::model::recorded::RecordedGear`].
pub use crate::model::recorded::RecordedGear as AugmentedGear;
pub use crate::model::recorded::{
    angle_harmonic, angle_harmonic_sc, dipole_force, drag, force_shape, load_shape, pow_positive,
    stribeck, Coefficients, ExtraTerm, Geometry, InputBend, Shape, DRAG_REFERENCE_SPEED, MAX_EXTRA,
    STRIBECK_POWER,
};
use std::f64::consts::TAU;

/// A small deterministic random generator (SplitMix64) with normal deviates, for synthetic data.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// Seeded generator.
    pub fn new(seed: u64) -> Self {
        Self(seed ^ 0x9E37_79B9_7F4A_7C15)
    }
    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Standard normal (Box–Muller).
    pub fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (TAU * u2).cos()
    }
}
