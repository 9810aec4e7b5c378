//! The error type of `vclay-io`.
//!
//! Every variant names the place of the problem: a file path, a line and column, a JSON path
//! (`entities[0].knots[1]`), an entity index, a parameter tuple or a mesh element.

use std::fmt;
use std::path::PathBuf;
use thiserror::Error;
use vclay_core::MeshError;
use vclay_spline::SplineError;

/// Where in a mesh file a problem is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum MeshLocation {
    /// The file as a whole (e.g. "no vertices").
    File,
    /// A 1-based line of a text file (OBJ, ASCII STL, ASCII PLY and every PLY header).
    Line(usize),
    /// A 0-based element of a binary file, e.g. `facet 12` or `face 7`.
    Element {
        /// The element kind (`vertex`, `face`, `facet`).
        kind: String,
        /// Its 0-based index.
        index: usize,
    },
}

/// Formats `path` + `location` the way compilers do: `mesh.obj:17`, `mesh.stl: facet 12`.
struct Place<'a>(&'a PathBuf, &'a MeshLocation);

impl fmt::Display for Place<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.1 {
            MeshLocation::File => write!(f, "{}", self.0.display()),
            MeshLocation::Line(l) => write!(f, "{}:{l}", self.0.display()),
            MeshLocation::Element { kind, index } => {
                write!(f, "{}: {kind} {index}", self.0.display())
            }
        }
    }
}

/// The error type of `vclay-io`.
#[derive(Debug, Error)]
pub enum IoError {
    /// The operating system could not read or write a file.
    #[error("{}: {source}", path.display())]
    File {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        #[source]
        source: std::io::Error,
    },
    /// An error in the content of a file (wraps the other variants with the file path).
    #[error("{}: {source}", path.display())]
    InFile {
        /// The file.
        path: PathBuf,
        /// What is wrong inside it.
        #[source]
        source: Box<IoError>,
    },
    /// The text is not valid JSON.
    #[error("line {line}, column {column}: invalid JSON: {message}")]
    JsonSyntax {
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What the JSON parser expected.
        message: String,
    },
    /// A key written twice in one JSON object (`"degree": 2, "degree": 3`); JSON parsers
    /// disagree on which one counts, so neither does.
    #[error(
        "line {line}, column {column}: duplicate key {} in the object at {path}",
        quote(key)
    )]
    DuplicateKey {
        /// 1-based line of the second occurrence.
        line: usize,
        /// 1-based column just after the second occurrence.
        column: usize,
        /// JSON path of the object, e.g. `entities[0]` (`top level` for the outermost one).
        path: String,
        /// The key.
        key: String,
    },
    /// Valid JSON of the wrong shape: a missing or unknown field, a wrong type, a wrong count.
    #[error("{path}: {message}")]
    Structure {
        /// JSON path of the offending value, e.g. `entities[0].control_points[2][1]`.
        path: String,
        /// What is wrong.
        message: String,
    },
    /// The `"type"` of an entity is not one of the known types.
    #[error(
        "{path}: unknown entity type {}, expected one of {}",
        quote(found),
        quoted_list(allowed)
    )]
    UnknownType {
        /// JSON path of the `type` field.
        path: String,
        /// The type given.
        found: String,
        /// The known types.
        allowed: &'static [&'static str],
    },
    /// An entity is well-formed JSON but not a valid spline (knots, weights, net shape).
    #[error("entity {index} ({kind}): {source}")]
    Entity {
        /// 0-based index of the entity in the file.
        index: usize,
        /// Its type, e.g. `nurbs-surface`.
        kind: &'static str,
        /// What the spline layer rejected.
        #[source]
        source: SplineError,
    },
    /// A model file with no entity in it.
    #[error("the model holds no entities")]
    EmptyModel,
    /// A bad parameter list (for `vclay eval`).
    #[error("{}: {message}", match index { Some(i) => format!("parameter tuple {i}"), None => "parameters".to_string() })]
    Params {
        /// 0-based index of the offending tuple, `None` for the list as a whole.
        index: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// A problem in a mesh file, with its place (`mesh.obj:17: ...`).
    #[error("{}: {message}", Place(path, location))]
    Mesh {
        /// The file (or the name given to an in-memory buffer).
        path: PathBuf,
        /// Where in the file.
        location: MeshLocation,
        /// What is wrong.
        message: String,
    },
    /// A mesh that cannot be written because it is invalid.
    #[error("cannot write {}: invalid mesh: {source}", path.display())]
    InvalidMesh {
        /// The target file.
        path: PathBuf,
        /// What [`vclay_core::TriMesh::validate`] found.
        #[source]
        source: MeshError,
    },
    /// A mesh value that the target format cannot store: a non-finite normal, or a coordinate
    /// beyond the `f32` range of binary STL (it would be written as `inf`).
    #[error("cannot write {}: {message}; nothing written", path.display())]
    Unwritable {
        /// The target file.
        path: PathBuf,
        /// What cannot be stored.
        message: String,
    },
    /// A malformed STEP or IGES file, with its place: `STEP line 41, entity #17: ...`,
    /// `IGES line 9, entity DE 3: ...`.
    #[error("{format} line {line}{}: {message}", match entity { Some(e) => format!(", entity {e}"), None => String::new() })]
    Cad {
        /// `STEP` or `IGES`.
        format: &'static str,
        /// 1-based line of the file.
        line: usize,
        /// The entity: `#17` (STEP instance) or `DE 3` (IGES directory entry), if known.
        entity: Option<String>,
        /// What is wrong.
        message: String,
    },
    /// The file extension does not name a supported mesh format.
    #[error("{}: unknown mesh format {}; expected .obj, .stl or .ply", path.display(), match ext { Some(e) => format!("\".{e}\""), None => "(no extension)".to_string() })]
    UnknownExtension {
        /// The file.
        path: PathBuf,
        /// Its extension, if any.
        ext: Option<String>,
    },
}

