//! The exception hierarchy: each kernel error type maps to one Python class, with the
//! kernel's own message (file, line, key, entity, command) as the text.
//!
//! ```text
//! VclayError
//! ├── FileError        reading or writing files: model JSON, meshes, .ovm, scenarios, sessions
//! ├── GeometryError    invalid geometry or parameters: knots, weights, lattices, FFD solves
//! ├── PdeError         PDE surface specs and solves
//! ├── RenderError      pictures
//! ├── SessionError     sessions: unknown model, nothing to undo
//! │   ├── CommandError a command that cannot apply (the session is unchanged)
//! │   └── DivergedError the simulation diverged (the model keeps its last good state)
//! ├── ArgumentError    an argument's value out of range or unknown, naming the argument;
//! │                    also a `ValueError`
//! └── MemoryLimitError work over the memory limit (`set_max_memory`), raised before any
//!                      allocation; also a `MemoryError`, as numpy raises for such sizes
//! ```

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};

create_exception!(
    vclay,
    VclayError,
    PyException,
    "Base class of every vclay error; the message names the place (file, line, key, entity)."
);
create_exception!(
    vclay,
    FileError,
    VclayError,
    "A file could not be read, parsed or written (model JSON, meshes, .ovm, scenarios, sessions)."
);
create_exception!(
    vclay,
    GeometryError,
    VclayError,
    "Invalid geometry or parameters: knot vectors, weights, control nets, lattices, FFD solves."
);
create_exception!(
    vclay,
    PdeError,
    VclayError,
    "A PDE surface spec is invalid or its solve failed."
);
create_exception!(
    vclay,
    RenderError,
    VclayError,
    "A picture could not be made."
);
create_exception!(
    vclay,
    SessionError,
    VclayError,
    "A session error: an unknown model, nothing to undo or redo, a model that failed."
);
create_exception!(
    vclay,
    CommandError,
    SessionError,
    "A command could not apply; the session is unchanged."
);
create_exception!(
    vclay,
    DivergedError,
    SessionError,
    "The simulation diverged; the model keeps its last good state."
);

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("VclayError", py.get_type::<VclayError>())?;
    m.add("FileError", py.get_type::<FileError>())?;
    m.add("GeometryError", py.get_type::<GeometryError>())?;
    m.add("PdeError", py.get_type::<PdeError>())?;
    m.add("RenderError", py.get_type::<RenderError>())?;
    m.add("SessionError", py.get_type::<SessionError>())?;
    m.add("CommandError", py.get_type::<CommandError>())?;
    m.add("DivergedError", py.get_type::<DivergedError>())?;
    m.add("MemoryLimitError", memory_limit_error(py)?)?;
    m.add("ArgumentError", argument_error(py)?)?;
    Ok(())
}

static MEMORY_LIMIT_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static ARGUMENT_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();

/// A class `name(VclayError, builtin)` with two bases, which `create_exception!` cannot make,
/// so it is made by `type(name, bases, dict)` once and kept in `cell`.
fn two_base<'py>(
    py: Python<'py>,
    cell: &'static PyOnceLock<Py<PyType>>,
    name: &str,
    builtin: Bound<'py, PyType>,
    doc: &str,
) -> PyResult<&'py Bound<'py, PyType>> {
    let ty = cell.get_or_try_init(py, || {
        let bases = PyTuple::new(py, [py.get_type::<VclayError>(), builtin])?;
        let dict = PyDict::new(py);
        dict.set_item("__module__", "vclay")?;
        dict.set_item("__doc__", doc)?;
        let t = py
            .get_type::<PyType>()
            .call1((name, bases, dict))?
            .cast_into::<PyType>()?;
        Ok::<_, PyErr>(t.unbind())
    })?;
    Ok(ty.bind(py))
}

