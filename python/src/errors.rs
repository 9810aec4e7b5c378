//! The exception hierarchy: each kernel error type maps to one Python class, with the
//! kernel's own message (file, line, key, entity, command) as the text.
//!
//! ```text
//! VclayError
//! ├── FileError        reading or writing files: model JSON, meshes, .ovm, scenarios, sessions
//! ├── GeometryError    invalid geometry or parameters: knots, weights, lattices, FFD solves
//! ├── PdeError         PDE surface specs and solves
//! ├── RenderError      pictures
//! └── SessionError     sessions: unknown model, nothing to undo
//!     ├── CommandError a command that cannot apply (the session is unchanged)
//!     └── DivergedError the simulation diverged (the model keeps its last good state)
//! ```

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

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
    Ok(())
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
