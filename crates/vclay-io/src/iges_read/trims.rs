//! IGES trimmed surfaces (144 with 142 boundaries) and manifold solid B-reps (186 with 502-514
//! topology) read into the trimmed B-rep of [`crate::trimmed`] (issue 30).
//!
//! **What.** Each trimmed surface (144) and each face (510) of a shell (514) becomes a
//! [`TrimmedFace`] on its imported surface: its loops are the model-space curves of its
//! boundaries (142's `CPTR`, split into the members of composite curves 102) or the edges of its
//! loops (508 over edge lists 504 and vertex lists 502). The faces are then made shells with
//! shared vertices and edges by [`crate::trimmed::shells_of_import`], as a STEP file's are.
//!
//! **Pcurves are computed, not read.** IGES writers give parameter-space curves in the
//! parametrization of the file's surface entity (OpenCASCADE writes angles of analytic surfaces
//! in degrees; many writers give none at all: 142's `BPTR` may be 0). vclay converts every
//! surface to an exact NURBS, so the pcurves are computed on that NURBS from the edges' 3D
//! curves (the model-space curves are what IGES 5.3 section 4.32 calls the preferred
//! representation when `PREF` is 2 and what every writer fills):
//! - on a *flat bilinear* surface (planes 108 and 190, whose NURBS parameters are an affine
//!   map of the plane) the pcurve is the edge's NURBS with its control points mapped by the
//!   inverse map: exact;
//! - an edge along an *iso-parameter line* (the circles and rulings of cylinders, cones,
//!   spheres and tori; the seam of a closed surface) gets the straight segment between its end
//!   parameters: exact in position;
//! - any other edge gets a degree-1 pcurve through [`PCURVE_POINTS`] points, each the
//!   surface's closest point to the edge (Newton's method on `|S(u,v) - C(t)|^2`, started from
//!   the previous point along the edge, or from the nearest of a grid of surface points):
//!   exact at those points (and marked so by [`crate::trimmed::pcurves_exact`]).
//!
//! On a surface closed in a direction (a full turn) a pcurve is kept continuous across the
//! seam, and an edge that lies on the seam gets both of its pcurves (one per side), which the
//! shell builder gives to the edge's two uses by continuity.
//!
//! **Topology.** In a 186 B-rep, vertices and edges are shared by their lists (502 and 504
//! pointers and indices). Trimmed surfaces (144) carry no topology: their boundary curves are
//! sewn, vertices merged when closer than [`SEW_RTOL`] times the diagonal of the model's
//! boundary points, edges merged when they join the same two vertices and the middle of one
//! lies on the other. A loop's vertex uses (508 items of type 1: the pole of a sphere) carry
//! no curve and are skipped, as STEP's `VERTEX_LOOP`s are.
//!
//! **Orientation.** A face's sense (whether its outward normal is `S_u x S_v`) is that of its
//! outer loop in the NURBS parameters, counter-clockwise about the outward normal; the shell
//! (514) face orientation flags, when given, are checked against it and a disagreement is
//! warned about.

use super::{Dir, Reader, err};
use crate::error::IoError;
use crate::step_read::{ParamAxis, TrimEdge, TrimLoop, TrimmedFace};
use std::collections::{BTreeMap, HashMap};
use vclay_core::Vec3;
use vclay_spline::{NurbsCurve, NurbsSurface, ParametricCurve, ParametricSurface};

/// Relative tolerance of sewing the boundaries of trimmed surfaces (see the module docs):
/// IGES files round coordinates to 9-15 significant digits.
pub const SEW_RTOL: f64 = 1e-7;

/// Points of a pcurve that is neither exact nor an iso-line (see the module docs).
pub const PCURVE_POINTS: usize = 65;

/// One boundary curve of a face as read: its 3D curve (in loop order its start is where the
/// previous one ends once `forward` is applied) and, for B-rep edges, the ids of its edge and
/// vertices.
struct Piece {
    curve: NurbsCurve,
    forward: bool,
    /// `(edge id, [start vertex id, end vertex id])` from a 504/502 list; `None` for boundary
    /// curves of trimmed surfaces (sewn later).
    ids: Option<(usize, [usize; 2])>,
}

/// A face before its pcurves: surface DE, loops (first the outer one when `outer_first`).
pub(super) struct RawFace {
    de: usize,
    surface: usize,
    loops: Vec<Vec<Piece>>,
    outer_first: bool,
    /// The shell's orientation flag for this face (514), if any.
    flag: Option<bool>,
}

