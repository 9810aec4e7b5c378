//! Small writers for triangle surfaces (the lattice boundary from [`crate::boundary_mesh`]):
//! Wavefront OBJ, ASCII STL and ASCII PLY. Local stand-ins until `vclay-io` unifies mesh
//! export.
//!
//! * OBJ: a comment line, `v x y z` per vertex, `f a b c` per triangle (1-based indices).
//! * STL: `solid NAME`, per triangle `facet normal nx ny nz` / `outer loop` / three
//!   `vertex x y z` / `endloop` / `endfacet`, then `endsolid NAME`; the normal is the unit
//!   right-hand normal of the triangle (zero for a degenerate one).
//! * PLY: `ply`, `format ascii 1.0`, `element vertex N` with `property double x|y|z`,
//!   `element face M` with `property list uchar int vertex_indices`, `end_header`, then the
//!   vertices and `3 a b c` per triangle (0-based).
//!
//! Triangles are counter-clockwise seen from outside. All writers write atomically (see
//! [`crate::formats::write_atomic`]).

use std::io::{self, Write};
use std::path::Path;

use vclay_core::TriMesh;

use crate::formats::{FormatError, Real, write_atomic};

/// Writes `mesh` as Wavefront OBJ.
pub fn write_obj_to(mesh: &TriMesh, w: &mut dyn Write) -> io::Result<()> {
    writeln!(w, "# vclay lattice boundary")?;
    for p in &mesh.positions {
        writeln!(w, "v {} {} {}", Real(p.x), Real(p.y), Real(p.z))?;
    }
    for t in &mesh.triangles {
        writeln!(w, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?;
    }
    Ok(())
}

/// Writes `mesh` as ASCII STL with solid name `name`.
pub fn write_stl_to(mesh: &TriMesh, name: &str, w: &mut dyn Write) -> io::Result<()> {
    writeln!(w, "solid {name}")?;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let n = (b - a).cross(&(c - a));
        let n = if n.norm() > 0.0 { n.normalize() } else { n };
        writeln!(
            w,
            "  facet normal {} {} {}",
            Real(n.x),
            Real(n.y),
            Real(n.z)
        )?;
        writeln!(w, "    outer loop")?;
        for p in [a, b, c] {
            writeln!(w, "      vertex {} {} {}", Real(p.x), Real(p.y), Real(p.z))?;
        }
        writeln!(w, "    endloop")?;
        writeln!(w, "  endfacet")?;
    }
    writeln!(w, "endsolid {name}")
}

/// Writes `mesh` as ASCII PLY.
pub fn write_ply_to(mesh: &TriMesh, w: &mut dyn Write) -> io::Result<()> {
    writeln!(w, "ply")?;
    writeln!(w, "format ascii 1.0")?;
    writeln!(w, "comment vclay lattice boundary")?;
    writeln!(w, "element vertex {}", mesh.positions.len())?;
    writeln!(w, "property double x")?;
    writeln!(w, "property double y")?;
    writeln!(w, "property double z")?;
    writeln!(w, "element face {}", mesh.triangles.len())?;
    writeln!(w, "property list uchar int vertex_indices")?;
    writeln!(w, "end_header")?;
    for p in &mesh.positions {
        writeln!(w, "{} {} {}", Real(p.x), Real(p.y), Real(p.z))?;
    }
    for t in &mesh.triangles {
        writeln!(w, "3 {} {} {}", t[0], t[1], t[2])?;
    }
    Ok(())
}

/// Writes `mesh` to `path` as OBJ (atomically).
pub fn write_obj(mesh: &TriMesh, path: &Path) -> Result<(), FormatError> {
    write_atomic(path, |w| write_obj_to(mesh, w))
}

/// Writes `mesh` to `path` as ASCII STL (atomically); the solid is named after the file stem.
pub fn write_stl(mesh: &TriMesh, path: &Path) -> Result<(), FormatError> {
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().replace(char::is_whitespace, "_"))
        .unwrap_or_else(|| "vclay".into());
    write_atomic(path, |w| write_stl_to(mesh, &name, w))
}

/// Writes `mesh` to `path` as ASCII PLY (atomically).
pub fn write_ply(mesh: &TriMesh, path: &Path) -> Result<(), FormatError> {
    write_atomic(path, |w| write_ply_to(mesh, w))
}
