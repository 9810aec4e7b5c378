//! Boundary representation (B-rep) of vclay's surfaces and volumes for CAD export: faces,
//! edges and vertices shared between faces, closed shells oriented outward.
//!
//! **What.** [`Shell::of_surface`] and [`Shell::of_volume`] turn one NURBS surface, or the six
//! boundary surfaces of a trivariate volume, into a [`Shell`]: one [`Face`] per surface bounded
//! by the loop of its four boundary iso-curves (`v = v0` along `+u`, `u = u1` along `+v`,
//! `v = v1` along `-u`, `u = u0` along `-v`: counter-clockwise in the parameter square, so
//! that the interior lies to the left about the normal `S_u x S_v`), with
//!
//! - the corners merged into [`Vertex`]es when they lie within the closure tolerance;
//! - boundary curves that coincide (same degree, same knots up to reversal, control points
//!   within the tolerance, proportional weights) merged into one [`Edge`], used twice: the seam
//!   of a torus, a sphere or a closed D-NURBS surface, and the twelve edges of a volume;
//! - boundary curves whose control points all lie within the tolerance of one point recorded as
//!   a [`LoopItem::Pole`] (the poles of a sphere or a swung egg): no edge, the loop passes the
//!   pole's vertex;
//! - face orientations made consistent through the shared edges (each edge traversed once in
//!   each direction) and then outward: the signed volume
//!   `V = 1/3 sum_f s_f int int S . (S_u x S_v) du dv` (the divergence theorem with `div x = 3`,
//!   `s_f = +-1` the face's sense) is made positive.
//!
//! Before that, faces without area (every control row along one direction collapsed to a point:
//! the axis face `r = 0` of a solid cylinder parametrized by radius and angle, the centre and
//! pole faces of a solid ball) and pairs of coinciding faces (the two angle faces of such a
//! volume, an inner seam) are dropped ([`Shell::of_volume`], [`Shell::of_surfaces`]): the faces
//! left bound the same region.
//!
//! The shell is closed when every edge is used exactly twice with opposite senses; anything
//! else (a free boundary, an edge shared by three faces, a non-orientable surface) makes an open
//! shell, which the writers export as such. The geometry is exact: surfaces are only clamped
//! (knot insertion, Piegl & Tiller algorithm A5.1) when their knot vectors are not, and edges
//! are boundary rows of the (clamped) control nets.
//!
//! **Tolerance.** Corners, curves and poles are compared with
//! `tol = CLOSURE_RTOL x size`, `size` the diagonal of the bounding box of the entity's control
//! points ([`closure_tolerance`]). With `CLOSURE_RTOL = 1e-9` this absorbs the rounding of knot
//! insertion and of simulations that keep seams shared (about `1e-15 x size`) with a wide margin,
//! and stays far below CAD's own merge tolerance (`1e-7` mm for a part of a few millimetres up
//! to metres), so two boundaries vclay merges are the same curve for any CAD system.
//!
//! **Limitations.** Boundary curves are merged only when they have the same parametrization
//! (knots equal, or equal after reversal): a closed surface whose seams are parametrized
//! differently on the two sides is exported as an open shell. A face whose whole boundary
//! degenerates (a surface collapsed to a point) is not supported and leaves the shell open.

use crate::error::IoError;
use std::collections::HashMap;
use vclay_core::Vec3;
use vclay_core::quadrature::GaussLegendre;
use vclay_spline::{KnotVector, NurbsCurve, NurbsSurface, NurbsVolume, ParametricSurface};

/// Relative closure tolerance: boundaries closer than `CLOSURE_RTOL x size` are merged.
pub const CLOSURE_RTOL: f64 = 1e-9;

/// The closure tolerance of a set of control points: [`CLOSURE_RTOL`] times the diagonal of
/// their bounding box (`f64::MIN_POSITIVE` for a single point).
pub fn closure_tolerance(points: &[Vec3]) -> f64 {
    let mut lo = Vec3::repeat(f64::INFINITY);
    let mut hi = Vec3::repeat(f64::NEG_INFINITY);
    for p in points {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let d = (hi - lo).norm();
    if d.is_finite() && d > 0.0 {
        CLOSURE_RTOL * d
    } else {
        f64::MIN_POSITIVE
    }
}

/// A vertex of a shell: a point where face corners meet.
#[derive(Clone, Debug, PartialEq)]
pub struct Vertex {
    /// Its position (the first corner merged into it).
    pub point: Vec3,
}

/// An edge of a shell: an exact NURBS curve from vertex `start` (at the curve's first
/// parameter) to vertex `end` (at its last; equal to `start` for a closed curve).
#[derive(Clone, Debug, PartialEq)]
pub struct Edge {
    /// The edge's geometry, a boundary curve of the first face that uses it.
    pub curve: NurbsCurve,
    /// Index of the start vertex.
    pub start: usize,
    /// Index of the end vertex.
    pub end: usize,
}

/// One element of a face's boundary loop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LoopItem {
    /// Edge `edge`, traversed from its start to its end when `forward`.
    Edge {
        /// Index of the edge.
        edge: usize,
        /// Whether the loop runs along the edge's curve direction.
        forward: bool,
        /// Index in [`Face::pcurves`] of the edge's curve in the face's parameter space, if
        /// known (trimmed faces; the boundary of a whole surface needs none).
        pcurve: Option<usize>,
    },
    /// A boundary side of the parameter square that collapses to vertex `vertex` (a pole).
    Pole {
        /// Index of the vertex.
        vertex: usize,
    },
}

