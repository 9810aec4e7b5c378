//! Seeded synthetic scans shared by the tests (no dependency: splitmix64 + Box-Muller).
#![allow(dead_code)]

use vclay_core::Vec3;

/// splitmix64.
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
    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Standard normal.
    pub fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

/// Saddle `z = 0.3 (x^2 - y^2)` over `[-1, 1]^2`.
pub fn saddle(x: f64, y: f64) -> f64 {
    0.3 * (x * x - y * y)
}

/// Wave `z = 0.15 sin(2 x) cos(1.5 y)` over `[-1, 1]^2`.
pub fn wave(x: f64, y: f64) -> f64 {
    0.15 * (2.0 * x).sin() * (1.5 * y).cos()
}

/// Paraboloid bump `z = 0.5 (1 - x^2 - y^2)`.
pub fn paraboloid(x: f64, y: f64) -> f64 {
    0.5 * (1.0 - x * x - y * y)
}

/// `n` points of `f` over `[-1, 1]^2` (uniform), with normal noise of standard deviation
/// `sigma` along z, skipping points with `skip(x, y)`.
pub fn scan(
    f: fn(f64, f64) -> f64,
    n: usize,
    sigma: f64,
    seed: u64,
    skip: impl Fn(f64, f64) -> bool,
) -> Vec<Vec3> {
    let mut rng = Rng(seed);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let x = 2.0 * rng.uniform() - 1.0;
        let y = 2.0 * rng.uniform() - 1.0;
        if skip(x, y) {
            continue;
        }
        out.push(Vec3::new(x, y, f(x, y) + sigma * rng.normal()));
    }
    out
}

/// Largest and RMS vertical deviation of the surface from `f` at its points on an
/// `m x m` parameter grid whose (x, y) fall inside `keep`.
pub fn deviation(
    s: &vclay_spline::NurbsSurface,
    f: fn(f64, f64) -> f64,
    m: usize,
    keep: impl Fn(f64, f64) -> bool,
) -> (f64, f64) {
    use vclay_spline::ParametricSurface;
    let (mut max, mut s2, mut n) = (0.0f64, 0.0, 0usize);
    for i in 0..=m {
        for j in 0..=m {
            let p = s.point(i as f64 / m as f64, j as f64 / m as f64).unwrap();
            if p.x.abs() > 0.98 || p.y.abs() > 0.98 || !keep(p.x, p.y) {
                continue;
            }
            let d = (p.z - f(p.x, p.y)).abs();
            max = max.max(d);
            s2 += d * d;
            n += 1;
        }
    }
    (max, (s2 / n.max(1) as f64).sqrt())
}
