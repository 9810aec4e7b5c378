//! Shared helpers for the integration tests.
#![allow(dead_code)]

use vclay_core::Vec3;
use vclay_lattice::{BoundaryRule, Features, Lattice, SubdivisionRules, SubdivisionSolid};

/// A small seeded generator (splitmix64), so the tests need no RNG crate.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [-1, 1).
    pub fn sym(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
    pub fn vec3(&mut self, scale: f64) -> Vec3 {
        Vec3::new(self.sym(), self.sym(), self.sym()) * scale
    }
}

/// Subdivides `lattice` `levels` times with `rule` and no tags.
pub fn solid(lattice: Lattice, rule: BoundaryRule, levels: usize) -> SubdivisionSolid {
    let f = Features::none(&lattice);
    SubdivisionSolid::new(lattice, f, SubdivisionRules::new(rule), levels).unwrap()
}

/// Moves every point by a random offset of size up to `scale`.
pub fn perturb(lattice: &mut Lattice, seed: u64, scale: f64) {
    let mut rng = Rng(seed);
    for p in lattice.points_mut() {
        *p += rng.vec3(scale);
    }
}
