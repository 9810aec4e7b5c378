//! Sculpting tools: forces on the data points (`subdivision-solids-journal.txt` section 5.4 and
//! the external force `f_d` of eqs 6-10).
//!
//! * [`Tool::Rope`]: the rope tool. A data point (the one nearest the 3D cursor when the rope is
//!   attached, found by linear search as in the paper) is pulled towards the cursor by a spring
//!   of stiffness `k` that only pulls ("non-compressible" rope: no force while the distance is
//!   below the rope length `L`): `f = -k (l - L) u` for `l > L`. The cursor can move.
//! * [`Tool::PointForce`]: a constant force on one data point.
//! * [`Tool::RegionForce`]: a total force shared equally by the data points within a radius of a
//!   centre (chosen when the tool is added).
//! * [`Tool::Gravity`]: `f_i = m_i g`.
//! * [`Tool::Inflation`]: a pressure `P` on the boundary: each boundary face adds `P N / k` to
//!   each of its `k` vertices, with `N` the outward area vector of the face (Newell's formula).

use vclay_core::Vec3;

use crate::springs::spring_hessian_apply;

/// An applied force.
#[derive(Clone, Debug, PartialEq)]
pub enum Tool {
    /// Rope from data point `point` to `cursor`.
    Rope {
        /// Data point pulled.
        point: usize,
        /// Cursor position.
        cursor: Vec3,
        /// Spring stiffness `k` (force per length).
        stiffness: f64,
        /// Rope length `L` (no force below it).
        length: f64,
    },
    /// A constant force on a data point.
    PointForce {
        /// Data point.
        point: usize,
        /// Force.
        force: Vec3,
    },
    /// A total force spread over data points.
    RegionForce {
        /// Data points (chosen at creation).
        points: Vec<usize>,
        /// Total force.
        force: Vec3,
        /// Centre used to choose the points (kept to re-choose them after an edit).
        center: Vec3,
        /// Radius used to choose the points.
        radius: f64,
    },
    /// Gravity, acceleration `g`.
    Gravity {
        /// Acceleration.
        g: Vec3,
    },
    /// Pressure on the boundary surface.
    Inflation {
        /// Pressure (force per area; negative deflates).
        pressure: f64,
    },
}

/// Outward boundary face loops of the data lattice, for [`Tool::Inflation`].
#[derive(Clone, Debug, Default)]
pub struct Boundary {
    /// Loop offsets.
    pub offsets: Vec<u32>,
    /// Loop vertices (outward orientation).
    pub verts: Vec<u32>,
}

impl Tool {
    /// Adds the tool's force to `f` and returns the tool's potential energy (rope only, else 0).
    pub fn add_forces(&self, d: &[Vec3], mass: &[f64], boundary: &Boundary, f: &mut [Vec3]) -> f64 {
        match self {
            Tool::Rope {
                point,
                cursor,
                stiffness,
                length,
            } => {
                let x = d[*point] - cursor;
                let l = x.norm();
                if l > *length && l > 0.0 {
                    f[*point] -= x * (stiffness * (l - length) / l);
                    0.5 * stiffness * (l - length).powi(2)
                } else {
                    0.0
                }
            }
            Tool::PointForce { point, force } => {
                f[*point] += force;
                0.0
            }
            Tool::RegionForce { points, force, .. } => {
                if !points.is_empty() {
                    let share = force / points.len() as f64;
                    for &i in points {
                        f[i] += share;
                    }
                }
                0.0
            }
            Tool::Gravity { g } => {
                for (fi, m) in f.iter_mut().zip(mass) {
                    *fi += g * *m;
                }
                0.0
            }
            Tool::Inflation { pressure } => {
                for w in boundary.offsets.windows(2) {
                    let lp = &boundary.verts[w[0] as usize..w[1] as usize];
                    let mut n = Vec3::zeros();
                    for i in 0..lp.len() {
                        n += d[lp[i] as usize].cross(&d[lp[(i + 1) % lp.len()] as usize]);
                    }
                    let share = n * (0.5 * pressure / lp.len() as f64);
                    for &v in lp {
                        f[v as usize] += share;
                    }
                }
                0.0
            }
        }
    }

    /// `out += K_tool y` for tools with stiffness (the rope), used by implicit integration.
    pub fn add_stiffness_product(&self, d: &[Vec3], y: &[Vec3], out: &mut [Vec3]) {
        if let Tool::Rope {
            point,
            cursor,
            stiffness,
            length,
        } = self
        {
            let x = d[*point] - cursor;
            if x.norm() > *length {
                out[*point] += spring_hessian_apply(x, *stiffness, *length, y[*point]);
            }
        }
    }

    /// Checks parameters and indices (`n` data points).
    pub fn validate(&self, n: usize) -> Result<(), crate::SolidsError> {
        use crate::error::invalid;
        let finite = |name: &str, v: &Vec3| {
            if v.iter().all(|c| c.is_finite()) {
                Ok(())
            } else {
                Err(invalid(name, format!("{:?}", v.as_slice()), "finite"))
            }
        };
        let index = |i: usize| {
            if i < n {
                Ok(())
            } else {
                Err(crate::SolidsError::NoSuchElement {
                    what: "data point",
                    index: i,
                    count: n,
                })
            }
        };
        match self {
            Tool::Rope {
                point,
                cursor,
                stiffness,
                length,
            } => {
                index(*point)?;
                finite("cursor", cursor)?;
                if !(stiffness.is_finite() && *stiffness >= 0.0) {
                    return Err(invalid("stiffness", stiffness, "non-negative and finite"));
                }
                if !(length.is_finite() && *length >= 0.0) {
                    return Err(invalid("length", length, "non-negative and finite"));
                }
            }
            Tool::PointForce { point, force } => {
                index(*point)?;
                finite("force", force)?;
            }
            Tool::RegionForce { points, force, .. } => {
                for &p in points {
                    index(p)?;
                }
                finite("force", force)?;
            }
            Tool::Gravity { g } => finite("g", g)?,
            Tool::Inflation { pressure } => {
                if !pressure.is_finite() {
                    return Err(invalid("pressure", pressure, "finite"));
                }
            }
        }
        Ok(())
    }
}

/// Index of the point of `d` nearest `x` (linear search, journal section 5.4); `None` if empty.
pub fn nearest(d: &[Vec3], x: &Vec3) -> Option<usize> {
    let mut best = None;
    let mut bd = f64::INFINITY;
    for (i, p) in d.iter().enumerate() {
        let q = (p - x).norm_squared();
        if q < bd {
            bd = q;
            best = Some(i);
        }
    }
    best
}

/// Indices of the points of `d` within `radius` of `c`.
pub fn within(d: &[Vec3], c: &Vec3, radius: f64) -> Vec<usize> {
    d.iter()
        .enumerate()
        .filter(|(_, p)| (*p - c).norm() <= radius)
        .map(|(i, _)| i)
        .collect()
}
