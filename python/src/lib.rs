//! # vclay (Python)
//!
//! The Python module `vclay` over the kernel crates and the session layer, built by maturin
//! (`pip install ./python`). Arrays go in and out as numpy arrays of `float64`; every batched
//! call loops in Rust (in parallel with rayon above [`PAR_MIN`] items) with the GIL released,
//! so no Python code runs per point.
//!
//! | Python | Rust |
//! | --- | --- |
//! | `load`, `save`, `convert`, `Curve`, `Surface`, `Volume` | `vclay_io`, `vclay_spline` |
//! | `Ffd` | `vclay_ffd` (`ffd-direct-manipulation.txt` eqs 7, 12) |
//! | `fit_surface` | `vclay_fit` (scan fitting, `d-nurbs.txt` eq 17 fairness) |
//! | `Lattice` | `vclay_lattice` (MacCracken-Joy subdivision, `.ovm`) |
//! | `PdeSurface` | `vclay_pde` (`dynamic-pde-surfaces.txt`) |
//! | `render` | `vclay_render` |
//! | `Session` | `vclay_session` (scenarios, commands, undo/redo, session files) |
//!
//! Errors: every vclay error becomes an exception of the `VclayError` hierarchy carrying the
//! kernel's located message ([`errors`]); wrong array shapes are `ValueError` (a programmer
//! error, as the Rust API asserts). D-NURBS surfaces from arrays: `dnurbs_surface` (a session
//! of one model); `Session.from_toml` takes a scenario as a string. Limitations: arrays are
//! copied once on the way in and once out (`evaluate_grid(out=...)` writes in place).

use pyo3::prelude::*;

mod errors;
mod ffd;
mod fit;
mod lattice;
mod limits;
mod nurbs;
mod pde;
mod render;
mod session;
mod util;

/// Batches at least this long are evaluated on rayon's thread pool; shorter ones on the
/// calling thread (a fork-join costs a few microseconds).
pub const PAR_MIN: usize = 2048;

/// vclay: physics-based free-form modeling from Python.
///
/// Models: `load(path)` returns the entities (`Curve`, `Surface`, `Volume`) of a model file
/// (vclay or geomdl JSON); `entity.evaluate(params)` maps an (n, d) parameter array to an
/// (n, 3) array of points. FFD lattices (`Ffd`), subdivision lattices (`Lattice`), PDE
/// surfaces (`PdeSurface`), pictures (`render`), file conversion (`convert`) and sessions
/// (`Session.load(scenario_or_session)`, `Session.from_toml(text)`, `dnurbs_surface(net)`,
/// `apply`, `step`, `save`) over the same kernel as the `vclay` command line. Errors are
/// `VclayError` subclasses with located messages.
#[pymodule]
#[pyo3(name = "vclay")]
fn vclay_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    errors::register(m)?;
    limits::register(m)?;
    nurbs::register(m)?;
    ffd::register(m)?;
    fit::register(m)?;
    lattice::register(m)?;
    pde::register(m)?;
    render::register(m)?;
    session::register(m)?;
    Ok(())
}
