//! `fit_surface`: a smooth surface fitted to a point cloud (`vclay_fit`, issue 20).

use pyo3::prelude::*;
use vclay_fit::{FitOptions, RobustMode};
use vclay_io::model::Entity as IoEntity;

use crate::errors::GeometryError;
use crate::{nurbs, util};

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(fit_surface, m)?)?;
    Ok(())
}

/// `fit_surface(points, grid=(32, 32), degree=3, fairness=(0.0, 1e-9), robust="auto",
/// weights=False, corrections=2)`: a B-spline (NURBS with `weights=True`) surface fitted to an
/// `(n, 3)` array of points with the D-NURBS thin-plate-under-tension fairness
/// (`fairness = (alpha, beta)`, dimensionless). `robust` is `vclay fit --robust`'s mode:
/// `"auto"` (plain least squares, robust once the first round shows gross outliers: the
/// report's `outliers_detected`), `"none"` or `None` (plain least squares), `"tukey"` or
/// `"huber"` (robust weights throughout).
/// Returns `(surface, report)`: a `Surface` and the report as a dict (docs/formats.md
/// section 11: `rms`, `max` closest-point distances, `fairness_energy`, `timings`, ...).
/// Bad clouds and options raise `GeometryError` with the located message.
#[pyfunction]
#[pyo3(signature = (points, grid=(32, 32), degree=3, fairness=(0.0, 1e-9), robust=Some("auto".to_owned()), weights=false, corrections=2),
    text_signature = "(points, grid=(32, 32), degree=3, fairness=(0.0, 1e-9), robust='auto', weights=False, corrections=2)")]
#[allow(clippy::type_complexity)]
fn fit_surface<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    grid: (i64, i64),
    degree: i64,
    fairness: (f64, f64),
    robust: Option<String>,
    weights: bool,
    corrections: i64,
) -> PyResult<(Py<PyAny>, Bound<'py, PyAny>)> {
    let grid = (
        util::count(grid.0, "grid[0]")?,
        util::count(grid.1, "grid[1]")?,
    );
    let degree = util::count(degree, "degree")?;
    let corrections = util::count(corrections, "corrections")?;
    let pts = util::points(points, "points")?;
    let robust = match robust {
        Some(s) => s.parse::<RobustMode>().map_err(GeometryError::new_err)?,
        None => RobustMode::None,
    };
    let opts = FitOptions {
        grid: [grid.0, grid.1],
        degree,
        tension: fairness.0,
        rigidity: fairness.1,
        corrections,
        robust,
        rational: weights,
        ..FitOptions::default()
    };
    // `vclay fit`'s estimate, against the memory limit.
    crate::limits::check(
        py,
        || format!("grid={grid:?} with {} points", pts.len()),
        vclay_fit::memory_estimate(pts.len(), &opts, rayon::current_num_threads()) as f64,
    )?;
    let fit = py
        .detach(|| vclay_fit::fit_surface(&pts, &opts))
        .map_err(|e| GeometryError::new_err(e.to_string()))?;
    let report =
        serde_json::to_value(&fit.report).map_err(|e| GeometryError::new_err(e.to_string()))?;
    let surface = nurbs::wrap(py, IoEntity::Surface(fit.surface), None)?;
    Ok((surface, util::json_to_py(py, &report)?))
}
