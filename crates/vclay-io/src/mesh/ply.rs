//! PLY reading (ASCII, binary little- and big-endian) and writing (ASCII, binary little-endian).

use super::{Ctx, Encoding, fmt_f64};
use crate::error::{IoError, MeshLocation, quote};
use std::io::Write;
use vclay_core::{TriMesh, Vec3};

pub(super) fn write(w: &mut dyn Write, mesh: &TriMesh, encoding: Encoding) -> std::io::Result<()> {
    if mesh.positions.len() > i32::MAX as usize {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "PLY with int indices holds at most 2^31 - 1 vertices",
        ));
    }
    let normals = !mesh.normals.is_empty();
    let format = match encoding {
        Encoding::Ascii => "ascii",
        Encoding::Binary => "binary_little_endian",
    };
    writeln!(w, "ply\nformat {format} 1.0\ncomment vclay mesh")?;
    writeln!(w, "element vertex {}", mesh.positions.len())?;
    writeln!(w, "property double x\nproperty double y\nproperty double z")?;
    if normals {
        writeln!(
            w,
            "property double nx\nproperty double ny\nproperty double nz"
        )?;
    }
    writeln!(w, "element face {}", mesh.triangles.len())?;
    writeln!(w, "property list uchar int vertex_indices\nend_header")?;
    for (k, p) in mesh.positions.iter().enumerate() {
        let n = normals.then(|| mesh.normals[k]);
        let vals = [Some(*p), n]
            .into_iter()
            .flatten()
            .flat_map(|v| [v.x, v.y, v.z]);
        match encoding {
            Encoding::Ascii => {
                let row: Vec<String> = vals.map(fmt_f64).collect();
                writeln!(w, "{}", row.join(" "))?;
            }
            Encoding::Binary => {
                for x in vals {
                    w.write_all(&x.to_le_bytes())?;
                }
            }
        }
    }
    for t in &mesh.triangles {
        match encoding {
            Encoding::Ascii => writeln!(w, "3 {} {} {}", t[0], t[1], t[2])?,
            Encoding::Binary => {
                w.write_all(&[3u8])?;
                for &i in t {
                    // Valid meshes index fewer than 2^31 vertices (checked above).
                    w.write_all(&(i as i32).to_le_bytes())?;
                }
            }
        }
    }
    Ok(())
}

/// A PLY scalar type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Clone, Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
    /// Header line of the `element` statement.
    line: usize,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    LittleEndian,
    BigEndian,
}

struct Header {
    format: Format,
    elements: Vec<Element>,
    /// Byte offset of the body.
    body: usize,
    /// Number of header lines (the body starts on the next line).
    lines: usize,
}

const TYPES: &str = "char, uchar, short, ushort, int, uint, float, double (or int8 ... float64)";

fn parse_header(bytes: &[u8], ctx: &Ctx) -> Result<Header, IoError> {
    let mut pos = 0;
    let mut line = 0;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(if line == 0 {
                ctx.err(
                    MeshLocation::File,
                    "not a PLY file (first line must be \"ply\")",
                )
            } else {
                ctx.line(line, "the header has no \"end_header\" line")
            });
        };
        let raw = String::from_utf8_lossy(&bytes[pos..pos + len]).into_owned();
        pos += len + 1;
        line += 1;
        let toks: Vec<&str> = raw.split_whitespace().collect();
        if line == 1 {
            if toks != ["ply"] {
                return Err(ctx.line(1, "not a PLY file (first line must be \"ply\")"));
            }
            continue;
        }
        match toks.as_slice() {
            [] => {}
            ["comment", ..] | ["obj_info", ..] => {}
            ["format", f, _version] => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::LittleEndian,
                    "binary_big_endian" => Format::BigEndian,
                    other => {
                        return Err(ctx.line(
                            line,
                            format!("unknown PLY format {}; expected ascii, binary_little_endian or binary_big_endian", quote(other)),
                        ));
                    }
                })
            }
            ["element", name, count] => {
                let count = count.parse().map_err(|_| {
                    ctx.line(
                        line,
                        format!(
                            "element count {} is not a non-negative integer",
                            quote(count)
                        ),
                    )
                })?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                    line,
                });
            }
            ["property", rest @ ..] => {
                let Some(el) = elements.last_mut() else {
                    return Err(ctx.line(line, "property before any element"));
                };
                let ty = |t: &str| {
                    Scalar::parse(t).ok_or_else(|| {
                        ctx.line(
                            line,
                            format!("unknown property type {}; expected {TYPES}", quote(t)),
                        )
                    })
                };
                let (kind, name) = match rest {
                    ["list", c, i, name] => {
                        let count = ty(c)?;
                        if !count.is_integer() {
                            return Err(ctx.line(
                                line,
                                format!("list count type {} is not an integer type", quote(c)),
                            ));
                        }
                        (
                            Kind::List {
                                count,
                                item: ty(i)?,
                            },
                            name,
                        )
                    }
                    [t, name] if *t != "list" => (Kind::Scalar(ty(t)?), name),
                    _ => {
                        return Err(ctx.line(
                            line,
                            "expected \"property TYPE NAME\" or \"property list COUNT_TYPE ITEM_TYPE NAME\"",
                        ));
                    }
                };
                el.props.push(Property {
                    name: name.to_string(),
                    kind,
                });
            }
            ["end_header"] => break,
            _ => {
                return Err(ctx.line(
                    line,
                    format!("unrecognized header line {}", quote(raw.trim())),
                ));
            }
        }
    }
    let Some(format) = format else {
        return Err(ctx.line(line, "the header has no \"format\" line"));
    };
    Ok(Header {
        format,
        elements,
        body: pos,
        lines: line,
    })
}