impl Reader<'_> {
    /// The curve `de` as a list of pieces: the members of composite curves (102, nested), each
    /// an exact NURBS in the referencing entity's space; `Err(t)` names a type not read.
    fn pieces(
        &self,
        de: usize,
        from: &Dir,
        depth: usize,
        used: &mut Vec<usize>,
    ) -> Result<Result<Vec<NurbsCurve>, u32>, IoError> {
        let dir = self.nested(de, from, depth)?;
        used.push(dir.de);
        if dir.kind != 102 {
            return Ok(self.edge_curve(dir, from)?.map(|c| vec![c]));
        }
        let ps = self.params(dir)?;
        let n = ps.int(1, "member count")?;
        ps.need(2 + n)?;
        let mut out = Vec::new();
        for k in 0..n {
            match self.pieces(ps.int(2 + k, "member pointer")?, dir, depth + 1, used)? {
                Ok(mut p) => out.append(&mut p),
                Err(t) => return Ok(Err(t)),
            }
        }
        if let Some((m, t)) = self.transform(dir, 0)? {
            for c in &mut out {
                c.transform(&m, &t);
            }
        }
        Ok(Ok(out))
    }

    /// A curve entity used as an edge: a B-spline (126) cut to its parameter range, or the
    /// curve read by [`Reader::curve`].
    fn edge_curve(&self, dir: &Dir, from: &Dir) -> Result<Result<NurbsCurve, u32>, IoError> {
        let c = match self.curve(dir.de, from, 1)? {
            Ok(c) => c,
            Err(t) => return Ok(Err(t)),
        };
        if dir.kind != 126 {
            return Ok(Ok(c));
        }
        let ps = self.params(dir)?;
        let k = ps.int(1, "upper index K")?;
        let m = ps.int(2, "degree M")?;
        let at = 7 + (k + m + 2) + 4 * (k + 1);
        let r = ps.reals(at, 2, "parameter range")?;
        let d = c.domain();
        let tol = c.knots().parameter_tolerance();
        if r[0] > d.min + tol || r[1] < d.max - tol {
            let part = crate::trimmed::curve_part(&c, r[0].max(d.min), r[1].min(d.max))
                .map_err(|e| ps.err(at, e))?;
            return Ok(Ok(part));
        }
        Ok(Ok(c))
    }

    /// A point (116) or direction (123) entity's three coordinates.
    fn xyz(
        &self,
        de: usize,
        from: &Dir,
        kind: u32,
        used: &mut Vec<usize>,
    ) -> Result<Vec3, IoError> {
        let dir = self.dir(de, from)?;
        if dir.kind != kind {
            return Err(err(
                from.line,
                Some(from.de),
                format!(
                    "entity {}: pointer {de} is an entity of type {}, expected {kind}",
                    from.kind, dir.kind
                ),
            ));
        }
        used.push(de);
        let ps = self.params(dir)?;
        ps.need(4)?;
        let mut p = Vec3::new(ps.real(1, "x")?, ps.real(2, "y")?, ps.real(3, "z")?);
        if let Some((m, t)) = self.transform(dir, 0)? {
            p = if kind == 123 { m * p } else { m * p + t };
        }
        Ok(p)
    }

    /// An analytic surface of a B-rep file (190 plane, 192 cylinder, 194 cone, 196 sphere,
    /// 198 torus; IGES 5.3 sections 4.138-4.147) converted exactly to NURBS: angle directions
    /// are full turns of rational quadratic arcs from the reference direction, counter-clockwise
    /// about the axis; unbounded directions (the plane's, the cylinder's and cone's height) span
    /// `hull`, the control points of the boundaries of the faces on the surface. `None` (with a
    /// warning) when `hull` spans nothing.
    pub(super) fn analytic_surface(
        &self,
        dir: &Dir,
        hull: &[Vec3],
        used: &mut Vec<usize>,
        warnings: &mut Vec<String>,
    ) -> Result<Option<NurbsSurface>, IoError> {
        use crate::step_read::{arc, revolve_between};
        use std::f64::consts::{FRAC_PI_2, TAU};
        let ps = self.params(dir)?;
        let unit = |v: Vec3, i: usize| -> Result<Vec3, IoError> {
            let n = v.norm();
            if n > 0.0 && n.is_finite() {
                Ok(v / n)
            } else {
                Err(ps.err(i, "zero direction"))
            }
        };
        // The frame: origin, unit axis and a unit reference direction normal to it.
        let frame = |o: Vec3, a: Vec3, r: Option<Vec3>| -> (Vec3, Vec3, Vec3) {
            let x0 = r.unwrap_or(if a.x.abs() < 0.9 {
                Vec3::x()
            } else {
                Vec3::y()
            });
            let mut x = x0 - a * a.dot(&x0);
            if x.norm() < 1e-9 {
                let y0 = if a.x.abs() < 0.9 {
                    Vec3::x()
                } else {
                    Vec3::y()
                };
                x = y0 - a * a.dot(&y0);
            }
            (o, a, x.normalize())
        };
        let range = |o: Vec3, e: Vec3| -> Option<[f64; 2]> {
            let (lo, hi) = hull
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |m, p| {
                    let t = (p - o).dot(&e);
                    (m.0.min(t), m.1.max(t))
                });
            (hi > lo).then_some([lo, hi])
        };
        let form1 = |n: usize| ps.toks.len() > n && !ps.toks[n].text.is_empty();
        let nothing = |warnings: &mut Vec<String>| {
            warnings.push(format!(
                "entity DE {} (type {}): no face bounds this unbounded surface; not imported",
                dir.de, dir.kind
            ));
        };
        let positive = |i: usize, what: &str| -> Result<f64, IoError> {
            let r = ps.real(i, what)?;
            if r > 0.0 {
                Ok(r)
            } else {
                Err(ps.err(i, format!("{what} must be positive, found {r}")))
            }
        };
        let line = |p: Vec3, q: Vec3, t0: f64, t1: f64| {
            NurbsCurve::new(1, vec![t0, t0, t1, t1], vec![p, q], None)
        };
        let s = match dir.kind {
            190 => {
                ps.need(3)?;
                let o = self.xyz(ps.int(1, "location pointer")?, dir, 116, used)?;
                let n = unit(self.xyz(ps.int(2, "normal pointer")?, dir, 123, used)?, 2)?;
                match super::plane_patch(n, n.dot(&o), hull) {
                    Some(s) => s.map_err(|e| ps.err(0, e))?,
                    None => {
                        nothing(warnings);
                        return Ok(None);
                    }
                }
            }
            192 | 194 => {
                let cone = dir.kind == 194;
                ps.need(if cone { 5 } else { 4 })?;
                let o = self.xyz(ps.int(1, "location pointer")?, dir, 116, used)?;
                let a = unit(self.xyz(ps.int(2, "axis pointer")?, dir, 123, used)?, 2)?;
                let r = ps.real(3, "radius")?;
                let (slope, refp) = if cone {
                    let deg = ps.real(4, "semi-angle")?;
                    if !(deg > 0.0 && deg < 90.0) {
                        return Err(ps.err(
                            4,
                            format!("semi-angle {deg} must be between 0 and 90 degrees"),
                        ));
                    }
                    (deg.to_radians().tan(), 5)
                } else {
                    (0.0, 4)
                };
                if r < 0.0 || (!cone && r == 0.0) {
                    return Err(ps.err(3, format!("radius must be positive, found {r}")));
                }
                let refdir = if form1(refp) && ps.int(refp, "reference direction pointer")? != 0 {
                    Some(self.xyz(ps.int(refp, "reference direction pointer")?, dir, 123, used)?)
                } else {
                    None
                };
                let (o, a, x) = frame(o, a, refdir);
                let Some([h0, h1]) = range(o, a) else {
                    nothing(warnings);
                    return Ok(None);
                };
                let at = |h: f64| o + x * (r + h * slope) + a * h;
                let g = line(at(h0), at(h1), h0, h1).map_err(|e| ps.err(0, e))?;
                revolve_between(o, a, &g, 0.0, TAU).map_err(|e| ps.err(0, e))?
            }
            196 => {
                ps.need(3)?;
                let o = self.xyz(ps.int(1, "centre pointer")?, dir, 116, used)?;
                let r = positive(2, "radius")?;
                let (a, refdir) = if form1(3) && ps.int(3, "axis pointer")? != 0 {
                    let a = unit(self.xyz(ps.int(3, "axis pointer")?, dir, 123, used)?, 3)?;
                    let rd = if form1(4) && ps.int(4, "reference direction pointer")? != 0 {
                        Some(self.xyz(ps.int(4, "reference direction pointer")?, dir, 123, used)?)
                    } else {
                        None
                    };
                    (a, rd)
                } else {
                    (Vec3::z(), None)
                };
                let (o, a, x) = frame(o, a, refdir);
                let (k, p, w) = arc(o, x, a, r, r, -FRAC_PI_2, FRAC_PI_2);
                let g = NurbsCurve::new(2, k, p, Some(w)).map_err(|e| ps.err(0, e))?;
                revolve_between(o, a, &g, 0.0, TAU).map_err(|e| ps.err(0, e))?
            }
            _ => {
                // 198 torus.
                ps.need(5)?;
                let o = self.xyz(ps.int(1, "centre pointer")?, dir, 116, used)?;
                let a = unit(self.xyz(ps.int(2, "axis pointer")?, dir, 123, used)?, 2)?;
                let major = positive(3, "major radius")?;
                let minor = positive(4, "minor radius")?;
                let refdir = if form1(5) && ps.int(5, "reference direction pointer")? != 0 {
                    Some(self.xyz(ps.int(5, "reference direction pointer")?, dir, 123, used)?)
                } else {
                    None
                };
                let (o, a, x) = frame(o, a, refdir);
                let (k, p, w) = arc(o + x * major, x, a, minor, minor, 0.0, TAU);
                let g = NurbsCurve::new(2, k, p, Some(w)).map_err(|e| ps.err(0, e))?;
                revolve_between(o, a, &g, 0.0, TAU).map_err(|e| ps.err(0, e))?
            }
        };
        let mut s = s;
        if let Some((m, t)) = self.transform(dir, 0)? {
            s.transform(&m, &t);
            super::finite(s.control_points(), dir)?;
        }
        Ok(Some(s))
    }

    /// The faces of the trimmed surfaces (144) and of the shells (514), before their surfaces
    /// are converted: see the module docs. A face whose boundary has a curve of a type not read
    /// is dropped with a warning (its surface is still imported, untrimmed).
    fn raw_faces(
        &self,
        used: &mut Vec<usize>,
        warnings: &mut Vec<String>,
    ) -> Result<Vec<RawFace>, IoError> {
        let mut faces = Vec::new();
        for dir in self.dirs {
            match dir.kind {
                144 => {
                    let ps = self.params(dir)?;
                    ps.need(5)?;
                    let surface = ps.int(1, "surface pointer")?;
                    let n1 = ps.int(2, "outer boundary flag")?;
                    let n2 = ps.int(3, "inner boundary count")?;
                    ps.need(5 + n2)?;
                    let mut bounds = Vec::new();
                    if n1 != 0 {
                        bounds.push(ps.int(4, "outer boundary pointer")?);
                    }
                    for k in 0..n2 {
                        bounds.push(ps.int(5 + k, "inner boundary pointer")?);
                    }
                    let mut loops = Vec::new();
                    let mut mine = vec![dir.de];
                    let mut dropped = None;
                    for b in bounds {
                        let on = self.dir(b, dir)?;
                        if on.kind != 142 {
                            dropped = Some(on.kind);
                            break;
                        }
                        mine.push(on.de);
                        let cos = self.params(on)?;
                        cos.need(6)?;
                        let model = cos.int(4, "model space curve pointer")?;
                        if model == 0 {
                            dropped = Some(142);
                            break;
                        }
                        let bptr = cos.int(3, "parameter curve pointer")?;
                        if bptr != 0 {
                            // Not used (see the module docs), but read: not "dropped".
                            let _ = self.pieces(bptr, on, 0, &mut mine)?;
                        }
                        match self.pieces(model, on, 0, &mut mine)? {
                            Ok(cs) => loops.push(
                                cs.into_iter()
                                    .map(|curve| Piece {
                                        curve,
                                        forward: true,
                                        ids: None,
                                    })
                                    .collect(),
                            ),
                            Err(t) => {
                                dropped = Some(t);
                                break;
                            }
                        }
                    }
                    if let Some(t) = dropped {
                        warnings.push(format!(
                            "entity DE {} (type 144): a boundary curve is of type {t}, not read; \
                             the surface is imported untrimmed",
                            dir.de
                        ));
                        continue;
                    }
                    used.append(&mut mine);
                    faces.push(RawFace {
                        de: dir.de,
                        surface,
                        loops,
                        outer_first: n1 != 0,
                        flag: None,
                    });
                }
                514 => {
                    let ps = self.params(dir)?;
                    ps.need(2)?;
                    let n = ps.int(1, "face count")?;
                    ps.need(2 + 2 * n)?;
                    used.push(dir.de);
                    for k in 0..n {
                        let fde = ps.int(2 + 2 * k, "face pointer")?;
                        let flag = ps.int(3 + 2 * k, "face orientation flag")? != 0;
                        let fdir = self.dir(fde, dir)?;
                        if fdir.kind != 510 {
                            return Err(ps.err(
                                2 + 2 * k,
                                format!(
                                    "face pointer {fde} is an entity of type {}, not 510",
                                    fdir.kind
                                ),
                            ));
                        }
                        match self.face(fdir, flag)? {
                            Ok((f, mut mine)) => {
                                used.append(&mut mine);
                                faces.push(f);
                            }
                            Err(t) => warnings.push(format!(
                                "entity DE {fde} (type 510): an edge curve is of type {t}, not \
                                 read; its surface is imported untrimmed"
                            )),
                        }
                    }
                }
                186 => used.push(dir.de),
                _ => {}
            }
        }
        Ok(faces)
    }

    /// A face (510) of a shell: its loops (508) over edge lists (504) and vertex lists (502).
    fn face(&self, dir: &Dir, flag: bool) -> Result<Result<(RawFace, Vec<usize>), u32>, IoError> {
        let ps = self.params(dir)?;
        ps.need(4)?;
        let surface = ps.int(1, "surface pointer")?;
        let n = ps.int(2, "loop count")?;
        let outer_first = ps.int(3, "outer loop flag")? != 0;
        ps.need(4 + n)?;
        let mut used = vec![dir.de];
        let mut loops = Vec::with_capacity(n);
        for k in 0..n {
            let ldir = self.dir(ps.int(4 + k, "loop pointer")?, dir)?;
            if ldir.kind != 508 {
                return Err(ps.err(
                    4 + k,
                    format!(
                        "loop pointer {} is an entity of type {}, not 508",
                        ldir.de, ldir.kind
                    ),
                ));
            }
            used.push(ldir.de);
            let lp = self.params(ldir)?;
            let m = lp.int(1, "edge count")?;
            let mut i = 2;
            // `m` is checked against the parameters as they are read (`need`).
            let mut pieces = Vec::new();
            for _ in 0..m {
                lp.need(i + 5)?;
                let kind = lp.int(i, "edge type")?;
                let list = lp.int(i + 1, "edge list pointer")?;
                let index = lp.int(i + 2, "edge index")?;
                let orient = lp.int(i + 3, "orientation flag")? != 0;
                let kp = lp.int(i + 4, "parameter curve count")?;
                lp.need(i + 5 + 2 * kp)?;
                for j in 0..kp {
                    let c = lp.int(i + 6 + 2 * j, "parameter curve pointer")?;
                    if c != 0 {
                        let _ = self.pieces(c, ldir, 0, &mut used)?;
                    }
                }
                i += 5 + 2 * kp;
                if kind == 1 {
                    // A vertex use (a pole): no curve.
                    continue;
                }
                let ldir2 = self.dir(list, ldir)?;
                if ldir2.kind != 504 {
                    return Err(lp.err(
                        i,
                        format!(
                            "edge list pointer {list} is an entity of type {}, not 504",
                            ldir2.kind
                        ),
                    ));
                }
                let (curve, v) = match self.edge_of_list(ldir2, index, &mut used)? {
                    Ok(e) => e,
                    Err(t) => return Ok(Err(t)),
                };
                pieces.push(Piece {
                    curve,
                    forward: orient,
                    ids: Some((list * 1_000_000 + index, v)),
                });
            }
            if !flag {
                // The loops are written for the surface's side (IGES 5.3 section 4.151: the
                // shell's flag says the face is used reversed): run them the other way.
                pieces.reverse();
                for p in &mut pieces {
                    p.forward = !p.forward;
                }
            }
            loops.push(pieces);
        }
        Ok(Ok((
            RawFace {
                de: dir.de,
                surface,
                loops,
                outer_first,
                flag: Some(flag),
            },
            used,
        )))
    }

    /// Edge `index` (1-based) of the edge list `list` (504): its curve and the ids of its start
    /// and end vertices (`DE * 1e6 + index` of their 502 lists).
    fn edge_of_list(
        &self,
        list: &Dir,
        index: usize,
        used: &mut Vec<usize>,
    ) -> Result<Result<(NurbsCurve, [usize; 2]), u32>, IoError> {
        let ps = self.params(list)?;
        let n = ps.int(1, "edge count")?;
        if index == 0 || index > n {
            return Err(ps.err(
                1,
                format!("edge index {index} is outside the list's 1..{n}"),
            ));
        }
        let at = 2 + 5 * (index - 1);
        ps.need(at + 5)?;
        used.push(list.de);
        let cde = ps.int(at, "curve pointer")?;
        let mut v = [0; 2];
        for k in 0..2 {
            let vl = ps.int(at + 1 + 2 * k, "vertex list pointer")?;
            let vi = ps.int(at + 2 + 2 * k, "vertex index")?;
            let vdir = self.dir(vl, list)?;
            if vdir.kind != 502 {
                return Err(ps.err(
                    at + 1 + 2 * k,
                    format!(
                        "vertex list pointer {vl} is an entity of type {}, not 502",
                        vdir.kind
                    ),
                ));
            }
            let vps = self.params(vdir)?;
            let nv = vps.int(1, "vertex count")?;
            if vi == 0 || vi > nv {
                return Err(ps.err(
                    at + 2 + 2 * k,
                    format!("vertex index {vi} is outside the list's 1..{nv}"),
                ));
            }
            used.push(vl);
            v[k] = vl * 1_000_000 + vi;
        }
        let pieces = match self.pieces(cde, list, 0, used)? {
            Ok(p) => p,
            Err(t) => return Ok(Err(t)),
        };
        let curve = if pieces.len() == 1 {
            pieces.into_iter().next().expect("one piece")
        } else {
            // A composite edge curve: not joined here.
            return Ok(Err(102));
        };
        Ok(Ok((curve, v)))
    }

    /// The points of vertex list `de` (502), for edge ends.
    fn vertex_point(&self, id: usize) -> Result<Vec3, IoError> {
        let (de, index) = (id / 1_000_000, id % 1_000_000);
        let dir = self.dir(de, &self.dirs[0])?;
        let ps = self.params(dir)?;
        let at = 2 + 3 * (index - 1);
        ps.need(at + 3)?;
        let mut p = Vec3::new(
            ps.real(at, "x")?,
            ps.real(at + 1, "y")?,
            ps.real(at + 2, "z")?,
        );
        if let Some((m, t)) = self.transform(dir, 0)? {
            p = m * p + t;
        }
        Ok(p)
    }
}