/// A face: a NURBS surface bounded by its outer loop and, for a trimmed face, inner loops
/// (holes); see [`crate::trimmed`] for trimmed faces.
#[derive(Clone, Debug, PartialEq)]
pub struct Face {
    /// The face's surface, with clamped knot vectors.
    pub surface: NurbsSurface,
    /// Whether the face's outward normal is the surface normal `S_u x S_v` (`false`: reversed).
    pub same_sense: bool,
    /// The outer loop, oriented counter-clockwise about the face's normal (for a whole surface
    /// the parameter square run counter-clockwise when `same_sense`, clockwise otherwise).
    pub bound: Vec<LoopItem>,
    /// The inner loops (holes), clockwise about the face's normal; empty for a whole surface.
    pub holes: Vec<Vec<LoopItem>>,
    /// The curves in the surface's parameter space (points `(u, v, 0)`) that
    /// [`LoopItem::Edge::pcurve`] refers to, each running in its edge's curve direction over
    /// the same parameter interval as the edge's 3D curve (a trimmed face); empty otherwise.
    pub pcurves: Vec<NurbsCurve>,
    /// The index of the face's surface among the model's entities, when the face is a
    /// trimmed face of a model ([`crate::trimmed`]); `None` for shells built from whole
    /// surfaces.
    pub entity: Option<usize>,
}

impl Face {
    /// The outer loop then the holes.
    pub fn loops(&self) -> impl Iterator<Item = &Vec<LoopItem>> {
        std::iter::once(&self.bound).chain(&self.holes)
    }

    /// A loop of this face as a polygon in the surface's parameters: each edge use's pcurve
    /// sampled at `samples` points (both ends included, at least 2) in loop direction; uses
    /// without a pcurve (poles, whole-surface boundaries) add nothing, so the polygon closes
    /// across them implicitly.
    pub fn loop_polygon(&self, l: &[LoopItem], samples: usize) -> Vec<[f64; 2]> {
        let n = samples.max(2);
        let mut out = Vec::with_capacity(l.len() * n);
        for it in l {
            if let LoopItem::Edge {
                forward,
                pcurve: Some(k),
                ..
            } = *it
                && let Some(c) = self.pcurves.get(k)
            {
                use vclay_spline::ParametricCurve;
                let d = c.domain();
                let mut seg: Vec<[f64; 2]> = (0..n)
                    .filter_map(|i| c.point(d.min + d.length() * i as f64 / (n - 1) as f64).ok())
                    .map(|q| [q.x, q.y])
                    .collect();
                if !forward {
                    seg.reverse();
                }
                out.extend(seg);
            }
        }
        out
    }
}

/// A connected set of faces sharing edges and vertices.
#[derive(Clone, Debug, PartialEq)]
pub struct Shell {
    /// The vertices.
    pub vertices: Vec<Vertex>,
    /// The edges.
    pub edges: Vec<Edge>,
    /// The faces.
    pub faces: Vec<Face>,
    /// Whether the shell is closed: every edge used exactly twice, in opposite directions, so
    /// that the faces bound a solid (and are oriented outward).
    pub closed: bool,
    /// The closure tolerance used to merge vertices and edges ([`closure_tolerance`]).
    pub tolerance: f64,
}

/// A boundary side of a face before merging.
struct Side {
    curve: NurbsCurve,
    start: usize,
    end: usize,
    /// Whether the loop runs along the curve.
    forward: bool,
}

fn clamp_surface(s: &NurbsSurface) -> Result<NurbsSurface, IoError> {
    let mut s = s.clone();
    for axis in 0..2 {
        if !s.knots()[axis].is_clamped() {
            s = s.clamped(axis).map_err(|e| structure(e.to_string()))?;
        }
    }
    Ok(s)
}

fn structure(message: String) -> IoError {
    IoError::Structure {
        path: "B-rep".into(),
        message,
    }
}

