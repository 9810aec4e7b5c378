//! STEP B-rep faces: elementary and swept surfaces converted exactly to NURBS, and the faces'
//! trimming loops (issue 20).
//!
//! **Surfaces** (ISO 10303-42 section 4.4; the parametrizations are the standard's):
//! - `PLANE`: `S(u,v) = C + u x + v y`, bilinear.
//! - `CYLINDRICAL_SURFACE`: `S(u,v) = C + R (cos u x + sin u y) + v z`.
//! - `CONICAL_SURFACE`: `S(u,v) = C + (R + v tan a)(cos u x + sin u y) + v z` (v along the axis,
//!   as in the standard; OpenCASCADE's own v runs along the generatrix, `v_occ cos a = v`).
//! - `SPHERICAL_SURFACE`: `S(u,v) = C + R cos v (cos u x + sin u y) + R sin v z`, v in [-pi/2, pi/2].
//! - `TOROIDAL_SURFACE`: `S(u,v) = C + (R + r cos v)(cos u x + sin u y) + r sin v z`.
//! - `SURFACE_OF_REVOLUTION`: the swept curve `c(v)` (`LINE`, `CIRCLE`, `ELLIPSE`, B-spline,
//!   `TRIMMED_CURVE` of a line or circle by parameter values) turned by the angle u about the
//!   `AXIS1_PLACEMENT`, counter-clockwise seen from the axis direction.
//! - `SURFACE_OF_LINEAR_EXTRUSION`: `S(u,v) = c(u) + v V` with the `VECTOR` V (magnitude included).
//!
//! Every angle direction is the exact rational quadratic circle (Piegl & Tiller, *The NURBS Book*,
//! algorithm A7.1): arcs of at most a quarter turn, end weights 1, middle weight `cos(d/2)` for an
//! arc of angle d; the surfaces are the tensor products of such arcs with the profile
//! (Piegl & Tiller section 8.5), so they are exact, not approximations. The NURBS parameter of an
//! angle direction equals the angle at the arc ends (knots at multiples of pi/2 for full turns)
//! and is related to it inside an arc by `tan((phi - d/2)/2) = tan(d/4) (2s - 1)` ([`ParamAxis`]);
//! linear directions keep the file's parameter exactly.
//!
//! **Parameter ranges of unbounded surfaces** (plane: u and v; cylinder and cone: v; extrusion: v;
//! a revolved `LINE`: its parameter): the smallest range containing the face's boundary, computed
//! from the control points of the exact NURBS of every boundary edge's 3D curve (lines: their end
//! vertices; circular arcs: their arc control points, which give the exact extent of a full
//! circle along the axes of its plane). Rows of these control points are projected onto the
//! surface's linear direction (for a plane `(p - C).x`, `(p - C).y`; for a cylinder or cone
//! `(p - C).z`; for an extrusion `p.V/|V|^2` minus the swept curve's own extent, which is
//! conservative). When several faces share a surface the ranges are merged. A surface with no
//! bounded face (or a degenerate range) gets the default range [`DEFAULT_RANGE`] in file units.
//!
//! **Trimming loops** are kept in [`TrimmedFace`]: each `FACE_OUTER_BOUND`/`FACE_BOUND`'s
//! `EDGE_LOOP`, each `ORIENTED_EDGE` with its `EDGE_CURVE`'s 3D curve (through `SURFACE_CURVE` and
//! `SEAM_CURVE`) as an exact NURBS from its start to its end vertex, and the `PCURVE` on this face's
//! surface when the file gives one (2D `LINE`, `CIRCLE`, `ELLIPSE` or B-spline in the surface's
//! file parameters, over the part between the vertices' surface parameters, or on swept surfaces
//! over the 3D curve's range). `VERTEX_LOOP`s (the poles of a sphere) carry no curve and are
//! skipped; `POLY_LOOP`s are listed as not read. Surfaces are imported whole; the loops become
//! the trimmed B-rep of [`crate::trimmed`] (kept by `vclay convert` to STEP and JSON) and are
//! applied when meshing by [`tessellate_trimmed`]: grid triangles whose parameter centroid lies
//! inside the loops' pcurve polygons (even-odd rule, whole turns tried on periodic directions)
//! are kept, so trimmed edges are exact only up to the grid spacing.

use super::{Ctx, Instance, Param, Reader};
use crate::error::IoError;
use std::collections::BTreeMap;
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use vclay_core::Vec3;
use vclay_spline::knots::KnotVector;
use vclay_spline::{NurbsCurve, NurbsSurface, ParametricCurve};

/// Range of an unbounded linear parameter when no face bounds the surface, in file units.
pub const DEFAULT_RANGE: [f64; 2] = [-1.0, 1.0];

/// How a parameter of a STEP surface or curve (the standard's, e.g. an angle in radians) maps to
/// the parameter of the NURBS it was converted to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamAxis {
    /// The NURBS parameter is the file's parameter.
    Linear,
    /// An angle direction made of rational quadratic arcs of angle `segment` each, from `start` to
    /// `end` (radians); the NURBS parameter equals the angle at the arc ends. `periodic` when the
    /// arcs make a full turn (angles outside are wrapped).
    Angle {
        /// First angle.
        start: f64,
        /// Last angle.
        end: f64,
        /// The angle of each arc (at most pi/2).
        segment: f64,
        /// Whether the arcs make a full turn.
        periodic: bool,
    },
}

impl ParamAxis {
    fn angle(start: f64, end: f64) -> Self {
        let n = arc_segments(end - start);
        ParamAxis::Angle {
            start,
            end,
            segment: (end - start) / n as f64,
            periodic: (end - start - TAU).abs() < 1e-12,
        }
    }

    /// The NURBS parameter of the file's parameter `x`: for an arc of angle `d` starting at the
    /// knot `t0`, the angle `phi` from its start is at `t0 + s d` with
    /// `tan((phi - d/2)/2) = tan(d/4) (2s - 1)` (the rational quadratic arc's parametrization).
    pub fn to_nurbs(&self, x: f64) -> f64 {
        match *self {
            ParamAxis::Linear => x,
            ParamAxis::Angle {
                start,
                end,
                segment,
                periodic,
            } => {
                let mut a = x;
                if periodic {
                    a = start + (x - start).rem_euclid(TAU);
                    // Keep the end of the turn at the end, not at the start.
                    if (x - end).abs() < 1e-12 * TAU.max(end.abs()) {
                        a = end;
                    }
                }
                let n = ((end - start) / segment).round().max(1.0);
                let k = ((a - start) / segment).floor().clamp(0.0, n - 1.0);
                let phi = a - start - k * segment;
                let s = ((phi - segment / 2.0) / 2.0).tan() / (segment / 4.0).tan();
                start + (k + (s + 1.0) / 2.0) * segment
            }
        }
    }
}

impl ParamAxis {
    /// The file's parameter of the NURBS parameter `t`, the inverse of [`ParamAxis::to_nurbs`]:
    /// `phi = d/2 + 2 atan(tan(d/4)(2s - 1))` inside the arc of the knot span.
    pub fn from_nurbs(&self, t: f64) -> f64 {
        match *self {
            ParamAxis::Linear => t,
            ParamAxis::Angle {
                start,
                end,
                segment,
                ..
            } => {
                let n = ((end - start) / segment).round().max(1.0);
                let k = ((t - start) / segment).floor().clamp(0.0, n - 1.0);
                let s = (t - start) / segment - k;
                let phi = segment / 2.0 + 2.0 * ((segment / 4.0).tan() * (2.0 * s - 1.0)).atan();
                start + k * segment + phi
            }
        }
    }
}

