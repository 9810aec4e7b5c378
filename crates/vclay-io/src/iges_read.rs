//! IGES (5.3 and earlier, fixed 80-column ASCII) import of Rational B-Spline Curves (entity 126)
//! and Rational B-Spline Surfaces (entity 128).
//!
//! **What.** Every entity 128 is imported, including the basis surfaces of trimmed surfaces
//! (144) and faces (510), untrimmed, with a warning. An entity 126 is imported when it is
//! independent: curves that are physically dependent (subordinate switch 01 or 03: trimming
//! curves, parts of composite curves) or 2D parametric (use flag 05) belong to a dropped
//! topology and are counted in a warning. Knots, weights and control points are taken as
//! written; IGES surface nets run with the u index fastest and are transposed to vclay's order.
//! Labels (directory entry field 18) become entity names.
//!
//! **How.** The Global section gives the parameter and record delimiters (default `,` and `;`);
//! the Directory Entry section (two lines per entity) gives each entity's type, parameter data
//! pointer and line count, status and transformation; the entity's Parameter Data lines
//! (columns 1-64) are joined and split at the delimiters, with Hollerith strings `nH...` read
//! as such and Fortran exponents `1.0D0` accepted.
//!
//! **Warnings.** [`CadImport::warnings`] lists every entity not read with counts per type
//! number (and its name for common types), trimming dropped, parameter ranges narrower than the
//! knot domain (the whole spline is imported), and transformation matrices (entity 124), which
//! are not applied.
//!
//! **Errors.** A malformed file is an [`IoError::Cad`] naming the line and the directory entry:
//! `IGES line 9, entity DE 3: entity 128: expected 362 parameters, found 300`.
//!
//! **Limitations.** No compressed ASCII or binary IGES; no other curve or surface types
//! (lines, arcs, planes, surfaces of revolution: listed as not read); trimming and B-rep
//! topology dropped; transformation matrices and units not applied.

use crate::error::IoError;
use crate::model::{Entity, NamedEntity};
use crate::step_read::CadImport;
use std::collections::BTreeMap;
use std::path::Path;
use vclay_core::Vec3;
use vclay_spline::{NurbsCurve, NurbsSurface};

fn err(line: usize, de: Option<usize>, message: impl Into<String>) -> IoError {
    IoError::Cad {
        format: "IGES",
        line,
        entity: de.map(|d| format!("DE {d}")),
        message: message.into(),
    }
}

/// The name of common IGES entity types, for warnings.
fn type_name(t: u32) -> &'static str {
    match t {
        100 => "circular arc",
        102 => "composite curve",
        104 => "conic arc",
        106 => "copious data",
        108 => "plane",
        110 => "line",
        112 => "parametric spline curve",
        114 => "parametric spline surface",
        116 => "point",
        118 => "ruled surface",
        120 => "surface of revolution",
        122 => "tabulated cylinder",
        124 => "transformation matrix",
        126 => "rational B-spline curve",
        128 => "rational B-spline surface",
        140 => "offset surface",
        141 => "boundary",
        142 => "curve on a parametric surface",
        143 => "bounded surface",
        144 => "trimmed surface",
        186 => "manifold solid B-rep",
        190 => "plane surface",
        192 => "right circular cylindrical surface",
        194 => "right circular conical surface",
        196 => "spherical surface",
        198 => "toroidal surface",
        308 => "subfigure definition",
        314 => "colour",
        402 => "associativity",
        406 => "property",
        408 => "subfigure instance",
        502 => "vertex list",
        504 => "edge list",
        508 => "loop",
        510 => "face",
        514 => "shell",
        _ => "",
    }
}

/// A directory entry.
struct Dir {
    /// Its sequence number (odd, 1-based).
    de: usize,
    /// File line of its first record.
    line: usize,
    kind: u32,
    pointer: usize,
    transform: usize,
    status: String,
    count: usize,
    label: String,
}

/// A parameter token with the file line it is on.
struct Tok {
    text: String,
    line: usize,
}

fn field(s: &str, k: usize) -> &str {
    s.get(k * 8..(k + 1) * 8).unwrap_or("").trim()
}

