//! OpenVolumeMesh's text format (`.ovm`, "OVM ASCII").
//!
//! # Layout
//! ```text
//! OVM ASCII
//! Vertices
//! n_v
//! x y z                      (n_v lines)
//! Edges
//! n_e
//! a b                        (n_e lines; half-edge 2e runs a -> b, 2e+1 runs b -> a)
//! Faces
//! n_f
//! k h_1 .. h_k               (n_f lines; k half-edge indices forming a closed loop)
//! Polyhedra
//! n_c
//! m g_1 .. g_m               (n_c lines; m half-face indices: 2f is face f as listed,
//!                             2f+1 is face f reversed)
//! ```
//! OpenVolumeMesh orients the half-faces of a cell with their normals (right-hand rule) pointing
//! *into* the cell; the writer follows this and the reader accepts both orientations (a whole
//! connected component listed inside out is flipped by [`Lattice::from_cells`]).
//!
//! # Reading
//! Blank lines are skipped and `#` starts a comment; keywords and the header are matched without
//! regard to case. Everything after the polyhedra (property sections) is ignored. Each element is
//! on its own line and errors name the file, the line and the element. Points, edges and faces
//! that no polyhedron uses make the lattice invalid ([`crate::LatticeError::UnusedPoint`]) or
//! are dropped (edges, faces). Ids are kept: vertex `i` is point `i`, and edges and faces used by
//! polyhedra keep their order and (where the orientation allows) their loops, so
//! `read(write(l)) == l` element for element.
//!
//! # Limitations
//! The binary variant ("OVM BINARY") is not supported; properties are neither read nor written.

use std::io::{self, Write};
use std::path::Path;

use vclay_core::Vec3;

use crate::edit::renumber_like;
use crate::formats::{FormatError, Real, display_name, read_text, write_atomic};
use crate::ids::{CellId, FaceId};
use crate::lattice::Lattice;

/// Reads a `.ovm` file.
pub fn read(path: &Path) -> Result<Lattice, FormatError> {
    let text = read_text(path)?;
    parse(&text, &display_name(path))
}

