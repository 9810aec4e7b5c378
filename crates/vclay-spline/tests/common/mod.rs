//! Shared fixtures for the spline tests: seeded random models.
#![allow(dead_code)]

use vclay_core::Vec3;
use vclay_spline::{KnotVector, NurbsCurve, NurbsSurface, NurbsVolume};

/// A tiny deterministic generator (SplitMix64), so tests need no RNG crate and are reproducible.
#[derive(Debug)]
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [a, b).
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn vec3(&mut self, s: f64) -> Vec3 {
        Vec3::new(self.range(-s, s), self.range(-s, s), self.range(-s, s))
    }
}

/// Random non-uniform clamped knots with some repeated interior knots.
pub fn random_knots(rng: &mut Rng, degree: usize, n: usize) -> Vec<f64> {
    let mut interior: Vec<f64> = (0..n - degree - 1).map(|_| rng.range(0.05, 0.95)).collect();
    interior.sort_by(f64::total_cmp);
    // Make one interior knot double when there is room, to exercise multiplicity.
    if interior.len() >= 2 && degree >= 2 {
        interior[1] = interior[0];
    }
    let mut k = vec![0.0; degree + 1];
    k.extend(interior);
    k.extend(vec![1.0; degree + 1]);
    k
}

pub fn random_curve(rng: &mut Rng, degree: usize, n: usize) -> NurbsCurve {
    let knots = random_knots(rng, degree, n);
    let pts = (0..n).map(|_| rng.vec3(2.0)).collect();
    let w = (0..n).map(|_| rng.range(0.3, 3.0)).collect();
    NurbsCurve::new(degree, knots, pts, Some(w)).unwrap()
}

pub fn random_surface(rng: &mut Rng, degree: [usize; 2], dims: [usize; 2]) -> NurbsSurface {
    let ku = KnotVector::new(random_knots(rng, degree[0], dims[0]), degree[0], dims[0]).unwrap();
    let kv = KnotVector::new(random_knots(rng, degree[1], dims[1]), degree[1], dims[1]).unwrap();
    let n = dims[0] * dims[1];
    let pts = (0..n).map(|_| rng.vec3(2.0)).collect();
    let w = (0..n).map(|_| rng.range(0.3, 3.0)).collect();
    NurbsSurface::from_flat([ku, kv], pts, w).unwrap()
}

pub fn random_volume(rng: &mut Rng, degree: [usize; 3], dims: [usize; 3]) -> NurbsVolume {
    let kvs: Vec<KnotVector> = (0..3)
        .map(|a| {
            KnotVector::new(random_knots(rng, degree[a], dims[a]), degree[a], dims[a]).unwrap()
        })
        .collect();
    let n = dims.iter().product();
    let pts = (0..n).map(|_| rng.vec3(2.0)).collect();
    let w = (0..n).map(|_| rng.range(0.3, 3.0)).collect();
    let [a, b, c]: [KnotVector; 3] = kvs.try_into().unwrap();
    NurbsVolume::from_flat([a, b, c], pts, w).unwrap()
}

pub fn samples(n: usize) -> Vec<f64> {
    (0..=n).map(|i| i as f64 / n as f64).collect()
}