/// The control points of the boundary curves of each face's surface, by surface DE (for the
/// extent of unbounded surfaces).
fn hulls(faces: &[RawFace]) -> BTreeMap<usize, Vec<Vec3>> {
    let mut out: BTreeMap<usize, Vec<Vec3>> = BTreeMap::new();
    for f in faces {
        let h = out.entry(f.surface).or_default();
        for p in f.loops.iter().flatten() {
            h.extend_from_slice(p.curve.control_points());
        }
    }
    out
}

/// Surface point inversion by Newton's method (see the module docs).
struct Inverter<'a> {
    s: &'a NurbsSurface,
    lo: [f64; 2],
    hi: [f64; 2],
    seeds: Vec<([f64; 2], Vec3)>,
    /// Whether the surface closes on itself in u, v (a full turn).
    closed: [bool; 2],
    /// Length scale of the surface (control net diagonal).
    size: f64,
}

impl<'a> Inverter<'a> {
    fn new(s: &'a NurbsSurface) -> Self {
        let d = s.domain();
        let (lo, hi) = ([d[0].min, d[1].min], [d[0].max, d[1].max]);
        let n = 24;
        let mut seeds = Vec::with_capacity(n * n);
        for i in 0..n {
            for j in 0..n {
                let uv = [
                    lo[0] + (hi[0] - lo[0]) * i as f64 / (n - 1) as f64,
                    lo[1] + (hi[1] - lo[1]) * j as f64 / (n - 1) as f64,
                ];
                if let Ok(p) = s.point(uv[0], uv[1]) {
                    seeds.push((uv, p));
                }
            }
        }
        let size = crate::brep::closure_tolerance(s.control_points()) / crate::brep::CLOSURE_RTOL;
        let tol = 1e-9 * size;
        let closes = |axis: usize| {
            (0..5).all(|k| {
                let t = if axis == 0 {
                    lo[1] + (hi[1] - lo[1]) * k as f64 / 4.0
                } else {
                    lo[0] + (hi[0] - lo[0]) * k as f64 / 4.0
                };
                let (a, b) = if axis == 0 {
                    (s.point(lo[0], t), s.point(hi[0], t))
                } else {
                    (s.point(t, lo[1]), s.point(t, hi[1]))
                };
                matches!((a, b), (Ok(a), Ok(b)) if (a - b).norm() <= tol)
            })
        };
        let closed = [closes(0), closes(1)];
        Inverter {
            s,
            lo,
            hi,
            seeds,
            closed,
            size,
        }
    }

