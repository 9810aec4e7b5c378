//! STEP (ISO 10303-21) import of B-spline curves and surfaces, polynomial and rational, and of
//! the elementary and swept surfaces of B-reps, from AP203, AP214 and AP242 files.
//!
//! **What.** Read: `B_SPLINE_CURVE_WITH_KNOTS`, `B_SPLINE_SURFACE_WITH_KNOTS` and the rational
//! complex entities `(BOUNDED_CURVE() B_SPLINE_CURVE(..) B_SPLINE_CURVE_WITH_KNOTS(..) ..
//! RATIONAL_B_SPLINE_CURVE(..) ..)` and `(.. B_SPLINE_SURFACE(..) B_SPLINE_SURFACE_WITH_KNOTS(..)
//! .. RATIONAL_B_SPLINE_SURFACE(..) ..)` (ISO 10303-42 section 4.4), with their
//! `CARTESIAN_POINT`s; and `PLANE`, `CYLINDRICAL_SURFACE`, `CONICAL_SURFACE`,
//! `SPHERICAL_SURFACE`, `TOROIDAL_SURFACE`, `SURFACE_OF_REVOLUTION` and
//! `SURFACE_OF_LINEAR_EXTRUSION` with their `AXIS2_PLACEMENT_3D`s, converted exactly to NURBS
//! ([`brep`](self) submodule: rational quadratic arcs; unbounded surfaces cut to the box of their
//! faces' boundaries, else [`DEFAULT_RANGE`]). Every such surface of the file is imported: those
//! of a `GEOMETRIC_SET`, the basis of a trimmed or offset surface, and the `FACE_SURFACE`
//! geometry of the `ADVANCED_FACE`s of a B-rep. The faces' trimming loops (`FACE_BOUND` ->
//! `EDGE_LOOP` -> `ORIENTED_EDGE` -> `EDGE_CURVE` with its 3D curve and its `PCURVE`s) are kept in
//! [`CadImport::faces`] ([`TrimmedFace`], in the file's parameters; applied when meshing by
//! [`tessellate_trimmed`], used by `vclay convert` to meshes and `vclay render`), and made the
//! trimmed B-rep of [`CadImport::shells`] ([`crate::trimmed`]: shared edges and vertices,
//! pcurves in the NURBS parameters; written back to STEP and JSON with the trims); the
//! surfaces themselves are entities, whole. A B-spline curve is imported
//! unless it is part of a B-rep's topology or of a surface definition (referenced by
//! `EDGE_CURVE`, `PCURVE`, `SURFACE_CURVE`, `SEAM_CURVE`, `DEFINITIONAL_REPRESENTATION` or a
//! swept surface) or lies in a 2D parameter space; a `TRIMMED_CURVE`'s basis is imported whole.
//! Names become entity names when not empty.
//!
//! **How.** A Part 21 tokenizer (comments, strings with `''`, enumerations `.T.`, `$`, `*`,
//! `#id` references, typed parameters `LENGTH_MEASURE(1.)`, binary `"..."`) feeds a parser
//! that keeps each instance's type(s), parameters and line; the data section is then read
//! entity by entity: faces first (their loops give the ranges of unbounded surfaces), then
//! surfaces and curves. Knots are expanded from distinct values and multiplicities; surface
//! nets are lists of rows along u, as vclay stores them, so nothing is reordered.
//!
//! **Warnings.** [`CadImport::warnings`] lists, per type with counts, every entity instance that
//! was not read (units and product data are not needed), says when the faces could not be made
//! a trimmed B-rep, and counts edges whose curves are of a type not read. Nothing is dropped
//! silently.
//!
//! **Errors.** A malformed file is an [`IoError::Cad`] naming the line and the entity:
//! `STEP line 41, entity #17: B_SPLINE_CURVE_WITH_KNOTS: knot multiplicities and knots differ
//! in length (4 and 3)`.
//!
//! **Limitations.** Meshing applies the trimming loops up to the grid spacing (triangles kept by
//! their parameter centroid; no exact trimmed boundary); shells are rebuilt from the faces'
//! shared edges (the file's `CLOSED_SHELL`s are not read as such); free lines and conics (outside a face's
//! loop or a swept surface) are listed as not read; `OFFSET_SURFACE`,
//! `RECTANGULAR_TRIMMED_SURFACE` and `CURVE_BOUNDED_SURFACE` are not read (their B-spline basis
//! is). `UNIFORM_*`, `QUASI_UNIFORM_*` and `BEZIER_*` subtypes (knots implied rather than given)
//! are listed as not read. Placements (`MAPPED_ITEM`, assemblies) and length units are not
//! applied: coordinates are taken as written; a plane-angle unit in degrees is applied to cone
//! semi-angles and circle trims.

mod brep;
pub(crate) use brep::{arc, extrude, revolve_between};

pub use brep::{
    DEFAULT_RANGE, MAX_TRIM_SAMPLES, ParamAxis, TrimEdge, TrimLoop, TrimmedFace, tessellate_trimmed,
};

use crate::error::IoError;
use crate::model::{Entity, NamedEntity};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::Path;
use vclay_core::Vec3;
use vclay_spline::{NurbsCurve, NurbsSurface};