/// Splits the joined parameter data at the delimiters, honouring Hollerith strings.
fn split(data: &[(char, usize)], pd: char, rd: char, de: usize) -> Result<Vec<Tok>, IoError> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut line = data.first().map_or(1, |c| c.1);
    let mut i = 0;
    while i < data.len() {
        let (c, l) = data[i];
        if cur.trim().is_empty() {
            line = l;
        }
        if c == 'H' && !cur.trim().is_empty() && cur.trim().chars().all(|d| d.is_ascii_digit()) {
            let n: usize = cur.trim().parse().unwrap_or(0);
            if i + n >= data.len() {
                return Err(err(
                    l,
                    Some(de),
                    "Hollerith string runs past the entity's data",
                ));
            }
            let s: String = data[i + 1..=i + n].iter().map(|c| c.0).collect();
            cur = format!("{n}H{s}");
            i += n + 1;
            continue;
        }
        if c == pd || c == rd {
            out.push(Tok {
                text: std::mem::take(&mut cur).trim().to_string(),
                line,
            });
            if c == rd {
                return Ok(out);
            }
        } else {
            cur.push(c);
        }
        i += 1;
    }
    Err(err(
        line,
        Some(de),
        format!("parameter data not terminated by '{rd}'"),
    ))
}

struct Params<'a> {
    toks: &'a [Tok],
    de: usize,
    kind: u32,
}

impl Params<'_> {
    fn line(&self, i: usize) -> usize {
        self.toks.get(i).or(self.toks.last()).map_or(1, |t| t.line)
    }

    fn err(&self, i: usize, m: impl std::fmt::Display) -> IoError {
        err(
            self.line(i),
            Some(self.de),
            format!("entity {}: {m}", self.kind),
        )
    }

    fn real(&self, i: usize, what: &str) -> Result<f64, IoError> {
        let t = self
            .toks
            .get(i)
            .ok_or_else(|| self.err(i, format!("missing {what} (parameter {i})")))?;
        if t.text.is_empty() {
            return Ok(0.0);
        }
        t.text
            .replace(['D', 'd'], "E")
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| {
                self.err(
                    i,
                    format!(
                        "{what} (parameter {i}): expected a number, found \"{}\"",
                        t.text
                    ),
                )
            })
    }

    fn int(&self, i: usize, what: &str) -> Result<usize, IoError> {
        let x = self.real(i, what)?;
        if x >= 0.0 && x.fract() == 0.0 && x < 1e7 {
            Ok(x as usize)
        } else {
            Err(self.err(
                i,
                format!("{what} (parameter {i}): expected a non-negative integer"),
            ))
        }
    }

    fn need(&self, n: usize) -> Result<(), IoError> {
        if self.toks.len() < n {
            return Err(self.err(
                self.toks.len(),
                format!("expected {n} parameters, found {}", self.toks.len()),
            ));
        }
        Ok(())
    }

    fn reals(&self, start: usize, n: usize, what: &str) -> Result<Vec<f64>, IoError> {
        (start..start + n).map(|i| self.real(i, what)).collect()
    }

    fn points(&self, start: usize, n: usize) -> Result<Vec<Vec3>, IoError> {
        (0..n)
            .map(|k| {
                let i = start + 3 * k;
                Ok(Vec3::new(
                    self.real(i, "control point")?,
                    self.real(i + 1, "control point")?,
                    self.real(i + 2, "control point")?,
                ))
            })
            .collect()
    }
}

