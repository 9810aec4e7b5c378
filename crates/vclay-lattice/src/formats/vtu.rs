//! VTK XML unstructured grid (`.vtu`), ASCII data arrays, write only.
//!
//! # Cell types
//! Each cell's type is detected from its topology, and its points are ordered as VTK's
//! reference cells require (VTK file formats, "linear cell types"):
//!
//! | cell | detection | VTK type | point order |
//! | --- | --- | --- | --- |
//! | tetrahedron | 4 triangles | `VTK_TETRA` = 10 | `0 1 2` with its right-hand normal towards `3` |
//! | hexahedron | 6 quads, 8 points of degree 3 | `VTK_HEXAHEDRON` = 12 | `0 1 2 3` normal towards `4 5 6 7`, `4 + i` joined to `i` |
//! | wedge | 2 triangles + 3 quads | `VTK_WEDGE` = 13 | `0 1 2` normal towards `3 4 5`, `3 + i` joined to `i` |
//! | pyramid | 1 quad + 4 triangles | `VTK_PYRAMID` = 14 | `0 1 2 3` normal towards the apex `4` |
//! | anything else | | `VTK_POLYHEDRON` = 42 | the cell's points in id order, faces listed outward |
//!
//! Every linear type thus has its base's right-hand normal pointing into the cell, which is
//! what VTK computes positive volumes and Jacobians for (checked with VTK 9.7's
//! `vtkCellSizeFilter`). For the wedge this contradicts the `vtkWedge` class documentation ("a
//! triangle whose normal points outward"), which VTK's own code does not follow: wedges written
//! by that text get negative volumes in ParaView, a known trap (meshio, GEOS and 4C fixed their
//! writers for it).
//!
//! After ordering, the faces implied by the VTK reference cell must be exactly the cell's faces;
//! a cell that fails this check (it cannot for valid lattices) is written as a polyhedron.
//! Polyhedra use the `faces` / `faceoffsets` arrays of the VTK XML format (version 1.0):
//! `faces` holds, per polyhedron, the face count followed by each face as its point count and
//! point ids; `faceoffsets` holds the end of each cell's run in `faces`, or `-1` for cells of other
//! types. These two arrays are only written when there is at least one polyhedron.
//!
//! Besides the points and cells the file carries one cell-data array, `cell_id` (the lattice cell
//! id), so a viewer can map picks back to the lattice, and optionally point-data arrays
//! ([`write_with_point_data`]; `vclay run` writes the displacement, velocity, spring force and mass
//! of each data point).

use std::io::{self, Write};
use std::path::Path;

use crate::formats::{FormatError, Real, write_atomic};
use crate::ids::{CellId, VertexId};
use crate::lattice::Lattice;
use vclay_core::Vec3;

/// `VTK_TETRA`.
pub const VTK_TETRA: u8 = 10;
/// `VTK_HEXAHEDRON`.
pub const VTK_HEXAHEDRON: u8 = 12;
/// `VTK_WEDGE`.
pub const VTK_WEDGE: u8 = 13;
/// `VTK_PYRAMID`.
pub const VTK_PYRAMID: u8 = 14;
/// `VTK_POLYHEDRON`.
pub const VTK_POLYHEDRON: u8 = 42;

/// Faces of the VTK reference cells as point positions, each oriented outward.
const TETRA_FACES: &[&[usize]] = &[&[0, 1, 3], &[1, 2, 3], &[2, 0, 3], &[0, 2, 1]];
const HEX_FACES: &[&[usize]] = &[
    &[0, 4, 7, 3],
    &[1, 2, 6, 5],
    &[0, 1, 5, 4],
    &[3, 7, 6, 2],
    &[0, 3, 2, 1],
    &[4, 5, 6, 7],
];
const WEDGE_FACES: &[&[usize]] = &[
    &[0, 2, 1],
    &[3, 4, 5],
    &[0, 1, 4, 3],
    &[1, 2, 5, 4],
    &[2, 0, 3, 5],
];
const PYRAMID_FACES: &[&[usize]] = &[
    &[0, 3, 2, 1],
    &[0, 1, 4],
    &[1, 2, 4],
    &[2, 3, 4],
    &[3, 0, 4],
];

