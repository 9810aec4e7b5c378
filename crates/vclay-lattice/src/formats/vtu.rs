//! VTK XML unstructured grid (`.vtu`), ASCII data arrays: [`write()`] and, for the subset it
//! writes, [`read`] / [`parse`] (issue 20: `vclay render` and `vclay convert` take `.vtu` lattices).
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

// ---------------------------------------------------------------------------------------------
// Reading

/// Most values of one data array accepted by [`parse`]: 2^28 (2 GiB of `f64`). The file text
/// bounds the count anyway (every value takes at least two bytes), so this only guards against
/// declared sizes that do not match the text.
pub const MAX_ARRAY_VALUES: usize = 1 << 28;

/// Reads a `.vtu` file of the subset [`write()`] writes (see [`parse`]).
pub fn read(path: &Path) -> Result<Lattice, FormatError> {
    let text = crate::formats::read_text(path)?;
    parse(&text, &crate::formats::display_name(path))
}

/// One `<DataArray>` of the file: its attributes, values and the line of its start tag.
struct Array {
    name: String,
    components: usize,
    values: Vec<f64>,
    line: usize,
}

/// The XML subset of VTK files: start tags with attributes and the text between tags.
struct Xml<'a> {
    text: &'a str,
    file: &'a str,
    /// Byte offsets of line starts.
    lines: Vec<usize>,
}

impl<'a> Xml<'a> {
    fn line_of(&self, at: usize) -> usize {
        self.lines.partition_point(|&s| s <= at)
    }

    fn syntax(&self, at: usize, expected: &str, found: &str) -> FormatError {
        FormatError::Syntax {
            file: self.file.to_string(),
            line: self.line_of(at),
            expected: expected.to_string(),
            found: format!("\"{}\"", found.chars().take(60).collect::<String>()),
        }
    }

    fn bad(
        &self,
        line: usize,
        element: impl Into<String>,
        message: impl Into<String>,
    ) -> FormatError {
        FormatError::BadElement {
            file: self.file.to_string(),
            line,
            element: element.into(),
            message: message.into(),
        }
    }

    /// The next start tag `<name ...>` at or after `from` (not `</...`, `<?...`, `<!...`):
    /// its name, attributes, whether it is self-closing, its start and the offset after it.
    #[allow(clippy::type_complexity)]
    fn next_tag(
        &self,
        from: usize,
    ) -> Result<Option<(&'a str, Vec<(&'a str, &'a str)>, bool, usize, usize)>, FormatError> {
        let mut i = from;
        loop {
            let Some(k) = self.text[i..].find('<') else {
                return Ok(None);
            };
            let start = i + k;
            let rest = &self.text[start + 1..];
            if rest.starts_with('/') || rest.starts_with('?') || rest.starts_with('!') {
                i = start + 1;
                continue;
            }
            let Some(end) = rest.find('>') else {
                return Err(self.syntax(start, "'>' closing the tag", rest));
            };
            let inner = &rest[..end];
            let (inner, closed) = match inner.strip_suffix('/') {
                Some(s) => (s, true),
                None => (inner, false),
            };
            let name_end = inner
                .find(|c: char| c.is_ascii_whitespace())
                .unwrap_or(inner.len());
            let name = &inner[..name_end];
            let mut attrs = Vec::new();
            let mut a = inner[name_end..].trim_start();
            while !a.is_empty() {
                let Some(eq) = a.find('=') else {
                    return Err(self.syntax(start, "an attribute name=\"value\"", a));
                };
                let key = a[..eq].trim();
                let v = a[eq + 1..].trim_start();
                let q = v.chars().next().filter(|&c| c == '"' || c == '\'');
                let Some(q) = q else {
                    return Err(self.syntax(start, "a quoted attribute value", v));
                };
                let Some(close) = v[1..].find(q) else {
                    return Err(self.syntax(start, "the closing quote of an attribute", v));
                };
                attrs.push((key, &v[1..1 + close]));
                a = v[close + 2..].trim_start();
            }
            return Ok(Some((name, attrs, closed, start, start + 1 + end + 1)));
        }
    }
}