/// Imports an IGES file's text. See the module documentation for what is read.
pub fn parse_iges(text: &str) -> Result<CadImport, IoError> {
    let mut sections: BTreeMap<char, Vec<(usize, String)>> = BTreeMap::new();
    for (k, raw) in text.lines().enumerate() {
        let l = raw.trim_end_matches('\r');
        if l.trim().is_empty() {
            continue;
        }
        let Some(sec) = l.chars().nth(72) else {
            return Err(err(
                k + 1,
                None,
                "expected an 80-column record with its section letter in column 73",
            ));
        };
        if k == 0 && sec == 'C' {
            return Err(err(1, None, "compressed ASCII IGES is not supported"));
        }
        if !"SGDPT".contains(sec) {
            return Err(err(
                k + 1,
                None,
                format!("unknown section letter '{sec}' in column 73 (expected S, G, D, P or T)"),
            ));
        }
        sections
            .entry(sec)
            .or_default()
            .push((k + 1, l.chars().take(72).collect()));
    }
    let empty = Vec::new();
    // Delimiters from the global section.
    let g: String = sections
        .get(&'G')
        .unwrap_or(&empty)
        .iter()
        .map(|(_, s)| s.as_str())
        .collect();
    let g: Vec<char> = g.chars().collect();
    let (mut pd, mut rd, mut pos) = (',', ';', 0);
    if g.len() >= 3 && g[0] == '1' && g[1] == 'H' {
        pd = g[2];
        pos = 3;
    }
    if g.get(pos) == Some(&pd) {
        pos += 1;
        if g.len() >= pos + 3 && g[pos] == '1' && g[pos + 1] == 'H' {
            rd = g[pos + 2];
        }
    }
    // Directory entries.
    let d = sections.get(&'D').unwrap_or(&empty);
    if !d.len().is_multiple_of(2) {
        return Err(err(
            d.last().map_or(1, |x| x.0),
            None,
            "odd number of directory entry lines (each entity has two)",
        ));
    }
    let mut dirs = Vec::with_capacity(d.len() / 2);
    for (k, pair) in d.chunks(2).enumerate() {
        let (line, a) = (&pair[0].0, &pair[0].1);
        let b = &pair[1].1;
        let de = 2 * k + 1;
        let num = |s: &str, what: &str, l: usize| -> Result<usize, IoError> {
            if s.is_empty() {
                return Ok(0);
            }
            s.trim_start_matches('-').parse::<usize>().map_err(|_| {
                err(
                    l,
                    Some(de),
                    format!("{what}: expected an integer, found \"{s}\""),
                )
            })
        };
        let kind = num(field(a, 0), "entity type", *line)? as u32;
        dirs.push(Dir {
            de,
            line: *line,
            kind,
            pointer: num(field(a, 1), "parameter data pointer", *line)?,
            transform: if field(a, 6).starts_with('-') {
                0
            } else {
                num(field(a, 6), "transformation matrix", *line)?
            },
            status: format!("{:0>8}", field(a, 8)),
            count: num(field(b, 3), "parameter line count", line + 1)?,
            label: field(b, 7).to_string(),
        });
    }
    let p = sections.get(&'P').unwrap_or(&empty);
    let mut entities = Vec::new();
    let mut not_read: BTreeMap<u32, usize> = BTreeMap::new();
    let mut warnings = Vec::new();
    let (mut dependent, mut trimmed) = (0usize, 0usize);
    for dir in &dirs {
        if matches!(dir.kind, 143 | 144 | 510) {
            trimmed += 1;
        }
        if !matches!(dir.kind, 126 | 128) {
            *not_read.entry(dir.kind).or_default() += 1;
            continue;
        }
        // `get`: a status field with a multi-byte character is not sliced mid-character (a
        // fuzzer's input panicked here, issue 17).
        let sub = dir.status.get(2..4).unwrap_or("");
        let use_flag = dir.status.get(4..6).unwrap_or("");
        if dir.kind == 126 && (matches!(sub, "01" | "03") || use_flag == "05") {
            dependent += 1;
            continue;
        }
        if dir.pointer == 0 || dir.pointer + dir.count - 1 > p.len() || dir.count == 0 {
            return Err(err(
                dir.line,
                Some(dir.de),
                format!(
                    "parameter data lines {}..{} are outside the P section ({} lines)",
                    dir.pointer,
                    dir.pointer + dir.count.max(1) - 1,
                    p.len()
                ),
            ));
        }
        let mut data = Vec::new();
        for (line, s) in &p[dir.pointer - 1..dir.pointer - 1 + dir.count] {
            data.extend(s.chars().take(64).map(|c| (c, *line)));
            data.push((' ', *line));
        }
        let toks = split(&data, pd, rd, dir.de)?;
        let ps = Params {
            toks: &toks,
            de: dir.de,
            kind: dir.kind,
        };
        if ps.int(0, "entity type")? != dir.kind as usize {
            return Err(ps.err(0, "the parameter data starts with another entity type"));
        }
        let name = (!dir.label.is_empty()).then(|| dir.label.clone());
        let (entity, range, domain) = if dir.kind == 126 {
            let k = ps.int(1, "upper index K")?;
            let m = ps.int(2, "degree M")?;
            let n = k + 1;
            let nk = k + m + 2;
            ps.need(7 + nk + n + 3 * n + 2)?;
            let knots = ps.reals(7, nk, "knot")?;
            let w = ps.reals(7 + nk, n, "weight")?;
            let pts = ps.points(7 + nk + n, n)?;
            let r = ps.reals(7 + nk + 4 * n, 2, "parameter range")?;
            let c = NurbsCurve::new(m, knots, pts, Some(w)).map_err(|e| ps.err(0, e))?;
            let dom = vclay_spline::ParametricCurve::domain(&c);
            (Entity::Curve(c), r, vec![dom.min, dom.max])
        } else {
            let (k1, k2) = (ps.int(1, "upper index K1")?, ps.int(2, "upper index K2")?);
            let (m1, m2) = (ps.int(3, "degree M1")?, ps.int(4, "degree M2")?);
            let (nu, nv) = (k1 + 1, k2 + 1);
            let (a, b) = (k1 + m1 + 2, k2 + m2 + 2);
            let nn = nu.saturating_mul(nv);
            ps.need(10 + a + b + 4 * nn + 4)?;
            let ku = ps.reals(10, a, "u knot")?;
            let kv = ps.reals(10 + a, b, "v knot")?;
            let wi = ps.reals(10 + a + b, nn, "weight")?;
            let pi = ps.points(10 + a + b + nn, nn)?;
            let r = ps.reals(10 + a + b + 4 * nn, 4, "parameter range")?;
            // IGES: u index fastest; vclay: v fastest.
            let mut pts = Vec::with_capacity(nn);
            let mut w = Vec::with_capacity(nn);
            for i in 0..nu {
                for j in 0..nv {
                    pts.push(pi[j * nu + i]);
                    w.push(wi[j * nu + i]);
                }
            }
            let s = NurbsSurface::from_flat(
                [
                    vclay_spline::KnotVector::new(ku, m1, nu)
                        .map_err(|e| ps.err(0, format!("u knots: {e}")))?,
                    vclay_spline::KnotVector::new(kv, m2, nv)
                        .map_err(|e| ps.err(0, format!("v knots: {e}")))?,
                ],
                pts,
                w,
            )
            .map_err(|e| ps.err(0, e))?;
            let dom = vclay_spline::ParametricSurface::domain(&s);
            (
                Entity::Surface(s),
                r,
                vec![dom[0].min, dom[0].max, dom[1].min, dom[1].max],
            )
        };
        let tol = 1e-9 * domain.iter().fold(1.0f64, |a, &x| a.max(x.abs()));
        if range.iter().zip(&domain).any(|(r, d)| (r - d).abs() > tol) {
            warnings.push(format!(
                "entity DE {} (type {}): parameter range {range:?} differs from the knot domain \
                 {domain:?}; the whole spline is imported",
                dir.de, dir.kind
            ));
        }
        if dir.transform != 0 {
            warnings.push(format!(
                "entity DE {} (type {}): transformation matrix DE {} not applied",
                dir.de, dir.kind, dir.transform
            ));
        }
        entities.push(NamedEntity { name, entity });
    }
    if trimmed > 0 {
        warnings.push(format!(
            "{trimmed} trimmed surface(s) or face(s): their B-spline surfaces are imported \
             untrimmed (trimming curves and topology are dropped)"
        ));
    }
    if dependent > 0 {
        warnings.push(format!(
            "{dependent} dependent or parameter-space curve(s) of type 126 not imported: they \
             belong to the dropped trimming or topology"
        ));
    }
    if !not_read.is_empty() {
        let mut v: Vec<(u32, usize)> = not_read.into_iter().collect();
        v.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
        let list: Vec<String> = v
            .iter()
            .map(|&(t, n)| match type_name(t) {
                "" => format!("{n} type {t}"),
                name => format!("{n} type {t} ({name})"),
            })
            .collect();
        warnings.push(format!(
            "entities not read (count per type): {}",
            list.join(", ")
        ));
    }
    if entities.is_empty() {
        return Err(err(
            1,
            None,
            format!(
                "no B-spline curve (126) or surface (128) to import{}",
                if warnings.is_empty() {
                    String::new()
                } else {
                    format!(" ({})", warnings.join("; "))
                }
            ),
        ));
    }
    Ok(CadImport {
        entities,
        warnings,
        faces: Vec::new(),
    })
}

/// Reads an IGES file (`.igs`, `.iges`). Errors name the file.
pub fn read_iges(path: impl AsRef<Path>) -> Result<CadImport, IoError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|e| IoError::file(path, e))?;
    parse_iges(&String::from_utf8_lossy(&bytes)).map_err(|e| e.in_file(path))
}