/// One edge of a trimming loop.
#[derive(Clone, Debug, PartialEq)]
pub struct TrimEdge {
    /// The `EDGE_CURVE`'s STEP id.
    pub step_id: usize,
    /// The edge's 3D curve as an exact NURBS. Lines and conics are built from the edge's start to
    /// its end vertex (in the direction of the underlying curve); a B-spline curve is kept whole
    /// and `range` says which part is the edge.
    pub curve: NurbsCurve,
    /// The parameter range of the edge on `curve` (increasing, in the curve's direction).
    pub range: [f64; 2],
    /// How the file's parameter of the edge's curve maps to the parameter of `curve` (angles of
    /// circles and ellipses; lines and B-splines keep theirs).
    pub axis: ParamAxis,
    /// The curve on this face's surface in the surface's file parameters (z = 0), over the part
    /// that is the edge when `pcurve_range` says so; `None` when the file has no pcurve for this
    /// face or it is of a type not read.
    pub pcurve: Option<NurbsCurve>,
    /// The parameter range of the edge on `pcurve`.
    pub pcurve_range: [f64; 2],
    /// How the file's parameter of the pcurve maps to the parameter of `pcurve`.
    pub pcurve_axis: ParamAxis,
    /// A seam's second pcurve on the same surface (`SEAM_CURVE`: the two sides of a closed
    /// surface), with its range and parameter map.
    pub seam_pcurve: Option<(NurbsCurve, [f64; 2], ParamAxis)>,
    /// Whether going round the loop follows the curve's direction (the `ORIENTED_EDGE`'s
    /// orientation combined with the `EDGE_CURVE`'s same_sense).
    pub forward: bool,
    /// The `VERTEX_POINT`s (STEP id and point) at the start and the end of the edge's part of
    /// `curve`, in the curve's direction (equal for a closed edge).
    pub vertices: [(usize, Vec3); 2],
}

/// A trimming loop of a face (`EDGE_LOOP` of a `FACE_BOUND`).
#[derive(Clone, Debug, PartialEq)]
pub struct TrimLoop {
    /// Given as `FACE_OUTER_BOUND`. STEP allows every loop to be a plain `FACE_BOUND` (as
    /// OpenCASCADE writes them); then no loop is marked outer.
    pub outer: bool,
    /// The bound's orientation flag (`.T.`: the loop as written).
    pub orientation: bool,
    /// The edges in loop order.
    pub edges: Vec<TrimEdge>,
}

/// A face of a B-rep: which imported surface it lies on and its trimming loops (applied only by
/// [`tessellate_trimmed`]).
#[derive(Clone, Debug, PartialEq)]
pub struct TrimmedFace {
    /// The face's STEP id (`ADVANCED_FACE` or `FACE_SURFACE`).
    pub step_id: usize,
    /// Index of the face's surface in [`super::CadImport::entities`].
    pub entity: usize,
    /// The STEP type of the surface (`PLANE`, `B_SPLINE_SURFACE_WITH_KNOTS`, ...).
    pub surface_type: String,
    /// How the surface's file parameters map to the NURBS parameters, along u and v.
    pub axes: [ParamAxis; 2],
    /// The face's same_sense flag: `false` when the face's normal is opposite to the surface's.
    pub same_sense: bool,
    /// The face's trimming loops.
    pub loops: Vec<TrimLoop>,
}

impl TrimmedFace {
    /// The NURBS surface parameters of a point given in the surface's file parameters (for
    /// example a pcurve point).
    pub fn to_nurbs_params(&self, u: f64, v: f64) -> [f64; 2] {
        [self.axes[0].to_nurbs(u), self.axes[1].to_nurbs(v)]
    }
}

/// Most samples per direction of [`tessellate_trimmed`].
pub const MAX_TRIM_SAMPLES: usize = 4096;