fn attr<'a>(attrs: &[(&'a str, &'a str)], key: &str) -> Option<&'a str> {
    attrs.iter().find(|(k, _)| *k == key).map(|(_, v)| *v)
}

/// Parses `.vtu` text of the subset [`write()`] writes; `name` is used in error messages.
///
/// Read: one `<Piece>` of an `UnstructuredGrid` with ASCII `<DataArray>`s: the points
/// (3 components), `connectivity`, `offsets` (end of each cell's run), `types` (10 tetrahedron,
/// 12 hexahedron, 13 wedge, 14 pyramid with VTK's point orders, 42 polyhedron with the `faces` /
/// `faceoffsets` arrays), and any point or cell data, which is skipped. The cells become a
/// [`Lattice`] through [`Lattice::from_cells`] (faces of the linear types from
/// [`reference_faces`]), so points and cells keep their order and a file written by [`write()`]
/// gives back the lattice's points exactly and its cells as the same point sets. Binary,
/// appended or compressed data, several pieces and other cell types are
/// [`FormatError::Unsupported`] or a located error; every count is checked against the
/// values present before it is used.
pub fn parse(text: &str, name: &str) -> Result<Lattice, FormatError> {
    let mut lines = vec![0];
    lines.extend(text.match_indices('\n').map(|(i, _)| i + 1));
    let x = Xml {
        text,
        file: name,
        lines,
    };
    let unsupported = |what: &str| FormatError::Unsupported {
        file: name.to_string(),
        what: what.to_string(),
    };
    // Header and piece.
    let mut at = 0;
    let mut piece: Option<(usize, usize, usize)> = None;
    let mut seen_file = false;
    let mut arrays: Vec<(String, Array)> = Vec::new();
    let mut section = String::new();
    while let Some((tag, attrs, closed, start, end)) = x.next_tag(at)? {
        at = end;
        match tag {
            "VTKFile" => {
                if attr(&attrs, "type") != Some("UnstructuredGrid") {
                    return Err(x.syntax(
                        start,
                        "a VTKFile of type=\"UnstructuredGrid\"",
                        attr(&attrs, "type").unwrap_or("(no type)"),
                    ));
                }
                if attr(&attrs, "compressor").is_some() {
                    return Err(unsupported("compressed VTK data"));
                }
                seen_file = true;
            }
            "Piece" => {
                if piece.is_some() {
                    return Err(unsupported("a file of several pieces"));
                }
                let count = |key: &str| -> Result<usize, FormatError> {
                    let v = attr(&attrs, key).unwrap_or("");
                    v.trim().parse::<usize>().map_err(|_| {
                        x.syntax(start, &format!("{key} as a non-negative integer"), v)
                    })
                };
                piece = Some((
                    count("NumberOfPoints")?,
                    count("NumberOfCells")?,
                    x.line_of(start),
                ));
            }
            "Points" | "Cells" | "PointData" | "CellData" => section = tag.to_string(),
            "AppendedData" => return Err(unsupported("appended (binary) VTK data")),
            "DataArray" => {
                let line = x.line_of(start);
                let aname = attr(&attrs, "Name").unwrap_or("").to_string();
                let format = attr(&attrs, "format").unwrap_or("ascii");
                if format != "ascii" {
                    return Err(unsupported(&format!(
                        "the {format} format of data array \"{aname}\" (only ascii is read)"
                    )));
                }
                let components = match attr(&attrs, "NumberOfComponents") {
                    None => 1,
                    Some(v) => v
                        .trim()
                        .parse::<usize>()
                        .ok()
                        .filter(|&c| (1..=16).contains(&c))
                        .ok_or_else(|| x.syntax(start, "NumberOfComponents from 1 to 16", v))?,
                };
                let mut values = Vec::new();
                if !closed {
                    let Some(k) = text[end..].find('<') else {
                        return Err(x.syntax(end, "</DataArray>", "end of file"));
                    };
                    let body = &text[end..end + k];
                    if !text[end + k..].starts_with("</DataArray") {
                        return Err(x.syntax(end + k, "</DataArray>", &text[end + k..]));
                    }
                    // Only the arrays that build the lattice are parsed.
                    let wanted = section == "Points"
                        || (section == "Cells"
                            && matches!(
                                aname.as_str(),
                                "connectivity" | "offsets" | "types" | "faces" | "faceoffsets"
                            ));
                    if wanted {
                        let mut off = end;
                        for tok in body.split_ascii_whitespace() {
                            // Offset of the token, for its line.
                            let p = text[off..].find(tok).map_or(off, |q| off + q);
                            off = p + tok.len();
                            let v: f64 = tok.parse().map_err(|_| {
                                x.syntax(p, &format!("a number in data array \"{aname}\""), tok)
                            })?;
                            if !v.is_finite() {
                                return Err(x.syntax(
                                    p,
                                    &format!("a finite number in data array \"{aname}\""),
                                    tok,
                                ));
                            }
                            if values.len() >= MAX_ARRAY_VALUES {
                                return Err(x.bad(
                                    line,
                                    format!("data array \"{aname}\""),
                                    "more than 2^28 values",
                                ));
                            }
                            values.push(v);
                        }
                    }
                    at = end + k + 1;
                }
                if section == "Points" || section == "Cells" {
                    let key = if section == "Points" {
                        "Points".to_string()
                    } else {
                        aname.clone()
                    };
                    if arrays.iter().any(|(k, _)| *k == key) {
                        return Err(x.bad(line, format!("data array \"{aname}\""), "given twice"));
                    }
                    arrays.push((
                        key,
                        Array {
                            name: aname,
                            components,
                            values,
                            line,
                        },
                    ));
                }
            }
            _ => {}
        }
    }
    if !seen_file {
        return Err(x.syntax(
            0,
            "a <VTKFile type=\"UnstructuredGrid\"> element",
            text.trim_start(),
        ));
    }
    let Some((np, nc, piece_line)) = piece else {
        return Err(x.syntax(text.len(), "a <Piece> element", "end of file"));
    };
    let get = |key: &str| -> Result<&Array, FormatError> {
        arrays
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, a)| a)
            .ok_or_else(|| x.bad(piece_line, "Piece", format!("no \"{key}\" data array")))
    };
    let pts = get("Points")?;
    if pts.components != 3 || pts.values.len() != 3 * np {
        return Err(x.bad(
            pts.line,
            format!("points array \"{}\"", pts.name),
            format!(
                "{} values in {} components for NumberOfPoints=\"{np}\" (3 components expected)",
                pts.values.len(),
                pts.components
            ),
        ));
    }
    let points: Vec<Vec3> = pts
        .values
        .chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect();
    // Integer arrays: whole numbers in range.
    let ints = |a: &Array, lo: f64, hi: f64| -> Result<Vec<i64>, FormatError> {
        a.values
            .iter()
            .enumerate()
            .map(|(i, &v)| {
                if v.fract() == 0.0 && v >= lo && v <= hi {
                    Ok(v as i64)
                } else {
                    Err(x.bad(
                        a.line,
                        format!("data array \"{}\" value {i}", a.name),
                        format!("{v} is not an integer from {lo} to {hi}"),
                    ))
                }
            })
            .collect()
    };
    let conn_a = get("connectivity")?;
    let conn = ints(conn_a, 0.0, (np as f64 - 1.0).max(0.0))?;
    if np == 0 && !conn.is_empty() {
        return Err(x.bad(
            conn_a.line,
            "connectivity",
            "point references but no points",
        ));
    }
    let offs_a = get("offsets")?;
    let offsets = ints(offs_a, 0.0, conn.len() as f64)?;
    let types_a = get("types")?;
    let types = ints(types_a, 0.0, 255.0)?;
    if offsets.len() != nc || types.len() != nc {
        return Err(x.bad(
            piece_line,
            "Piece",
            format!(
                "NumberOfCells=\"{nc}\" but {} offsets and {} types",
                offsets.len(),
                types.len()
            ),
        ));
    }
    let poly = types.contains(&i64::from(VTK_POLYHEDRON));
    let (faces, faceoffsets) = if poly {
        let fa = get("faces")?;
        let fo = get("faceoffsets")?;
        let faces = ints(fa, 0.0, u32::MAX as f64)?;
        let fos = ints(fo, -1.0, faces.len() as f64)?;
        if fos.len() != nc {
            return Err(x.bad(
                fo.line,
                "faceoffsets",
                format!("{} values for {nc} cells", fos.len()),
            ));
        }
        (faces, fos)
    } else {
        (Vec::new(), Vec::new())
    };
    let mut cells: Vec<Vec<Vec<u32>>> = Vec::with_capacity(nc);
    let (mut prev, mut prev_face) = (0usize, 0usize);
    for c in 0..nc {
        let end = offsets[c] as usize;
        let cell_err = |m: String| x.bad(offs_a.line, format!("cell {c}"), m);
        if end < prev {
            return Err(cell_err(format!(
                "offset {end} is smaller than the previous one {prev}"
            )));
        }
        let ids: Vec<u32> = conn[prev..end].iter().map(|&v| v as u32).collect();
        prev = end;
        let t = types[c] as u8;
        let cell: Vec<Vec<u32>> = match t {
            VTK_TETRA | VTK_HEXAHEDRON | VTK_WEDGE | VTK_PYRAMID => {
                let want = match t {
                    VTK_TETRA => 4,
                    VTK_HEXAHEDRON => 8,
                    VTK_WEDGE => 6,
                    _ => 5,
                };
                if ids.len() != want {
                    return Err(cell_err(format!(
                        "VTK type {t} has {want} points, found {}",
                        ids.len()
                    )));
                }
                reference_faces(t)
                    .iter()
                    .map(|f| f.iter().map(|&i| ids[i]).collect())
                    .collect()
            }
            VTK_POLYHEDRON => {
                let fend = faceoffsets[c];
                if fend < 0 {
                    return Err(cell_err("a polyhedron with faceoffset -1".into()));
                }
                let fend = fend as usize;
                if fend < prev_face {
                    return Err(cell_err(format!(
                        "faceoffset {fend} is smaller than the previous one {prev_face}"
                    )));
                }
                let run = &faces[prev_face..fend];
                prev_face = fend;
                let mut loops = Vec::new();
                let Some((&nf, mut rest)) = run.split_first() else {
                    return Err(cell_err("an empty run in \"faces\"".into()));
                };
                for k in 0..nf {
                    let Some((&n, r)) = rest.split_first() else {
                        return Err(cell_err(format!(
                            "face {k} of {nf} is missing in \"faces\""
                        )));
                    };
                    let n = n as usize;
                    if n > r.len() {
                        return Err(cell_err(format!(
                            "face {k} has {n} points but the run ends"
                        )));
                    }
                    let l: Vec<u32> = r[..n].iter().map(|&v| v as u32).collect();
                    if let Some(&bad) = l.iter().find(|&&v| v as usize >= np) {
                        return Err(FormatError::BadReference {
                            file: name.to_string(),
                            line: offs_a.line,
                            element: format!("cell {c} face {k}"),
                            kind: "point",
                            index: u64::from(bad),
                            count: np,
                            counted: "points",
                        });
                    }
                    loops.push(l);
                    rest = &r[n..];
                }
                if !rest.is_empty() {
                    return Err(cell_err(format!(
                        "{} values after its {nf} faces in \"faces\"",
                        rest.len()
                    )));
                }
                loops
            }
            _ => {
                return Err(cell_err(format!(
                    "VTK cell type {t} is not read (10, 12, 13, 14 and 42 are)"
                )));
            }
        };
        if faceoffsets.get(c).is_some_and(|&f| f >= 0) && t != VTK_POLYHEDRON {
            return Err(cell_err(
                "a faceoffset for a cell that is not a polyhedron".into(),
            ));
        }
        cells.push(cell);
    }
    if prev != conn.len() {
        return Err(x.bad(
            offs_a.line,
            "offsets",
            format!(
                "the last offset {prev} leaves {} connectivity values unused",
                conn.len() - prev
            ),
        ));
    }
    Lattice::from_cells(points, &cells).map_err(|source| FormatError::Lattice {
        file: name.to_string(),
        source,
    })
}