/// `MemoryLimitError(VclayError, MemoryError)`.
fn memory_limit_error(py: Python<'_>) -> PyResult<&Bound<'_, PyType>> {
    two_base(
        py,
        &MEMORY_LIMIT_ERROR,
        "MemoryLimitError",
        py.get_type::<pyo3::exceptions::PyMemoryError>(),
        "Work over the memory limit (`vclay.set_max_memory`, default 4 GiB), raised before \
         anything is allocated; the message names the argument and the estimate. Also a \
         `MemoryError`, as numpy raises for sizes it cannot allocate.",
    )
}

/// `ArgumentError(VclayError, ValueError)`.
fn argument_error(py: Python<'_>) -> PyResult<&Bound<'_, PyType>> {
    two_base(
        py,
        &ARGUMENT_ERROR,
        "ArgumentError",
        py.get_type::<pyo3::exceptions::PyValueError>(),
        "An argument's value is out of range or unknown (a negative count, an unknown engine \
         or preset, a negative stiffness); the message names the argument. Also a \
         `ValueError`, as Python and numpy raise for bad values.",
    )
}

/// A `MemoryLimitError` with `msg`.
pub fn memory_limit(py: Python<'_>, msg: String) -> PyErr {
    match memory_limit_error(py) {
        Ok(t) => PyErr::from_type(t.clone(), msg),
        Err(e) => e,
    }
}

/// An `ArgumentError` with `msg` (callable without the GIL: it takes it).
pub fn argument(msg: String) -> PyErr {
    Python::attach(|py| match argument_error(py) {
        Ok(t) => PyErr::from_type(t.clone(), msg),
        Err(e) => e,
    })
}

/// Kernel errors as Python exceptions.
pub trait IntoPy {
    /// The exception for this error.
    fn py_err(self) -> PyErr;
}

impl IntoPy for vclay_io::IoError {
    fn py_err(self) -> PyErr {
        FileError::new_err(self.to_string())
    }
}

impl IntoPy for vclay_spline::SplineError {
    fn py_err(self) -> PyErr {
        GeometryError::new_err(self.to_string())
    }
}

impl IntoPy for vclay_ffd::FfdError {
    fn py_err(self) -> PyErr {
        GeometryError::new_err(self.to_string())
    }
}

impl IntoPy for vclay_lattice::LatticeError {
    fn py_err(self) -> PyErr {
        GeometryError::new_err(self.to_string())
    }
}

impl IntoPy for vclay_lattice::FormatError {
    fn py_err(self) -> PyErr {
        FileError::new_err(self.to_string())
    }
}

impl IntoPy for vclay_lattice::command::CommandError {
    fn py_err(self) -> PyErr {
        use vclay_lattice::command::CommandError as E;
        match self {
            e @ (E::BadPrimitive { .. } | E::TooManyLevels { .. } | E::Subdivision { .. }) => {
                GeometryError::new_err(e.to_string())
            }
            e => FileError::new_err(e.to_string()),
        }
    }
}

impl IntoPy for vclay_pde::PdeError {
    fn py_err(self) -> PyErr {
        PdeError::new_err(self.to_string())
    }
}

impl IntoPy for vclay_render::RenderError {
    fn py_err(self) -> PyErr {
        RenderError::new_err(self.to_string())
    }
}

impl IntoPy for vclay_session::SessionError {
    fn py_err(self) -> PyErr {
        use vclay_session::SessionError as E;
        let msg = self.to_string();
        match self {
            E::Command { .. } => CommandError::new_err(msg),
            E::Diverged { .. } => DivergedError::new_err(msg),
            E::File { .. } | E::Io { .. } | E::NotASession { .. } => FileError::new_err(msg),
            E::OverLimit(_) => Python::attach(|py| {
                memory_limit(
                    py,
                    format!("{msg} (lower it, or raise vclay.set_max_memory)"),
                )
            }),
            _ => SessionError::new_err(msg),
        }
    }
}

/// `result.map_err(IntoPy::py_err)`.
pub trait PyResultExt<T> {
    /// The result with the error as a Python exception.
    fn py(self) -> PyResult<T>;
}

impl<T, E: IntoPy> PyResultExt<T> for Result<T, E> {
    fn py(self) -> PyResult<T> {
        self.map_err(IntoPy::py_err)
    }
}