    fn clamp(&self, uv: [f64; 2]) -> [f64; 2] {
        [
            uv[0].clamp(self.lo[0], self.hi[0]),
            uv[1].clamp(self.lo[1], self.hi[1]),
        ]
    }

    /// Newton iterations on `|S - p|^2` from `uv`; the parameters and the distance reached.
    fn newton(&self, p: Vec3, uv: [f64; 2]) -> ([f64; 2], f64) {
        let mut uv = self.clamp(uv);
        for _ in 0..40 {
            let Ok(d) = self.s.derivatives(uv[0], uv[1], 1) else {
                break;
            };
            let (s, su, sv) = (d[0][0], d[1][0], d[0][1]);
            let r = s - p;
            let (a, b, c) = (su.dot(&su), su.dot(&sv), sv.dot(&sv));
            let (g0, g1) = (su.dot(&r), sv.dot(&r));
            let reg = 1e-14 * (a + c) + f64::MIN_POSITIVE;
            let (a, c) = (a + reg, c + reg);
            let det = a * c - b * b;
            if det.is_nan() || det <= 0.0 {
                break;
            }
            let du = -(c * g0 - b * g1) / det;
            let dv = -(a * g1 - b * g0) / det;
            let next = self.clamp([uv[0] + du, uv[1] + dv]);
            let step = (next[0] - uv[0]).abs() / (self.hi[0] - self.lo[0])
                + (next[1] - uv[1]).abs() / (self.hi[1] - self.lo[1]);
            uv = next;
            // Quadratic convergence: a step of 1e-13 of the domain leaves an error far below.
            if step < 1e-13 {
                break;
            }
        }
        let dist = self
            .s
            .point(uv[0], uv[1])
            .map_or(f64::INFINITY, |q| (q - p).norm());
        (uv, dist)
    }

