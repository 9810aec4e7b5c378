//! Material of a dynamic solid: mass density, damping density and the stiffness of the two kinds
//! of springs, uniform or per control cell.
//!
//! The continuous model (`subdivision-solids-journal.txt` eq 5) has a mass density `mu(x)` and a
//! damping density `gamma(x)`; the lattice lumps them onto the data points:
//!
//! `m_i = sum_{cells c containing i} mu_c |V_c| / n_c`, `gamma_i = sum_c gamma_c |V_c| / n_c`
//!
//! with `|V_c|` the rest volume of data cell `c` and `n_c` its number of vertices. The springs of
//! journal section 5.1 get a stiffness proportional to their rest length,
//! `k = E l0 (u^T diag(a) u)` (`u` the unit rest direction, `a` the anisotropy), so that the
//! lattice behaves the same at every subdivision level (a cube of springs of side `h` has
//! stiffness `E h`, which is what a block of modulus `E` of that size has). Edge springs use the
//! mean `E_edge` of the cells around the edge, virtual springs the mean `E_virtual` of the cells
//! on either side of their face.

use crate::error::{SolidsError, invalid};

/// Default [`Material::density`].
pub const DEFAULT_DENSITY: f64 = 1.0;
/// Default [`Material::damping`].
pub const DEFAULT_DAMPING: f64 = 2.0;
/// Default [`Material::edge_stiffness`].
pub const DEFAULT_EDGE_STIFFNESS: f64 = 100.0;
/// Default [`Material::virtual_stiffness`].
pub const DEFAULT_VIRTUAL_STIFFNESS: f64 = 50.0;

/// Material of one cell (or of the whole solid).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Mass per unit volume `mu` (> 0). Default: [`DEFAULT_DENSITY`].
    pub density: f64,
    /// Damping per unit volume `gamma` (>= 0); `gamma / mu` is the damping rate in 1/s.
    /// Default: [`DEFAULT_DAMPING`].
    pub damping: f64,
    /// Modulus `E_edge` of the edge springs (>= 0). Default: [`DEFAULT_EDGE_STIFFNESS`].
    pub edge_stiffness: f64,
    /// Modulus `E_virtual` of the virtual springs (>= 0). Default:
    /// [`DEFAULT_VIRTUAL_STIFFNESS`].
    pub virtual_stiffness: f64,
    /// Stiffness scale per world axis `a` (each > 0); `[1, 1, 1]` is isotropic. Default:
    /// `[1, 1, 1]`.
    pub anisotropy: [f64; 3],
}

impl Default for Material {
    fn default() -> Self {
        Self {
            density: DEFAULT_DENSITY,
            damping: DEFAULT_DAMPING,
            edge_stiffness: DEFAULT_EDGE_STIFFNESS,
            virtual_stiffness: DEFAULT_VIRTUAL_STIFFNESS,
            anisotropy: [1.0; 3],
        }
    }
}

impl Material {
    /// Checks every field; the error names the field.
    pub fn validate(&self) -> Result<(), SolidsError> {
        let pos = |name: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(invalid(name, v, "positive and finite"))
            }
        };
        let nonneg = |name: &str, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(invalid(name, v, "non-negative and finite"))
            }
        };
        pos("density", self.density)?;
        nonneg("damping", self.damping)?;
        nonneg("edge_stiffness", self.edge_stiffness)?;
        nonneg("virtual_stiffness", self.virtual_stiffness)?;
        for (a, &v) in self.anisotropy.iter().enumerate() {
            pos(&format!("anisotropy[{a}]"), v)?;
        }
        Ok(())
    }

    /// Direction factor `u^T diag(a) u` for a unit vector `u`.
    pub(crate) fn direction_factor(&self, u: [f64; 3]) -> f64 {
        (0..3).map(|a| self.anisotropy[a] * u[a] * u[a]).sum()
    }
}

/// A material per control cell (heterogeneous solids).
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialField {
    cells: Vec<Material>,
}

impl MaterialField {
    /// The same material in each of `cells` control cells.
    pub fn uniform(material: Material, cells: usize) -> Self {
        Self {
            cells: vec![material; cells],
        }
    }

    /// One material per control cell, each validated (the error names the cell's field).
    pub fn from_cells(cells: Vec<Material>) -> Result<Self, SolidsError> {
        for m in &cells {
            m.validate()?;
        }
        Ok(Self { cells })
    }

    /// Material of control cell `c`.
    pub fn cell(&self, c: usize) -> &Material {
        &self.cells[c]
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// Whether there are no cells.
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// All cell materials.
    pub fn cells(&self) -> &[Material] {
        &self.cells
    }

    /// Changes cells: `f` edits the material of each listed cell (all cells when `cells` is
    /// `None`); the results are validated and nothing changes on error.
    pub fn update(
        &mut self,
        cells: Option<&[usize]>,
        f: impl Fn(&mut Material),
    ) -> Result<(), SolidsError> {
        let mut next = self.cells.clone();
        let all: Vec<usize>;
        let list = match cells {
            Some(l) => l,
            None => {
                all = (0..next.len()).collect();
                &all
            }
        };
        for &c in list {
            let count = next.len();
            let m = next.get_mut(c).ok_or(SolidsError::NoSuchElement {
                what: "control cell",
                index: c,
                count,
            })?;
            f(m);
            m.validate()?;
        }
        self.cells = next;
        Ok(())
    }

    /// Re-indexes after an edit: `map[new] = Some(old)` copies the old cell's material, `None`
    /// (a new cell) takes `fill`.
    pub fn remap(&self, map: &[Option<usize>], fill: Material) -> Self {
        Self {
            cells: map
                .iter()
                .map(|o| o.map_or(fill, |c| self.cells[c]))
                .collect(),
        }
    }
}