/// The outward face loops of the VTK reference cell `vtk_type` (points by position in the cell's
/// point list); empty for other types.
pub fn reference_faces(vtk_type: u8) -> &'static [&'static [usize]] {
    match vtk_type {
        VTK_TETRA => TETRA_FACES,
        VTK_HEXAHEDRON => HEX_FACES,
        VTK_WEDGE => WEDGE_FACES,
        VTK_PYRAMID => PYRAMID_FACES,
        _ => &[],
    }
}

/// The VTK type of cell `c` and its points in VTK order (for a polyhedron: its points in id
/// order).
pub fn vtk_cell(lattice: &Lattice, c: CellId) -> (u8, Vec<VertexId>) {
    let loops = outward_loops(lattice, c);
    let tris = loops.iter().filter(|l| l.len() == 3).count();
    let quads = loops.iter().filter(|l| l.len() == 4).count();
    let candidate = match (loops.len(), tris, quads) {
        (4, 4, 0) => {
            // Base: the first triangle, reversed so that its normal points inward.
            let b = &loops[0];
            let apex = other_points(lattice, c, b);
            (apex.len() == 1).then(|| (VTK_TETRA, vec![b[0], b[2], b[1], apex[0]]))
        }
        (5, 4, 1) => {
            let b = loops.iter().find(|l| l.len() == 4).unwrap();
            let apex = other_points(lattice, c, b);
            (apex.len() == 1).then(|| (VTK_PYRAMID, vec![b[0], b[3], b[2], b[1], apex[0]]))
        }
        (5, 2, 3) => {
            // Base: a triangle, reversed so that its normal points inward (towards the top).
            let b = loops.iter().find(|l| l.len() == 3).unwrap();
            let base = vec![b[0], b[2], b[1]];
            lift(lattice, c, &base).map(|top| (VTK_WEDGE, [base, top].concat()))
        }
        (6, 0, 6) => {
            let b = &loops[0];
            let base = vec![b[0], b[3], b[2], b[1]];
            lift(lattice, c, &base).map(|top| (VTK_HEXAHEDRON, [base, top].concat()))
        }
        _ => None,
    };
    match candidate {
        Some((t, pts)) if faces_match(&loops, &pts, reference_faces(t)) => (t, pts),
        _ => (VTK_POLYHEDRON, lattice.cell_vertices(c).to_vec()),
    }
}

/// The cell's face loops oriented outward for it.
fn outward_loops(lattice: &Lattice, c: CellId) -> Vec<Vec<VertexId>> {
    lattice
        .cell_faces(c)
        .iter()
        .map(|&f| {
            let mut l = lattice.face_vertices(f).to_vec();
            if lattice.cell_uses_face_reversed(c, f) {
                l.reverse();
            }
            l
        })
        .collect()
}

/// Points of cell `c` not in `base`.
fn other_points(lattice: &Lattice, c: CellId, base: &[VertexId]) -> Vec<VertexId> {
    lattice
        .cell_vertices(c)
        .iter()
        .copied()
        .filter(|v| !base.contains(v))
        .collect()
}

/// For each base point, its unique cell neighbour outside the base (`None` if not unique).
fn lift(lattice: &Lattice, c: CellId, base: &[VertexId]) -> Option<Vec<VertexId>> {
    let mut top = Vec::with_capacity(base.len());
    for &v in base {
        let mut found = None;
        for &e in lattice.cell_edges(c) {
            let [a, b] = lattice.edge_vertices(e);
            let w = if a == v {
                b
            } else if b == v {
                a
            } else {
                continue;
            };
            if !base.contains(&w) {
                if found.is_some() {
                    return None;
                }
                found = Some(w);
            }
        }
        top.push(found?);
    }
    Some(top)
}