impl TrimmedFace {
    /// The trimming loops as closed polygons in the surface's file parameters: each edge's
    /// pcurve sampled at `per_edge` points (at least 2, at most 1000) over the edge, in loop
    /// direction; of a seam's two pcurves the one that continues the polygon is taken. `None`
    /// when an edge has no pcurve (the face is then treated as untrimmed).
    pub fn loop_polygons(&self, per_edge: usize) -> Option<Vec<Vec<[f64; 2]>>> {
        let n = per_edge.clamp(2, 1000);
        let sample = |c: &NurbsCurve, r: [f64; 2], forward: bool| -> Option<Vec<[f64; 2]>> {
            let mut pts = (0..n)
                .map(|k| {
                    let t = r[0] + (r[1] - r[0]) * k as f64 / (n - 1) as f64;
                    c.point(t).ok().map(|p| [p.x, p.y])
                })
                .collect::<Option<Vec<_>>>()?;
            if !forward {
                pts.reverse();
            }
            Some(pts)
        };
        let mut out = Vec::new();
        for l in &self.loops {
            let mut poly: Vec<[f64; 2]> = Vec::new();
            for e in &l.edges {
                let pc = e.pcurve.as_ref()?;
                let mut cands = vec![sample(pc, e.pcurve_range, e.forward)?];
                if let Some((c2, r2, _)) = &e.seam_pcurve {
                    cands.push(sample(c2, *r2, e.forward)?);
                }
                let pick = match poly.last() {
                    Some(q) => cands
                        .into_iter()
                        .min_by(|a, b| {
                            let d = |p: &[f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
                            d(&a[0]).total_cmp(&d(&b[0]))
                        })
                        .unwrap_or_default(),
                    None => cands.swap_remove(0),
                };
                poly.extend(pick);
            }
            if poly.len() >= 3 {
                out.push(poly);
            }
        }
        Some(out)
    }

    /// Whether the point `(u, v)` of the surface's file parameters lies inside the face: inside
    /// an odd number of `polygons` (even-odd rule over all loops, so holes are holes whatever
    /// their orientation), trying whole turns along periodic angle directions.
    pub fn contains(&self, polygons: &[Vec<[f64; 2]>], u: f64, v: f64) -> bool {
        let turns = |a: &ParamAxis| match a {
            ParamAxis::Angle { periodic: true, .. } => &[0.0, -1.0, 1.0, -2.0, 2.0][..],
            _ => &[0.0][..],
        };
        for &ku in turns(&self.axes[0]) {
            for &kv in turns(&self.axes[1]) {
                let (x, y) = (u + ku * TAU, v + kv * TAU);
                let mut inside = false;
                for poly in polygons {
                    let m = poly.len();
                    for i in 0..m {
                        let (a, b) = (poly[i], poly[(i + 1) % m]);
                        if (a[1] > y) != (b[1] > y) {
                            let xc = a[0] + (y - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                            if x < xc {
                                inside = !inside;
                            }
                        }
                    }
                }
                if inside {
                    return true;
                }
            }
        }
        false
    }
}

/// Tessellates the face's `surface` (its entity in the import) on a `samples` grid of its NURBS
/// parameters and keeps the triangles whose parameter centroid lies inside the face's trimming
/// loops ([`TrimmedFace::contains`], pcurves sampled at 32 points per edge), so trimmed faces
/// (a cylinder's disc caps, a box's faces) are cut to their boundary up to the grid spacing.
/// Faces without loops (a sphere's) or with an edge lacking a pcurve are tessellated whole.
/// Normals are computed from the kept triangles. `samples` must be 2 to [`MAX_TRIM_SAMPLES`].
pub fn tessellate_trimmed(
    face: &TrimmedFace,
    surface: &NurbsSurface,
    samples: [usize; 2],
) -> Result<vclay_core::TriMesh, String> {
    use vclay_spline::ParametricSurface;
    if samples
        .iter()
        .any(|&n| !(2..=MAX_TRIM_SAMPLES).contains(&n))
    {
        return Err(format!(
            "samples {samples:?}: each must be from 2 to {MAX_TRIM_SAMPLES}"
        ));
    }
    let polys = if face.loops.is_empty() {
        None
    } else {
        face.loop_polygons(32)
    };
    let d = surface.domain();
    let [nu, nv] = samples;
    let at =
        |i: usize, n: usize, k: usize| d[k].min + (d[k].max - d[k].min) * i as f64 / (n - 1) as f64;
    let mut mesh = vclay_core::TriMesh::new();
    for i in 0..nu {
        for j in 0..nv {
            let p = surface
                .point(at(i, nu, 0), at(j, nv, 1))
                .map_err(|e| e.to_string())?;
            mesh.positions.push(p);
        }
    }
    let id = |i: usize, j: usize| (i * nv + j) as u32;
    for i in 0..nu - 1 {
        for j in 0..nv - 1 {
            let (u0, u1, v0, v1) = (
                at(i, nu, 0),
                at(i + 1, nu, 0),
                at(j, nv, 1),
                at(j + 1, nv, 1),
            );
            for (tri, cu, cv) in [
                (
                    [id(i, j), id(i + 1, j), id(i + 1, j + 1)],
                    (u0 + 2.0 * u1) / 3.0,
                    (2.0 * v0 + v1) / 3.0,
                ),
                (
                    [id(i, j), id(i + 1, j + 1), id(i, j + 1)],
                    (2.0 * u0 + u1) / 3.0,
                    (v0 + 2.0 * v1) / 3.0,
                ),
            ] {
                let keep = match &polys {
                    Some(p) => {
                        face.contains(p, face.axes[0].from_nurbs(cu), face.axes[1].from_nurbs(cv))
                    }
                    None => true,
                };
                if keep {
                    mesh.triangles.push(if face.same_sense {
                        tri
                    } else {
                        [tri[0], tri[2], tri[1]]
                    });
                }
            }
        }
    }
    mesh.compute_normals();
    Ok(mesh)
}

// ---------------------------------------------------------------------------------------------
// Exact arcs

fn arc_segments(angle: f64) -> usize {
    ((angle / FRAC_PI_2) - 1e-9).ceil().max(1.0) as usize
}

/// The exact elliptic arc `c + rx cos t x + ry sin t y`, `t` from `t0` to `t1` (`t0 < t1 <= t0 +
/// 2 pi`), parametrized on `[t0, t1]` with knots at the arc joints (Piegl & Tiller A7.1).
pub(crate) fn arc(
    c: Vec3,
    x: Vec3,
    y: Vec3,
    rx: f64,
    ry: f64,
    t0: f64,
    t1: f64,
) -> (Vec<f64>, Vec<Vec3>, Vec<f64>) {
    let n = arc_segments(t1 - t0);
    let d = (t1 - t0) / n as f64;
    let w = (d / 2.0).cos();
    let at = |t: f64, scale: f64| c + x * (rx * t.cos() * scale) + y * (ry * t.sin() * scale);
    let mut pts = vec![at(t0, 1.0)];
    let mut ws = vec![1.0];
    let mut knots = vec![t0; 3];
    for k in 0..n {
        let a = t0 + k as f64 * d;
        pts.push(at(a + d / 2.0, 1.0 / w));
        ws.push(w);
        let b = if k + 1 == n { t1 } else { a + d };
        pts.push(at(b, 1.0));
        ws.push(1.0);
        let m = if k + 1 == n { 3 } else { 2 };
        knots.extend(std::iter::repeat_n(b, m));
    }
    (knots, pts, ws)
}

fn arc_curve(
    c: Vec3,
    x: Vec3,
    y: Vec3,
    rx: f64,
    ry: f64,
    t0: f64,
    t1: f64,
) -> Result<NurbsCurve, String> {
    let (k, p, w) = arc(c, x, y, rx, ry, t0, t1);
    NurbsCurve::new(2, k, p, Some(w)).map_err(|e| e.to_string())
}

fn segment_curve(p: Vec3, d: Vec3, t0: f64, t1: f64) -> Result<NurbsCurve, String> {
    NurbsCurve::new(1, vec![t0, t0, t1, t1], vec![p + d * t0, p + d * t1], None)
        .map_err(|e| e.to_string())
}

/// Turns `profile` a full turn about the axis through `c` along the unit `a`, the angle measured
/// counter-clockwise seen from `a`: `P_ij = c + h_j a + cos_i p_j + sin_i (a x p_j)` with the
/// profile point's height `h_j` and radial part `p_j`, weights multiplied (exact, Piegl & Tiller
/// section 8.5). u is the angle (knots at multiples of pi/2), v the profile's parameter.
fn revolve(c: Vec3, a: Vec3, profile: &NurbsCurve) -> Result<NurbsSurface, String> {
    revolve_between(c, a, profile, 0.0, TAU)
}

/// [`revolve`] from the angle `t0` to `t1` (`t0 < t1 <= t0 + 2 pi`; u runs over `[t0, t1]`
/// with knots at the arc joints).
pub(crate) fn revolve_between(
    c: Vec3,
    a: Vec3,
    profile: &NurbsCurve,
    t0: f64,
    t1: f64,
) -> Result<NurbsSurface, String> {
    let (ku, circle, cw) = arc(Vec3::zeros(), Vec3::x(), Vec3::y(), 1.0, 1.0, t0, t1);
    let np = profile.control_points().len();
    let mut pts = Vec::with_capacity(circle.len() * np);
    let mut ws = Vec::with_capacity(circle.len() * np);
    for (q, &wq) in circle.iter().zip(&cw) {
        for (p, &wp) in profile.control_points().iter().zip(profile.weights()) {
            let d = p - c;
            let h = d.dot(&a);
            let r = d - a * h;
            pts.push(c + a * h + r * q.x + a.cross(&r) * q.y);
            ws.push(wq * wp);
        }
    }
    let kv = KnotVector::new(ku, 2, circle.len()).map_err(|e| e.to_string())?;
    NurbsSurface::from_flat([kv, profile.knots().clone()], pts, ws).map_err(|e| e.to_string())
}

/// `S(u,v) = c(u) + v V`, v in `[v0, v1]`.
pub(crate) fn extrude(
    curve: &NurbsCurve,
    dir: Vec3,
    v0: f64,
    v1: f64,
) -> Result<NurbsSurface, String> {
    let mut pts = Vec::new();
    let mut ws = Vec::new();
    for (p, &w) in curve.control_points().iter().zip(curve.weights()) {
        pts.push(p + dir * v0);
        pts.push(p + dir * v1);
        ws.extend([w, w]);
    }
    let kv = KnotVector::new(vec![v0, v0, v1, v1], 1, 2).map_err(|e| e.to_string())?;
    NurbsSurface::from_flat([curve.knots().clone(), kv], pts, ws).map_err(|e| e.to_string())
}

// ---------------------------------------------------------------------------------------------
// Reading placements, curves and faces

/// An orthonormal frame (`AXIS2_PLACEMENT_3D` or `_2D`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Frame {
    o: Vec3,
    x: Vec3,
    y: Vec3,
    z: Vec3,
}

/// A curve read from the file, in its own (file) parametrization.
#[derive(Clone, Debug)]
enum Geom {
    /// `p + t d`.
    Line { p: Vec3, d: Vec3 },
    /// `c + rx cos t x + ry sin t y`.
    Conic { f: Frame, rx: f64, ry: f64 },
    /// A B-spline curve (parameter as written).
    Spline(NurbsCurve),
    /// A basis curve restricted to `[t0, t1]` of its parameter.
    Trimmed(Box<Geom>, f64, f64),
}

impl Geom {
    /// The exact NURBS of the part `[t0, t1]` (B-splines: whole) and how its parameter relates
    /// to the file's.
    fn nurbs(&self, t0: f64, t1: f64) -> Result<(NurbsCurve, ParamAxis), String> {
        match self {
            Geom::Line { p, d } => Ok((segment_curve(*p, *d, t0, t1)?, ParamAxis::Linear)),
            Geom::Conic { f, rx, ry } => Ok((
                arc_curve(f.o, f.x, f.y, *rx, *ry, t0, t1)?,
                ParamAxis::angle(t0, t1),
            )),
            Geom::Spline(c) => Ok((c.clone(), ParamAxis::Linear)),
            Geom::Trimmed(b, _, _) => b.nurbs(t0, t1),
        }
    }