/// Why a value could not be read.
enum ReadError {
    /// The data ended.
    Eof,
    /// A token is not a number.
    NotANumber(String),
}

/// The body of the file: text tokens with their lines, or bytes.
enum Source<'a> {
    Ascii {
        tokens: Vec<(&'a str, usize)>,
        pos: usize,
        last_line: usize,
    },
    Binary {
        bytes: &'a [u8],
        pos: usize,
        big_endian: bool,
    },
}

impl Source<'_> {
    fn read(&mut self, t: Scalar) -> Result<f64, ReadError> {
        match self {
            Source::Ascii {
                tokens,
                pos,
                last_line,
            } => {
                let &(tok, line) = tokens.get(*pos).ok_or(ReadError::Eof)?;
                *pos += 1;
                *last_line = line;
                tok.parse::<f64>()
                    .ok()
                    .filter(|x| !t.is_integer() || x.fract() == 0.0)
                    .ok_or_else(|| ReadError::NotANumber(tok.to_string()))
            }
            Source::Binary {
                bytes,
                pos,
                big_endian,
            } => {
                let n = t.size();
                let b = bytes.get(*pos..*pos + n).ok_or(ReadError::Eof)?;
                *pos += n;
                let mut a = [0u8; 8];
                a[..n].copy_from_slice(b);
                if *big_endian {
                    a[..n].reverse();
                }
                Ok(match t {
                    Scalar::I8 => f64::from(a[0] as i8),
                    Scalar::U8 => f64::from(a[0]),
                    Scalar::I16 => f64::from(i16::from_le_bytes([a[0], a[1]])),
                    Scalar::U16 => f64::from(u16::from_le_bytes([a[0], a[1]])),
                    Scalar::I32 => f64::from(i32::from_le_bytes([a[0], a[1], a[2], a[3]])),
                    Scalar::U32 => f64::from(u32::from_le_bytes([a[0], a[1], a[2], a[3]])),
                    Scalar::F32 => f64::from(f32::from_le_bytes([a[0], a[1], a[2], a[3]])),
                    Scalar::F64 => f64::from_le_bytes(a),
                })
            }
        }
    }

    /// An error in row `index` of element `kind`: at a line for text, at the element for binary.
    fn err(&self, ctx: &Ctx, kind: &str, index: usize, message: &str) -> IoError {
        match self {
            Source::Ascii { last_line, .. } => {
                ctx.line(*last_line, format!("{kind} {index}: {message}"))
            }
            Source::Binary { .. } => ctx.element(kind, index, message),
        }
    }
}

/// Position of the property called `name` if it is a scalar.
fn scalar_prop(el: &Element, name: &str) -> Option<usize> {
    el.props
        .iter()
        .position(|p| p.name == name && matches!(p.kind, Kind::Scalar(_)))
}

