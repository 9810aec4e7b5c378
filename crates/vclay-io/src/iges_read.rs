//! IGES (5.3 and earlier, fixed 80-column ASCII) import of curves (126 rational B-spline, 110
//! line, 100 circular arc, 104 elliptic arc) and surfaces (128 rational B-spline, 120 surface
//! of revolution, 122 tabulated cylinder, 108 plane; the analytic 190-198 of B-rep files), with
//! the trims of trimmed surfaces (144) and manifold solid B-reps (186) read into shells
//! ([`trims`]).
//!
//! **What.** Every surface is imported, including the basis surfaces of trimmed surfaces (144)
//! and faces (510); their loops become [`CadImport::shells`] ([`trims`]). A curve is imported when it is independent:
//! curves that are physically dependent (subordinate switch 01 or 03: trimming curves, parts of
//! composite curves, generatrices) or 2D parametric (use flag 05) belong to a dropped topology
//! or to a surface and are counted in a warning. Knots, weights and control points are taken as
//! written; IGES surface nets run with the u index fastest and are transposed to vclay's order.
//! Labels (directory entry field 18) become entity names.
//!
//! **Exact conversions** (Piegl & Tiller, *The NURBS Book*, sections 7.3 and 8.3-8.5): a line is
//! a degree-1 NURBS on `[0, 1]`; a circular arc (in the plane `z = ZT`, counter-clockwise from
//! its start to its end point; a full circle when they coincide) a rational quadratic with
//! knots at its quarter joints, parametrized by the angle at the joints; a surface of
//! revolution turns its generatrix about the axis line from the start to the terminate angle
//! (u the angle, v the generatrix's parameter); a tabulated cylinder sweeps its directrix by
//! the generatrix vector (`S(u, v) = C(u) + v (L - C(u0))`, v in `[0, 1]`); a plane
//! `A x + B y + C z = D` is the least-area rectangle of the plane holding the control points
//! of its bounding curve (form 1) or, for an unbounded plane (form 0), of the
//! outer boundaries of the trimmed surfaces on it (the model-space curve of 144's outer 142).
//!
//! **Transformation matrices** (entity 124, `x -> R x + T`) are applied: an entity's own, a
//! matrix's own matrix (chained, at most 16 deep), and those of referenced curves, which map
//! into the referencing entity's space (IGES section 3.2.3). NURBS are affinely invariant, so
//! this is exact. Points a matrix sends past the range of numbers are an error.
//!
//! **How.** The Global section gives the parameter and record delimiters (default `,` and `;`);
//! the Directory Entry section (two lines per entity) gives each entity's type, parameter data
//! pointer and line count, status and transformation; the entity's Parameter Data lines
//! (columns 1-64) are joined and split at the delimiters, with Hollerith strings `nH...` read
//! as such and Fortran exponents `1.0D0` accepted.
//!
//! **Warnings.** [`CadImport::warnings`] lists every entity not read with counts per type
//! number (and its name for common types), trimming dropped, parameter ranges narrower than the
//! knot domain (the whole spline is imported), surfaces whose generatrix, directrix or
//! boundary is of a type not read, and unbounded planes with no boundary to size them.
//!
//! **Errors.** A malformed file is an [`IoError::Cad`] naming the line and the directory entry:
//! `IGES line 9, entity DE 3: entity 128: expected 362 parameters, found 300`; pointers to
//! entries that do not exist, an axis that is not a line, angles out of order, zero-length
//! lines and zero-radius arcs are named the same way.
//!
//! **Limitations.** No compressed ASCII or binary IGES; conics (104) other than ellipses in
//! standard position, parametric splines (112, 114), ruled and offset surfaces (118, 140) are
//! listed as not read; units not applied; a plane sized by a trimmed surface's boundary ignores
//! a matrix on the 144 itself.

use crate::error::IoError;
use crate::model::{Entity, NamedEntity};
use crate::step_read::CadImport;
use crate::step_read::{arc, extrude, revolve_between};
use nalgebra::Matrix3;
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::f64::consts::TAU;
use std::path::Path;
use vclay_core::Vec3;
use vclay_spline::{NurbsCurve, NurbsSurface};