/// Whether the reference faces over `pts` are exactly `loops` (same cycles, same direction).
fn faces_match(loops: &[Vec<VertexId>], pts: &[VertexId], reference: &[&[usize]]) -> bool {
    let canon = |l: &[VertexId]| -> Vec<VertexId> {
        let s = (0..l.len()).min_by_key(|&i| l[i]).unwrap();
        (0..l.len()).map(|i| l[(s + i) % l.len()]).collect()
    };
    let mut have: Vec<Vec<VertexId>> = loops.iter().map(|l| canon(l)).collect();
    let mut want: Vec<Vec<VertexId>> = reference
        .iter()
        .map(|f| canon(&f.iter().map(|&i| pts[i]).collect::<Vec<_>>()))
        .collect();
    have.sort();
    want.sort();
    have == want
}

/// A point-data array of a `.vtu` file: one value per lattice point, in point order (shown by
/// ParaView as a colouring or glyph field).
#[derive(Clone, Copy, Debug)]
pub enum PointData<'a> {
    /// One scalar per point (`Float64`, 1 component).
    Scalars(&'a str, &'a [f64]),
    /// One vector per point (`Float64`, 3 components).
    Vectors(&'a str, &'a [Vec3]),
}

impl PointData<'_> {
    fn name(&self) -> &str {
        match self {
            PointData::Scalars(n, _) | PointData::Vectors(n, _) => n,
        }
    }

    fn len(&self) -> usize {
        match self {
            PointData::Scalars(_, v) => v.len(),
            PointData::Vectors(_, v) => v.len(),
        }
    }
}

/// Writes `lattice` as a VTK XML unstructured grid.
pub fn write_to(lattice: &Lattice, w: &mut dyn Write) -> io::Result<()> {
    write_with_point_data_to(lattice, &[], w)
}