/// The result of importing a CAD file: the geometry read and what was not.
#[derive(Clone, Debug, PartialEq)]
pub struct CadImport {
    /// The curves and surfaces read, in the order of their entity numbers (STEP `#id`, IGES
    /// directory entry).
    pub entities: Vec<NamedEntity>,
    /// What was not read or was simplified, one sentence each (empty when everything was read).
    pub warnings: Vec<String>,
    /// The faces of a STEP B-rep: the entity each lies on and its trimming loops as read, in
    /// the file's parameters ([`tessellate_trimmed`] applies them when meshing). Empty for IGES
    /// and JSON.
    pub faces: Vec<TrimmedFace>,
    /// The trimmed B-rep ([`crate::trimmed`]): shells of faces whose surfaces are among
    /// `entities`, with shared edges and vertices, loops and pcurves in the surfaces' NURBS
    /// parameters; built from `faces` for STEP, read from `"shells"` for a JSON model. Empty
    /// when the file has none.
    pub shells: Vec<crate::brep::Shell>,
}

/// A parameter of a Part 21 instance.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Param {
    Int(i64),
    Real(f64),
    Str(String),
    Enum(String),
    Ref(usize),
    List(Vec<Param>),
    Typed(String, Vec<Param>),
    /// `$`
    Unset,
    /// `*`
    Derived,
    /// `"0123"`
    Binary,
}

/// One partial entity: `NAME(params)`.
#[derive(Clone, Debug)]
pub(crate) struct Part {
    name: String,
    params: Vec<Param>,
}

/// An instance `#id = ...;` with the 1-based line it starts on.
#[derive(Clone, Debug)]
pub(crate) struct Instance {
    id: usize,
    line: usize,
    /// One part for a simple instance, several for a complex one.
    parts: Vec<Part>,
}

impl Instance {
    fn type_name(&self) -> String {
        if self.parts.len() == 1 {
            self.parts[0].name.clone()
        } else {
            let names: Vec<&str> = self.parts.iter().map(|p| p.name.as_str()).collect();
            format!("({})", names.join(" "))
        }
    }

    fn part(&self, name: &str) -> Option<&Part> {
        self.parts.iter().find(|p| p.name == name)
    }

    fn is(&self, name: &str) -> bool {
        self.part(name).is_some()
    }
}

// ---------------------------------------------------------------------------------------------
// Tokenizer

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Keyword(String),
    Ref(usize),
    Int(i64),
    Real(f64),
    Str(String),
    Enum(String),
    Binary,
    Dollar,
    Star,
    LParen,
    RParen,
    Comma,
    Semi,
    Eq,
}

fn err(line: usize, entity: Option<usize>, message: impl Into<String>) -> IoError {
    IoError::Cad {
        format: "STEP",
        line,
        entity: entity.map(|e| format!("#{e}")),
        message: message.into(),
    }
}

/// Splits the text into tokens with their 1-based lines.
fn tokenize(text: &str) -> Result<Vec<(Tok, usize)>, IoError> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let (mut i, mut line) = (0, 1);
    while i < b.len() {
        let c = b[i];
        let start_line = line;
        match c {
            b'\n' => {
                line += 1;
                i += 1;
            }
            b' ' | b'\t' | b'\r' => i += 1,
            b'/' if b.get(i + 1) == Some(&b'*') => {
                i += 2;
                loop {
                    if i + 1 >= b.len() {
                        return Err(err(start_line, None, "unterminated comment"));
                    }
                    if b[i] == b'*' && b[i + 1] == b'/' {
                        i += 2;
                        break;
                    }
                    if b[i] == b'\n' {
                        line += 1;
                    }
                    i += 1;
                }
            }
            b'\'' => {
                let mut s = Vec::new();
                i += 1;
                loop {
                    match b.get(i) {
                        None => return Err(err(start_line, None, "unterminated string")),
                        Some(b'\'') if b.get(i + 1) == Some(&b'\'') => {
                            s.push(b'\'');
                            i += 2;
                        }
                        Some(b'\'') => {
                            i += 1;
                            break;
                        }
                        Some(&ch) => {
                            if ch == b'\n' {
                                line += 1;
                            } else if ch != b'\r' {
                                s.push(ch);
                            }
                            i += 1;
                        }
                    }
                }
                out.push((
                    Tok::Str(String::from_utf8_lossy(&s).into_owned()),
                    start_line,
                ));
            }
            b'"' => {
                let end = b[i + 1..].iter().position(|&x| x == b'"');
                let Some(end) = end else {
                    return Err(err(start_line, None, "unterminated binary value"));
                };
                i += end + 2;
                out.push((Tok::Binary, start_line));
            }
            b'#' => {
                let s = i + 1;
                let mut e = s;
                while e < b.len() && b[e].is_ascii_digit() {
                    e += 1;
                }
                let id = text[s..e]
                    .parse()
                    .map_err(|_| err(line, None, "'#' not followed by an entity number"))?;
                out.push((Tok::Ref(id), line));
                i = e;
            }
            b'.' if b
                .get(i + 1)
                .is_some_and(|x| x.is_ascii_alphabetic() || *x == b'_') =>
            {
                let s = i + 1;
                let mut e = s;
                while e < b.len() && (b[e].is_ascii_alphanumeric() || b[e] == b'_') {
                    e += 1;
                }
                if b.get(e) != Some(&b'.') {
                    return Err(err(line, None, "unterminated enumeration (expected '.')"));
                }
                out.push((Tok::Enum(text[s..e].to_ascii_uppercase()), line));
                i = e + 1;
            }
            b'0'..=b'9' | b'-' | b'+' | b'.' => {
                let s = i;
                let mut e = i + 1;
                let mut real = c == b'.';
                while e < b.len() {
                    match b[e] {
                        b'0'..=b'9' => {}
                        b'.' | b'E' | b'e' => real = true,
                        b'-' | b'+' if matches!(b[e - 1], b'E' | b'e') => {}
                        _ => break,
                    }
                    e += 1;
                }
                let t = &text[s..e];
                let tok = if real {
                    Tok::Real(
                        t.parse()
                            .map_err(|_| err(line, None, format!("invalid real \"{t}\"")))?,
                    )
                } else {
                    Tok::Int(
                        t.parse()
                            .map_err(|_| err(line, None, format!("invalid integer \"{t}\"")))?,
                    )
                };
                out.push((tok, line));
                i = e;
            }
            b'A'..=b'Z' | b'a'..=b'z' | b'_' | b'!' => {
                let s = i;
                let mut e = i + 1;
                while e < b.len() && (b[e].is_ascii_alphanumeric() || b[e] == b'_' || b[e] == b'-')
                {
                    e += 1;
                }
                out.push((Tok::Keyword(text[s..e].to_ascii_uppercase()), line));
                i = e;
            }
            b'$' | b'*' | b'(' | b')' | b',' | b';' | b'=' => {
                out.push((
                    match c {
                        b'$' => Tok::Dollar,
                        b'*' => Tok::Star,
                        b'(' => Tok::LParen,
                        b')' => Tok::RParen,
                        b',' => Tok::Comma,
                        b';' => Tok::Semi,
                        _ => Tok::Eq,
                    },
                    line,
                ));
                i += 1;
            }
            _ => {
                let ch = text[i..].chars().next().unwrap_or('?');
                return Err(err(line, None, format!("unexpected character '{ch}'")));
            }
        }
    }
    Ok(out)
}