pub mod trims;

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

/// An entity's parameter tokens, with its directory entry number and type for messages.
struct Params {
    toks: Vec<Tok>,
    de: usize,
    kind: u32,
}

impl Params {
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

/// Most nested references followed (transformation chains, curves inside curves): deeper is a
/// cycle or a hostile file.
const MAX_DEPTH: usize = 16;

/// An affine map `x -> m x + t` (entity 124).
type Affine = (Matrix3<f64>, Vec3);

/// The directory and parameter sections, for reading entities that reference others.
struct Reader<'a> {
    dirs: &'a [Dir],
    p: &'a [(usize, String)],
    pd: char,
    rd: char,
    /// Warnings met while reading referenced entities.
    warnings: RefCell<Vec<String>>,
}

impl Reader<'_> {
    /// The directory entry `de`, referenced by `from`.
    fn dir(&self, de: usize, from: &Dir) -> Result<&Dir, IoError> {
        if de % 2 == 1 && (de - 1) / 2 < self.dirs.len() {
            Ok(&self.dirs[(de - 1) / 2])
        } else {
            Err(err(
                from.line,
                Some(from.de),
                format!(
                    "entity {}: pointer {de} is not a directory entry (odd, 1 to {})",
                    from.kind,
                    2 * self.dirs.len() - 1
                ),
            ))
        }
    }

    /// The directory entry `de` reached through `depth` nested references (curves inside
    /// composite curves, surfaces' curves): an error past [`MAX_DEPTH`] (a cycle or a hostile
    /// file).
    fn nested(&self, de: usize, from: &Dir, depth: usize) -> Result<&Dir, IoError> {
        let dir = self.dir(de, from)?;
        if depth >= MAX_DEPTH {
            return Err(err(
                dir.line,
                Some(dir.de),
                format!("curves nested deeper than {MAX_DEPTH} (a cycle?)"),
            ));
        }
        Ok(dir)
    }

    /// The parameters of `dir` (its type number first, checked).
    fn params(&self, dir: &Dir) -> Result<Params, IoError> {
        let p = self.p;
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
        let ps = Params {
            toks: split(&data, self.pd, self.rd, dir.de)?,
            de: dir.de,
            kind: dir.kind,
        };
        if ps.int(0, "entity type")? != dir.kind as usize {
            return Err(ps.err(0, "the parameter data starts with another entity type"));
        }
        Ok(ps)
    }

    /// The map of `dir`'s transformation matrix (entity 124), composed with the 124's own
    /// (`x -> M2 (M x + T) + T2`); `None` when it has none.
    fn transform(&self, dir: &Dir, depth: usize) -> Result<Option<Affine>, IoError> {
        if dir.transform == 0 {
            return Ok(None);
        }
        if depth >= MAX_DEPTH {
            return Err(err(
                dir.line,
                Some(dir.de),
                format!("transformation matrices chained deeper than {MAX_DEPTH} (a cycle?)"),
            ));
        }
        let t = self.dir(dir.transform, dir)?;
        if t.kind != 124 {
            return Err(err(
                dir.line,
                Some(dir.de),
                format!(
                    "transformation matrix pointer {} is an entity of type {}, not 124",
                    dir.transform, t.kind
                ),
            ));
        }
        let ps = self.params(t)?;
        ps.need(13)?;
        let v = ps.reals(1, 12, "matrix entry")?;
        let m = Matrix3::new(v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10]);
        let tr = Vec3::new(v[3], v[7], v[11]);
        Ok(Some(match self.transform(t, depth + 1)? {
            None => (m, tr),
            Some((m2, t2)) => (m2 * m, m2 * tr + t2),
        }))
    }

    /// Curve entity `de` (referenced by `from`) as a NURBS curve in the referencing entity's
    /// space (its own transformation applied): 126, 110 (line), 100 (circular arc). `Ok(Err(t))`
    /// for another type `t`.
    fn curve(
        &self,
        de: usize,
        from: &Dir,
        depth: usize,
    ) -> Result<Result<NurbsCurve, u32>, IoError> {
        let dir = self.nested(de, from, depth)?;
        if !matches!(dir.kind, 100 | 104 | 110 | 126) {
            return Ok(Err(dir.kind));
        }
        let ps = self.params(dir)?;
        let mut c = match dir.kind {
            126 => self.bspline_curve(&ps)?,
            110 => {
                ps.need(7)?;
                let p = ps.points(1, 2)?;
                if p[0] == p[1] {
                    return Err(ps.err(1, "line of zero length"));
                }
                NurbsCurve::new(1, vec![0.0, 0.0, 1.0, 1.0], p, None).map_err(|e| ps.err(0, e))?
            }
            104 => {
                // Conic arc in the plane z = ZT, counter-clockwise from start to end: ellipses
                // in standard position (A x^2 + C y^2 + F = 0) are read, exactly.
                ps.need(12)?;
                let v = ps.reals(1, 11, "conic coefficient")?;
                let (a, b, c, d, e, f, zt) = (v[0], v[1], v[2], v[3], v[4], v[5], v[6]);
                let scale = a.abs().max(c.abs()).max(f.abs());
                let off = b.abs().max(d.abs()).max(e.abs());
                if !(off <= 1e-12 * scale && a * f < 0.0 && c * f < 0.0) {
                    // A parabola, a hyperbola or a conic not in standard position.
                    return Ok(Err(104));
                }
                let (rx, ry) = ((-f / a).sqrt(), (-f / c).sqrt());
                let t0 = (v[8] / ry).atan2(v[7] / rx);
                let mut t1 = (v[10] / ry).atan2(v[9] / rx);
                while t1 <= t0 + 1e-12 {
                    t1 += TAU;
                }
                let (knots, pts, w) = arc(
                    Vec3::new(0.0, 0.0, zt),
                    Vec3::x(),
                    Vec3::y(),
                    rx,
                    ry,
                    t0,
                    t1,
                );
                NurbsCurve::new(2, knots, pts, Some(w)).map_err(|e| ps.err(0, e))?
            }
            _ => {
                // 100: in the plane z = ZT, centre, start and end, counter-clockwise.
                ps.need(8)?;
                let v = ps.reals(1, 7, "arc coordinate")?;
                let (zt, c, s, e) = (v[0], [v[1], v[2]], [v[3], v[4]], [v[5], v[6]]);
                let r = (s[0] - c[0]).hypot(s[1] - c[1]);
                let re = (e[0] - c[0]).hypot(e[1] - c[1]);
                if r <= 0.0 {
                    return Err(ps.err(1, "arc of zero radius"));
                }
                if (r - re).abs() > 1e-6 * r.max(1.0) {
                    self.warnings.borrow_mut().push(format!(
                        "entity DE {} (type 100): end point is {:.3e} off the circle; the arc \
                         ends at its angle",
                        dir.de,
                        (r - re).abs()
                    ));
                }
                let a0 = (s[1] - c[1]).atan2(s[0] - c[0]);
                let mut a1 = (e[1] - c[1]).atan2(e[0] - c[0]);
                // Equal start and end: a full circle.
                while a1 <= a0 + 1e-12 {
                    a1 += TAU;
                }
                let (knots, pts, w) = arc(
                    Vec3::new(c[0], c[1], zt),
                    Vec3::x(),
                    Vec3::y(),
                    r,
                    r,
                    a0,
                    a1,
                );
                NurbsCurve::new(2, knots, pts, Some(w)).map_err(|e| ps.err(0, e))?
            }
        };
        if let Some((m, t)) = self.transform(dir, 0)? {
            c.transform(&m, &t);
            finite(c.control_points(), dir)?;
        }
        Ok(Ok(c))
    }

    /// The control points of curve `de` or of the members of a composite curve (102), in the
    /// referencing entity's space: a hull of the curve, for the extent of planes.
    fn curve_points(
        &self,
        de: usize,
        from: &Dir,
        depth: usize,
    ) -> Result<Result<Vec<Vec3>, u32>, IoError> {
        let dir = self.dir(de, from)?;
        if dir.kind != 102 {
            return Ok(self
                .curve(de, from, depth)?
                .map(|c| c.control_points().to_vec()));
        }
        if depth >= MAX_DEPTH {
            return Err(err(
                dir.line,
                Some(dir.de),
                format!("curves nested deeper than {MAX_DEPTH} (a cycle?)"),
            ));
        }
        let ps = self.params(dir)?;
        let n = ps.int(1, "member count")?;
        ps.need(2 + n)?;
        let mut out = Vec::new();
        for k in 0..n {
            match self.curve_points(ps.int(2 + k, "member pointer")?, dir, depth + 1)? {
                Ok(p) => out.extend(p),
                Err(t) => return Ok(Err(t)),
            }
        }
        if let Some((m, t)) = self.transform(dir, 0)? {
            for p in &mut out {
                *p = m * *p + t;
            }
            finite(&out, dir)?;
        }
        Ok(Ok(out))
    }

    /// Entity 126 (the parameter range is checked against the knot domain).
    fn bspline_curve(&self, ps: &Params) -> Result<NurbsCurve, IoError> {
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
        self.check_range(ps, &r, &[dom.min, dom.max]);
        Ok(c)
    }

    /// Entity 128 (IGES nets run with the u index fastest: transposed to vclay's order).
    fn bspline_surface(&self, ps: &Params) -> Result<NurbsSurface, IoError> {
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
        self.check_range(ps, &r, &[dom[0].min, dom[0].max, dom[1].min, dom[1].max]);
        Ok(s)
    }

    /// Warns when a B-spline's parameter range is narrower than its knot domain.
    fn check_range(&self, ps: &Params, range: &[f64], domain: &[f64]) {
        let tol = 1e-9 * domain.iter().fold(1.0f64, |a, &x| a.max(x.abs()));
        if range.iter().zip(domain).any(|(r, d)| (r - d).abs() > tol) {
            self.warnings.borrow_mut().push(format!(
                "entity DE {} (type {}): parameter range {range:?} differs from the knot domain \
                 {domain:?}; the whole spline is imported",
                ps.de, ps.kind
            ));
        }
    }

    /// Surface entity `dir` as a NURBS surface in model space: 128, 120 (surface of
    /// revolution), 122 (tabulated cylinder), 108 (plane: bounded by its own curve, or by the
    /// outer boundaries in `bounds`). `None` (with a warning) when it cannot be built.
    fn surface(
        &self,
        dir: &Dir,
        bounds: &BTreeMap<usize, Vec<Vec3>>,
        warnings: &mut Vec<String>,
    ) -> Result<Option<NurbsSurface>, IoError> {
        let ps = self.params(dir)?;
        let unsupported = |what: &str, t: u32, warnings: &mut Vec<String>| {
            warnings.push(format!(
                "entity DE {} (type {}): its {what} is an entity of type {t}, not read; the \
                 surface is not imported",
                dir.de, dir.kind
            ));
        };
        let mut s = match dir.kind {
            128 => self.bspline_surface(&ps)?,
            120 => {
                ps.need(5)?;
                let axis = self.dir(ps.int(1, "axis pointer")?, dir)?;
                if axis.kind != 110 {
                    return Err(ps.err(
                        1,
                        format!("the axis is of type {}, not a line (110)", axis.kind),
                    ));
                }
                let line = match self.curve(axis.de, dir, 1)? {
                    Ok(line) => line,
                    Err(t) => {
                        unsupported("axis", t, warnings);
                        return Ok(None);
                    }
                };
                let (a0, a1) = (line.control_points()[0], line.control_points()[1]);
                let generatrix = match self.curve(ps.int(2, "generatrix pointer")?, dir, 1)? {
                    Ok(c) => c,
                    Err(t) => {
                        unsupported("generatrix", t, warnings);
                        return Ok(None);
                    }
                };
                let (sa, ta) = (ps.real(3, "start angle")?, ps.real(4, "terminate angle")?);
                if !(ta > sa && ta - sa <= TAU * (1.0 + 1e-12)) {
                    return Err(ps.err(
                        3,
                        format!("angles {sa} to {ta}: need start < terminate <= start + 2 pi"),
                    ));
                }
                revolve_between(a0, (a1 - a0).normalize(), &generatrix, sa, ta.min(sa + TAU))
                    .map_err(|e| ps.err(0, e))?
            }
            122 => {
                ps.need(5)?;
                let directrix = match self.curve(ps.int(1, "directrix pointer")?, dir, 1)? {
                    Ok(c) => c,
                    Err(t) => {
                        unsupported("directrix", t, warnings);
                        return Ok(None);
                    }
                };
                let end = ps.points(2, 1)?[0];
                let dom = vclay_spline::ParametricCurve::domain(&directrix);
                let start = vclay_spline::ParametricCurve::point(&directrix, dom.min)
                    .map_err(|e| ps.err(1, e))?;
                if end == start {
                    return Err(ps.err(2, "generatrix of zero length"));
                }
                extrude(&directrix, end - start, 0.0, 1.0).map_err(|e| ps.err(0, e))?
            }
            _ => {
                // 108: A x + B y + C z = D; form 1/-1 bounded by the curve at PTR.
                ps.need(6)?;
                let v = ps.reals(1, 4, "plane coefficient")?;
                let n = Vec3::new(v[0], v[1], v[2]);
                if n.norm() == 0.0 {
                    return Err(ps.err(1, "plane normal (A, B, C) is zero"));
                }
                let ptr = ps.int(5, "bounding curve pointer")?;
                let hull = if ptr != 0 {
                    match self.curve_points(ptr, dir, 1)? {
                        Ok(p) => p,
                        Err(t) => {
                            unsupported("bounding curve", t, warnings);
                            return Ok(None);
                        }
                    }
                } else if let Some(p) = bounds.get(&dir.de) {
                    p.clone()
                } else {
                    warnings.push(format!(
                        "entity DE {} (type 108): unbounded plane without a trimmed surface's \
                         boundary to give its extent; not imported",
                        dir.de
                    ));
                    return Ok(None);
                };
                match plane_patch(n, v[3], &hull) {
                    Some(s) => s.map_err(|e| ps.err(0, e))?,
                    None => {
                        warnings.push(format!(
                            "entity DE {} (type 108): its bounding curve spans no area; not \
                             imported",
                            dir.de
                        ));
                        return Ok(None);
                    }
                }
            }
        };
        if let Some((m, t)) = self.transform(dir, 0)? {
            s.transform(&m, &t);
            finite(s.control_points(), dir)?;
        }
        Ok(Some(s))
    }
}