    /// The parameters of the surface point closest to `p`, started from `hint` and from the
    /// nearest grid point; the nearer result.
    fn invert(&self, p: Vec3, hint: Option<[f64; 2]>) -> [f64; 2] {
        // Continuation along an edge: the previous point's parameters usually converge.
        let from_hint = hint.map(|h| self.newton(p, h));
        if let Some((uv, d)) = from_hint
            && d <= 1e-9 * self.size
        {
            return uv;
        }
        let seed = self
            .seeds
            .iter()
            .min_by(|a, b| {
                (a.1 - p)
                    .norm_squared()
                    .total_cmp(&(b.1 - p).norm_squared())
            })
            .map_or([self.lo[0], self.lo[1]], |s| s.0);
        let a = self.newton(p, seed);
        match from_hint {
            // Prefer the continuation unless it is clearly farther.
            Some(b) if b.1 <= a.1 + 1e-9 * self.size => b.0,
            _ => a.0,
        }
    }

    /// Whether the surface is degenerate at `uv` in direction `axis` (a pole: `S_u = 0`).
    fn degenerate(&self, uv: [f64; 2], axis: usize) -> bool {
        match self.s.derivatives(uv[0], uv[1], 1) {
            Ok(d) => {
                let (su, sv) = (d[1][0], d[0][1]);
                let (x, y) = if axis == 0 { (su, sv) } else { (sv, su) };
                x.norm() <= 1e-9 * y.norm().max(self.size)
            }
            Err(_) => false,
        }
    }
}

