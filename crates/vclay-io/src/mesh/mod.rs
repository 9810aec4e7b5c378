//! Triangle mesh files: Wavefront OBJ, STL (ASCII and binary) and PLY (ASCII and binary).
//!
//! **What.** [`read_mesh`] and [`write_mesh`] pick the format from the file extension (`.obj`,
//! `.stl`, `.ply`, any case). Writers produce:
//! - OBJ: `v` lines, `vn` lines when the mesh has normals, faces `f a//a b//b c//c` (1-based);
//! - STL: binary by default, ASCII on request; facet normals computed from the triangles;
//! - PLY: `binary_little_endian` by default, `ascii` on request; `double` coordinates, normals as
//!   `nx ny nz` when present, faces as `list uchar int vertex_indices`.
//!
//! Readers accept:
//! - OBJ: `v` (extra components such as `w` or colors ignored), `vn`, `vt`, `f` with corners
//!   `v`, `v/vt`, `v//vn`, `v/vt/vn`, negative (relative) indices, polygons (fan-triangulated),
//!   `#` comments; other statements (`o`, `g`, `s`, `usemtl`, `mtllib`, `l`, ...) are ignored;
//! - STL: ASCII and binary, told apart by content (a binary file whose size matches its triangle
//!   count is binary even when its header starts with `solid`); identical vertices are merged;
//! - PLY: `ascii`, `binary_little_endian`, `binary_big_endian`; a `vertex` element with `x y z`
//!   of any numeric type and optional `nx ny nz`; a `face` element with a list property
//!   `vertex_indices` (or `vertex_index`) of any integer count and index types; other elements
//!   and properties are skipped.
//!
//! **How.** Everything is written by hand (each format is a page of code), so errors can name
//! their place: `mesh.obj:17: face references vertex 203 but only 200 vertices are defined`
//! (file and line for text), `mesh.stl: facet 12: ...` (element index for binary). Every reader
//! rejects non-finite coordinates, out-of-range indices, truncated data and files without
//! vertices. Writes go to a temporary file in the same directory that is renamed over the
//! target, so a failed write never destroys an existing file.
//!
//! **Limitations.**
//! - STL stores `f32` and no vertex normals: meshes read from STL have no normals (call
//!   [`TriMesh::compute_normals`]).
//! - OBJ normals are per corner; a vertex used with different normals is duplicated, and when
//!   some face corner has no normal the mesh gets none. Vertices not used by any face keep a
//!   zero normal. Texture coordinates, materials, groups, line continuations (`\`) and free-form
//!   geometry are not read.
//! - PLY `tristrips` and other non-`face` elements are skipped; colors are not read.

mod obj;
mod ply;
mod stl;

use crate::error::{IoError, MeshLocation};
use std::collections::HashMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use vclay_core::{MeshError, TriMesh, Vec3};

/// A mesh file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MeshFormat {
    /// Wavefront OBJ (`.obj`), always text.
    Obj,
    /// Stereolithography (`.stl`), ASCII or binary.
    Stl,
    /// Polygon File Format (`.ply`), ASCII or binary.
    Ply,
}

/// Text or binary encoding for formats that have both (STL, PLY).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Encoding {
    /// Human-readable text.
    Ascii,
    /// Binary (STL: little-endian `f32`; PLY: `binary_little_endian` with `double` coordinates).
    #[default]
    Binary,
}

impl MeshFormat {
    /// The format named by the extension of `path` (`.obj`, `.stl`, `.ply`, any case).
    pub fn from_path(path: impl AsRef<Path>) -> Result<Self, IoError> {
        let path = path.as_ref();
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("obj") => Ok(MeshFormat::Obj),
            Some("stl") => Ok(MeshFormat::Stl),
            Some("ply") => Ok(MeshFormat::Ply),
            _ => Err(IoError::UnknownExtension {
                path: path.to_path_buf(),
                ext: path.extension().map(|e| e.to_string_lossy().into_owned()),
            }),
        }
    }

    /// The usual file extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            MeshFormat::Obj => "obj",
            MeshFormat::Stl => "stl",
            MeshFormat::Ply => "ply",
        }
    }
}

/// Reads a mesh, choosing the format by extension. Errors name the file and the place in it.
pub fn read_mesh(path: impl AsRef<Path>) -> Result<TriMesh, IoError> {
    let path = path.as_ref();
    let format = MeshFormat::from_path(path)?;
    let bytes = std::fs::read(path).map_err(|e| IoError::file(path, e))?;
    decode_mesh(&bytes, format, path)
}

/// Writes a mesh, choosing the format by extension (STL and PLY binary), atomically.
pub fn write_mesh(path: impl AsRef<Path>, mesh: &TriMesh) -> Result<(), IoError> {
    write_mesh_with(path, mesh, Encoding::Binary)
}

/// Writes a mesh in the format of the extension and the given encoding (ignored for OBJ, which
/// is always text), atomically: a failed write never destroys an existing file.
pub fn write_mesh_with(
    path: impl AsRef<Path>,
    mesh: &TriMesh,
    encoding: Encoding,
) -> Result<(), IoError> {
    let path = path.as_ref();
    let format = MeshFormat::from_path(path)?;
    mesh.validate().map_err(|source| IoError::InvalidMesh {
        path: path.to_path_buf(),
        source,
    })?;
    check_representable(path, mesh, format, encoding)?;
    crate::util::write_atomic(path, |w| write_valid(w, mesh, format, encoding))
}