/// Boundary row `(index along the other axis fixed)` of a surface net as a curve.
fn boundary_curve(s: &NurbsSurface, axis: usize, last: bool) -> Result<NurbsCurve, IoError> {
    // axis 0: the curve runs along u at v = v0 (last = false) or v = v1.
    let [nu, nv] = s.dims();
    let (n, idx): (usize, Box<dyn Fn(usize) -> usize>) = if axis == 0 {
        let j = if last { nv - 1 } else { 0 };
        (nu, Box::new(move |i| i * nv + j))
    } else {
        let i = if last { nu - 1 } else { 0 };
        (nv, Box::new(move |j| i * nv + j))
    };
    let pts = (0..n).map(|k| s.control_points()[idx(k)]).collect();
    let ws = (0..n).map(|k| s.weights()[idx(k)]).collect();
    NurbsCurve::from_knot_vector(s.knots()[axis].clone(), pts, ws)
        .map_err(|e| structure(e.to_string()))
}

fn is_point(c: &NurbsCurve, tol: f64) -> bool {
    let p0 = c.control_points()[0];
    c.control_points().iter().all(|p| (p - p0).norm() <= tol)
}

/// Whether `b` is the same curve as `a` (`Some(true)`), the same reversed (`Some(false)`), or
/// neither.
fn same_curve(a: &NurbsCurve, b: &NurbsCurve, tol: f64) -> Option<bool> {
    if a.degree() != b.degree() || a.control_points().len() != b.control_points().len() {
        return None;
    }
    let (ka, kb) = (a.knots().as_slice(), b.knots().as_slice());
    let ptol = a
        .knots()
        .parameter_tolerance()
        .max(b.knots().parameter_tolerance());
    let n = ka.len();
    let (a0, a1) = (ka[0], ka[n - 1]);
    let (b0, b1) = (kb[0], kb[n - 1]);
    let np = a.control_points().len();
    let matches = |rev: bool| {
        let knots_ok = (0..n).all(|i| {
            // Map b's knots onto a's interval (reversed when `rev`) and compare.
            let t = if rev { kb[n - 1 - i] } else { kb[i] };
            let s = (t - b0) / (b1 - b0);
            let s = if rev { 1.0 - s } else { s };
            (a0 + s * (a1 - a0) - ka[i]).abs() <= ptol
        });
        if !knots_ok {
            return false;
        }
        let k = |i: usize| if rev { np - 1 - i } else { i };
        let r = b.weights()[k(0)] / a.weights()[0];
        (0..np).all(|i| {
            (a.control_points()[i] - b.control_points()[k(i)]).norm() <= tol
                && (b.weights()[k(i)] - r * a.weights()[i]).abs()
                    <= 1e-12 * b.weights()[k(i)].abs().max(1.0)
        })
    };
    if matches(false) {
        Some(true)
    } else if matches(true) {
        Some(false)
    } else {
        None
    }
}

/// Grid cell of a point for the vertex hash: cells of the tolerance's size, so a point within
/// the tolerance of another lies in the same or a neighbouring cell.
type Cell = [i64; 3];

/// A use of an edge by a face loop: (face, runs along the edge in the face's natural loop).
type EdgeUse = (usize, bool);

/// Whether a surface has no area: every control row along u, or every one along v, collapses
/// to a point (the axis face `r = 0` of a solid cylinder, the pole faces of a solid ball).
fn is_degenerate_face(s: &NurbsSurface, tol: f64) -> bool {
    let [nu, nv] = s.dims();
    let p = s.control_points();
    let rows_u = (0..nv).all(|j| (0..nu).all(|i| (p[i * nv + j] - p[j]).norm() <= tol));
    let rows_v = (0..nu).all(|i| (0..nv).all(|j| (p[i * nv + j] - p[i * nv]).norm() <= tol));
    rows_u || rows_v
}

/// Whether two surfaces are the same within `tol`: same degrees and knots, control points
/// within `tol` and proportional weights, possibly with u and/or v reversed.
fn same_face(a: &NurbsSurface, b: &NurbsSurface, tol: f64) -> bool {
    if a.dims() != b.dims() || a.degree() != b.degree() {
        return false;
    }
    let [nu, nv] = a.dims();
    let knots_match = |axis: usize, rev: bool| {
        let (ka, kb) = (a.knots()[axis].as_slice(), b.knots()[axis].as_slice());
        let n = ka.len();
        let ptol = a.knots()[axis].parameter_tolerance();
        (0..n).all(|i| {
            let t = if rev {
                ka[0] + ka[n - 1] - kb[n - 1 - i]
            } else {
                kb[i]
            };
            (t - ka[i]).abs() <= ptol
        })
    };
    [(false, false), (true, false), (false, true), (true, true)]
        .into_iter()
        .any(|(ru, rv)| {
            if !knots_match(0, ru) || !knots_match(1, rv) {
                return false;
            }
            let idx = |i: usize, j: usize| {
                let i = if ru { nu - 1 - i } else { i };
                let j = if rv { nv - 1 - j } else { j };
                i * nv + j
            };
            let r = b.weights()[idx(0, 0)] / a.weights()[0];
            (0..nu).all(|i| {
                (0..nv).all(|j| {
                    let (k, l) = (i * nv + j, idx(i, j));
                    (a.control_points()[k] - b.control_points()[l]).norm() <= tol
                        && (b.weights()[l] - r * a.weights()[k]).abs()
                            <= 1e-12 * b.weights()[l].abs().max(1.0)
                })
            })
        })
}

