//! `PdeSurface`: a dynamic PDE surface (`dynamic-pde-surfaces.txt` eq 1) compiled from a spec
//! dict (the JSON of `docs/formats.md` section 6), solved at an instant by collocation least
//! squares (`vclay_pde`), evaluated at parameter arrays or tessellated.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use vclay_core::TriMesh;
use vclay_pde::{ModelSolution, PdeModel};

use crate::errors::PyResultExt;
use crate::util;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PdeSurface>()
}

/// A PDE surface model: one or more patches from a spec (dict or JSON text; errors name the
/// place in the spec: `PdeError`).
#[pyclass(module = "vclay", frozen)]
#[derive(Debug)]
pub struct PdeSurface {
    model: PdeModel,
    /// The spec text and whether it is TOML (else JSON): what pickling saves.
    source: (String, bool),
}

impl PdeSurface {
    fn from_source(text: String, toml: bool) -> PyResult<Self> {
        let model = if toml {
            PdeModel::from_toml(&text, "spec")
        } else {
            PdeModel::from_json(&text, "spec")
        }
        .py()?;
        Ok(Self {
            model,
            source: (text, toml),
        })
    }

    fn solve_at(&self, py: Python<'_>, t: f64) -> PyResult<ModelSolution> {
        let m = &self.model;
        py.detach(|| m.solve(t)).py()
    }
}

#[pymethods]
impl PdeSurface {
    /// `PdeSurface(spec)`: `spec` a dict (or JSON text) in the spec format of `vclay pde`.
    #[new]
    fn new(spec: &Bound<'_, PyAny>) -> PyResult<Self> {
        let v = util::py_to_json(spec, "spec", crate::errors::PdeError::new_err)?;
        let text = serde_json::to_string(&v).map_err(|e| PyValueError::new_err(e.to_string()))?;
        Self::from_source(text, false)
    }

    /// `PdeSurface.read(path)`: a spec file (JSON, or TOML by extension).
    #[staticmethod]
    fn read(path: std::path::PathBuf) -> PyResult<Self> {
        let model = PdeModel::read(&path).py()?;
        let text = std::fs::read_to_string(&path)
            .map_err(|e| crate::errors::FileError::new_err(format!("{}: {e}", path.display())))?;
        let toml = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
        Ok(Self {
            model,
            source: (text, toml),
        })
    }

    /// `PdeSurface.from_toml(text)`: a spec given as TOML text (the fields of the JSON spec).
    #[staticmethod]
    fn from_toml(text: String) -> PyResult<Self> {
        Self::from_source(text, true)
    }

    /// Pickling and `copy`: the spec text, compiled again on loading.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let py = slf.py();
        let (text, toml) = &slf.get().source;
        let args = (text.clone(),);
        let ctor = if *toml {
            slf.get_type().getattr("from_toml")?
        } else {
            slf.get_type().into_any()
        };
        (ctor, args).into_pyobject(py).map(|t| t.into_any())
    }

    /// Patch names, in order.
    #[getter]
    fn patches(&self) -> Vec<String> {
        self.model.patches.iter().map(|p| p.name.clone()).collect()
    }

    /// Points of patch `patch` at time `t` for an `(n, 2)` array of `(u, v)`: `(n, 3)`.
    #[pyo3(signature = (params, t = 0.0, patch = 0))]
    fn evaluate<'py>(
        &self,
        py: Python<'py>,
        params: &Bound<'py, PyAny>,
        t: f64,
        patch: i64,
    ) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let patch = util::count(patch, "patch")?;
        let p = self.model.patches.get(patch).ok_or_else(|| {
            PyValueError::new_err(format!(
                "patch {patch}: the model has {} patches",
                self.model.patches.len()
            ))
        })?;
        let (uv, n) = util::rows(params, 2, "params")?;
        let sol = self.solve_at(py, t)?;
        let s = &sol.patches[patch];
        let mut out = vec![0.0; n * 3];
        py.detach(|| {
            util::fill(&mut out, 3, |start, chunk| {
                for (k, o) in chunk.chunks_exact_mut(3).enumerate() {
                    let i = start + k;
                    let q = vclay_pde::surface::point(p, s, uv[2 * i], uv[2 * i + 1]);
                    o.copy_from_slice(&[q.x, q.y, q.z]);
                }
                Ok::<(), ()>(())
            })
        })
        .expect("evaluation does not fail");
        Ok(util::array2(py, out, n, 3))
    }

    /// Every patch at time `t` tessellated on `grid = (nu, nv)` samples: `(vertices, triangles,
    /// normals)`.
    #[pyo3(signature = (t = 0.0, grid = (64, 64)), text_signature = "(self, /, t=0.0, grid=(64, 64))")]
    fn mesh<'py>(&self, py: Python<'py>, t: f64, grid: (i64, i64)) -> PyResult<Bound<'py, PyAny>> {
        let grid = (
            util::count(grid.0, "grid[0]")?,
            util::count(grid.1, "grid[1]")?,
        );
        if grid.0 < 2 || grid.1 < 2 {
            return Err(PyValueError::new_err("grid: at least 2 x 2 samples"));
        }
        // `vclay pde --grid`'s estimate, against the memory limit.
        crate::limits::check(
            py,
            || format!("grid={grid:?} ({} patches)", self.model.patches.len()),
            vclay_session::limits::grid_mesh_bytes(grid.0, grid.1, self.model.patches.len()),
        )?;
        let sol = self.solve_at(py, t)?;
        let m = &self.model;
        let mesh = py.detach(|| {
            let mut mesh = TriMesh::new();
            m.tessellate(&sol, grid.0, grid.1, &mut mesh);
            mesh
        });
        util::mesh_arrays(py, &mesh)
    }

    /// Largest root-mean-square collocation residual over the patches at time `t`.
    #[pyo3(signature = (t = 0.0))]
    fn residual(&self, py: Python<'_>, t: f64) -> PyResult<f64> {
        Ok(self.solve_at(py, t)?.residual_rms())
    }

    /// The residual at time `t` against the surface's size (`vclay_pde::ResidualCheck`, the
    /// check `vclay pde` prints): a dict with `residual_rms`, `size` (bounding-box diagonal),
    /// `ratio` (`residual_rms / size`) and `warning` (a sentence when `ratio` is over
    /// `vclay_pde::RESIDUAL_WARNING_RATIO`, 1 %, else None).
    #[pyo3(signature = (t = 0.0))]
    fn residual_check<'py>(
        &self,
        py: Python<'py>,
        t: f64,
    ) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        let sol = self.solve_at(py, t)?;
        let m = &self.model;
        let c = py.detach(|| sol.residual_check(m));
        let d = pyo3::types::PyDict::new(py);
        d.set_item("residual_rms", c.residual_rms)?;
        d.set_item("size", c.size)?;
        d.set_item("ratio", c.ratio)?;
        d.set_item("warning", c.warning())?;
        Ok(d)
    }

    /// Number of patches.
    fn __len__(&self) -> usize {
        self.model.patches.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "<vclay PdeSurface {:?}: {} patches>",
            self.model.name,
            self.model.patches.len()
        )
    }
}