/// Most characters of a token from a file that a message quotes ([`quote`]).
pub const MAX_QUOTED_CHARS: usize = 80;

/// `token` in double quotes for a message, cut to its first [`MAX_QUOTED_CHARS`] characters
/// (with `...` and its full length) when longer, so that a megabyte-long key or word in a file
/// does not become a megabyte-long message. Quotes, backslashes and control characters are
/// escaped as in Rust and JSON strings (`\"`, `\\`, `\n`).
pub(crate) fn quote(token: &str) -> String {
    let n = token.chars().count();
    let shown: String = token.chars().take(MAX_QUOTED_CHARS).collect();
    let mut escaped = String::with_capacity(shown.len());
    for c in shown.chars() {
        match c {
            '"' | '\\' => {
                escaped.push('\\');
                escaped.push(c);
            }
            c if c.is_control() => escaped.extend(c.escape_default()),
            c => escaped.push(c),
        }
    }
    if n > MAX_QUOTED_CHARS {
        format!("\"{escaped}...\" ({n} characters)")
    } else {
        format!("\"{escaped}\"")
    }
}

fn quoted_list(items: &[&str]) -> String {
    items
        .iter()
        .map(|s| format!("\"{s}\""))
        .collect::<Vec<_>>()
        .join(", ")
}

impl IoError {
    /// Wraps `self` with the file it came from (idempotent for errors that already name a file).
    pub(crate) fn in_file(self, path: &std::path::Path) -> IoError {
        match self {
            e @ (IoError::File { .. }
            | IoError::InFile { .. }
            | IoError::Mesh { .. }
            | IoError::InvalidMesh { .. }
            | IoError::UnknownExtension { .. }) => e,
            e => IoError::InFile {
                path: path.to_path_buf(),
                source: Box::new(e),
            },
        }
    }

    /// An OS error on `path`.
    pub(crate) fn file(path: &std::path::Path, source: std::io::Error) -> IoError {
        IoError::File {
            path: path.to_path_buf(),
            source,
        }
    }
}