    /// The curve's natural bounded range, if it has one (conics: a full turn).
    fn natural_range(&self) -> Option<[f64; 2]> {
        match self {
            Geom::Line { .. } => None,
            Geom::Conic { .. } => Some([0.0, TAU]),
            Geom::Spline(c) => {
                let d = c.domain();
                Some([d.min, d.max])
            }
            Geom::Trimmed(_, a, b) => Some([*a, *b]),
        }
    }

    fn closed(&self) -> bool {
        match self {
            Geom::Conic { .. } => true,
            Geom::Trimmed(..) | Geom::Line { .. } => false,
            Geom::Spline(c) => {
                let d = c.domain();
                match (c.point(d.min), c.point(d.max)) {
                    (Ok(a), Ok(b)) => (a - b).norm() <= 1e-9 * a.norm().max(1.0),
                    _ => false,
                }
            }
        }
    }

    /// The parameter of the point of a 2D curve (a pcurve) nearest to `uv`, trying whole turns
    /// along the periodic directions.
    fn param_of_uv(&self, uv: [f64; 2], periodic: [bool; 2]) -> f64 {
        // Whole turns tried from the nearest: 0, -1, 1, -2, 2 (ties keep the first).
        let ks = |p: bool| if p { &[0, -1, 1, -2, 2][..] } else { &[0][..] };
        let mut best = (f64::INFINITY, 0.0);
        for &ku in ks(periodic[0]) {
            for &kv in ks(periodic[1]) {
                let q = Vec3::new(uv[0] + TAU * ku as f64, uv[1] + TAU * kv as f64, 0.0);
                let t = self.param_of(q);
                let d = match self.point_at(t) {
                    Some(p) => (p - q).norm(),
                    None => continue,
                };
                if d < best.0 - 1e-12 * (1.0 + uv[0].abs() + uv[1].abs()) {
                    best = (d, t);
                }
            }
        }
        best.1
    }

    /// The point at the file parameter `t`.
    fn point_at(&self, t: f64) -> Option<Vec3> {
        match self {
            Geom::Line { p, d } => Some(p + d * t),
            Geom::Conic { f, rx, ry } => Some(f.o + f.x * (rx * t.cos()) + f.y * (ry * t.sin())),
            Geom::Spline(c) => c.point(t).ok(),
            Geom::Trimmed(b, _, _) => b.point_at(t),
        }
    }

    /// The parameter of a point on the curve (vertices): closed forms for lines and conics,
    /// sampling then Newton steps for B-splines.
    fn param_of(&self, q: Vec3) -> f64 {
        match self {
            Geom::Line { p, d } => (q - p).dot(d) / d.norm_squared(),
            Geom::Conic { f, rx, ry } => {
                let r = q - f.o;
                let t = (r.dot(&f.y) / ry).atan2(r.dot(&f.x) / rx).rem_euclid(TAU);
                // A vertex at the start (angle -1e-17) is at 0, not at a full turn.
                if t > TAU * (1.0 - 1e-12) { 0.0 } else { t }
            }
            Geom::Trimmed(b, _, _) => b.param_of(q),
            Geom::Spline(c) => {
                let d = c.domain();
                // Most vertices are a curve's ends: checked first (1e-9 of the curve's size),
                // which spares the sampling below (issue 30: 10,000-face files).
                let tol = crate::brep::closure_tolerance(c.control_points());
                for t in [d.min, d.max] {
                    if c.point(t).is_ok_and(|p| (p - q).norm() <= tol) {
                        return t;
                    }
                }
                let n = 64 * c.control_points().len().clamp(1, 64);
                let mut best = (f64::INFINITY, d.min);
                for i in 0..=n {
                    let t = d.min + (d.max - d.min) * i as f64 / n as f64;
                    if let Ok(p) = c.point(t) {
                        let e = (p - q).norm_squared();
                        if e < best.0 {
                            best = (e, t);
                        }
                    }
                }
                let mut t = best.1;
                for _ in 0..20 {
                    let Ok(ds) = c.derivatives(t, 2) else { break };
                    if ds.len() < 3 {
                        break;
                    }
                    let r = ds[0] - q;
                    let f1 = r.dot(&ds[1]);
                    let f2 = ds[1].norm_squared() + r.dot(&ds[2]);
                    if f2.abs() < 1e-300 {
                        break;
                    }
                    let nt = (t - f1 / f2).clamp(d.min, d.max);
                    if (nt - t).abs() <= 1e-15 * (d.max - d.min).max(1.0) {
                        t = nt;
                        break;
                    }
                    t = nt;
                }
                t
            }
        }
    }
}

/// The file parameters of a point on an elementary surface (closed forms), for the ranges of
/// pcurves.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Inverse {
    Plane(Frame),
    /// Cylinder or cone: angle and height.
    Axial(Frame),
    Sphere(Frame),
    Torus(Frame, f64),
}

impl Inverse {
    fn frame(&self) -> &Frame {
        match self {
            Inverse::Plane(f) | Inverse::Axial(f) | Inverse::Sphere(f) | Inverse::Torus(f, _) => f,
        }
    }

    fn uv(&self, p: Vec3) -> [f64; 2] {
        let f = self.frame();
        let d = p - f.o;
        let (x, y, h) = (d.dot(&f.x), d.dot(&f.y), d.dot(&f.z));
        let u = y.atan2(x);
        let rho = x.hypot(y);
        match self {
            Inverse::Plane(_) => [x, y],
            Inverse::Axial(_) => [u, h],
            Inverse::Sphere(_) => [u, h.atan2(rho)],
            Inverse::Torus(_, r) => [u, h.atan2(rho - r)],
        }
    }

    fn periodic(&self) -> [bool; 2] {
        match self {
            Inverse::Plane(_) => [false, false],
            Inverse::Axial(_) | Inverse::Sphere(_) => [true, false],
            Inverse::Torus(..) => [true, true],
        }
    }
}