/// Drops faces without area and pairs of coinciding faces (an inner seam, such as the two
/// `theta` faces of a solid cylinder or ball parametrized by angle): what is left bounds the
/// same region.
fn prune_faces(faces: Vec<NurbsSurface>, tol: f64) -> Vec<NurbsSurface> {
    let faces: Vec<NurbsSurface> = faces
        .into_iter()
        .filter(|f| !is_degenerate_face(f, tol))
        .collect();
    // Candidates share the grid cell (of the tolerance's size) of their control-point centroid,
    // which reversing u or v does not move, or a neighbouring one.
    let cell = |f: &NurbsSurface| -> Cell {
        let p = f.control_points();
        let c = p.iter().sum::<Vec3>() / p.len() as f64;
        [c.x, c.y, c.z].map(|x| (x / tol).floor() as i64)
    };
    let cells: Vec<Cell> = faces.iter().map(cell).collect();
    let mut grid: HashMap<Cell, Vec<usize>> = HashMap::new();
    for (i, c) in cells.iter().enumerate() {
        grid.entry(*c).or_default().push(i);
    }
    let mut keep = vec![true; faces.len()];
    for i in 0..faces.len() {
        if !keep[i] {
            continue;
        }
        let c = cells[i];
        let mut partner = None;
        'search: for d in 0..27i64 {
            let key = [
                c[0].saturating_add(d % 3 - 1),
                c[1].saturating_add(d / 3 % 3 - 1),
                c[2].saturating_add(d / 9 - 1),
            ];
            for &j in grid.get(&key).map_or(&[][..], Vec::as_slice) {
                if j != i && keep[j] && same_face(&faces[i], &faces[j], tol) {
                    partner = Some(j);
                    break 'search;
                }
            }
        }
        if let Some(j) = partner {
            keep[i] = false;
            keep[j] = false;
        }
    }
    faces
        .into_iter()
        .zip(keep)
        .filter_map(|(f, k)| k.then_some(f))
        .collect()
}

struct Builder {
    tol: f64,
    vertices: Vec<Vertex>,
    edges: Vec<Edge>,
    faces: Vec<Face>,
    /// Vertices by grid cell.
    grid: HashMap<Cell, Vec<usize>>,
    /// Edges by their (smaller, larger) end vertices.
    by_ends: HashMap<(usize, usize), Vec<usize>>,
}

impl Builder {
    fn new(tol: f64) -> Self {
        Builder {
            tol,
            vertices: Vec::new(),
            edges: Vec::new(),
            faces: Vec::new(),
            grid: HashMap::new(),
            by_ends: HashMap::new(),
        }
    }

    fn cell(&self, p: &Vec3) -> Cell {
        // Saturating float-to-int casts: a huge coordinate only makes cells coarser.
        [p.x, p.y, p.z].map(|c| (c / self.tol).floor() as i64)
    }