/// Whether the surface is a flat bilinear patch (a parallelogram, weights 1): its parameters
/// are then an affine map of the plane. Returns the inverse map `p -> (u, v)` as origin,
/// and the two dual vectors.
/// A flat bilinear patch's corner, its two edge vectors and its parameter ranges.
type Affine = (Vec3, Vec3, Vec3, [f64; 2], [f64; 2]);

fn affine_inverse(s: &NurbsSurface) -> Option<Affine> {
    if s.degree() != [1, 1] || s.dims() != [2, 2] || s.weights().iter().any(|&w| w != 1.0) {
        return None;
    }
    let (p00, p01, p10, p11) = (
        s.control_point(0, 0),
        s.control_point(0, 1),
        s.control_point(1, 0),
        s.control_point(1, 1),
    );
    let (eu, ev) = (p10 - p00, p01 - p00);
    let size = eu.norm() + ev.norm();
    if (p11 - p10 - ev).norm() > 1e-12 * size {
        return None;
    }
    let d = s.domain();
    Some((p00, eu, ev, [d[0].min, d[0].max], [d[1].min, d[1].max]))
}

/// The pcurve(s) of the 3D `curve` on the face's surface, in its NURBS parameters, over the
/// curve's domain (see the module docs): the pcurve, and a second one on the other side of the
/// seam when the curve lies on it.
fn pcurves(
    inv: &Inverter<'_>,
    curve: &NurbsCurve,
) -> Result<(NurbsCurve, Option<NurbsCurve>), String> {
    let d = curve.domain();
    let (t0, t1) = (d.min, d.max);
    let seg = |a: [f64; 2], b: [f64; 2]| {
        NurbsCurve::new(
            1,
            vec![t0, t0, t1, t1],
            vec![Vec3::new(a[0], a[1], 0.0), Vec3::new(b[0], b[1], 0.0)],
            None,
        )
        .map_err(|e| e.to_string())
    };
    if let Some((o, eu, ev, ur, vr)) = affine_inverse(inv.s) {
        // Solve p - o = a eu + b ev in the plane (least squares, exact for points on it).
        let (g11, g12, g22) = (eu.dot(&eu), eu.dot(&ev), ev.dot(&ev));
        let det = g11 * g22 - g12 * g12;
        let map = |p: &Vec3| {
            let r = p - o;
            let (x, y) = (r.dot(&eu), r.dot(&ev));
            let a = (g22 * x - g12 * y) / det;
            let b = (g11 * y - g12 * x) / det;
            Vec3::new(
                ur[0] + a * (ur[1] - ur[0]),
                vr[0] + b * (vr[1] - vr[0]),
                0.0,
            )
        };
        let pts: Vec<Vec3> = curve.control_points().iter().map(map).collect();
        let c = NurbsCurve::new(
            curve.degree(),
            curve.knots().as_slice().to_vec(),
            pts,
            Some(curve.weights().to_vec()),
        )
        .map_err(|e| e.to_string())?;
        return Ok((c, None));
    }
    let n = PCURVE_POINTS;
    let mut uv: Vec<[f64; 2]> = Vec::with_capacity(n);
    for k in 0..n {
        let t = t0 + (t1 - t0) * k as f64 / (n - 1) as f64;
        let p = curve.point(t).map_err(|e| e.to_string())?;
        let hint = uv.last().copied();
        uv.push(inv.invert(p, hint));
    }
    // At a pole the degenerate parameter is free: take it from the neighbour.
    for axis in 0..2 {
        for k in 0..n {
            if inv.degenerate(uv[k], axis) {
                let nb = if k + 1 < n {
                    k + 1
                } else {
                    k.saturating_sub(1)
                };
                if nb != k && !inv.degenerate(uv[nb], axis) {
                    uv[k][axis] = uv[nb][axis];
                }
            }
        }
    }
    // Continuous across the seam of a closed direction, then inside the domain.
    for axis in 0..2 {
        if !inv.closed[axis] {
            continue;
        }
        crate::trimmed::unwrap_turn(&mut uv, axis, [inv.lo[axis], inv.hi[axis]], 1e-9);
        uv.iter_mut()
            .for_each(|p| p[axis] = p[axis].clamp(inv.lo[axis], inv.hi[axis]));
    }
    let iso = |axis: usize| {
        let span = inv.hi[axis] - inv.lo[axis];
        uv.iter()
            .all(|p| (p[axis] - uv[0][axis]).abs() <= 1e-7 * span)
    };
    if iso(0) || iso(1) {
        let (a, b) = (uv[0], uv[n - 1]);
        let first = seg(a, b)?;
        // On the seam: the other side too.
        for axis in 0..2 {
            let span = inv.hi[axis] - inv.lo[axis];
            if inv.closed[axis] && iso(axis) {
                let at_lo = (a[axis] - inv.lo[axis]).abs() <= 1e-7 * span;
                let at_hi = (a[axis] - inv.hi[axis]).abs() <= 1e-7 * span;
                if at_lo || at_hi {
                    let other = if at_lo { inv.hi[axis] } else { inv.lo[axis] };
                    let (mut a2, mut b2) = (a, b);
                    a2[axis] = other;
                    b2[axis] = other;
                    return Ok((first, Some(seg(a2, b2)?)));
                }
            }
        }
        return Ok((first, None));
    }
    let mut knots = vec![t0; 2];
    for k in 1..n - 1 {
        knots.push(t0 + (t1 - t0) * k as f64 / (n - 1) as f64);
    }
    knots.extend([t1; 2]);
    let pts = uv.iter().map(|p| Vec3::new(p[0], p[1], 0.0)).collect();
    let c = NurbsCurve::new(1, knots, pts, None).map_err(|e| e.to_string())?;
    Ok((c, None))
}

/// An edge found by sewing: its id, its curve and its vertices.
type SewnEdge = (usize, NurbsCurve, [usize; 2]);