/// A converted surface: the NURBS, its parameter map and its name.
pub(crate) type Converted = (NurbsSurface, [ParamAxis; 2], Option<String>);

/// The face-level data of one surface gathered before it is converted.
#[derive(Default)]
pub(crate) struct SurfaceUse {
    /// Control points of the boundary edges of the faces on this surface.
    pub(crate) hull: Vec<Vec3>,
}

/// A face read from the file, before its surface is converted.
pub(crate) struct FaceData {
    pub(crate) step_id: usize,
    pub(crate) surface: usize,
    pub(crate) same_sense: bool,
    pub(crate) loops: Vec<TrimLoop>,
    /// Edges whose curves are of a type not read.
    pub(crate) skipped: usize,
}

fn real_of(c: &Ctx<'_>, p: &Param, what: &str) -> Result<f64, IoError> {
    let x = c.real(p, what)?;
    if x.is_finite() {
        Ok(x)
    } else {
        Err(c.err(format!("{what}: not a finite number")))
    }
}

fn positive(c: &Ctx<'_>, p: &Param, what: &str) -> Result<f64, IoError> {
    let x = real_of(c, p, what)?;
    if x > 0.0 {
        Ok(x)
    } else {
        Err(c.err(format!("{what} must be positive, found {x}")))
    }
}

fn bool_of(c: &Ctx<'_>, p: &Param, what: &str) -> Result<bool, IoError> {
    match p {
        Param::Enum(e) if e == "T" => Ok(true),
        Param::Enum(e) if e == "F" => Ok(false),
        _ => Err(c.err(format!("{what}: expected .T. or .F."))),
    }
}

