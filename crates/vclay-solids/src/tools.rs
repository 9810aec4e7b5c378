//! Sculpting tools: forces on the data points (`subdivision-solids-journal.txt` section 5.4 and
//! the external force `f_d` of eqs 6-10).
//!
//! * [`Tool::Rope`]: the rope tool. A data point (the one nearest the 3D cursor when the rope is
//!   attached, found by linear search as in the paper) is pulled towards the cursor by a spring
//!   of stiffness `k` that only pulls ("non-compressible" rope: no force while the distance is
//!   below the rope length `L`): `f = -k (l - L) u` for `l > L`. The cursor can move.
//! * [`Tool::PointForce`]: a constant force on one data point.
//! * [`Tool::RegionForce`]: a total force shared by the data points within a radius of a centre
//!   (chosen when the tool is added), equally (the paper) or by a [`Falloff`] of the distance
//!   from the centre (a sculpting brush's profile).
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
    /// A total force spread over data points: point `points[k]` takes the share
    /// `weights[k] / sum(weights)` (equal shares when `weights` is empty).
    RegionForce {
        /// Data points (chosen at creation).
        points: Vec<usize>,
        /// Total force.
        force: Vec3,
        /// Centre used to choose the points (kept to re-choose them after an edit).
        center: Vec3,
        /// Radius used to choose the points.
        radius: f64,
        /// How the share falls off with the distance from the centre.
        falloff: Falloff,
        /// The falloff's weight of each point of `points` at creation (empty: equal shares).
        weights: Vec<f64>,
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
        self.add_forces_in(d, mass, boundary, f, 0..d.len())
    }

    /// [`Tool::add_forces`] restricted to the data points in `range`: `f[i - range.start]` is
    /// the force on point `i`; the energy counts when the rope's point lies in the range. The
    /// blocks of a partition of the points together add what one call over all points adds,
    /// so threads can apply a tool to their own blocks.
    pub fn add_forces_in(
        &self,
        d: &[Vec3],
        mass: &[f64],
        boundary: &Boundary,
        f: &mut [Vec3],
        range: std::ops::Range<usize>,
    ) -> f64 {
        let base = range.start;
        let mut add = |i: usize, x: Vec3| {
            if range.contains(&i) {
                f[i - base] += x;
            }
        };
        match self {
            Tool::Rope {
                point,
                cursor,
                stiffness,
                length,
            } => {
                let x = d[*point] - cursor;
                let l = x.norm();
                if l > *length && l > 0.0 && range.contains(point) {
                    add(*point, -x * (stiffness * (l - length) / l));
                    0.5 * stiffness * (l - length).powi(2)
                } else {
                    0.0
                }
            }
            Tool::PointForce { point, force } => {
                add(*point, *force);
                0.0
            }
            Tool::RegionForce {
                points,
                force,
                weights,
                ..
            } => {
                let total: f64 = weights.iter().sum();
                if weights.len() == points.len() && total > 0.0 {
                    for (&i, w) in points.iter().zip(weights) {
                        add(i, force * (w / total));
                    }
                } else if !points.is_empty() {
                    let share = force / points.len() as f64;
                    for &i in points {
                        add(i, share);
                    }
                }
                0.0
            }
            Tool::Gravity { g } => {
                for i in range.clone() {
                    add(i, g * mass[i]);
                }
                0.0
            }
            Tool::Inflation { pressure } => {
                for w in boundary.offsets.windows(2) {
                    let lp = &boundary.verts[w[0] as usize..w[1] as usize];
                    if !lp.iter().any(|&v| range.contains(&(v as usize))) {
                        continue;
                    }
                    let mut n = Vec3::zeros();
                    for i in 0..lp.len() {
                        n += d[lp[i] as usize].cross(&d[lp[(i + 1) % lp.len()] as usize]);
                    }
                    let share = n * (0.5 * pressure / lp.len() as f64);
                    for &v in lp {
                        add(v as usize, share);
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
            Tool::RegionForce {
                points,
                force,
                weights,
                ..
            } => {
                for &p in points {
                    index(p)?;
                }
                finite("force", force)?;
                if !(weights.is_empty() || weights.len() == points.len())
                    || weights.iter().any(|w| !(w.is_finite() && *w >= 0.0))
                {
                    return Err(invalid(
                        "weights",
                        weights.len(),
                        "one finite non-negative weight per point, or none",
                    ));
                }
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

/// The profile of a region force (a sculpting brush): the weight of a point at distance `r`
/// from the centre of a region of radius `R`, as a function of `t = r / R` in `[0, 1]`, with
/// `s = 1 - t`. The names are Blender's sculpt-brush falloff presets.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Falloff {
    /// `1`: every point the same share (the paper's region force).
    #[default]
    Constant,
    /// `3 s^2 - 2 s^3` (smoothstep): full at the centre, flat at both ends.
    Smooth,
    /// `s`.
    Linear,
    /// `sqrt(1 - t^2)`: a hemisphere.
    Sphere,
    /// `s^2`: concentrated at the centre.
    Sharp,
}

impl Falloff {
    /// Every falloff, in the order front ends list them.
    pub const ALL: [Falloff; 5] = [
        Falloff::Constant,
        Falloff::Smooth,
        Falloff::Linear,
        Falloff::Sphere,
        Falloff::Sharp,
    ];

    /// The weight at `t = r / R` (clamped to `[0, 1]`).
    pub fn weight(self, t: f64) -> f64 {
        let t = if t.is_finite() {
            t.clamp(0.0, 1.0)
        } else {
            1.0
        };
        let s = 1.0 - t;
        match self {
            Falloff::Constant => 1.0,
            Falloff::Smooth => s * s * (3.0 - 2.0 * s),
            Falloff::Linear => s,
            Falloff::Sphere => (1.0 - t * t).max(0.0).sqrt(),
            Falloff::Sharp => s * s,
        }
    }

    /// The name in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Falloff::Constant => "constant",
            Falloff::Smooth => "smooth",
            Falloff::Linear => "linear",
            Falloff::Sphere => "sphere",
            Falloff::Sharp => "sharp",
        }
    }

    /// The falloff named `name` (see [`Falloff::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|f| f.name() == name)
    }

    /// The weights of `points` of `d` for a region at `center` of `radius` (empty for
    /// [`Falloff::Constant`]: equal shares). A region of radius 0 weighs its points equally.
    pub fn weights(self, d: &[Vec3], points: &[usize], center: &Vec3, radius: f64) -> Vec<f64> {
        if self == Falloff::Constant || radius <= 0.0 {
            return Vec::new();
        }
        points
            .iter()
            .map(|&i| self.weight((d[i] - center).norm() / radius))
            .collect()
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn falloffs_are_full_at_the_centre_and_zero_at_the_rim_but_constant() {
        for f in Falloff::ALL {
            assert_eq!(f.weight(0.0), 1.0, "{f:?}");
            let rim = f.weight(1.0);
            assert_eq!(rim, if f == Falloff::Constant { 1.0 } else { 0.0 }, "{f:?}");
            // Non-increasing from the centre out.
            let w: Vec<f64> = (0..=10).map(|k| f.weight(k as f64 / 10.0)).collect();
            assert!(w.windows(2).all(|p| p[1] <= p[0]), "{f:?} {w:?}");
            assert_eq!(Falloff::from_name(f.name()), Some(f));
        }
        assert!((Falloff::Smooth.weight(0.5) - 0.5).abs() < 1e-15);
        assert!(Falloff::Sharp.weight(0.5) < Falloff::Linear.weight(0.5));
    }

    #[test]
    fn a_weighted_region_force_keeps_its_total_and_leans_to_the_centre() {
        let d: Vec<Vec3> = (0..5)
            .map(|i| Vec3::new(i as f64 * 0.25, 0.0, 0.0))
            .collect();
        let points: Vec<usize> = (0..5).collect();
        let center = Vec3::zeros();
        let weights = Falloff::Smooth.weights(&d, &points, &center, 1.25);
        let tool = Tool::RegionForce {
            points,
            force: Vec3::new(0.0, 0.0, 2.0),
            center,
            radius: 1.25,
            falloff: Falloff::Smooth,
            weights,
        };
        let mut f = vec![Vec3::zeros(); 5];
        tool.add_forces(&d, &[1.0; 5], &Boundary::default(), &mut f);
        let total: f64 = f.iter().map(|x| x.z).sum();
        assert!((total - 2.0).abs() < 1e-14, "{total}");
        assert!(f.windows(2).all(|p| p[1].z < p[0].z), "{f:?}");
        assert!(tool.validate(5).is_ok());
    }

    #[test]
    fn tools_applied_block_by_block_add_up_to_the_whole() {
        // A 3 x 3 grid of points in the plane z = x y / 4, with boundary loops over its four
        // cells (an open sheet is enough to exercise the loops that cross blocks).
        let d: Vec<Vec3> = (0..9)
            .map(|i| {
                let (x, y) = ((i % 3) as f64, (i / 3) as f64);
                Vec3::new(x, y, 0.25 * x * y)
            })
            .collect();
        let mass: Vec<f64> = (0..9).map(|i| 1.0 + i as f64).collect();
        let mut boundary = Boundary {
            offsets: vec![0],
            verts: Vec::new(),
        };
        for c in [0, 1, 3, 4] {
            boundary.verts.extend([c, c + 1, c + 4, c + 3]);
            boundary.offsets.push(boundary.verts.len() as u32);
        }
        let tools = [
            Tool::Rope {
                point: 4,
                cursor: Vec3::new(3.0, 1.0, 2.0),
                stiffness: 5.0,
                length: 0.5,
            },
            Tool::PointForce {
                point: 7,
                force: Vec3::new(0.0, 1.0, 0.0),
            },
            Tool::RegionForce {
                points: vec![1, 2, 5],
                force: Vec3::new(0.3, 0.0, 0.0),
                center: Vec3::zeros(),
                radius: 1.0,
                falloff: Falloff::Constant,
                weights: vec![],
            },
            Tool::RegionForce {
                points: vec![1, 2, 5],
                force: Vec3::new(0.3, 0.0, 0.0),
                center: Vec3::zeros(),
                radius: 2.5,
                falloff: Falloff::Smooth,
                weights: vec![0.9, 0.5, 0.1],
            },
            Tool::Gravity {
                g: Vec3::new(0.0, 0.0, -9.81),
            },
            Tool::Inflation { pressure: 2.0 },
        ];
        for tool in &tools {
            let mut whole = vec![Vec3::zeros(); 9];
            let e = tool.add_forces(&d, &mass, &boundary, &mut whole);
            assert!(
                whole.iter().any(|x| x.norm() > 0.0),
                "{tool:?} adds a force"
            );
            let mut parts = vec![Vec3::zeros(); 9];
            let mut e_parts = 0.0;
            for r in [0..4, 4..5, 5..9] {
                e_parts += tool.add_forces_in(&d, &mass, &boundary, &mut parts[r.clone()], r);
            }
            assert_eq!(whole, parts, "{tool:?}");
            assert_eq!(e, e_parts, "{tool:?}");
        }
    }
}