// ---------------------------------------------------------------------------------------------
// Parser

struct Parser {
    toks: Vec<(Tok, usize)>,
    pos: usize,
    /// The instance being parsed, for error messages.
    entity: Option<usize>,
}

impl Parser {
    fn line(&self) -> usize {
        self.toks
            .get(self.pos)
            .or(self.toks.last())
            .map_or(1, |t| t.1)
    }

    fn peek(&self) -> Option<&Tok> {
        self.toks.get(self.pos).map(|t| &t.0)
    }

    fn next(&mut self) -> Result<Tok, IoError> {
        // Each token is consumed once: moved out rather than cloned (issue 30: 10,000-face
        // files).
        let line = self.line();
        let t = self
            .toks
            .get_mut(self.pos)
            .map(|t| std::mem::replace(&mut t.0, Tok::Comma))
            .ok_or_else(|| err(line, self.entity, "unexpected end of file"))?;
        self.pos += 1;
        Ok(t)
    }

    fn expect(&mut self, want: &Tok, what: &str) -> Result<(), IoError> {
        let line = self.line();
        let t = self.next()?;
        if &t == want {
            Ok(())
        } else {
            Err(err(
                line,
                self.entity,
                format!("expected {what}, found {t:?}"),
            ))
        }
    }

    fn keyword(&mut self) -> Result<String, IoError> {
        let line = self.line();
        match self.next()? {
            Tok::Keyword(k) => Ok(k),
            t => Err(err(
                line,
                self.entity,
                format!("expected an entity name, found {t:?}"),
            )),
        }
    }

    /// `( p, p, ... )` after the opening parenthesis was consumed.
    fn params(&mut self) -> Result<Vec<Param>, IoError> {
        let mut out = Vec::new();
        if self.peek() == Some(&Tok::RParen) {
            self.pos += 1;
            return Ok(out);
        }
        loop {
            out.push(self.param()?);
            let line = self.line();
            match self.next()? {
                Tok::Comma => {}
                Tok::RParen => return Ok(out),
                t => {
                    return Err(err(
                        line,
                        self.entity,
                        format!("expected ',' or ')', found {t:?}"),
                    ));
                }
            }
        }
    }

    fn param(&mut self) -> Result<Param, IoError> {
        let line = self.line();
        Ok(match self.next()? {
            Tok::Int(i) => Param::Int(i),
            Tok::Real(x) => Param::Real(x),
            Tok::Str(s) => Param::Str(s),
            Tok::Enum(e) => Param::Enum(e),
            Tok::Ref(r) => Param::Ref(r),
            Tok::Binary => Param::Binary,
            Tok::Dollar => Param::Unset,
            Tok::Star => Param::Derived,
            Tok::LParen => Param::List(self.params()?),
            Tok::Keyword(k) => {
                self.expect(&Tok::LParen, "'(' after a type name")?;
                Param::Typed(k, self.params()?)
            }
            t => {
                return Err(err(
                    line,
                    self.entity,
                    format!("expected a parameter, found {t:?}"),
                ));
            }
        })
    }
}