impl<'a> Reader<'a> {
    /// The instance a parameter refers to, checked to have one of the `types`.
    fn target(&self, p: &Param, types: &[&str], from: &Ctx<'_>) -> Result<&'a Instance, IoError> {
        let Param::Ref(id) = p else {
            return Err(from.err(format!("expected a reference to a {}", types.join(" or "))));
        };
        let inst = self.get(*id, from)?;
        if types.iter().any(|t| inst.is(t)) {
            Ok(inst)
        } else {
            Err(from.err(format!(
                "#{id} is a {}, expected a {}",
                inst.type_name(),
                types.join(" or ")
            )))
        }
    }

    fn direction(&mut self, p: &Param, from: &Ctx<'_>) -> Result<Vec3, IoError> {
        let inst = self.target(p, &["DIRECTION"], from)?;
        let c = Ctx {
            inst,
            part: "DIRECTION",
        };
        let ps = c.params(2)?;
        let xs = c.reals(&ps[1], "direction ratios")?;
        let v = match xs[..] {
            [x, y, z] => Vec3::new(x, y, z),
            [x, y] => Vec3::new(x, y, 0.0),
            _ => return Err(c.err(format!("expected 2 or 3 ratios, found {}", xs.len()))),
        };
        let n = v.norm();
        if !(n.is_finite() && n > 1e-300) {
            return Err(c.err("direction of zero or non-finite length"));
        }
        self.used.insert(inst.id);
        Ok(v / n)
    }

    /// `AXIS2_PLACEMENT_3D(name, location, axis, ref_direction)` or `AXIS2_PLACEMENT_2D(name,
    /// location, ref_direction)`; defaults z = (0,0,1), x = (1,0,0) (ISO 10303-42 4.4.5).
    pub(crate) fn frame(&mut self, p: &Param, from: &Ctx<'_>) -> Result<Frame, IoError> {
        let inst = self.target(p, &["AXIS2_PLACEMENT_3D", "AXIS2_PLACEMENT_2D"], from)?;
        let three = inst.is("AXIS2_PLACEMENT_3D");
        let c = Ctx {
            inst,
            part: if three {
                "AXIS2_PLACEMENT_3D"
            } else {
                "AXIS2_PLACEMENT_2D"
            },
        };
        let ps = c.params(if three { 4 } else { 3 })?;
        let (o, _) = self.point(&ps[1], &c)?;
        let (z, xref) = if three {
            let z = match &ps[2] {
                Param::Unset => Vec3::z(),
                p => self.direction(p, &c)?,
            };
            (z, &ps[3])
        } else {
            (Vec3::z(), &ps[2])
        };
        let xr = match xref {
            Param::Unset => {
                if z.x.abs() < 0.9 {
                    Vec3::x()
                } else {
                    Vec3::y()
                }
            }
            p => self.direction(p, &c)?,
        };
        let x = xr - z * xr.dot(&z);
        if x.norm() < 1e-12 {
            return Err(c.err("ref_direction is parallel to the axis"));
        }
        let x = x.normalize();
        self.used.insert(inst.id);
        Ok(Frame {
            o,
            x,
            y: z.cross(&x),
            z,
        })
    }

    /// A curve of the kinds the B-rep reader converts, or `None` for another type.
    fn geom(&mut self, id: usize, from: &Ctx<'_>, depth: usize) -> Result<Option<Geom>, IoError> {
        let inst = self.get(id, from)?;
        if depth > 8 {
            return Err(from.err("curves nested too deeply"));
        }
        let g = if inst.parts.len() == 1 && inst.is("LINE") {
            let c = Ctx { inst, part: "LINE" };
            let ps = c.params(3)?;
            let (p, _) = self.point(&ps[1], &c)?;
            let vi = self.target(&ps[2], &["VECTOR"], &c)?;
            let cv = Ctx {
                inst: vi,
                part: "VECTOR",
            };
            let vs = cv.params(3)?;
            let d = self.direction(&vs[1], &cv)?;
            let m = real_of(&cv, &vs[2], "magnitude")?;
            if m.abs() < 1e-300 {
                return Err(cv.err("magnitude is zero"));
            }
            self.used.insert(vi.id);
            Geom::Line { p, d: d * m }
        } else if inst.parts.len() == 1 && (inst.is("CIRCLE") || inst.is("ELLIPSE")) {
            let circle = inst.is("CIRCLE");
            let c = Ctx {
                inst,
                part: if circle { "CIRCLE" } else { "ELLIPSE" },
            };
            let ps = c.params(if circle { 3 } else { 4 })?;
            let f = self.frame(&ps[1], &c)?;
            let rx = positive(&c, &ps[2], "radius")?;
            let ry = if circle {
                rx
            } else {
                positive(&c, &ps[3], "second semi-axis")?
            };
            Geom::Conic { f, rx, ry }
        } else if inst.parts.len() == 1 && inst.is("TRIMMED_CURVE") {
            let c = Ctx {
                inst,
                part: "TRIMMED_CURVE",
            };
            let ps = c.params(6)?;
            let Param::Ref(basis) = ps[1] else {
                return Err(c.err("basis curve: expected a reference"));
            };
            let Some(b) = self.geom(basis, &c, depth + 1)? else {
                return Ok(None);
            };
            let trim = |p: &Param| -> Option<f64> {
                let Param::List(v) = p else { return None };
                v.iter().find_map(|x| match x {
                    Param::Typed(n, a) if n == "PARAMETER_VALUE" && a.len() == 1 => match a[0] {
                        Param::Real(r) => Some(r),
                        Param::Int(i) => Some(i as f64),
                        _ => None,
                    },
                    _ => None,
                })
            };
            let (Some(a), Some(z)) = (trim(&ps[2]), trim(&ps[3])) else {
                // Trimmed by points only: not read.
                return Ok(None);
            };
            let sense = bool_of(&c, &ps[4], "sense_agreement")?;
            let (mut a, mut z) = if sense { (a, z) } else { (z, a) };
            if matches!(b, Geom::Conic { .. }) {
                a *= self.angle_unit;
                z *= self.angle_unit;
                if z <= a {
                    z += TAU;
                }
                if z - a > TAU * (1.0 + 1e-12) {
                    return Err(c.err("a trimmed circle or ellipse spans more than a full turn"));
                }
            }
            if !(a.is_finite() && z.is_finite() && z > a) {
                return Err(c.err("trimming parameters must increase along the curve"));
            }
            Geom::Trimmed(Box::new(b), a, z)
        } else if super::is_curve_type(inst) {
            match self.curve(inst)? {
                Ok(e) => match e.entity {
                    crate::model::Entity::Curve(c) => Geom::Spline(c),
                    _ => return Ok(None),
                },
                Err(super::Skip::TwoD) => {
                    // A 2D B-spline (pcurve): read it with z = 0.
                    let c = self.curve_2d(inst)?;
                    Geom::Spline(c)
                }
                Err(super::Skip::Unsupported) => return Ok(None),
            }
        } else {
            return Ok(None);
        };
        self.used.insert(id);
        Ok(Some(g))
    }

    /// The closed-form inverse of an elementary surface, `None` for other surfaces.
    fn surface_inverse(&mut self, id: usize) -> Result<Option<Inverse>, IoError> {
        let Some(inst) = self.all.get(&id) else {
            return Ok(None);
        };
        if inst.parts.len() != 1 {
            return Ok(None);
        }
        let kind = inst.parts[0].name.as_str();
        let c = Ctx { inst, part: kind };
        let Some(Param::Ref(_)) = inst.parts[0].params.get(1) else {
            return Ok(None);
        };
        let pos = inst.parts[0].params[1].clone();
        Ok(match kind {
            "PLANE" => Some(Inverse::Plane(self.frame(&pos, &c)?)),
            "CYLINDRICAL_SURFACE" | "CONICAL_SURFACE" => {
                Some(Inverse::Axial(self.frame(&pos, &c)?))
            }
            "SPHERICAL_SURFACE" => Some(Inverse::Sphere(self.frame(&pos, &c)?)),
            "TOROIDAL_SURFACE" => {
                let ps = c.params(4)?;
                let r = real_of(&c, &ps[2], "major_radius")?;
                Some(Inverse::Torus(self.frame(&pos, &c)?, r))
            }
            _ => None,
        })
    }

    /// A vertex's point.
    fn vertex(&mut self, p: &Param, from: &Ctx<'_>) -> Result<(usize, Vec3), IoError> {
        let inst = self.target(p, &["VERTEX_POINT"], from)?;
        let c = Ctx {
            inst,
            part: "VERTEX_POINT",
        };
        let ps = c.params(2)?;
        let (q, _) = self.point(&ps[1], &c)?;
        self.used.insert(inst.id);
        Ok((inst.id, q))
    }

    /// An `ORIENTED_EDGE` of a loop of a face on the surface `surface`; `None` when its curve is
    /// of a type not read or its vertices bound no part of it.
    fn edge(
        &mut self,
        p: &Param,
        surface: usize,
        from: &Ctx<'_>,
    ) -> Result<Option<TrimEdge>, IoError> {
        let oe = self.target(p, &["ORIENTED_EDGE"], from)?;
        let co = Ctx {
            inst: oe,
            part: "ORIENTED_EDGE",
        };
        let ps = co.params(5)?;
        let orientation = bool_of(&co, &ps[4], "orientation")?;
        let ec = self.target(&ps[3], &["EDGE_CURVE"], &co)?;
        let ce = Ctx {
            inst: ec,
            part: "EDGE_CURVE",
        };
        let es = ce.params(5)?;
        let (v1, p1) = self.vertex(&es[1], &ce)?;
        let (v2, p2) = self.vertex(&es[2], &ce)?;
        let same_sense = bool_of(&ce, &es[4], "same_sense")?;
        let Param::Ref(gid) = es[3] else {
            return Err(ce.err("edge_geometry: expected a reference"));
        };
        // SURFACE_CURVE / SEAM_CURVE(name, curve_3d, (pcurves), master): the 3D curve and the
        // pcurve on this surface.
        let g = self.get(gid, &ce)?;
        let (curve3d, pcurve_refs) = if let Some(part) = g
            .parts
            .iter()
            .find(|p| p.name == "SURFACE_CURVE" || p.name == "SEAM_CURVE")
        {
            let cs = Ctx {
                inst: g,
                part: if part.name == "SURFACE_CURVE" {
                    "SURFACE_CURVE"
                } else {
                    "SEAM_CURVE"
                },
            };
            let ps = cs.params(4)?;
            let Param::Ref(c3) = ps[1] else {
                return Err(cs.err("curve_3d: expected a reference"));
            };
            self.used.insert(gid);
            (c3, cs.list(&ps[2], "associated geometry")?.to_vec())
        } else {
            (gid, Vec::new())
        };
        let Some(geom) = self.geom(curve3d, &ce, 0)? else {
            return Ok(None);
        };
        // The edge's range on the curve, in the curve's direction.
        let (a, b) = if same_sense { (p1, p2) } else { (p2, p1) };
        let mut t0 = geom.param_of(a);
        let mut t1 = geom.param_of(b);
        if let Some([lo, hi]) = geom.natural_range()
            && geom.closed()
        {
            {
                let period = hi - lo;
                if v1 == v2 {
                    t1 = t0 + period;
                } else if t1 <= t0 {
                    t1 += period;
                }
                if matches!(geom, Geom::Spline(_)) && v1 == v2 {
                    (t0, t1) = (lo, hi);
                }
            }
        }
        if !(t0.is_finite() && t1.is_finite()) || t1 <= t0 {
            return Ok(None);
        }
        let (curve, axis) = geom.nurbs(t0, t1).map_err(|e| ce.err(e))?;
        let range = match geom {
            Geom::Spline(_) => [t0, t1],
            _ => {
                let d = curve.domain();
                [d.min, d.max]
            }
        };
        // The pcurve on this face's surface, if given.
        let mut pcurve = None;
        let mut pcurve_range = [0.0, 0.0];
        let mut pcurve_axis = ParamAxis::Linear;
        let mut seam_pcurve = None;
        let mut first = (pcurve_range, pcurve_axis);
        for r in &pcurve_refs {
            let Param::Ref(pid) = r else { continue };
            let pi = self.get(*pid, &ce)?;
            if !pi.is("PCURVE") {
                continue;
            }
            let cp = Ctx {
                inst: pi,
                part: "PCURVE",
            };
            let pps = cp.params(3)?;
            if pps[1] != Param::Ref(surface) {
                continue;
            }
            self.used.insert(*pid);
            let dr = self.target(&pps[2], &["DEFINITIONAL_REPRESENTATION"], &cp)?;
            let cd = Ctx {
                inst: dr,
                part: "DEFINITIONAL_REPRESENTATION",
            };
            let ds = cd.params(3)?;
            self.used.insert(dr.id);
            if let Param::Ref(ctx) = ds[2] {
                self.used.insert(ctx);
            }
            let items = cd.list(&ds[1], "items")?;
            let Some(Param::Ref(c2)) = items.first() else {
                continue;
            };
            if let Some(g2) = self.geom(*c2, &cd, 0)? {
                // The edge's part of the pcurve: the pcurve parameters of the surface
                // parameters of its vertices (elementary surfaces), else the 3D curve's range
                // (a common parameter, as B-rep writers keep it).
                let inv = self.surface_inverse(surface)?;
                let shared = match &g2 {
                    Geom::Spline(c) => {
                        let d = c.domain();
                        (t0.max(d.min), t1.min(d.max))
                    }
                    _ => (t0, t1),
                };
                let (r0, r1) = match inv {
                    Some(inv) => {
                        let ra = g2.param_of_uv(inv.uv(a), inv.periodic());
                        let rb = g2.param_of_uv(inv.uv(b), inv.periodic());
                        if v1 == v2 {
                            (ra, ra + (shared.1 - shared.0))
                        } else if rb > ra {
                            (ra, rb)
                        } else if matches!(g2, Geom::Conic { .. }) {
                            (ra, rb + TAU)
                        } else {
                            shared
                        }
                    }
                    None => shared,
                };
                if r1 > r0 {
                    let (pc, pa) = g2.nurbs(r0, r1).map_err(|e| cd.err(e))?;
                    pcurve_axis = pa;
                    pcurve_range = match g2 {
                        Geom::Spline(_) => [r0, r1],
                        _ => {
                            let d = pc.domain();
                            [d.min, d.max]
                        }
                    };
                    if pcurve.is_none() {
                        pcurve = Some(pc);
                    } else if seam_pcurve.is_none() {
                        // A seam's second pcurve: keep both.
                        seam_pcurve = Some((pc, pcurve_range, pcurve_axis));
                        (pcurve_range, pcurve_axis) = first;
                    }
                    first = (pcurve_range, pcurve_axis);
                }
            }
        }
        self.used.insert(ec.id);
        self.used.insert(oe.id);
        Ok(Some(TrimEdge {
            step_id: ec.id,
            curve,
            range,
            axis,
            pcurve,
            pcurve_range,
            pcurve_axis,
            seam_pcurve,
            forward: orientation == same_sense,
            vertices: if same_sense {
                [(v1, p1), (v2, p2)]
            } else {
                [(v2, p2), (v1, p1)]
            },
        }))
    }

    /// An `ADVANCED_FACE` or `FACE_SURFACE` with its loops.
    pub(crate) fn face(&mut self, inst: &'a Instance) -> Result<FaceData, IoError> {
        let part = if inst.is("ADVANCED_FACE") {
            "ADVANCED_FACE"
        } else {
            "FACE_SURFACE"
        };
        let c = Ctx { inst, part };
        let ps = c.params(4)?;
        let Param::Ref(surface) = ps[2] else {
            return Err(c.err("face_geometry: expected a reference"));
        };
        self.get(surface, &c)?;
        let same_sense = bool_of(&c, &ps[3], "same_sense")?;
        let mut loops = Vec::new();
        let mut skipped = 0;
        for b in c.list(&ps[1], "bounds")? {
            let bi = self.target(b, &["FACE_BOUND", "FACE_OUTER_BOUND"], &c)?;
            let outer = bi.is("FACE_OUTER_BOUND");
            let cb = Ctx {
                inst: bi,
                part: if outer {
                    "FACE_OUTER_BOUND"
                } else {
                    "FACE_BOUND"
                },
            };
            let bs = cb.params(3)?;
            let orientation = bool_of(&cb, &bs[2], "orientation")?;
            let li = self.target(&bs[1], &["EDGE_LOOP", "VERTEX_LOOP", "POLY_LOOP"], &cb)?;
            if li.is("VERTEX_LOOP") {
                // A degenerate loop (a pole): no curve to keep.
                self.used.insert(li.id);
                if let Some(Param::Ref(v)) = li.parts[0].params.get(1) {
                    self.used.insert(*v);
                    if let Some(Param::Ref(p)) = self
                        .all
                        .get(v)
                        .and_then(|vi| vi.parts[0].params.get(1).cloned())
                    {
                        self.used.insert(p);
                    }
                }
                self.used.insert(bi.id);
                continue;
            }
            if li.is("POLY_LOOP") {
                continue;
            }
            let cl = Ctx {
                inst: li,
                part: "EDGE_LOOP",
            };
            let ls = cl.params(2)?;
            let mut edges = Vec::new();
            for e in cl.list(&ls[1], "edge list")? {
                match self.edge(e, surface, &cl)? {
                    Some(e) => edges.push(e),
                    None => skipped += 1,
                }
            }
            self.used.insert(li.id);
            self.used.insert(bi.id);
            loops.push(TrimLoop {
                outer,
                orientation,
                edges,
            });
        }
        self.used.insert(inst.id);
        Ok(FaceData {
            step_id: inst.id,
            surface,
            same_sense,
            loops,
            skipped,
        })
    }

    /// Converts an elementary or swept surface exactly, or `None` for another type. `hull` holds
    /// the control points of the boundaries of the faces on it (for unbounded directions).
    pub(crate) fn elementary(
        &mut self,
        inst: &'a Instance,
        hull: &[Vec3],
    ) -> Result<Option<Converted>, IoError> {
        if inst.parts.len() != 1 {
            return Ok(None);
        }
        let kind = inst.parts[0].name.as_str();
        let c = Ctx { inst, part: kind };
        let name = |p: &Param| Reader::name(p);
        let range = |o: Vec3, e: Vec3| -> [f64; 2] {
            let (lo, hi) = hull
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
                    let t = (p - o).dot(&e);
                    (a.0.min(t), a.1.max(t))
                });
            if hi > lo { [lo, hi] } else { DEFAULT_RANGE }
        };
        let full = ParamAxis::angle(0.0, TAU);
        let map = |e: String| c.err(e);
        let out = match kind {
            "PLANE" => {
                let ps = c.params(2)?;
                let f = self.frame(&ps[1], &c)?;
                let [u0, u1] = range(f.o, f.x);
                let [v0, v1] = range(f.o, f.y);
                let corner = |u: f64, v: f64| f.o + f.x * u + f.y * v;
                let s = NurbsSurface::new(
                    [1, 1],
                    [vec![u0, u0, u1, u1], vec![v0, v0, v1, v1]],
                    vec![
                        vec![corner(u0, v0), corner(u0, v1)],
                        vec![corner(u1, v0), corner(u1, v1)],
                    ],
                    None,
                )
                .map_err(|e| c.err(e))?;
                (s, [ParamAxis::Linear, ParamAxis::Linear], name(&ps[0]))
            }
            "CYLINDRICAL_SURFACE" | "CONICAL_SURFACE" => {
                let cone = kind == "CONICAL_SURFACE";
                let ps = c.params(if cone { 4 } else { 3 })?;
                let f = self.frame(&ps[1], &c)?;
                let r = real_of(&c, &ps[2], "radius")?;
                let slope = if cone {
                    let a = real_of(&c, &ps[3], "semi_angle")? * self.angle_unit;
                    if !(a > 0.0 && a < FRAC_PI_2) {
                        return Err(c.err(format!("semi_angle {a} rad must be between 0 and pi/2")));
                    }
                    a.tan()
                } else {
                    if r <= 0.0 {
                        return Err(c.err(format!("radius must be positive, found {r}")));
                    }
                    0.0
                };
                if r < 0.0 {
                    return Err(c.err(format!("radius must not be negative, found {r}")));
                }
                let [v0, v1] = range(f.o, f.z);
                let at = |v: f64| f.o + f.x * (r + v * slope) + f.z * v;
                let profile = NurbsCurve::new(1, vec![v0, v0, v1, v1], vec![at(v0), at(v1)], None)
                    .map_err(|e| c.err(e))?;
                let s = revolve(f.o, f.z, &profile).map_err(map)?;
                (s, [full, ParamAxis::Linear], name(&ps[0]))
            }
            "SPHERICAL_SURFACE" => {
                let ps = c.params(3)?;
                let f = self.frame(&ps[1], &c)?;
                let r = positive(&c, &ps[2], "radius")?;
                let profile = arc_curve(f.o, f.x, f.z, r, r, -FRAC_PI_2, FRAC_PI_2).map_err(map)?;
                let s = revolve(f.o, f.z, &profile).map_err(map)?;
                (
                    s,
                    [full, ParamAxis::angle(-FRAC_PI_2, FRAC_PI_2)],
                    name(&ps[0]),
                )
            }
            "TOROIDAL_SURFACE" => {
                let ps = c.params(4)?;
                let f = self.frame(&ps[1], &c)?;
                let major = positive(&c, &ps[2], "major_radius")?;
                let minor = positive(&c, &ps[3], "minor_radius")?;
                let profile =
                    arc_curve(f.o + f.x * major, f.x, f.z, minor, minor, 0.0, TAU).map_err(map)?;
                let s = revolve(f.o, f.z, &profile).map_err(map)?;
                (s, [full, full], name(&ps[0]))
            }
            "SURFACE_OF_REVOLUTION" => {
                let ps = c.params(3)?;
                let ai = self.target(&ps[2], &["AXIS1_PLACEMENT"], &c)?;
                let ca = Ctx {
                    inst: ai,
                    part: "AXIS1_PLACEMENT",
                };
                let aps = ca.params(3)?;
                let (o, _) = self.point(&aps[1], &ca)?;
                let a = match &aps[2] {
                    Param::Unset => Vec3::z(),
                    p => self.direction(p, &ca)?,
                };
                self.used.insert(ai.id);
                let Param::Ref(cid) = ps[1] else {
                    return Err(c.err("swept_curve: expected a reference"));
                };
                let Some(g) = self.geom(cid, &c, 0)? else {
                    return Ok(None);
                };
                let [t0, t1] = match g.natural_range() {
                    Some(r) => r,
                    None => {
                        // A line: the range of its points' heights along the axis.
                        let Geom::Line { p, d } = &g else {
                            unreachable!("only lines are unbounded")
                        };
                        let da = d.dot(&a);
                        if da.abs() < 1e-12 * d.norm() {
                            DEFAULT_RANGE
                        } else {
                            let [h0, h1] = range(*p, a);
                            let (x, y) = (h0 / da, h1 / da);
                            if x < y { [x, y] } else { [y, x] }
                        }
                    }
                };
                let (profile, axis) = g.nurbs(t0, t1).map_err(map)?;
                let s = revolve(o, a, &profile).map_err(map)?;
                (s, [full, axis], name(&ps[0]))
            }
            "SURFACE_OF_LINEAR_EXTRUSION" => {
                let ps = c.params(3)?;
                let Param::Ref(cid) = ps[1] else {
                    return Err(c.err("swept_curve: expected a reference"));
                };
                let vi = self.target(&ps[2], &["VECTOR"], &c)?;
                let cv = Ctx {
                    inst: vi,
                    part: "VECTOR",
                };
                let vs = cv.params(3)?;
                let d = self.direction(&vs[1], &cv)?;
                let m = real_of(&cv, &vs[2], "magnitude")?;
                if m.abs() < 1e-300 {
                    return Err(cv.err("magnitude is zero"));
                }
                self.used.insert(vi.id);
                let dir = d * m;
                let Some(g) = self.geom(cid, &c, 0)? else {
                    return Ok(None);
                };
                let Some([t0, t1]) = g.natural_range() else {
                    // An extruded line is a plane: not converted here (rare in files).
                    return Ok(None);
                };
                let (curve, axis) = g.nurbs(t0, t1).map_err(map)?;
                let [p0, p1] = range(Vec3::zeros(), d);
                let (c0, c1) = curve
                    .control_points()
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
                        (a.0.min(p.dot(&d)), a.1.max(p.dot(&d)))
                    });
                let [v0, v1] = if hull.is_empty() {
                    DEFAULT_RANGE
                } else {
                    let (a, b) = ((p0 - c1) / m, (p1 - c0) / m);
                    if a < b { [a, b] } else { [b, a] }
                };
                let s = extrude(&curve, dir, v0, v1).map_err(map)?;
                (s, [axis, ParamAxis::Linear], name(&ps[0]))
            }
            _ => return Ok(None),
        };
        Ok(Some(out))
    }
}

