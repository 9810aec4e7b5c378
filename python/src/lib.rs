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
//! | `load_part`, `Part` (trimmed faces of CAD parts) | `vclay_io::brep`, `vclay_io::trimmed` |
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
mod part;
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
/// (vclay or geomdl JSON, STEP, IGES; recognized by content); `entity.evaluate(params)` maps an
/// (n, d) parameter array to an (n, 3) array of points. FFD lattices (`Ffd`), subdivision
/// lattices (`Lattice`), PDE surfaces (`PdeSurface`), pictures (`render`), file conversion
/// (`convert`) and sessions (`open(path)`, `Session.from_toml(text)`, `dnurbs_surface(net)`,
/// `clay(mesh)`; `apply`, `step`, `save`) over the same kernel as the `vclay` command line.
///
/// Naming:
/// - Verbs change or make things, nouns read them: `Session.step(n)` advances, `steps()` is
///   the count of steps taken; `apply`, `undo`, `redo`, `schedule`, `set_control_points`,
///   `set_weights`, `add` change a session; `energy()`, `params()`, `control_points()`,
///   `weights()`, `mesh()`, `surface()` read it.
/// - Properties for what an object has without arguments (`Entity.control_points`,
///   `Ffd.control_points`, `Lattice.points`, writable where they can change); methods where an
///   argument chooses (`Session.control_points(model=None)`: a session has several models).
///   Arrays have the same shape everywhere: a control net is `(n, 3)`, `(nu, nv, 3)` or
///   `(nu, nv, nw, 3)`, its weights the same without the last axis.
/// - Files: `load`/`save` read and write exact NURBS entities, `read_mesh`/`write_mesh`
///   triangle meshes, `convert(input, output)` goes from file to file (as `vclay convert`),
///   `open(path)` (= `Session.load`) opens any file as a session and `Session.save` writes a
///   session file, `Session.export(path)` writes one model's geometry in the format its
///   extension names, `Lattice.read`/`write` lattices.
/// - Triangles: `Entity.tessellate(samples)` samples exact geometry, `Session.mesh()` and
///   `PdeSurface.mesh()` give a model's display surface, `Lattice.boundary()` a lattice's
///   boundary faces; all return `(vertices, triangles, normals)`.
/// - Sizes are `samples` (per parametric axis), `grid` (samples per axis of a PDE surface or
///   fit), `levels` (subdivision), `n` (steps); counts are non-negative integers, and a
///   negative one raises `ArgumentError` naming the argument.
///
/// Energies (`Session.energy()`): `total` = `kinetic` + `elastic` + `tools`.
///
/// Errors are `VclayError` subclasses with located messages; `ArgumentError` is also a
/// `ValueError`, `MemoryLimitError` (work over `max_memory()`, raised before allocating) also a
/// `MemoryError`. Objects pickle and copy exactly (a pickled `Session` continues bit for bit),
/// so Dask and multiprocessing can ship them.
#[pymodule]
#[pyo3(name = "vclay")]
fn vclay_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    errors::register(m)?;
    limits::register(m)?;
    nurbs::register(m)?;
    part::register(m)?;
    ffd::register(m)?;
    fit::register(m)?;
    lattice::register(m)?;
    pde::register(m)?;
    render::register(m)?;
    session::register(m)?;
    Ok(())
}