/// [`write_mesh`] up to the rename: the checked mesh written to a temporary file beside `path`,
/// renamed over it by [`crate::Staged::commit`] (for commands that write several files all or
/// none).
pub fn stage_mesh(path: impl AsRef<Path>, mesh: &TriMesh) -> Result<crate::Staged, IoError> {
    let path = path.as_ref();
    let format = MeshFormat::from_path(path)?;
    let encoding = Encoding::Binary;
    mesh.validate().map_err(|source| IoError::InvalidMesh {
        path: path.to_path_buf(),
        source,
    })?;
    check_representable(path, mesh, format, encoding)?;
    crate::util::stage(path, |w| write_valid(w, mesh, format, encoding))
}

/// Encodes a mesh in memory.
pub fn encode_mesh(
    mesh: &TriMesh,
    format: MeshFormat,
    encoding: Encoding,
) -> Result<Vec<u8>, MeshError> {
    mesh.validate()?;
    let mut out = Vec::new();
    // Writing into a Vec cannot fail.
    let _ = write_valid(&mut out, mesh, format, encoding);
    Ok(out)
}

/// Decodes a mesh from memory; `name` is the file name used in error messages. The encoding
/// (STL and PLY) is detected from the content.
pub fn decode_mesh(
    bytes: &[u8],
    format: MeshFormat,
    name: impl AsRef<Path>,
) -> Result<TriMesh, IoError> {
    let ctx = Ctx {
        path: name.as_ref().to_path_buf(),
    };
    let mesh = match format {
        MeshFormat::Obj => obj::read(bytes, &ctx)?,
        MeshFormat::Stl => stl::read(bytes, &ctx)?,
        MeshFormat::Ply => ply::read(bytes, &ctx)?,
    };
    if mesh.positions.is_empty() {
        return Err(ctx.err(MeshLocation::File, "no vertices"));
    }
    // The readers check everything as they go; this is a last line of defence.
    mesh.validate()
        .map_err(|e| ctx.err(MeshLocation::File, e.to_string()))?;
    Ok(mesh)
}

/// Rejects what a format would write as `inf` or `nan` (issue 17): non-finite normals, and
/// coordinates beyond `f32::MAX` in binary STL (which stores `f32`).
fn check_representable(
    path: &Path,
    mesh: &TriMesh,
    format: MeshFormat,
    encoding: Encoding,
) -> Result<(), IoError> {
    let err = |message: String| IoError::Unwritable {
        path: path.to_path_buf(),
        message,
    };
    if let Some(i) = mesh
        .normals
        .iter()
        .position(|n| !n.iter().all(|c| c.is_finite()))
    {
        return Err(err(format!("normal {i} has a non-finite coordinate")));
    }
    if format == MeshFormat::Stl && encoding == Encoding::Binary {
        let max = f64::from(f32::MAX);
        if let Some(i) = mesh
            .positions
            .iter()
            .position(|p| p.iter().any(|c| c.abs() > max))
        {
            return Err(err(format!(
                "vertex {i} has a coordinate beyond the range of binary STL's 32-bit floats \
                 (about 3.4e38); write .obj or .ply"
            )));
        }
    }
    Ok(())
}

fn write_valid(
    w: &mut dyn Write,
    mesh: &TriMesh,
    format: MeshFormat,
    encoding: Encoding,
) -> std::io::Result<()> {
    match (format, encoding) {
        (MeshFormat::Obj, _) => obj::write(w, mesh),
        (MeshFormat::Stl, Encoding::Ascii) => stl::write_ascii(w, mesh),
        (MeshFormat::Stl, Encoding::Binary) => stl::write_binary(w, mesh),
        (MeshFormat::Ply, e) => ply::write(w, mesh, e),
    }
}

/// The file being read, for error messages.
#[derive(Debug)]
pub(crate) struct Ctx {
    path: PathBuf,
}

impl Ctx {
    fn err(&self, location: MeshLocation, message: impl Into<String>) -> IoError {
        IoError::Mesh {
            path: self.path.clone(),
            location,
            message: message.into(),
        }
    }
    fn line(&self, line: usize, message: impl Into<String>) -> IoError {
        self.err(MeshLocation::Line(line), message)
    }
    fn element(&self, kind: &str, index: usize, message: impl Into<String>) -> IoError {
        self.err(
            MeshLocation::Element {
                kind: kind.into(),
                index,
            },
            message,
        )
    }
}

/// Shortest text that reads back as the same `f64` (`1.0`, `0.1`, `1e-7`).
fn fmt_f64(x: f64) -> String {
    format!("{x:?}")
}

/// Unit normal of a triangle, or zero when it is degenerate.
fn facet_normal(mesh: &TriMesh, t: &[u32; 3]) -> Vec3 {
    let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
    let n = (b - a).cross(&(c - a));
    let len = n.norm();
    if len > 0.0 && len.is_finite() {
        n / len
    } else {
        Vec3::zeros()
    }
}

/// Builds a mesh from triangle soup, merging bit-identical vertices (`-0.0` equals `0.0`).
#[derive(Debug, Default)]
struct Welder {
    mesh: TriMesh,
    index: HashMap<[u64; 3], u32>,
}

impl Welder {
    fn vertex(&mut self, p: Vec3) -> u32 {
        let key = [p.x, p.y, p.z].map(|c| (c + 0.0).to_bits());
        let next = self.mesh.positions.len() as u32;
        *self.index.entry(key).or_insert_with(|| {
            self.mesh.positions.push(p);
            next
        })
    }
    fn triangle(&mut self, corners: [Vec3; 3]) {
        let t = corners.map(|p| self.vertex(p));
        self.mesh.triangles.push(t);
    }
}