/// An error unless every point is finite (a transformation matrix can overflow them).
fn finite(points: &[Vec3], dir: &Dir) -> Result<(), IoError> {
    if points.iter().all(|p| p.iter().all(|x| x.is_finite())) {
        Ok(())
    } else {
        Err(err(
            dir.line,
            Some(dir.de),
            format!(
                "entity {}: its transformation matrix (DE {}) maps control points past the                  range of numbers",
                dir.kind, dir.transform
            ),
        ))
    }
}

/// The least-area rectangle of the plane `n . x = d` holding the projections of `hull` (one of
/// its sides lies along an edge of their convex hull, Freeman & Shapira 1975, so a polygonal
/// face gets its own rectangle exactly); bilinear, u and v along the rectangle's sides. `None`
/// when the points span no area.
fn plane_patch(
    n: Vec3,
    d: f64,
    hull: &[Vec3],
) -> Option<Result<NurbsSurface, vclay_spline::SplineError>> {
    let nn = n.norm_squared();
    let origin = n * (d / nn);
    let z = n / nn.sqrt();
    let x = if z.x.abs() < 0.9 {
        Vec3::x()
    } else {
        Vec3::y()
    };
    let x = (x - z * z.dot(&x)).normalize();
    let y = z.cross(&x);
    let flat: Vec<[f64; 2]> = hull
        .iter()
        .map(|p| [(p - origin).dot(&x), (p - origin).dot(&y)])
        .collect();
    if flat.iter().flatten().any(|c| !c.is_finite()) {
        return None;
    }
    let h = vclay_spline::triangular::convex_hull(&flat);
    if h.len() < 3 {
        return None;
    }
    // (area, side direction, [lo, hi] along it, [lo, hi] across it)
    type Candidate = (f64, [f64; 2], [f64; 2], [f64; 2]);
    let mut best: Option<Candidate> = None;
    for i in 0..h.len() {
        let (a, b) = (h[i], h[(i + 1) % h.len()]);
        let len = (b[0] - a[0]).hypot(b[1] - a[1]);
        if len == 0.0 {
            continue;
        }
        let e = [(b[0] - a[0]) / len, (b[1] - a[1]) / len];
        let (mut s, mut t) = (
            [f64::INFINITY, f64::NEG_INFINITY],
            [f64::INFINITY, f64::NEG_INFINITY],
        );
        for q in &h {
            let (ps, pt) = (q[0] * e[0] + q[1] * e[1], q[1] * e[0] - q[0] * e[1]);
            s = [s[0].min(ps), s[1].max(ps)];
            t = [t[0].min(pt), t[1].max(pt)];
        }
        let area = (s[1] - s[0]) * (t[1] - t[0]);
        if best.is_none_or(|b| area < b.0) {
            best = Some((area, e, s, t));
        }
    }
    let (_, e, s, t) = best?;
    let size = (s[1] - s[0]).max(t[1] - t[0]);
    if !(size.is_finite() && s[1] - s[0] > 1e-12 * size && t[1] - t[0] > 1e-12 * size) {
        return None;
    }
    // In-plane direction e and its left normal (-e1, e0), back to 3D.
    let (du, dv) = (x * e[0] + y * e[1], y * e[0] - x * e[1]);
    let at = |a: f64, b: f64| origin + du * a + dv * b;
    let pts = vec![
        at(s[0], t[0]),
        at(s[0], t[1]),
        at(s[1], t[0]),
        at(s[1], t[1]),
    ];
    Some(NurbsSurface::clamped_uniform([1, 1], [2, 2], pts))
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
    let r = Reader {
        dirs: &dirs,
        p,
        pd,
        rd,
        warnings: RefCell::new(Vec::new()),
    };
    let mut entities = Vec::new();
    let mut not_read: BTreeMap<u32, usize> = BTreeMap::new();
    let mut warnings = Vec::new();
    let (mut dependent, mut trimmed) = (0usize, 0usize);
    // Unbounded planes (108 form 0) take their extent from the outer boundaries of the trimmed
    // surfaces (144) on them: model-space curves (142's CPTR, its fourth parameter).
    let mut plane_bounds: BTreeMap<usize, Vec<Vec3>> = BTreeMap::new();
    for dir in dirs.iter().filter(|d| d.kind == 144) {
        let ps = r.params(dir)?;
        ps.need(5)?;
        let (base, n1, outer) = (
            ps.int(1, "surface pointer")?,
            ps.int(2, "outer boundary flag")?,
            ps.int(4, "outer boundary pointer")?,
        );
        if r.dir(base, dir)?.kind != 108 || n1 == 0 || outer == 0 {
            continue;
        }
        let on = r.dir(outer, dir)?;
        if on.kind != 142 {
            continue;
        }
        let cos = r.params(on)?;
        cos.need(6)?;
        let model_curve = cos.int(4, "model space curve pointer")?;
        if model_curve == 0 {
            continue;
        }
        match r.curve_points(model_curve, on, 0)? {
            Ok(points) => plane_bounds.entry(base).or_default().extend(points),
            Err(kind) => warnings.push(format!(
                "entity DE {} (type 144): its outer boundary has a curve of type {kind}, not read; \
                 it does not bound plane DE {base}",
                dir.de
            )),
        }
    }
    // Trimmed surfaces and B-rep faces (their loops) and the extents of the unbounded analytic
    // surfaces of B-rep files.
    let (raw_faces, hulls, used, mut trim_warnings) = trims::gather(&r)?;
    let used: std::collections::HashSet<usize> = used.into_iter().collect();
    let mut surface_index: std::collections::HashMap<usize, usize> = Default::default();
    for dir in &dirs {
        if matches!(dir.kind, 143 | 144 | 510) && !used.contains(&dir.de) {
            trimmed += 1;
        }
        let curve = matches!(dir.kind, 100 | 104 | 110 | 126);
        let surface = matches!(
            dir.kind,
            108 | 120 | 122 | 128 | 190 | 192 | 194 | 196 | 198
        );
        if !curve && !surface {
            // Transformation matrices are applied to the entities that name them; the trims'
            // entities are read into the B-rep.
            // Associativities, properties and colours (402, 406, 314) carry no geometry.
            if !matches!(dir.kind, 124 | 314 | 402 | 406) && !used.contains(&dir.de) {
                *not_read.entry(dir.kind).or_default() += 1;
            }
            continue;
        }
        // `get`: a status field with a multi-byte character is not sliced mid-character (a
        // fuzzer's input panicked here, issue 17).
        let sub = dir.status.get(2..4).unwrap_or("");
        let use_flag = dir.status.get(4..6).unwrap_or("");
        if curve && (matches!(sub, "01" | "03") || use_flag == "05") {
            if !used.contains(&dir.de) {
                dependent += 1;
            }
            continue;
        }
        let name = (!dir.label.is_empty()).then(|| dir.label.clone());
        let entity = if curve {
            match r.curve(dir.de, dir, 0)? {
                Ok(c) => Entity::Curve(c),
                Err(kind) => {
                    *not_read.entry(kind).or_default() += 1;
                    continue;
                }
            }
        } else if dir.kind >= 190 {
            let hull = hulls.get(&dir.de).map_or(&[][..], |h| h.as_slice());
            match r.analytic_surface(dir, hull, &mut Vec::new(), &mut warnings)? {
                Some(s) => Entity::Surface(s),
                None => continue,
            }
        } else {
            match r.surface(dir, &plane_bounds, &mut warnings)? {
                Some(s) => Entity::Surface(s),
                None => continue,
            }
        };
        if surface {
            surface_index.insert(dir.de, entities.len());
        }
        entities.push(NamedEntity { name, entity });
    }
    warnings.append(&mut r.warnings.borrow_mut());
    if trimmed > 0 {
        warnings.push(format!(
            "{trimmed} trimmed surface(s) or face(s): their base surfaces are imported \
             untrimmed (trimming curves and topology are dropped)"
        ));
    }
    if dependent > 0 {
        warnings.push(format!(
            "{dependent} dependent or parameter-space curve(s) (types 100, 110, 126) not imported \
             as curves: they belong to a surface or to the dropped trimming or topology"
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
    let faces = trims::read(&r, raw_faces, &surface_index, &entities, &mut trim_warnings)?;
    warnings.append(&mut trim_warnings);
    let mut import = CadImport {
        entities,
        warnings,
        faces,
        shells: Vec::new(),
    };
    if !import.faces.is_empty() {
        match crate::trimmed::shells_of_import(&import) {
            Ok(mut shells) => {
                for sh in &mut shells {
                    trims::orient(sh);
                }
                import.shells = shells;
            }
            Err(e) => import.warnings.push(format!(
                "the faces' trims could not be made a B-rep ({e}): the faces' surfaces are \
                 imported whole, their loops kept only for meshing"
            )),
        }
    }
    Ok(import)
}

/// Reads an IGES file (`.igs`, `.iges`). Errors name the file.
pub fn read_iges(path: impl AsRef<Path>) -> Result<CadImport, IoError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|e| IoError::file(path, e))?;
    parse_iges(&String::from_utf8_lossy(&bytes)).map_err(|e| e.in_file(path))
}