/// The control points of a face's boundary curves, for the ranges of unbounded directions.
pub(crate) fn hull_points(face: &FaceData, out: &mut Vec<Vec3>) {
    for l in &face.loops {
        for e in &l.edges {
            out.extend_from_slice(e.curve.control_points());
        }
    }
}

/// Groups the faces by surface.
pub(crate) fn by_surface(faces: &[FaceData]) -> BTreeMap<usize, SurfaceUse> {
    let mut m: BTreeMap<usize, SurfaceUse> = BTreeMap::new();
    for f in faces {
        hull_points(f, &mut m.entry(f.surface).or_default().hull);
    }
    m
}

/// The plane-angle unit of the file in radians: pi/180 when a `CONVERSION_BASED_UNIT` named
/// like `DEGREE` is a `PLANE_ANGLE_UNIT`, else 1.
pub(crate) fn angle_unit(all: &BTreeMap<usize, Instance>) -> f64 {
    for inst in all.values() {
        if inst.is("PLANE_ANGLE_UNIT")
            && let Some(p) = inst.part("CONVERSION_BASED_UNIT")
            && let Some(Param::Str(n)) = p.params.first()
            && n.to_ascii_uppercase().starts_with("DEG")
        {
            return PI / 180.0;
        }
    }
    1.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The angle-to-parameter map inverts the rational quadratic arc: the NURBS point at the
    /// mapped parameter is the circle point at the angle.
    #[test]
    fn arc_parameter_map_is_exact() {
        for (t0, t1) in [(0.0, TAU), (-FRAC_PI_2, FRAC_PI_2), (0.3, 2.0)] {
            let c = arc_curve(Vec3::zeros(), Vec3::x(), Vec3::y(), 2.0, 2.0, t0, t1).unwrap();
            let ax = ParamAxis::angle(t0, t1);
            for i in 0..=40 {
                let th = t0 + (t1 - t0) * i as f64 / 40.0;
                let p = c.point(ax.to_nurbs(th)).unwrap();
                let q = Vec3::new(2.0 * th.cos(), 2.0 * th.sin(), 0.0);
                assert!((p - q).norm() < 1e-14, "{t0}..{t1} at {th}: {p} vs {q}");
            }
        }
        // Periodic wrap.
        let ax = ParamAxis::angle(0.0, TAU);
        assert!((ax.to_nurbs(-FRAC_PI_2) - 1.5 * PI).abs() < 1e-12);
        assert!((ax.to_nurbs(TAU) - TAU).abs() < 1e-12);
    }
}
