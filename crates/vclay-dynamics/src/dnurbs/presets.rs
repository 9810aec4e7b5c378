//! The physical parameters of `d-nurbs.txt` Table 1 as named presets.

use super::{Density, Material};

/// One row of `d-nurbs.txt` Table 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Preset {
    /// Application name as in the table.
    pub name: &'static str,
    /// Mass density `mu`.
    pub mu: f64,
    /// Damping density `gamma`.
    pub gamma: f64,
    /// Tension `alpha_11, alpha_22` (curves use the first).
    pub alpha: [f64; 2],
    /// Rigidity `beta_11, beta_12, beta_22` (curves use the first).
    pub beta: [f64; 3],
    /// Time step.
    pub dt: f64,
    /// Spring stiffness `k`.
    pub k: f64,
}

impl Preset {
    /// The material for a curve (`alpha_11`, `beta_11`).
    pub fn curve_material(&self) -> Material {
        Material::curve(self.mu, self.gamma, self.alpha[0], self.beta[0])
    }

    /// The material for a surface.
    pub fn surface_material(&self) -> Material {
        Material {
            mu: Density::Constant(self.mu),
            gamma: Density::Constant(self.gamma),
            alpha: self.alpha.iter().map(|&a| Density::Constant(a)).collect(),
            beta: self.beta.iter().map(|&b| Density::Constant(b)).collect(),
        }
    }

    /// Looks a preset up by name (case-insensitive, `-`, `_` and spaces ignored).
    pub fn by_name(name: &str) -> Option<&'static Preset> {
        let key = |s: &str| {
            s.chars()
                .filter(|c| c.is_alphanumeric())
                .flat_map(char::to_lowercase)
                .collect::<String>()
        };
        let k = key(name);
        TABLE_1.iter().find(|p| key(p.name) == k)
    }
}

const fn row(
    name: &'static str,
    mu: f64,
    gamma: f64,
    a: [f64; 2],
    b: [f64; 3],
    dt: f64,
    k: f64,
) -> Preset {
    Preset {
        name,
        mu,
        gamma,
        alpha: a,
        beta: b,
        dt,
        k,
    }
}

/// `d-nurbs.txt` Table 1, row by row.
pub const TABLE_1: [Preset; 11] = [
    row(
        "Curve fitting",
        0.0,
        50.0,
        [20.0, 0.0],
        [60.0, 0.0, 0.0],
        0.001,
        1000.0,
    ),
    row(
        "Hemisphere fitting",
        0.0,
        50.0,
        [10.0, 10.0],
        [5.0, 5.0, 5.0],
        0.02,
        5000.0,
    ),
    row(
        "Convex/Concave fitting",
        0.0,
        50.0,
        [10.0, 10.0],
        [5.0, 5.0, 5.0],
        0.03,
        2000.0,
    ),
    row(
        "Sinusoidal fitting",
        0.0,
        100.0,
        [2.0, 2.0],
        [10.0, 10.0, 10.0],
        0.02,
        3000.0,
    ),
    row(
        "Edge rounding",
        0.0,
        500.0,
        [1000.0, 0.0],
        [1.0, 0.0, 0.0],
        0.04,
        0.0,
    ),
    row(
        "Corner rounding",
        0.0,
        50.0,
        [1000.0, 1000.0],
        [10.0, 10.0, 10.0],
        0.04,
        0.0,
    ),
    row(
        "Bevel rounding",
        0.0,
        25.0,
        [100.0, 100.0],
        [0.0, 0.0, 0.0],
        0.04,
        0.0,
    ),
    row(
        "Egg sculpting",
        1.0,
        25.0,
        [100.0, 100.0],
        [20.0, 20.0, 20.0],
        0.002,
        3000.0,
    ),
    row(
        "Toroid sculpting",
        1.0,
        100.0,
        [25.0, 25.0],
        [10.0, 10.0, 10.0],
        0.003,
        4000.0,
    ),
    row(
        "Hat sculpting",
        2.0,
        100.0,
        [5.0, 5.0],
        [1.0, 1.0, 1.0],
        0.004,
        5000.0,
    ),
    row(
        "Glass sculpting",
        2.0,
        50.0,
        [15.0, 15.0],
        [4.0, 4.0, 4.0],
        0.001,
        2000.0,
    ),
];