    fn vertex(&mut self, p: Vec3) -> usize {
        let c = self.cell(&p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let key = [
                        c[0].saturating_add(dx),
                        c[1].saturating_add(dy),
                        c[2].saturating_add(dz),
                    ];
                    if let Some(ids) = self.grid.get(&key)
                        && let Some(&i) = ids
                            .iter()
                            .find(|&&i| (self.vertices[i].point - p).norm() <= self.tol)
                    {
                        return i;
                    }
                }
            }
        }
        self.vertices.push(Vertex { point: p });
        let id = self.vertices.len() - 1;
        self.grid.entry(c).or_default().push(id);
        id
    }

    fn add_face(&mut self, surface: NurbsSurface) -> Result<(), IoError> {
        let s = clamp_surface(&surface)?;
        let [nu, nv] = s.dims();
        let cp = s.control_points();
        let c00 = self.vertex(cp[0]);
        let c10 = self.vertex(cp[(nu - 1) * nv]);
        let c11 = self.vertex(cp[nu * nv - 1]);
        let c01 = self.vertex(cp[nv - 1]);
        let sides = [
            Side {
                curve: boundary_curve(&s, 0, false)?,
                start: c00,
                end: c10,
                forward: true,
            },
            Side {
                curve: boundary_curve(&s, 1, true)?,
                start: c10,
                end: c11,
                forward: true,
            },
            Side {
                curve: boundary_curve(&s, 0, true)?,
                start: c01,
                end: c11,
                forward: false,
            },
            Side {
                curve: boundary_curve(&s, 1, false)?,
                start: c00,
                end: c01,
                forward: false,
            },
        ];
        let mut bound = Vec::with_capacity(4);
        for side in sides {
            if is_point(&side.curve, self.tol) {
                bound.push(LoopItem::Pole { vertex: side.start });
                continue;
            }
            let key = (side.start.min(side.end), side.start.max(side.end));
            let found = self.by_ends.get(&key).and_then(|ids| {
                ids.iter().find_map(|&i| {
                    let e = &self.edges[i];
                    let same = same_curve(&e.curve, &side.curve, self.tol)?;
                    let ends = if same {
                        (side.start, side.end)
                    } else {
                        (side.end, side.start)
                    };
                    (ends == (e.start, e.end)).then_some((i, same))
                })
            });
            let (edge, same) = found.unwrap_or_else(|| {
                self.edges.push(Edge {
                    curve: side.curve.clone(),
                    start: side.start,
                    end: side.end,
                });
                let id = self.edges.len() - 1;
                self.by_ends.entry(key).or_default().push(id);
                (id, true)
            });
            bound.push(LoopItem::Edge {
                edge,
                forward: side.forward == same,
                pcurve: None,
            });
        }
        self.faces.push(Face {
            surface: s,
            same_sense: true,
            bound,
            holes: Vec::new(),
            pcurves: Vec::new(),
            entity: None,
        });
        Ok(())
    }

    fn finish(mut self) -> Shell {
        // Uses of each edge: (face, forward in the face's natural loop).
        let mut uses: Vec<Vec<EdgeUse>> = vec![Vec::new(); self.edges.len()];
        for (f, face) in self.faces.iter().enumerate() {
            for item in &face.bound {
                if let LoopItem::Edge { edge, forward, .. } = *item {
                    uses[edge].push((f, forward));
                }
            }
        }
        let manifold = uses.iter().all(|u| u.len() == 2);
        // Orient faces consistently: an edge's two uses must run in opposite directions once
        // each face's flip is applied. Breadth-first over the faces.
        let nf = self.faces.len();
        // Per face: (its use, the other face's use) of every edge it shares.
        let mut adjacent: Vec<Vec<(EdgeUse, EdgeUse)>> = vec![Vec::new(); nf];
        for u in uses.iter().filter(|u| u.len() == 2) {
            adjacent[u[0].0].push((u[0], u[1]));
            adjacent[u[1].0].push((u[1], u[0]));
        }
        let mut flip: Vec<Option<bool>> = vec![None; nf];
        let mut orientable = true;
        for seed in 0..nf {
            if flip[seed].is_some() {
                continue;
            }
            flip[seed] = Some(false);
            let mut queue = vec![seed];
            while let Some(f) = queue.pop() {
                let ff = flip[f].unwrap_or(false);
                for &(a, b) in &adjacent[f] {
                    // Need (a.1 ^ ff) != (b.1 ^ fb).
                    let want = !(a.1 ^ ff) ^ b.1;
                    match flip[b.0] {
                        None => {
                            flip[b.0] = Some(want);
                            queue.push(b.0);
                        }
                        Some(x) if x != want => orientable = false,
                        Some(_) => {}
                    }
                }
            }
        }
        let mut flip: Vec<bool> = flip.into_iter().map(|f| f.unwrap_or(false)).collect();
        let closed = manifold && orientable && !self.edges.is_empty();
        if closed {
            let v: f64 = self
                .faces
                .iter()
                .zip(&flip)
                .map(|(f, &fl)| {
                    let vf = surface_volume_integral(&f.surface, 8);
                    if fl { -vf } else { vf }
                })
                .sum();
            if v < 0.0 {
                flip.iter_mut().for_each(|f| *f = !*f);
            }
        }
        for (face, fl) in self.faces.iter_mut().zip(flip) {
            if fl {
                face.same_sense = false;
                face.bound.reverse();
                for item in &mut face.bound {
                    if let LoopItem::Edge { forward, .. } = item {
                        *forward = !*forward;
                    }
                }
            }
        }
        Shell {
            vertices: self.vertices,
            edges: self.edges,
            faces: self.faces,
            closed,
            tolerance: self.tol,
        }
    }
}

/// `1/3 int int S . (S_u x S_v) du dv` over a surface's domain, with `n`-point Gauss-Legendre
/// quadrature on each knot span (the surface's contribution to the enclosed volume, divergence
/// theorem).
pub fn surface_volume_integral(s: &NurbsSurface, n: usize) -> f64 {
    let Ok(g) = GaussLegendre::new(n) else {
        return 0.0;
    };
    let spans = |k: &KnotVector| -> Vec<(f64, f64)> {
        let d = k.distinct();
        let dom = k.domain();
        d.windows(2)
            .map(|w| (w[0].0, w[1].0))
            .filter(|(a, b)| *a >= dom.min && *b <= dom.max && b > a)
            .collect()
    };
    let (su, sv) = (spans(&s.knots()[0]), spans(&s.knots()[1]));
    let mut total = 0.0;
    for &(a, b) in &su {
        for (u, wu) in g.on_interval(a, b).collect::<Vec<_>>() {
            for &(c, d) in &sv {
                for (v, wv) in g.on_interval(c, d) {
                    if let Ok(dd) = s.derivatives(u, v, 1) {
                        total += wu * wv * dd[0][0].dot(&dd[1][0].cross(&dd[0][1]));
                    }
                }
            }
        }
    }
    total / 3.0
}