/// Writes `lattice` as a VTK XML unstructured grid with the point-data arrays `data`. An array
/// whose length is not the number of points, or whose name is empty, repeated or not plain
/// (letters, digits, `_`, `-`), is an `InvalidInput` error naming it, and nothing is written.
pub fn write_with_point_data_to(
    lattice: &Lattice,
    data: &[PointData<'_>],
    w: &mut dyn Write,
) -> io::Result<()> {
    for (i, d) in data.iter().enumerate() {
        let name = d.name();
        let plain = !name.is_empty()
            && name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
        let problem = if !plain {
            Some("its name must be letters, digits, '_' or '-'".to_string())
        } else if data[..i].iter().any(|e| e.name() == name) {
            Some("the name is used twice".to_string())
        } else if d.len() != lattice.num_points() {
            Some(format!(
                "{} values for {} points",
                d.len(),
                lattice.num_points()
            ))
        } else {
            None
        };
        if let Some(p) = problem {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("point-data array {i} \"{name}\": {p}"),
            ));
        }
    }
    let nc = lattice.num_cells();
    let mut connectivity: Vec<u32> = Vec::new();
    let mut offsets: Vec<usize> = Vec::with_capacity(nc);
    let mut types: Vec<u8> = Vec::with_capacity(nc);
    let mut faces: Vec<i64> = Vec::new();
    let mut faceoffsets: Vec<i64> = Vec::with_capacity(nc);
    for c in 0..nc {
        let cid = CellId::new(c);
        let (t, pts) = vtk_cell(lattice, cid);
        connectivity.extend(pts.iter().map(|v| v.0));
        offsets.push(connectivity.len());
        types.push(t);
        if t == VTK_POLYHEDRON {
            let loops = outward_loops(lattice, cid);
            faces.push(loops.len() as i64);
            for l in &loops {
                faces.push(l.len() as i64);
                faces.extend(l.iter().map(|v| i64::from(v.0)));
            }
            faceoffsets.push(faces.len() as i64);
        } else {
            faceoffsets.push(-1);
        }
    }
    writeln!(w, "<?xml version=\"1.0\"?>")?;
    writeln!(
        w,
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">"
    )?;
    writeln!(w, "  <UnstructuredGrid>")?;
    writeln!(
        w,
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{nc}\">",
        lattice.num_points()
    )?;
    writeln!(w, "      <Points>")?;
    writeln!(
        w,
        "        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">"
    )?;
    for p in lattice.points() {
        writeln!(w, "          {} {} {}", Real(p.x), Real(p.y), Real(p.z))?;
    }
    writeln!(w, "        </DataArray>")?;
    writeln!(w, "      </Points>")?;
    writeln!(w, "      <Cells>")?;
    array(w, "Int64", "connectivity", connectivity.iter())?;
    array(w, "Int64", "offsets", offsets.iter())?;
    array(w, "UInt8", "types", types.iter())?;
    if types.contains(&VTK_POLYHEDRON) {
        array(w, "Int64", "faces", faces.iter())?;
        array(w, "Int64", "faceoffsets", faceoffsets.iter())?;
    }
    writeln!(w, "      </Cells>")?;
    if !data.is_empty() {
        writeln!(w, "      <PointData>")?;
        for d in data {
            match d {
                PointData::Scalars(name, v) => {
                    array(w, "Float64", name, v.iter().map(|&x| Real(x)))?;
                }
                PointData::Vectors(name, v) => {
                    writeln!(
                        w,
                        "        <DataArray type=\"Float64\" Name=\"{name}\" NumberOfComponents=\"3\" format=\"ascii\">"
                    )?;
                    for p in v.iter() {
                        writeln!(w, "          {} {} {}", Real(p.x), Real(p.y), Real(p.z))?;
                    }
                    writeln!(w, "        </DataArray>")?;
                }
            }
        }
        writeln!(w, "      </PointData>")?;
    }
    writeln!(w, "      <CellData>")?;
    array(w, "Int64", "cell_id", 0..nc)?;
    writeln!(w, "      </CellData>")?;
    writeln!(w, "    </Piece>")?;
    writeln!(w, "  </UnstructuredGrid>")?;
    writeln!(w, "</VTKFile>")?;
    Ok(())
}

/// One ASCII data array, 16 values a line.
fn array<T: std::fmt::Display>(
    w: &mut dyn Write,
    ty: &str,
    name: &str,
    values: impl Iterator<Item = T>,
) -> io::Result<()> {
    writeln!(
        w,
        "        <DataArray type=\"{ty}\" Name=\"{name}\" format=\"ascii\">"
    )?;
    let mut line = String::new();
    for (i, v) in values.enumerate() {
        if i % 16 == 0 {
            if !line.is_empty() {
                writeln!(w, "{line}")?;
            }
            line.clear();
            line.push_str("          ");
        } else {
            line.push(' ');
        }
        line.push_str(&v.to_string());
    }
    if !line.is_empty() {
        writeln!(w, "{line}")?;
    }
    writeln!(w, "        </DataArray>")
}

/// `.vtu` text of `lattice`.
pub fn to_string(lattice: &Lattice) -> String {
    let mut buf = Vec::new();
    write_to(lattice, &mut buf).expect("writing to memory cannot fail");
    String::from_utf8(buf).expect("ASCII output")
}

/// Writes `lattice` to `path` (atomically: a temporary file renamed over the target).
pub fn write(lattice: &Lattice, path: &Path) -> Result<(), FormatError> {
    write_with_point_data(lattice, &[], path)
}

/// Writes `lattice` with point-data arrays to `path` (atomically), see
/// [`write_with_point_data_to`].
pub fn write_with_point_data(
    lattice: &Lattice,
    data: &[PointData<'_>],
    path: &Path,
) -> Result<(), FormatError> {
    write_atomic(path, |w| write_with_point_data_to(lattice, data, w))
}