/// Parses `.ovm` text; `name` is used in error messages.
pub fn parse(text: &str, name: &str) -> Result<Lattice, FormatError> {
    let mut r = Reader {
        lines: text.lines().enumerate(),
        file: name,
        line: 0,
    };
    let header = r.next("the header \"OVM ASCII\"")?;
    let norm = header.split_whitespace().collect::<Vec<_>>().join(" ");
    if norm.eq_ignore_ascii_case("OVM BINARY") {
        return Err(FormatError::Unsupported {
            file: name.to_string(),
            what: "the binary OVM format".into(),
        });
    }
    if !norm.eq_ignore_ascii_case("OVM ASCII") {
        return Err(r.syntax("the header \"OVM ASCII\"", header));
    }

    let nv = r.section("Vertices")?;
    let mut points = Vec::with_capacity(nv.min(1 << 20));
    for i in 0..nv {
        let what = format!("vertex {i} as three numbers");
        let line = r.next(&what)?;
        let xs: Vec<f64> = line
            .split_whitespace()
            .map(|t| t.parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| r.syntax(&what, line))?;
        if xs.len() != 3 || !xs.iter().all(|x| x.is_finite()) {
            return Err(r.syntax(&format!("vertex {i} as three finite numbers"), line));
        }
        points.push(Vec3::new(xs[0], xs[1], xs[2]));
    }

    let ne = r.section("Edges")?;
    let mut edges: Vec<[u32; 2]> = Vec::with_capacity(ne.min(1 << 20));
    for e in 0..ne {
        let element = format!("edge {e}");
        let ids = r.ints(&element, Some(2))?;
        for &v in &ids {
            if v >= nv as u64 {
                return Err(r.reference(&element, "vertex", v, nv, "vertices"));
            }
        }
        if ids[0] == ids[1] {
            return Err(r.element(&element, format!("both ends are vertex {}", ids[0])));
        }
        edges.push([ids[0] as u32, ids[1] as u32]);
    }

    let nf = r.section("Faces")?;
    let mut faces: Vec<Vec<u32>> = Vec::with_capacity(nf.min(1 << 20));
    for f in 0..nf {
        let element = format!("face {f}");
        let hes = r.ints(&element, None)?;
        let mut lp = Vec::with_capacity(hes.len());
        for &h in &hes {
            if h >= 2 * ne as u64 {
                return Err(r.reference(&element, "half-edge", h, ne, "edges"));
            }
            let [a, b] = edges[(h / 2) as usize];
            lp.push(if h % 2 == 0 { [a, b] } else { [b, a] });
        }
        if lp.len() < 3 {
            return Err(r.element(
                &element,
                format!("has {} half-edges, a face needs at least 3", lp.len()),
            ));
        }
        for i in 0..lp.len() {
            let j = (i + 1) % lp.len();
            if lp[i][1] != lp[j][0] {
                return Err(r.element(
                    &element,
                    format!(
                        "half-edge {} ends at vertex {} but the next one, {}, starts at vertex {}",
                        hes[i], lp[i][1], hes[j], lp[j][0]
                    ),
                ));
            }
        }
        faces.push(lp.iter().map(|h| h[0]).collect());
    }

    let nc = r.section("Polyhedra")?;
    let mut cells: Vec<Vec<Vec<u32>>> = Vec::with_capacity(nc.min(1 << 20));
    for c in 0..nc {
        let element = format!("polyhedron {c}");
        let hfs = r.ints(&element, None)?;
        if hfs.len() < 4 {
            return Err(r.element(
                &element,
                format!(
                    "has {} half-faces, a polyhedron needs at least 4",
                    hfs.len()
                ),
            ));
        }
        let mut cell = Vec::with_capacity(hfs.len());
        for &g in &hfs {
            if g >= 2 * nf as u64 {
                return Err(r.reference(&element, "half-face", g, nf, "faces"));
            }
            let mut lp = faces[(g / 2) as usize].clone();
            // OVM half-faces of a cell point into it; from_cells wants them pointing out.
            if g % 2 == 0 {
                lp.reverse();
            }
            cell.push(lp);
        }
        cells.push(cell);
    }

    let lattice_err = |source| FormatError::Lattice {
        file: name.to_string(),
        source,
    };
    let built = Lattice::from_cells(points, &cells).map_err(lattice_err)?;
    let ref_edges: Vec<Option<[u32; 2]>> = edges.into_iter().map(Some).collect();
    let ref_faces: Vec<Option<Vec<u32>>> = faces.into_iter().map(Some).collect();
    let (lattice, _, _) = renumber_like(built, &ref_edges, &ref_faces).map_err(lattice_err)?;
    Ok(lattice)
}

/// Writes `lattice` as `.ovm` text.
pub fn write_to(lattice: &Lattice, w: &mut dyn Write) -> io::Result<()> {
    writeln!(w, "OVM ASCII")?;
    writeln!(w, "Vertices")?;
    writeln!(w, "{}", lattice.num_points())?;
    for p in lattice.points() {
        writeln!(w, "{} {} {}", Real(p.x), Real(p.y), Real(p.z))?;
    }
    writeln!(w, "Edges")?;
    writeln!(w, "{}", lattice.num_edges())?;
    for [a, b] in lattice.edges() {
        writeln!(w, "{} {}", a.0, b.0)?;
    }
    writeln!(w, "Faces")?;
    writeln!(w, "{}", lattice.num_faces())?;
    let mut line = String::new();
    for f in 0..lattice.num_faces() {
        let fid = FaceId::new(f);
        let vs = lattice.face_vertices(fid);
        let es = lattice.face_edges(fid);
        line.clear();
        line.push_str(&vs.len().to_string());
        for (i, e) in es.iter().enumerate() {
            let forward = lattice.edge_vertices(*e)[0] == vs[i];
            let h = 2 * u64::from(e.0) + u64::from(!forward);
            line.push(' ');
            line.push_str(&h.to_string());
        }
        writeln!(w, "{line}")?;
    }
    writeln!(w, "Polyhedra")?;
    writeln!(w, "{}", lattice.num_cells())?;
    for c in 0..lattice.num_cells() {
        let cid = CellId::new(c);
        let fs = lattice.cell_faces(cid);
        line.clear();
        line.push_str(&fs.len().to_string());
        for &f in fs {
            // The stored loop points out of the front cell: its inward half-face is 2f+1.
            let g = 2 * u64::from(f.0) + u64::from(!lattice.cell_uses_face_reversed(cid, f));
            line.push(' ');
            line.push_str(&g.to_string());
        }
        writeln!(w, "{line}")?;
    }
    Ok(())
}