/// Sewing of boundary curves without topology: vertex and edge ids by position.
struct Sewing {
    tol: f64,
    cells: HashMap<[i64; 3], Vec<usize>>,
    points: Vec<Vec3>,
    /// Edges by their (sorted) vertex pair: (id, a point in the middle of the curve, curve).
    edges: HashMap<[usize; 2], Vec<SewnEdge>>,
    next_edge: usize,
}

impl Sewing {
    fn vertex(&mut self, p: Vec3) -> usize {
        let cell =
            |p: &Vec3| -> [i64; 3] { [0, 1, 2].map(|k| (p[k] / (4.0 * self.tol)).floor() as i64) };
        let c = cell(&p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(ids) = self.cells.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) {
                        for &i in ids {
                            if (self.points[i] - p).norm() <= self.tol {
                                return i;
                            }
                        }
                    }
                }
            }
        }
        self.points.push(p);
        let id = self.points.len() - 1;
        self.cells.entry(c).or_default().push(id);
        id
    }

    /// The edge of `curve` from vertex `a` to `b`: an existing edge joining the same vertices
    /// whose curve passes through this one's middle, or a new one. Returns its id, its curve
    /// and its vertices (those of the first curve seen, the edge's direction) and whether
    /// `curve` runs the same way.
    fn edge(
        &mut self,
        a: usize,
        b: usize,
        curve: &NurbsCurve,
    ) -> (usize, NurbsCurve, [usize; 2], bool) {
        let key = if a <= b { [a, b] } else { [b, a] };
        let d = curve.domain();
        let at = |c: &NurbsCurve, s: f64| {
            let d = c.domain();
            c.point(d.min + (d.max - d.min) * s)
                .unwrap_or_else(|_| Vec3::repeat(f64::NAN))
        };
        let mid = curve.point(0.5 * (d.min + d.max)).unwrap_or(self.points[a]);
        let list = self.edges.entry(key).or_default();
        let near = |c: &NurbsCurve| {
            (0..=256)
                .map(|k| (at(c, k as f64 / 256.0) - mid).norm())
                .fold(f64::INFINITY, f64::min)
        };
        // The sampled distance is within the chord error of 256 samples of the other curve.
        let len = curve
            .control_points()
            .windows(2)
            .map(|w| (w[1] - w[0]).norm())
            .sum::<f64>();
        let tol = self.tol.max(1e-4 * len);
        if let Some((id, c, ends)) = list.iter().find(|(_, c, _)| near(c) <= tol) {
            let same = if a != b {
                ends[0] == a
            } else {
                // A closed edge: compare the points just after the start.
                let p = at(curve, 0.01);
                (at(c, 0.01) - p).norm() <= (at(c, 0.99) - p).norm()
            };
            return (*id, c.clone(), *ends, same);
        }
        self.next_edge += 1;
        let id = self.next_edge;
        list.push((id, curve.clone(), [a, b]));
        (id, curve.clone(), [a, b], true)
    }
}

/// The trimmed faces of an IGES file (see the module docs). `surfaces` maps a surface DE to its
/// index in `entities` (the imported ones).
pub(super) fn read(
    r: &Reader<'_>,
    faces: Vec<RawFace>,
    surfaces: &HashMap<usize, usize>,
    entities: &[crate::model::NamedEntity],
    warnings: &mut Vec<String>,
) -> Result<Vec<TrimmedFace>, IoError> {
    let mut all_points = Vec::new();
    for f in &faces {
        for p in f.loops.iter().flatten() {
            all_points.extend_from_slice(p.curve.control_points());
        }
    }
    let size = crate::brep::closure_tolerance(&all_points) / crate::brep::CLOSURE_RTOL;
    let mut sew = Sewing {
        tol: SEW_RTOL * size,
        cells: HashMap::new(),
        points: Vec::new(),
        edges: HashMap::new(),
        next_edge: 0,
    };
    let mut out = Vec::with_capacity(faces.len());
    for f in faces {
        let Some(&entity) = surfaces.get(&f.surface) else {
            warnings.push(format!(
                "entity DE {} (type {}): its surface DE {} was not imported; the face is dropped",
                f.de,
                if f.flag.is_some() { 510 } else { 144 },
                f.surface
            ));
            continue;
        };
        let Some(crate::model::Entity::Surface(surface)) = entities.get(entity).map(|e| &e.entity)
        else {
            continue;
        };
        let inv = Inverter::new(surface);
        let at = |m: String| err(1, Some(f.de), m);
        let mut loops = Vec::with_capacity(f.loops.len());
        for (li, l) in f.loops.iter().enumerate() {
            let mut edges = Vec::with_capacity(l.len());
            let forwards = directions(l, sew.tol);
            for (piece, forward) in l.iter().zip(forwards) {
                let mut forward = forward;
                let mut c = &piece.curve;
                let canonical;
                let d = c.domain();
                let (p0, p1) = (
                    c.point(d.min).map_err(|e| at(e.to_string()))?,
                    c.point(d.max).map_err(|e| at(e.to_string()))?,
                );
                let (edge_id, vids, vpts) = match piece.ids {
                    Some((e, [a, b])) => {
                        let (pa, pb) = (r.vertex_point(a)?, r.vertex_point(b)?);
                        // The list's start vertex is at the curve's start (else swapped).
                        if (pa - p0).norm() + (pb - p1).norm()
                            <= (pb - p0).norm() + (pa - p1).norm()
                        {
                            (e, [a, b], [pa, pb])
                        } else {
                            (e, [b, a], [pb, pa])
                        }
                    }
                    None => {
                        let (a, b) = (sew.vertex(p0), sew.vertex(p1));
                        let (e, first, ends, same) = sew.edge(a, b, c);
                        // A sewn edge keeps the curve (and direction) of its first use.
                        canonical = first;
                        c = &canonical;
                        if !same {
                            forward = !forward;
                        }
                        (e, ends, [sew.points[ends[0]], sew.points[ends[1]]])
                    }
                };
                let d = c.domain();
                let (pc, seam) =
                    pcurves(&inv, c).map_err(|m| at(format!("loop {li}: pcurve: {m}")))?;
                edges.push(TrimEdge {
                    step_id: edge_id,
                    curve: c.clone(),
                    range: [d.min, d.max],
                    axis: ParamAxis::Linear,
                    pcurve: Some(pc),
                    pcurve_range: [d.min, d.max],
                    pcurve_axis: ParamAxis::Linear,
                    seam_pcurve: seam.map(|s| (s, [d.min, d.max], ParamAxis::Linear)),
                    forward,
                    vertices: [(vids[0], vpts[0]), (vids[1], vpts[1])],
                });
            }
            loops.push(TrimLoop {
                outer: f.outer_first && li == 0,
                orientation: true,
                edges,
            });
        }
        // The sense is set from the outer loop once the shells are built ([`orient`]).
        let same_sense = f.flag.unwrap_or(true);
        out.push(TrimmedFace {
            step_id: f.de,
            entity,
            surface_type: "IGES".into(),
            axes: [ParamAxis::Linear, ParamAxis::Linear],
            same_sense,
            loops,
        });
    }
    Ok(out)
}

