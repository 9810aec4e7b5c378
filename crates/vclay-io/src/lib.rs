//! # vclay-io
//!
//! vclay's files: the JSON model format ([`model`]), parameter lists for `vclay eval`
//! ([`params`]) and triangle meshes in OBJ, STL and PLY ([`mesh`]); exchange formats: glTF binary
//! ([`gltf`]), STEP ([`step`], [`step_read`]) and IGES ([`iges`], [`iges_read`]) export and
//! import of B-spline curves and surfaces, NURBS-Python JSON ([`geomdl`]). The
//! formats are specified in `docs/formats.md`.
//!
//! Every reader validates everything and names the place of an error: the file, then a line and
//! column (`line 3, column 7: invalid JSON: ...`), a JSON path
//! (`entities[0].control_points[2][1]: expected an array of 3 numbers, found a string`), an
//! entity (`entity 1 (nurbs-surface): knot vector along u: ...`), a parameter tuple or a mesh line
//! or element (`mesh.obj:17: face references vertex 203 but only 200 vertices are defined`).
//! Every writer goes through a temporary file in the target's directory that is renamed over the
//! target, so a failed write never destroys an existing file. No input makes a reader panic.
//!
//! ```
//! use vclay_io::model::{parse_model, to_json_string, Entity};
//! let text = r#"{"type": "nurbs-curve", "degree": 1, "knots": [0, 0, 1, 1],
//!                "control_points": [[0, 0, 0], [1, 2, 3]]}"#;
//! let model = parse_model(text).unwrap();
//! assert_eq!(model[0].param_dims(), 1);
//! assert_eq!(parse_model(&to_json_string(&model)).unwrap(), model);
//! ```
//!
//! Limitations: see each module.
#![warn(missing_docs)]

pub mod brep;
pub mod cloud;
pub mod error;
pub mod geomdl;
pub mod gltf;
pub mod iges;
pub mod iges_read;
mod json;
pub mod mesh;
pub mod model;
pub mod params;
pub mod step;
pub mod step_read;
pub mod triangular;
pub mod trimmed;
mod util;

pub use error::{IoError, MeshLocation};
pub use mesh::{
    Encoding, MeshFormat, decode_mesh, encode_mesh, read_mesh, stage_mesh, write_mesh,
    write_mesh_with,
};
pub use model::{
    ENTITY_TYPES, Entity, NamedEntity, import_model, parse_model, parse_named_model, read_model,
    read_named_model, stage_model, to_json, write_model, write_named_model,
};
pub use params::{parse_params, read_params};
pub use step_read::CadImport;
pub use util::{STALE_TEMP_AGE, Staged, TEMP_PREFIX, stage, write_atomic};