impl Shell {
    /// The shell of one surface: closed when its boundaries close up (a torus, a sphere, a
    /// closed D-NURBS surface), open otherwise.
    pub fn of_surface(s: &NurbsSurface) -> Result<Shell, IoError> {
        Self::of_surfaces(std::slice::from_ref(s))
    }

    /// The shell of a volume's six boundary surfaces (`u = u0, u1, v = v0, v1, w = w0, w1`, from
    /// the clamped volume), less those without area and pairs that coincide: closed for a
    /// volume whose boundary closes up. Volumes with unclamped knot vectors are clamped first
    /// (exact).
    pub fn of_volume(v: &NurbsVolume) -> Result<Shell, IoError> {
        let mut v = v.clone();
        for axis in 0..3 {
            if !v.knots()[axis].is_clamped() {
                v = v.clamped(axis).map_err(|e| structure(e.to_string()))?;
            }
        }
        let faces = crate::step::volume_boundary_surfaces(&v)
            .ok_or_else(|| structure("volume knot vectors could not be clamped".into()))?;
        let tol = closure_tolerance(v.control_points());
        let mut b = Builder::new(tol);
        for f in prune_faces(faces, tol) {
            b.add_face(f)?;
        }
        Ok(b.finish())
    }

    /// One shell of several surfaces joined along their coinciding boundaries (patches of one
    /// surface, such as the bicubic patches of a subdivision solid's limit surface): closed when
    /// they close up. The tolerance is that of all their control points together.
    pub fn of_surfaces(surfaces: &[NurbsSurface]) -> Result<Shell, IoError> {
        let all: Vec<Vec3> = surfaces
            .iter()
            .flat_map(|s| s.control_points().iter().copied())
            .collect();
        let tol = closure_tolerance(&all);
        let mut b = Builder::new(tol);
        for s in prune_faces(surfaces.to_vec(), tol) {
            b.add_face(s)?;
        }
        Ok(b.finish())
    }

    /// The enclosed volume `1/3 sum_f s_f int int S . (S_u x S_v) du dv` with `n`-point
    /// Gauss-Legendre quadrature per knot span (positive for a closed shell, whose faces are
    /// oriented outward); meaningful only for a closed shell of whole (untrimmed) faces.
    pub fn volume(&self, n: usize) -> f64 {
        self.faces
            .iter()
            .map(|f| {
                let v = surface_volume_integral(&f.surface, n);
                if f.same_sense { v } else { -v }
            })
            .sum()
    }

    /// How many times each edge is used by the loops, and with which directions: for a closed
    /// shell every entry is one forward and one backward use.
    pub fn edge_uses(&self) -> Vec<(usize, usize)> {
        let mut u = vec![(0, 0); self.edges.len()];
        for f in &self.faces {
            for item in f.loops().flatten() {
                if let LoopItem::Edge { edge, forward, .. } = *item {
                    if forward {
                        u[edge].0 += 1;
                    } else {
                        u[edge].1 += 1;
                    }
                }
            }
        }
        u
    }
}

/// One shell of all the surfaces of a model and the boundary faces of its volumes, joined along
/// coinciding boundaries ([`Shell::of_surfaces`]); `None` when the model has only curves.
pub fn joined_shell(entities: &[crate::model::NamedEntity]) -> Result<Option<Shell>, IoError> {
    use crate::model::Entity;
    let mut surfaces = Vec::new();
    for e in entities {
        match &e.entity {
            Entity::Curve(_) => {}
            Entity::Surface(s) => surfaces.push(s.clone()),
            Entity::Volume(v) => {
                let mut v = v.clone();
                for axis in 0..3 {
                    if !v.knots()[axis].is_clamped() {
                        v = v.clamped(axis).map_err(|e| structure(e.to_string()))?;
                    }
                }
                surfaces.extend(
                    crate::step::volume_boundary_surfaces(&v).ok_or_else(|| {
                        structure("volume knot vectors could not be clamped".into())
                    })?,
                );
            }
        }
    }
    if surfaces.is_empty() {
        return Ok(None);
    }
    Shell::of_surfaces(&surfaces).map(Some)
}

/// What the B-rep layout of a model holds: closed shells (solids), open shells and loose curves.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BrepSummary {
    /// Surfaces and volumes whose boundary is closed: written as solids.
    pub solids: usize,
    /// Surfaces that do not close up: written as open shells.
    pub open_shells: usize,
    /// Curves: written as loose curves.
    pub curves: usize,
}

impl BrepSummary {
    /// The summary of the joined layout: every surface and volume face in one shell
    /// ([`joined_shell`]).
    pub fn joined(entities: &[crate::model::NamedEntity]) -> Result<Self, IoError> {
        let shell = joined_shell(entities)?;
        let closed = shell.as_ref().is_some_and(|s| s.closed);
        Ok(BrepSummary {
            solids: usize::from(closed),
            open_shells: usize::from(shell.is_some() && !closed),
            curves: entities
                .iter()
                .filter(|e| matches!(e.entity, crate::model::Entity::Curve(_)))
                .count(),
        })
    }