/// Parses the exchange structure into its data-section instances, by id.
pub(crate) fn parse_instances(text: &str) -> Result<BTreeMap<usize, Instance>, IoError> {
    let toks = tokenize(text)?;
    let mut p = Parser {
        toks,
        pos: 0,
        entity: None,
    };
    let first = p.keyword().ok();
    if first.as_deref() != Some("ISO-10303-21") {
        return Err(err(
            1,
            None,
            "not a STEP file: it must begin with ISO-10303-21;",
        ));
    }
    p.expect(&Tok::Semi, "';'")?;
    let mut out = BTreeMap::new();
    loop {
        let line = p.line();
        let Some(t) = p.peek().cloned() else {
            return Err(err(line, None, "missing END-ISO-10303-21;"));
        };
        match t {
            Tok::Keyword(k) if k == "END-ISO-10303-21" => break,
            Tok::Keyword(k) if k == "HEADER" => {
                p.pos += 1;
                p.expect(&Tok::Semi, "';'")?;
                // Header entities: NAME(params); until ENDSEC.
                loop {
                    let k = p.keyword()?;
                    if k == "ENDSEC" {
                        p.expect(&Tok::Semi, "';'")?;
                        break;
                    }
                    p.expect(&Tok::LParen, "'('")?;
                    p.params()?;
                    p.expect(&Tok::Semi, "';'")?;
                }
            }
            Tok::Keyword(k) if k == "DATA" => {
                p.pos += 1;
                if p.peek() == Some(&Tok::LParen) {
                    p.pos += 1;
                    p.params()?;
                }
                p.expect(&Tok::Semi, "';' after DATA")?;
                loop {
                    let line = p.line();
                    match p.next()? {
                        Tok::Keyword(k) if k == "ENDSEC" => {
                            p.expect(&Tok::Semi, "';'")?;
                            break;
                        }
                        Tok::Ref(id) => {
                            p.entity = Some(id);
                            p.expect(&Tok::Eq, "'='")?;
                            let parts = if p.peek() == Some(&Tok::LParen) {
                                p.pos += 1;
                                let mut parts = Vec::new();
                                while p.peek() != Some(&Tok::RParen) {
                                    let name = p.keyword()?;
                                    p.expect(&Tok::LParen, "'('")?;
                                    parts.push(Part {
                                        name,
                                        params: p.params()?,
                                    });
                                }
                                p.pos += 1;
                                if parts.is_empty() {
                                    return Err(err(line, Some(id), "empty complex entity"));
                                }
                                parts
                            } else {
                                let name = p.keyword()?;
                                p.expect(&Tok::LParen, "'('")?;
                                vec![Part {
                                    name,
                                    params: p.params()?,
                                }]
                            };
                            p.expect(&Tok::Semi, "';' at the end of the entity")?;
                            if out.insert(id, Instance { id, line, parts }).is_some() {
                                return Err(err(line, Some(id), "entity number defined twice"));
                            }
                            p.entity = None;
                        }
                        t => {
                            return Err(err(
                                line,
                                None,
                                format!("expected '#id = ...' or ENDSEC, found {t:?}"),
                            ));
                        }
                    }
                }
            }
            Tok::Keyword(k) => {
                return Err(err(
                    line,
                    None,
                    format!("unexpected {k}: expected HEADER, DATA or END-ISO-10303-21"),
                ));
            }
            t => return Err(err(line, None, format!("unexpected {t:?}"))),
        }
    }
    Ok(out)
}

// ---------------------------------------------------------------------------------------------
// Entities

/// Reads typed values out of instances, naming the instance in errors.
struct Reader<'a> {
    all: &'a BTreeMap<usize, Instance>,
    /// Instances consumed as parts of what was read (points, the splines themselves).
    used: HashSet<usize>,
    /// The file's plane-angle unit in radians.
    angle_unit: f64,
}

struct Ctx<'a> {
    inst: &'a Instance,
    part: &'a str,
}

impl Ctx<'_> {
    fn err(&self, message: impl std::fmt::Display) -> IoError {
        err(
            self.inst.line,
            Some(self.inst.id),
            format!("{}: {message}", self.part),
        )
    }

    fn int(&self, p: &Param, what: &str) -> Result<usize, IoError> {
        match p {
            Param::Int(i) if *i >= 0 => Ok(*i as usize),
            _ => Err(self.err(format!("{what}: expected a non-negative integer"))),
        }
    }

    fn real(&self, p: &Param, what: &str) -> Result<f64, IoError> {
        match p {
            Param::Real(x) => Ok(*x),
            Param::Int(i) => Ok(*i as f64),
            Param::Typed(_, v) if v.len() == 1 => self.real(&v[0], what),
            _ => Err(self.err(format!("{what}: expected a number"))),
        }
    }

    fn list<'p>(&self, p: &'p Param, what: &str) -> Result<&'p [Param], IoError> {
        match p {
            Param::List(v) => Ok(v),
            _ => Err(self.err(format!("{what}: expected a list"))),
        }
    }

    fn reals(&self, p: &Param, what: &str) -> Result<Vec<f64>, IoError> {
        self.list(p, what)?
            .iter()
            .map(|x| self.real(x, what))
            .collect()
    }

    fn ints(&self, p: &Param, what: &str) -> Result<Vec<usize>, IoError> {
        self.list(p, what)?
            .iter()
            .map(|x| self.int(x, what))
            .collect()
    }

    fn params(&self, n: usize) -> Result<&[Param], IoError> {
        let part = self
            .inst
            .part(self.part)
            .ok_or_else(|| self.err("missing"))?;
        if part.params.len() != n {
            return Err(self.err(format!(
                "expected {n} parameters, found {}",
                part.params.len()
            )));
        }
        Ok(&part.params)
    }

    /// Expands `(knots, multiplicities)`.
    fn knots(&self, mults: &Param, knots: &Param, axis: &str) -> Result<Vec<f64>, IoError> {
        let m = self.ints(mults, &format!("{axis}knot multiplicities"))?;
        let k = self.reals(knots, &format!("{axis}knots"))?;
        if m.len() != k.len() {
            return Err(self.err(format!(
                "{axis}knot multiplicities and knots differ in length ({} and {})",
                m.len(),
                k.len()
            )));
        }
        if m.iter().sum::<usize>() > 1_000_000 {
            return Err(self.err(format!("{axis}knot multiplicities too large")));
        }
        Ok(m.iter()
            .zip(&k)
            .flat_map(|(&m, &k)| std::iter::repeat_n(k, m))
            .collect())
    }
}