pub(super) fn read(bytes: &[u8], ctx: &Ctx) -> Result<TriMesh, IoError> {
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(ctx.err(MeshLocation::File, "no vertices (the file is empty)"));
    }
    let header = parse_header(bytes, ctx)?;
    let body = &bytes[header.body..];
    let mut src = match header.format {
        Format::Ascii => {
            let text = std::str::from_utf8(body).map_err(|e| {
                ctx.err(
                    MeshLocation::File,
                    format!("ASCII PLY body is not valid text: {e}"),
                )
            })?;
            let tokens = text
                .lines()
                .enumerate()
                .flat_map(|(n, l)| l.split_whitespace().map(move |t| (t, header.lines + n + 1)))
                .collect();
            Source::Ascii {
                tokens,
                pos: 0,
                last_line: header.lines,
            }
        }
        f => Source::Binary {
            bytes: body,
            pos: 0,
            big_endian: f == Format::BigEndian,
        },
    };

    let vertex = header.elements.iter().find(|e| e.name == "vertex");
    let nverts = vertex.map_or(0, |e| e.count);
    if nverts == 0 {
        return Err(ctx.err(MeshLocation::File, "no vertices"));
    }
    if nverts > u32::MAX as usize {
        return Err(ctx.err(MeshLocation::File, "more than 2^32 - 1 vertices"));
    }
    let mut mesh = TriMesh::new();
    for el in &header.elements {
        let is_vertex = el.name == "vertex";
        let is_face = el.name == "face";
        // Positions of x y z (required) and nx ny nz (optional) among the properties.
        let xyz = if is_vertex {
            let p: Vec<Option<usize>> =
                ["x", "y", "z"].iter().map(|n| scalar_prop(el, n)).collect();
            match p.as_slice() {
                [Some(x), Some(y), Some(z)] => Some([*x, *y, *z]),
                _ => {
                    return Err(ctx.line(
                        el.line,
                        "element vertex lacks one of the scalar properties x, y, z",
                    ));
                }
            }
        } else {
            None
        };
        let nxyz = match ["nx", "ny", "nz"].map(|n| scalar_prop(el, n)) {
            [Some(x), Some(y), Some(z)] if is_vertex => Some([x, y, z]),
            _ => None,
        };
        let list_prop = if is_face {
            let found = el.props.iter().position(|p| {
                matches!(p.kind, Kind::List { .. })
                    && (p.name == "vertex_indices" || p.name == "vertex_index")
            });
            if found.is_none() {
                return Err(ctx.line(
                    el.line,
                    "element face lacks a list property vertex_indices (or vertex_index)",
                ));
            }
            found
        } else {
            None
        };
        if is_vertex {
            // A vertex takes at least 3 bytes in any encoding: never trust the count alone.
            let cap = el.count.min(body.len() / 3);
            mesh.positions.reserve(cap);
            if nxyz.is_some() {
                mesh.normals.reserve(cap);
            }
        }
        if el.props.is_empty() {
            // Nothing to read, however large the declared count.
            continue;
        }
        let mut row = vec![0.0; el.props.len()];
        let mut list: Vec<f64> = Vec::new();
        for r in 0..el.count {
            let eof = |src: &Source<'_>| {
                src.err(
                    ctx,
                    &el.name,
                    r,
                    &format!(
                        "the file ends inside this element (the header declares {} {} elements)",
                        el.count, el.name
                    ),
                )
            };
            let nan = |src: &Source<'_>, tok: String| {
                src.err(
                    ctx,
                    &el.name,
                    r,
                    &format!("{} is not a valid value for its property type", quote(&tok)),
                )
            };
            for (k, p) in el.props.iter().enumerate() {
                match p.kind {
                    Kind::Scalar(t) => {
                        row[k] = src.read(t).map_err(|e| match e {
                            ReadError::Eof => eof(&src),
                            ReadError::NotANumber(tok) => nan(&src, tok),
                        })?;
                    }
                    Kind::List { count, item } => {
                        let n = src.read(count).map_err(|e| match e {
                            ReadError::Eof => eof(&src),
                            ReadError::NotANumber(tok) => nan(&src, tok),
                        })?;
                        if n < 0.0 {
                            return Err(src.err(
                                ctx,
                                &el.name,
                                r,
                                &format!("list {} has negative length {n}", p.name),
                            ));
                        }
                        let keep = list_prop == Some(k);
                        if keep {
                            list.clear();
                        }
                        for _ in 0..n as u64 {
                            let x = src.read(item).map_err(|e| match e {
                                ReadError::Eof => eof(&src),
                                ReadError::NotANumber(tok) => nan(&src, tok),
                            })?;
                            if keep {
                                list.push(x);
                            }
                        }
                    }
                }
            }
            if let Some([x, y, z]) = xyz {
                let p = Vec3::new(row[x], row[y], row[z]);
                if !p.iter().all(|c| c.is_finite()) {
                    return Err(src.err(ctx, "vertex", r, "non-finite coordinate"));
                }
                mesh.positions.push(p);
                if let Some([x, y, z]) = nxyz {
                    let n = Vec3::new(row[x], row[y], row[z]);
                    if !n.iter().all(|c| c.is_finite()) {
                        return Err(src.err(ctx, "vertex", r, "non-finite normal"));
                    }
                    mesh.normals.push(n);
                }
            }
            if is_face {
                if list.len() < 3 {
                    return Err(src.err(
                        ctx,
                        "face",
                        r,
                        &format!("has {} vertices; at least 3 are needed", list.len()),
                    ));
                }
                let mut idx = Vec::with_capacity(list.len());
                for &i in &list {
                    if i < 0.0 || i >= nverts as f64 || i.fract() != 0.0 {
                        return Err(src.err(
                            ctx,
                            "face",
                            r,
                            &format!(
                                "references vertex {i} but only {nverts} vertices are defined (indices start at 0)"
                            ),
                        ));
                    }
                    idx.push(i as u32);
                }
                for k in 1..idx.len() - 1 {
                    mesh.triangles.push([idx[0], idx[k], idx[k + 1]]);
                }
            }
        }
    }
    Ok(mesh)
}
