//! File formats of lattices: OpenVolumeMesh `.ovm` (read and write), VTK XML unstructured grids
//! `.vtu` (write, and read of what it writes) and the boundary surface as OBJ, ASCII STL and ASCII PLY (write).
//!
//! # What
//! * [`ovm`]: the text format of OpenVolumeMesh (vertices, edges as vertex pairs, faces as
//!   half-edge lists, polyhedra as half-face lists); round trips every lattice exactly (ids,
//!   loops and orientation).
//! * [`vtu`]: VTK's XML unstructured grid with ASCII data arrays (read back by [`vtu::parse`]); hexahedra, wedges, tetrahedra and
//!   pyramids are recognised by their topology, every other cell is written as a VTK polyhedron.
//! * [`surface`]: small writers for the outward boundary surface (triangles from
//!   [`crate::boundary_mesh`]); the `vclay-io` crate will take these over.
//!
//! Layouts, cell-type detection and limitations are documented in `docs/formats.md`, section 4.
//!
//! # How
//! Readers report malformed input as a [`FormatError`] naming the file, the line and the element
//! (`cube.ovm:23: face 4 references half-edge 99 but there are 24 edges`). Writers write to a
//! temporary file in the target's directory and rename it over the target, so a failed write
//! never destroys an existing file.

use std::fmt;
use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use thiserror::Error;

use crate::error::LatticeError;

pub mod ovm;
pub mod surface;
pub mod vtu;

/// Problems reading or writing lattice files.
#[derive(Debug, Error)]
pub enum FormatError {
    /// The operating system refused a read or write.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: io::Error,
    },
    /// A line does not have the expected form.
    #[error("{file}:{line}: expected {expected}, found {found}")]
    Syntax {
        /// File name (as given).
        file: String,
        /// 1-based line number.
        line: usize,
        /// What the reader expected.
        expected: String,
        /// What it found (quoted text or "end of file").
        found: String,
    },
    /// An element refers to a lower-dimensional element that does not exist.
    #[error("{file}:{line}: {element} references {kind} {index} but there are {count} {counted}")]
    BadReference {
        /// File name (as given).
        file: String,
        /// 1-based line number.
        line: usize,
        /// The referring element, e.g. "face 4".
        element: String,
        /// Kind of the reference, e.g. "half-edge".
        kind: &'static str,
        /// The index given.
        index: u64,
        /// Number of elements that exist.
        count: usize,
        /// What `count` counts, e.g. "edges".
        counted: &'static str,
    },
    /// An element is structurally wrong (e.g. its half-edges do not form a closed loop).
    #[error("{file}:{line}: {element}: {message}")]
    BadElement {
        /// File name (as given).
        file: String,
        /// 1-based line number.
        line: usize,
        /// The element, e.g. "face 3".
        element: String,
        /// What is wrong.
        message: String,
    },
    /// The file is well formed but its cells do not form a valid lattice.
    #[error("{file}: {source}")]
    Lattice {
        /// File name (as given), or a description of the source.
        file: String,
        /// What the lattice construction found.
        source: LatticeError,
    },
    /// A feature of the format that is not supported.
    #[error("{file}: {what} is not supported")]
    Unsupported {
        /// File name (as given).
        file: String,
        /// The feature.
        what: String,
    },
}

impl FormatError {
    pub(crate) fn io(path: &Path, source: io::Error) -> Self {
        FormatError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// The file name used in messages: the path as the caller gave it.
pub(crate) fn display_name(path: &Path) -> String {
    path.display().to_string()
}

static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Writes a file atomically: `write` fills a temporary file next to `path`
/// (`.NAME.tmp-PID-N`), which is then renamed over `path`. On any error the temporary file is
/// removed and `path` is left untouched. A missing folder is created; temporary files of earlier,
/// killed writes of the same name are removed (see [`STALE_TEMP_AGE`]).
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> Result<(), FormatError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .ok_or_else(|| {
            FormatError::io(
                path,
                io::Error::new(io::ErrorKind::InvalidInput, "not a file name"),
            )
        })?
        .to_string_lossy()
        .into_owned();
    if !dir.is_dir() {
        fs::create_dir_all(&dir).map_err(|e| FormatError::io(path, e))?;
    }
    remove_stale_temps(&dir, &name);
    let tmp = dir.join(format!(
        ".{name}.tmp-{}-{}",
        std::process::id(),
        TEMP_COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let result = (|| -> io::Result<()> {
        let file = File::create(&tmp)?;
        let mut w = BufWriter::new(file);
        write(&mut w)?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = fs::remove_file(&tmp);
        return Err(FormatError::io(path, e));
    }
    Ok(())
}

/// Age after which a temporary file `.NAME.tmp-PID-N` is taken for the leftover of a killed
/// write even when process PID runs (or cannot be checked: not Linux): one hour, far longer than
/// any write takes. A file whose process is gone (Linux: no `/proc/PID`) is removed at once.
pub const STALE_TEMP_AGE: std::time::Duration = std::time::Duration::from_secs(3600);

/// Removes stale temporary files of target `name` from `dir` (best effort).
fn remove_stale_temps(dir: &Path, name: &str) {
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    let prefix = format!(".{name}.tmp-");
    let now = std::time::SystemTime::now();
    let linux = cfg!(target_os = "linux") && Path::new("/proc/self").exists();
    for entry in entries.flatten() {
        let file = entry.file_name();
        let file = file.to_string_lossy();
        let Some(rest) = file.strip_prefix(&prefix) else {
            continue;
        };
        let pid = rest.split('-').next().and_then(|p| p.parse::<u32>().ok());
        let Some(meta) = entry.metadata().ok().filter(|m| m.is_file()) else {
            continue;
        };
        let old = meta
            .modified()
            .ok()
            .and_then(|t| now.duration_since(t).ok())
            .is_some_and(|age| age > STALE_TEMP_AGE);
        let dead = linux
            && pid.is_some_and(|p| {
                p != std::process::id() && !Path::new(&format!("/proc/{p}")).exists()
            });
        if old || dead {
            let _ = fs::remove_file(entry.path());
        }
    }
}

/// Reads a whole text file, mapping errors to [`FormatError::Io`].
pub(crate) fn read_text(path: &Path) -> Result<String, FormatError> {
    fs::read_to_string(path).map_err(|e| FormatError::io(path, e))
}

/// Formats an `f64` so that it reads back to the same value (Rust's shortest round-trip form).
pub(crate) struct Real(pub f64);

impl fmt::Display for Real {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:?}", self.0)
    }
}