/// Why a curve or surface was not imported, for the warnings.
enum Skip {
    /// Not a B-spline with knots (e.g. `PLANE`, `UNIFORM_CURVE`): listed by type.
    Unsupported,
    /// A 2D curve (parameter space of a face).
    TwoD,
}

impl<'a> Reader<'a> {
    fn get(&self, id: usize, from: &Ctx<'_>) -> Result<&'a Instance, IoError> {
        self.all
            .get(&id)
            .ok_or_else(|| from.err(format!("reference to #{id}, which is not defined")))
    }

    /// A `CARTESIAN_POINT` of 2 or 3 coordinates (2D points get z = 0, flagged by `false`).
    fn point(&mut self, p: &Param, from: &Ctx<'_>) -> Result<(Vec3, bool), IoError> {
        let Param::Ref(id) = p else {
            return Err(from.err("expected a reference to a CARTESIAN_POINT"));
        };
        let inst = self.get(*id, from)?;
        let c = Ctx {
            inst,
            part: "CARTESIAN_POINT",
        };
        if !inst.is("CARTESIAN_POINT") {
            return Err(from.err(format!(
                "#{id} is a {}, expected a CARTESIAN_POINT",
                inst.type_name()
            )));
        }
        let ps = c.params(2)?;
        let xs = c.reals(&ps[1], "coordinates")?;
        self.used.insert(*id);
        match xs[..] {
            [x, y, z] => Ok((Vec3::new(x, y, z), true)),
            [x, y] => Ok((Vec3::new(x, y, 0.0), false)),
            _ => Err(c.err(format!("expected 2 or 3 coordinates, found {}", xs.len()))),
        }
    }

    fn name(p: &Param) -> Option<String> {
        match p {
            Param::Str(s) if !s.is_empty() => Some(s.clone()),
            _ => None,
        }
    }

    /// A B-spline curve instance, or why it is skipped.
    fn curve(&mut self, inst: &Instance) -> Result<Result<NamedEntity, Skip>, IoError> {
        self.curve_in(inst, false)
    }

    /// A 2D B-spline curve (a pcurve) with z = 0.
    fn curve_2d(&mut self, inst: &Instance) -> Result<NurbsCurve, IoError> {
        match self.curve_in(inst, true)? {
            Ok(NamedEntity {
                entity: Entity::Curve(c),
                ..
            }) => Ok(c),
            _ => Err(err(inst.line, Some(inst.id), "not a B-spline curve")),
        }
    }

    fn curve_in(
        &mut self,
        inst: &Instance,
        allow_2d: bool,
    ) -> Result<Result<NamedEntity, Skip>, IoError> {
        // Simple form: all attributes in one part; complex form: spread over parts.
        let (name, degree, cps, mults, knots, weights);
        if inst.parts.len() == 1 && inst.is("B_SPLINE_CURVE_WITH_KNOTS") {
            let c = Ctx {
                inst,
                part: "B_SPLINE_CURVE_WITH_KNOTS",
            };
            let ps = c.params(9)?;
            name = Self::name(&ps[0]);
            degree = c.int(&ps[1], "degree")?;
            cps = c.list(&ps[2], "control points")?.to_vec();
            mults = ps[6].clone();
            knots = ps[7].clone();
            weights = None;
        } else if inst.is("B_SPLINE_CURVE") && inst.is("B_SPLINE_CURVE_WITH_KNOTS") {
            let c = Ctx {
                inst,
                part: "B_SPLINE_CURVE",
            };
            let ps = c.params(5)?;
            degree = c.int(&ps[0], "degree")?;
            cps = c.list(&ps[1], "control points")?.to_vec();
            let ck = Ctx {
                inst,
                part: "B_SPLINE_CURVE_WITH_KNOTS",
            };
            let ks = ck.params(3)?;
            mults = ks[0].clone();
            knots = ks[1].clone();
            name = inst
                .part("REPRESENTATION_ITEM")
                .and_then(|p| p.params.first())
                .and_then(Self::name);
            weights = match inst.part("RATIONAL_B_SPLINE_CURVE") {
                Some(_) => {
                    let cr = Ctx {
                        inst,
                        part: "RATIONAL_B_SPLINE_CURVE",
                    };
                    let ws = cr.params(1)?;
                    Some(cr.reals(&ws[0], "weights")?)
                }
                None => None,
            };
        } else {
            return Ok(Err(Skip::Unsupported));
        }
        let c = Ctx {
            inst,
            part: "B_SPLINE_CURVE_WITH_KNOTS",
        };
        let knots = c.knots(&mults, &knots, "")?;
        let mut pts = Vec::with_capacity(cps.len());
        let mut planar2d = false;
        for p in &cps {
            let (q, three) = self.point(p, &c)?;
            planar2d |= !three;
            pts.push(q);
        }
        if planar2d && !allow_2d {
            return Ok(Err(Skip::TwoD));
        }
        let curve = NurbsCurve::new(degree, knots, pts, weights).map_err(|e| c.err(e))?;
        Ok(Ok(NamedEntity {
            name,
            entity: Entity::Curve(curve),
        }))
    }

    /// A B-spline surface instance, or why it is skipped.
    fn surface(&mut self, inst: &Instance) -> Result<Result<NamedEntity, Skip>, IoError> {
        let (name, du, dv, net, mu, mv, ku, kv, weights);
        if inst.parts.len() == 1 && inst.is("B_SPLINE_SURFACE_WITH_KNOTS") {
            let c = Ctx {
                inst,
                part: "B_SPLINE_SURFACE_WITH_KNOTS",
            };
            let ps = c.params(13)?;
            name = Self::name(&ps[0]);
            du = c.int(&ps[1], "u degree")?;
            dv = c.int(&ps[2], "v degree")?;
            net = ps[3].clone();
            (mu, mv, ku, kv) = (ps[8].clone(), ps[9].clone(), ps[10].clone(), ps[11].clone());
            weights = None;
        } else if inst.is("B_SPLINE_SURFACE") && inst.is("B_SPLINE_SURFACE_WITH_KNOTS") {
            let c = Ctx {
                inst,
                part: "B_SPLINE_SURFACE",
            };
            let ps = c.params(7)?;
            du = c.int(&ps[0], "u degree")?;
            dv = c.int(&ps[1], "v degree")?;
            net = ps[2].clone();
            let ck = Ctx {
                inst,
                part: "B_SPLINE_SURFACE_WITH_KNOTS",
            };
            let ks = ck.params(5)?;
            (mu, mv, ku, kv) = (ks[0].clone(), ks[1].clone(), ks[2].clone(), ks[3].clone());
            name = inst
                .part("REPRESENTATION_ITEM")
                .and_then(|p| p.params.first())
                .and_then(Self::name);
            weights = match inst.part("RATIONAL_B_SPLINE_SURFACE") {
                Some(_) => {
                    let cr = Ctx {
                        inst,
                        part: "RATIONAL_B_SPLINE_SURFACE",
                    };
                    let ws = cr.params(1)?;
                    let rows = cr.list(&ws[0], "weights")?;
                    let mut flat = Vec::new();
                    for r in rows {
                        flat.push(cr.reals(r, "weights")?);
                    }
                    Some(flat)
                }
                None => None,
            };
        } else {
            return Ok(Err(Skip::Unsupported));
        }
        let c = Ctx {
            inst,
            part: "B_SPLINE_SURFACE_WITH_KNOTS",
        };
        let ku = c.knots(&mu, &ku, "u ")?;
        let kv = c.knots(&mv, &kv, "v ")?;
        let rows = c.list(&net, "control points")?;
        let mut pts = Vec::with_capacity(rows.len());
        for r in rows {
            let row = c.list(r, "control point row")?;
            let mut out = Vec::with_capacity(row.len());
            for p in row {
                let (q, three) = self.point(p, &c)?;
                if !three {
                    return Ok(Err(Skip::TwoD));
                }
                out.push(q);
            }
            pts.push(out);
        }
        let s = NurbsSurface::new([du, dv], [ku, kv], pts, weights).map_err(|e| c.err(e))?;
        Ok(Ok(NamedEntity {
            name,
            entity: Entity::Surface(s),
        }))
    }
}

/// Entity types whose curve references are topology or surface definitions, not free curves.
const CURVE_USERS: [&str; 8] = [
    "EDGE_CURVE",
    "PCURVE",
    "SURFACE_CURVE",
    "SEAM_CURVE",
    "INTERSECTION_CURVE",
    "DEFINITIONAL_REPRESENTATION",
    "SURFACE_OF_REVOLUTION",
    "SURFACE_OF_LINEAR_EXTRUSION",
];

/// All references in a parameter list.
fn refs(params: &[Param], out: &mut Vec<usize>) {
    for p in params {
        match p {
            Param::Ref(r) => out.push(*r),
            Param::List(v) | Param::Typed(_, v) => refs(v, out),
            _ => {}
        }
    }
}

fn is_curve_type(inst: &Instance) -> bool {
    inst.parts.iter().any(|p| {
        matches!(
            p.name.as_str(),
            "B_SPLINE_CURVE" | "B_SPLINE_CURVE_WITH_KNOTS"
        )
    })
}

fn is_surface_type(inst: &Instance) -> bool {
    inst.parts.iter().any(|p| {
        matches!(
            p.name.as_str(),
            "B_SPLINE_SURFACE" | "B_SPLINE_SURFACE_WITH_KNOTS"
        )
    })
}

/// The elementary and swept surface types converted exactly to NURBS ([`brep`]).
const ELEMENTARY: [&str; 7] = [
    "PLANE",
    "CYLINDRICAL_SURFACE",
    "CONICAL_SURFACE",
    "SPHERICAL_SURFACE",
    "TOROIDAL_SURFACE",
    "SURFACE_OF_REVOLUTION",
    "SURFACE_OF_LINEAR_EXTRUSION",
];

/// Imports a STEP file's text. See the module documentation for what is read.
pub fn parse_step(text: &str) -> Result<CadImport, IoError> {
    let all = parse_instances(text)?;
    // Which instances reference each curve through topology or surface definitions.
    let mut bound_curves: HashSet<usize> = HashSet::new();
    for inst in all.values() {
        if inst
            .parts
            .iter()
            .any(|p| CURVE_USERS.contains(&p.name.as_str()))
        {
            let mut r = Vec::new();
            for p in &inst.parts {
                refs(&p.params, &mut r);
            }
            bound_curves.extend(r);
        }
    }
    let mut rd = Reader {
        all: &all,
        used: HashSet::new(),
        angle_unit: brep::angle_unit(&all),
    };
    // Faces first: their trimming loops, and the boundary points of each surface (for the
    // ranges of unbounded surfaces).
    let mut face_data = Vec::new();
    for inst in all.values() {
        if inst.is("ADVANCED_FACE") || inst.is("FACE_SURFACE") {
            face_data.push(rd.face(inst)?);
        }
    }
    let uses = brep::by_surface(&face_data);
    // Surface id -> (entity index, type, parameter map).
    let mut on: HashMap<usize, (usize, String, [ParamAxis; 2])> = HashMap::new();
    let mut entities = Vec::new();
    let (mut edge_curves, mut curves_2d) = (0usize, 0usize);
    let mut elementary = 0usize;
    for inst in all.values() {
        let got = if is_surface_type(inst) {
            rd.surface(inst)?
        } else if inst.parts.len() == 1 && ELEMENTARY.contains(&inst.parts[0].name.as_str()) {
            let hull = uses.get(&inst.id).map_or(&[][..], |u| &u.hull[..]);
            if let Some((s, axes, name)) = rd.elementary(inst, hull)? {
                rd.used.insert(inst.id);
                on.insert(inst.id, (entities.len(), inst.parts[0].name.clone(), axes));
                elementary += 1;
                entities.push(NamedEntity {
                    name,
                    entity: Entity::Surface(s),
                });
            }
            continue;
        } else if is_curve_type(inst) {
            if bound_curves.contains(&inst.id) {
                // Read it all the same so that a malformed one is reported, then drop it.
                let r = rd.curve(inst)?;
                rd.used.insert(inst.id);
                match r {
                    Ok(_) => edge_curves += 1,
                    Err(Skip::TwoD) => curves_2d += 1,
                    Err(Skip::Unsupported) => {
                        rd.used.remove(&inst.id);
                    }
                }
                continue;
            }
            rd.curve(inst)?
        } else {
            continue;
        };
        match got {
            Ok(e) => {
                rd.used.insert(inst.id);
                if matches!(e.entity, Entity::Surface(_)) {
                    on.insert(
                        inst.id,
                        (
                            entities.len(),
                            inst.type_name(),
                            [ParamAxis::Linear, ParamAxis::Linear],
                        ),
                    );
                }
                entities.push(e);
            }
            Err(Skip::TwoD) => {
                rd.used.insert(inst.id);
                curves_2d += 1;
            }
            Err(Skip::Unsupported) => {}
        }
    }
    let mut faces = Vec::new();
    let (mut faces_off, mut skipped_edges) = (0usize, 0usize);
    for f in face_data {
        skipped_edges += f.skipped;
        match on.get(&f.surface) {
            Some((entity, surface_type, axes)) => faces.push(TrimmedFace {
                step_id: f.step_id,
                entity: *entity,
                surface_type: surface_type.clone(),
                axes: *axes,
                same_sense: f.same_sense,
                loops: f.loops,
            }),
            None => faces_off += 1,
        }
    }
    let mut warnings = Vec::new();
    if elementary > 0 {
        warnings.push(format!(
            "{elementary} elementary or swept surface(s) converted exactly to NURBS; unbounded \
             ones (planes, cylinders, cones, extrusions) are cut to their faces' boundary box"
        ));
    }
    if faces_off > 0 {
        warnings.push(format!(
            "{faces_off} face(s) lie on surfaces of a type not read: dropped with their loops"
        ));
    }
    if skipped_edges > 0 {
        warnings.push(format!(
            "{skipped_edges} edge(s) of trimming loops have curves of a type not read: \
             missing from their loops"
        ));
    }
    // Edge curves, pcurves and surface-definition curves are kept (in the faces' trimming loops
    // and the surfaces they define): nothing is dropped, so no warning (issue 29: reading our
    // own files is silent).
    let _ = (edge_curves, curves_2d);
    let mut not_read: HashMap<String, usize> = HashMap::new();
    for inst in all.values() {
        let name = inst.type_name();
        if !rd.used.contains(&inst.id) && !is_structure(&name) {
            *not_read.entry(name).or_default() += 1;
        }
    }
    if !not_read.is_empty() {
        let mut v: Vec<(String, usize)> = not_read.into_iter().collect();
        v.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
        let list: Vec<String> = v.iter().map(|(t, n)| format!("{n} {t}")).collect();
        warnings.push(format!(
            "geometry not read (count per type): {}",
            list.join(", ")
        ));
    }
    if entities.is_empty() {
        return Err(err(
            1,
            None,
            format!(
                "no B-spline, elementary or swept curve or surface to import ({})",
                warnings.join("; ")
            ),
        ));
    }
    let mut import = CadImport {
        entities,
        warnings,
        faces,
        shells: Vec::new(),
    };
    if !import.faces.is_empty() {
        match crate::trimmed::shells_of_import(&import) {
            Ok(shells) => import.shells = shells,
            Err(e) => import.warnings.push(format!(
                "the faces' trims could not be made a B-rep ({e}): the faces' surfaces are \
                 imported whole, their loops kept only for meshing"
            )),
        }
    }
    Ok(import)
}

/// Reads a STEP file (`.step`, `.stp`). Errors name the file.
pub fn read_step(path: impl AsRef<Path>) -> Result<CadImport, IoError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|e| IoError::file(path, e))?;
    parse_step(&String::from_utf8_lossy(&bytes)).map_err(|e| e.in_file(path))
}