    /// Builds the shell of every surface and volume of `entities` and counts them.
    pub fn of(entities: &[crate::model::NamedEntity]) -> Result<Self, IoError> {
        use crate::model::Entity;
        let mut out = BrepSummary::default();
        for e in entities {
            let shell = match &e.entity {
                Entity::Curve(_) => {
                    out.curves += 1;
                    continue;
                }
                Entity::Surface(s) => Shell::of_surface(s)?,
                Entity::Volume(v) => Shell::of_volume(v)?,
            };
            if shell.closed {
                out.solids += 1;
            } else {
                out.open_shells += 1;
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn torus_has_one_vertex_two_seams_and_is_closed_outward() {
        let t = NurbsSurface::torus(2.0, 0.5).unwrap();
        let sh = Shell::of_surface(&t).unwrap();
        assert!(sh.closed);
        assert_eq!(
            (sh.vertices.len(), sh.edges.len(), sh.faces.len()),
            (1, 2, 1)
        );
        assert!(sh.edge_uses().iter().all(|&u| u == (1, 1)));
        assert!(
            sh.faces[0].same_sense,
            "the torus normal already points out"
        );
        let exact = 2.0 * PI * PI * 2.0 * 0.25;
        assert!(
            (sh.volume(20) - exact).abs() < 1e-12 * exact,
            "{}",
            sh.volume(20)
        );
    }

    #[test]
    fn sphere_has_poles_and_a_seam() {
        let s = NurbsSurface::sphere(1.5).unwrap();
        let sh = Shell::of_surface(&s).unwrap();
        assert!(sh.closed);
        assert_eq!((sh.vertices.len(), sh.edges.len()), (2, 1));
        let poles = sh.faces[0]
            .bound
            .iter()
            .filter(|i| matches!(i, LoopItem::Pole { .. }))
            .count();
        assert_eq!(poles, 2);
        let exact = 4.0 / 3.0 * PI * 1.5f64.powi(3);
        assert!((sh.volume(20) - exact).abs() < 1e-12 * exact);
        // Reversing the parametrization (swapping u and v) flips the face, not the volume.
        let swapped = transposed(&s);
        let sh2 = Shell::of_surface(&swapped).unwrap();
        assert!(sh2.closed && !sh2.faces[0].same_sense);
        assert!((sh2.volume(20) - exact).abs() < 1e-12 * exact);
    }

    #[test]
    fn open_and_periodic_surfaces() {
        // A flat sheet: open, four edges used once.
        let pts = (0..9)
            .map(|k| Vec3::new((k / 3) as f64, (k % 3) as f64, 0.0))
            .collect();
        let sheet = NurbsSurface::clamped_uniform([2, 2], [3, 3], pts).unwrap();
        let sh = Shell::of_surface(&sheet).unwrap();
        assert!(!sh.closed);
        assert_eq!((sh.vertices.len(), sh.edges.len()), (4, 4));
        // A closed D-NURBS-style tube: periodic (unclamped uniform) along v, clamped along u
        // with flat caps collapsed to poles: clamping makes the seam and poles appear.
        let (n, p) = (6, 3);
        let mut pts = Vec::new();
        let rings = [0.0, 1.0, 1.2, 1.0, 0.0];
        for (i, r) in rings.iter().enumerate() {
            for j in 0..n + p {
                let a = 2.0 * PI * (j % n) as f64 / n as f64;
                pts.push(Vec3::new(r * a.cos(), r * a.sin(), i as f64 - 2.0));
            }
        }
        let ku = KnotVector::clamped_uniform(2, rings.len()).unwrap();
        let kv = KnotVector::uniform(p, n + p).unwrap();
        let w = vec![1.0; pts.len()];
        let s = NurbsSurface::from_flat([ku, kv], pts, w).unwrap();
        let sh = Shell::of_surface(&s).unwrap();
        assert!(sh.closed, "{:?}", sh.edge_uses());
        assert_eq!(sh.edges.len(), 1);
        assert!(sh.volume(20) > 0.0);
    }

    /// `s` with u and v swapped (its normal reversed).
    fn transposed(s: &NurbsSurface) -> NurbsSurface {
        let [nu, nv] = s.dims();
        let (mut pts, mut ws) = (Vec::new(), Vec::new());
        for j in 0..nv {
            for i in 0..nu {
                pts.push(s.control_points()[i * nv + j]);
                ws.push(s.weights()[i * nv + j]);
            }
        }
        let k = s.knots();
        NurbsSurface::from_flat([k[1].clone(), k[0].clone()], pts, ws).unwrap()
    }

    #[test]
    fn separate_patches_join_into_one_solid() {
        let v = NurbsVolume::box_lattice(
            [2, 1, 2],
            [3, 2, 4],
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(2.0, 1.0, 2.0),
        )
        .unwrap();
        let mut faces = crate::step::volume_boundary_surfaces(&v).unwrap();
        // Parametrizations as separate patches may come: some transposed, order shuffled.
        faces[1] = transposed(&faces[1]);
        faces[4] = transposed(&faces[4]);
        faces.swap(0, 5);
        let sh = Shell::of_surfaces(&faces).unwrap();
        assert!(sh.closed);
        assert_eq!(
            (sh.vertices.len(), sh.edges.len(), sh.faces.len()),
            (8, 12, 6)
        );
        assert!(sh.edge_uses().iter().all(|&u| u == (1, 1)));
        assert!((sh.volume(6) - 2.0).abs() < 1e-12, "{}", sh.volume(6));
        // Five of the six: an open shell, the free edges used once.
        let open = Shell::of_surfaces(&faces[..5]).unwrap();
        assert!(!open.closed);
        assert_eq!(
            open.edge_uses().iter().filter(|u| u.0 + u.1 == 1).count(),
            4
        );
    }

    /// A solid cylinder of radius `r` and height `h` parametrized by (radius, angle, height):
    /// its `r = 0` face is the axis, its two angle faces coincide.
    fn solid_cylinder(r: f64, h: f64) -> NurbsVolume {
        let c = NurbsCurve::circle(Vec3::zeros(), Vec3::x(), Vec3::y(), 1.0).unwrap();
        let (mut pts, mut ws) = (Vec::new(), Vec::new());
        for rad in [0.0, r] {
            for (p, &w) in c.control_points().iter().zip(c.weights()) {
                for z in [0.0, h] {
                    pts.push(Vec3::new(rad * p.x, rad * p.y, z));
                    ws.push(w);
                }
            }
        }
        let lin = KnotVector::clamped_uniform(1, 2).unwrap();
        NurbsVolume::from_flat([lin.clone(), c.knots().clone(), lin], pts, ws).unwrap()
    }

    #[test]
    fn collapsed_and_coinciding_volume_faces_are_dropped() {
        let v = solid_cylinder(0.5, 2.0);
        let sh = Shell::of_volume(&v).unwrap();
        // Side (with a seam) and two disks (each a pole and a radial seam): three faces.
        assert!(sh.closed, "{:?}", sh.edge_uses());
        assert_eq!(sh.faces.len(), 3);
        assert!(sh.edge_uses().iter().all(|&u| u == (1, 1)));
        let exact = PI * 0.25 * 2.0;
        assert!(
            (sh.volume(20) - exact).abs() < 1e-12 * exact,
            "{}",
            sh.volume(20)
        );
    }

    #[test]
    fn many_patches_share_vertices_and_edges() {
        // A 50 x 50 grid of bilinear patches on a wavy sheet: (n+1)^2 vertices, 2 n (n+1)
        // edges, inner edges used twice in opposite directions (hash lookups, not pairwise).
        let n = 50;
        let at = |i: usize, j: usize| {
            let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
            Vec3::new(x, y, 0.1 * (7.0 * x).sin() * (5.0 * y).cos())
        };
        let lin = KnotVector::clamped_uniform(1, 2).unwrap();
        let patches: Vec<NurbsSurface> = (0..n * n)
            .map(|k| {
                let (i, j) = (k / n, k % n);
                let pts = vec![at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1)];
                NurbsSurface::from_flat([lin.clone(), lin.clone()], pts, vec![1.0; 4]).unwrap()
            })
            .collect();
        let sh = Shell::of_surfaces(&patches).unwrap();
        assert!(!sh.closed);
        assert_eq!(sh.vertices.len(), (n + 1) * (n + 1));
        assert_eq!(sh.edges.len(), 2 * n * (n + 1));
        let uses = sh.edge_uses();
        assert_eq!(
            uses.iter().filter(|&&u| u == (1, 1)).count(),
            2 * n * (n - 1)
        );
        assert!(sh.faces.iter().all(|f| f.same_sense));
    }

    #[test]
    fn volume_boundary_is_a_closed_outward_shell() {
        let v = NurbsVolume::box_lattice(
            [1, 2, 2],
            [2, 3, 4],
            Vec3::zeros(),
            Vec3::new(1.0, 2.0, 3.0),
        )
        .unwrap();
        let sh = Shell::of_volume(&v).unwrap();
        assert!(sh.closed);
        assert_eq!(
            (sh.vertices.len(), sh.edges.len(), sh.faces.len()),
            (8, 12, 6)
        );
        assert!(sh.edge_uses().iter().all(|&u| u == (1, 1)));
        assert!((sh.volume(6) - 6.0).abs() < 1e-12);
        // Faces u = u0, v = v1, w = w0 have inward surface normals for a right-handed volume.
        let senses: Vec<bool> = sh.faces.iter().map(|f| f.same_sense).collect();
        assert_eq!(senses, [false, true, true, false, false, true]);
    }
}
