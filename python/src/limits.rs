//! The memory limit of the module (`set_max_memory`, `max_memory`) and the checks made before
//! allocating, with the session layer's estimates (`vclay_session::limits`, the same as
//! `vclay --max-memory`'s). Over the limit, `MemoryLimitError` (a `VclayError` and a
//! `MemoryError`) names the argument and the estimate.

use std::sync::atomic::{AtomicU64, Ordering};

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use vclay_session::limits::{self, DEFAULT_MAX_MEMORY};

static MAX_MEMORY: AtomicU64 = AtomicU64::new(DEFAULT_MAX_MEMORY);

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("DEFAULT_MAX_MEMORY", DEFAULT_MAX_MEMORY)?;
    m.add_function(wrap_pyfunction!(set_max_memory, m)?)?;
    m.add_function(wrap_pyfunction!(max_memory, m)?)?;
    Ok(())
}

/// The limit in bytes.
pub fn max() -> u64 {
    MAX_MEMORY.load(Ordering::Relaxed)
}

/// Fails with `MemoryLimitError` when the work described by `what` (an argument and its value)
/// needs about `bytes`, more than the limit.
pub fn check(py: Python<'_>, what: impl FnOnce() -> String, bytes: f64) -> PyResult<()> {
    limits::check(what, bytes, max()).map_err(|e| {
        crate::errors::memory_limit(py, format!("{e} (lower it, or raise vclay.set_max_memory)"))
    })
}

/// `check` for `count` float64 values.
pub fn check_f64s(py: Python<'_>, what: impl FnOnce() -> String, count: f64) -> PyResult<()> {
    check(py, what, limits::f64_bytes(count))
}

/// `set_max_memory(nbytes)`: the most memory one call may ask for, in bytes (default
/// `DEFAULT_MAX_MEMORY`, 4 GiB, as `vclay --max-memory`); `None` restores the default. Calls
/// whose estimate is over it raise `MemoryLimitError` before allocating anything.
#[pyfunction]
#[pyo3(signature = (nbytes = None), text_signature = "(nbytes=None)")]
fn set_max_memory(nbytes: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
    let v = match nbytes {
        None => DEFAULT_MAX_MEMORY,
        Some(n) => {
            let v: i128 = n.extract().map_err(|_| {
                PyValueError::new_err("set_max_memory: nbytes must be a positive integer (bytes)")
            })?;
            if v <= 0 || v > u64::MAX as i128 {
                return Err(PyValueError::new_err(format!(
                    "set_max_memory: nbytes = {v}: expected a positive number of bytes"
                )));
            }
            v as u64
        }
    };
    MAX_MEMORY.store(v, Ordering::Relaxed);
    Ok(())
}

/// `max_memory()`: the memory limit in bytes (see `set_max_memory`).
#[pyfunction]
fn max_memory() -> u64 {
    max()
}