/// Whether the loop runs along each piece's curve: as given for B-rep edges (508's
/// orientation flags); for the members of a trimmed surface's boundary (each written in its
/// own curve's direction by some writers), the direction that starts where the previous piece
/// ends (within `tol`).
fn directions(l: &[Piece], tol: f64) -> Vec<bool> {
    if l.iter().any(|p| p.ids.is_some()) || l.len() < 2 {
        return l.iter().map(|p| p.forward).collect();
    }
    let ends: Vec<[Vec3; 2]> = l
        .iter()
        .map(|p| {
            let d = p.curve.domain();
            let at = |t: f64| p.curve.point(t).unwrap_or_else(|_| Vec3::repeat(f64::NAN));
            [at(d.min), at(d.max)]
        })
        .collect();
    let close = |a: Vec3, b: Vec3| (a - b).norm() <= tol;
    let mut out = vec![true; l.len()];
    // The first piece: the direction whose end touches the second piece.
    out[0] = close(ends[0][1], ends[1][0]) || close(ends[0][1], ends[1][1]);
    let mut at = if out[0] { ends[0][1] } else { ends[0][0] };
    for k in 1..l.len() {
        out[k] = close(ends[k][0], at) || !close(ends[k][1], at);
        at = if out[k] { ends[k][1] } else { ends[k][0] };
    }
    out
}

/// Twice the signed area of a polygon (positive counter-clockwise), over the jump from its last
/// point back to its first (a pole or seam the loop crosses implicitly).
fn area(p: &[[f64; 2]]) -> f64 {
    let n = p.len();
    (0..n)
        .map(|i| {
            let (a, b) = (p[i], p[(i + 1) % n]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum()
}

/// What [`gather`] finds: the faces, the control points of their boundaries by surface DE,
/// the DEs read and the warnings.
pub(super) type Gathered = (
    Vec<RawFace>,
    BTreeMap<usize, Vec<Vec3>>,
    Vec<usize>,
    Vec<String>,
);

/// Reads the trims (see the module docs): the raw faces and the surfaces' hulls first (the
/// extent of unbounded analytic surfaces comes from them), then, once surfaces are imported,
/// [`read`].
pub(super) fn gather(r: &Reader<'_>) -> Result<Gathered, IoError> {
    let mut used = Vec::new();
    let mut warnings = Vec::new();
    let faces = r.raw_faces(&mut used, &mut warnings)?;
    // The curves that define surfaces (axes, generatrices, directrices, bounding curves) are
    // read with them: not dropped.
    for dir in r.dirs {
        if (190..=198).contains(&dir.kind) {
            let ps = r.params(dir)?;
            for i in 1..ps.toks.len() {
                if let Ok(de) = ps.int(i, "pointer")
                    && de % 2 == 1
                    && r.dir(de, dir).is_ok_and(|d| matches!(d.kind, 116 | 123))
                {
                    used.push(de);
                }
            }
            continue;
        }
        let fields: &[usize] = match dir.kind {
            120 => &[1, 2],
            122 => &[1],
            108 => &[5],
            _ => continue,
        };
        let ps = r.params(dir)?;
        for &i in fields {
            if let Ok(de) = ps.int(i, "pointer")
                && de != 0
                && r.dir(de, dir).is_ok()
            {
                let _ = r.pieces(de, dir, 0, &mut used)?;
            }
        }
    }
    let h = hulls(&faces);
    Ok((faces, h, used, warnings))
}

/// Sets each face's sense from its outer loop as the shell builder gave it pcurves: the outer
/// loop runs counter-clockwise about the outward normal ([`crate::brep::Face::bound`]), so the
/// sign of its area in the NURBS parameters is the sign of `same_sense`. A closed shell whose
/// loops all run the other way (its volume then comes out negative) has every loop reversed
/// first. Faces whose outer loop spans no area keep their sense.
pub(super) fn orient(sh: &mut crate::brep::Shell) {
    use crate::brep::LoopItem;
    let loop_area = |f: &crate::brep::Face| area(&f.loop_polygon(&f.bound, 17));
    let set_senses = |sh: &mut crate::brep::Shell| {
        for f in &mut sh.faces {
            let a = loop_area(f);
            if a != 0.0 && a.is_finite() {
                f.same_sense = a > 0.0;
            }
        }
    };
    set_senses(sh);
    if !sh.closed {
        return;
    }
    let volume =
        crate::trimmed::tessellate_shell(sh, 4).map(|m| crate::trimmed::sculpt::mesh_volume(&m));
    if matches!(volume, Ok(v) if v < 0.0) {
        for f in &mut sh.faces {
            for l in std::iter::once(&mut f.bound).chain(f.holes.iter_mut()) {
                l.reverse();
                for it in l.iter_mut() {
                    if let LoopItem::Edge { forward, .. } = it {
                        *forward = !*forward;
                    }
                }
            }
        }
        set_senses(sh);
    }
}