/// `.ovm` text of `lattice`.
pub fn to_string(lattice: &Lattice) -> String {
    let mut buf = Vec::new();
    write_to(lattice, &mut buf).expect("writing to memory cannot fail");
    String::from_utf8(buf).expect("ASCII output")
}

/// Writes `lattice` to `path` (atomically: a temporary file renamed over the target).
pub fn write(lattice: &Lattice, path: &Path) -> Result<(), FormatError> {
    write_atomic(path, |w| write_to(lattice, w))
}

/// Line reader that skips blank lines and `#` comments and remembers the line number.
struct Reader<'a, I: Iterator<Item = (usize, &'a str)>> {
    lines: I,
    file: &'a str,
    line: usize,
}

impl<'a, I: Iterator<Item = (usize, &'a str)>> Reader<'a, I> {
    /// The next non-blank line with comments removed, trimmed.
    fn next(&mut self, expected: &str) -> Result<&'a str, FormatError> {
        for (i, raw) in self.lines.by_ref() {
            self.line = i + 1;
            let text = raw.split('#').next().unwrap_or("").trim();
            if !text.is_empty() {
                return Ok(text);
            }
        }
        self.line += 1;
        Err(FormatError::Syntax {
            file: self.file.to_string(),
            line: self.line,
            expected: expected.to_string(),
            found: "end of file".into(),
        })
    }

    fn syntax(&self, expected: &str, found: &str) -> FormatError {
        FormatError::Syntax {
            file: self.file.to_string(),
            line: self.line,
            expected: expected.to_string(),
            found: format!("\"{found}\""),
        }
    }

    fn element(&self, element: &str, message: String) -> FormatError {
        FormatError::BadElement {
            file: self.file.to_string(),
            line: self.line,
            element: element.to_string(),
            message,
        }
    }

    fn reference(
        &self,
        element: &str,
        kind: &'static str,
        index: u64,
        count: usize,
        counted: &'static str,
    ) -> FormatError {
        FormatError::BadReference {
            file: self.file.to_string(),
            line: self.line,
            element: element.to_string(),
            kind,
            index,
            count,
            counted,
        }
    }

    /// A section keyword followed by its count.
    fn section(&mut self, keyword: &str) -> Result<usize, FormatError> {
        let expected = format!("the section keyword \"{keyword}\"");
        let line = self.next(&expected)?;
        if !line.eq_ignore_ascii_case(keyword) {
            return Err(self.syntax(&expected, line));
        }
        let what = format!("the number of {}", keyword.to_ascii_lowercase());
        let line = self.next(&what)?;
        line.parse::<usize>()
            .map_err(|_| self.syntax(&format!("{what} (a non-negative integer)"), line))
    }

    /// A line of non-negative integers: exactly `fixed` of them, or a count followed by that
    /// many.
    fn ints(&mut self, element: &str, fixed: Option<usize>) -> Result<Vec<u64>, FormatError> {
        let what = match fixed {
            Some(n) => format!("{element} as {n} non-negative integers"),
            None => format!("{element} as a count followed by that many indices"),
        };
        let line = self.next(&what)?;
        let nums: Vec<u64> = line
            .split_whitespace()
            .map(|t| t.parse::<u64>())
            .collect::<Result<_, _>>()
            .map_err(|_| self.syntax(&what, line))?;
        match fixed {
            Some(n) if nums.len() == n => Ok(nums),
            Some(_) => Err(self.syntax(&what, line)),
            None => {
                let Some((&k, rest)) = nums.split_first() else {
                    return Err(self.syntax(&what, line));
                };
                if k != rest.len() as u64 {
                    return Err(self.element(
                        element,
                        format!("declares {k} indices but lists {}", rest.len()),
                    ));
                }
                Ok(rest.to_vec())
            }
        }
    }
}