/// Whether a STEP entity type is file structure rather than geometry: product data, contexts,
/// units, representations, shells and solids that hold faces, presentation (colours, styles),
/// assembly links. Such entities carry no shape of their own, so leaving them unread drops
/// nothing and is not warned about (the warning names only geometry that is dropped).
fn is_structure(type_name: &str) -> bool {
    // Complex instances list their parts in parentheses: structure when every part is.
    if type_name.starts_with('(') {
        return type_name
            .trim_matches(['(', ')'])
            .split_whitespace()
            .all(is_structure);
    }
    const PREFIXES: [&str; 12] = [
        "PRODUCT",
        "APPLICATION_",
        "SHAPE_",
        "PRESENTATION_",
        "SURFACE_STYLE",
        "CURVE_STYLE",
        "FILL_AREA",
        "MECHANICAL_DESIGN",
        "PROPERTY_DEFINITION",
        "DESCRIPTIVE_REPRESENTATION",
        "NEXT_ASSEMBLY",
        "DRAUGHTING_",
    ];
    const SUFFIXES: [&str; 6] = [
        "_CONTEXT",
        "_UNIT",
        "_REPRESENTATION",
        "_SHELL",
        "_STYLE",
        "_ASSIGNMENT",
    ];
    // Placements (a representation's frame: an axis placement, its directions and origin) are
    // coordinate frames, not shape; an unused one is the product's own frame.
    const NAMES: [&str; 23] = [
        "REPRESENTATION",
        "GEOMETRIC_CURVE_SET",
        "GEOMETRIC_SET",
        "AXIS2_PLACEMENT_3D",
        "AXIS2_PLACEMENT_2D",
        "AXIS1_PLACEMENT",
        "DIRECTION",
        "CARTESIAN_POINT",
        "SI_UNIT",
        "NAMED_UNIT",
        "DIMENSIONAL_EXPONENTS",
        "UNCERTAINTY_MEASURE_WITH_UNIT",
        "MANIFOLD_SOLID_BREP",
        "BREP_WITH_VOIDS",
        "SHELL_BASED_SURFACE_MODEL",
        "STYLED_ITEM",
        "OVER_RIDING_STYLED_ITEM",
        "COLOUR_RGB",
        "DRAUGHTING_PRE_DEFINED_COLOUR",
        "ITEM_DEFINED_TRANSFORMATION",
        "CONTEXT_DEPENDENT_SHAPE_REPRESENTATION",
        "REPRESENTATION_RELATIONSHIP",
        "REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION",
    ];
    NAMES.contains(&type_name)
        || PREFIXES.iter().any(|p| type_name.starts_with(p))
        || SUFFIXES.iter().any(|x| type_name.ends_with(x))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_strings_enums_typed_and_complex() {
        let text = "ISO-10303-21;\nHEADER;\nFILE_NAME('a''b',$);\nENDSEC;\nDATA;\n\
                    /* c */ #1=FOO('it''s',.T.,$,*,(1,-2.5E-1,#2),LENGTH_MEASURE(1.),\"0F\");\n\
                    #2=( A() B(3) );\nENDSEC;\nEND-ISO-10303-21;\n";
        let all = parse_instances(text).unwrap();
        let p = &all[&1].parts[0].params;
        assert_eq!(p[0], Param::Str("it's".into()));
        assert_eq!(p[1], Param::Enum("T".into()));
        assert_eq!(p[2], Param::Unset);
        assert_eq!(p[3], Param::Derived);
        assert_eq!(
            p[4],
            Param::List(vec![Param::Int(1), Param::Real(-0.25), Param::Ref(2)])
        );
        assert_eq!(
            p[5],
            Param::Typed("LENGTH_MEASURE".into(), vec![Param::Real(1.0)])
        );
        assert_eq!(p[6], Param::Binary);
        assert_eq!(all[&1].line, 6);
        assert_eq!(all[&2].type_name(), "(A B)");
    }

    #[test]
    fn syntax_errors_are_located() {
        let text = "ISO-10303-21;\nDATA;\n#1=FOO(1,\n2;\nENDSEC;\nEND-ISO-10303-21;\n";
        let e = parse_instances(text).unwrap_err().to_string();
        assert!(e.contains("line 4") && e.contains("#1"), "{e}");
    }
}
