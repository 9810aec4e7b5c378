//! Trimmed B-rep models (issue 30): faces that are a NURBS surface bounded by outer and inner
//! loops of shared edges, each edge use with its curve in the face's parameter space.
//!
//! **What.** A trimmed model is the model's entities (the faces' surfaces among them) and a list
//! of [`Shell`]s (the types of [`crate::brep`]) whose faces carry the trims:
//!
//! - [`Vertex`]es and [`Edge`]s are shared: an edge is an exact NURBS curve from its start vertex
//!   (at the curve's first parameter) to its end vertex (at its last), used by the loops of the
//!   faces it bounds (twice, in opposite directions, in a closed shell; twice in the same loop
//!   for the seam of a closed surface);
//! - a [`Face`] refers to its surface entity ([`Face::entity`]), has a sense
//!   ([`Face::same_sense`]: `false` when its outward normal is `-(S_u x S_v)`), an outer loop
//!   ([`Face::bound`]) and inner loops ([`Face::holes`]); each [`LoopItem::Edge`] says which
//!   way the loop runs along the edge and which of the face's [`Face::pcurves`] is the edge in
//!   the surface's NURBS parameters (points `(u, v, 0)`), running in the edge's direction;
//! - a shell is closed when every edge is used exactly twice in opposite directions: a solid.
//!
//! The loops live in the surface's parameter space, so a face keeps its trims when its surface's
//! control points move (sculpting): the pcurves do not change, the 3D edges are those of the
//! surface along them.
//!
//! **How.** [`shells_of_import`] builds the shells of a STEP import from its
//! [`TrimmedFace`]s: vertices and edges merged by their STEP ids (`VERTEX_POINT`,
//! `EDGE_CURVE`), faces grouped into shells by the edges they share, the B-spline part of an
//! edge cut out exactly by knot insertion ([`curve_part`]), a bound with orientation `.F.`
//! reversed, the loop flagged `FACE_OUTER_BOUND` (or, when no loop is, the one whose pcurves
//! span the largest parameter box) made the outer one. Pcurves are mapped from the STEP
//! surface's parameters to those of its NURBS: exactly (the curve itself) when both directions
//! keep the file's parameter (planes, B-spline surfaces, the height of cylinders and cones),
//! and along an angle direction ([`ParamAxis::Angle`]) exactly for iso-parameter lines (a
//! straight segment between the mapped ends) and otherwise as a polyline through
//! [`PCURVE_POLYLINE_POINTS`] mapped points (exact at those points; [`Face`]s with such
//! pcurves are marked by [`pcurves_exact`] returning `false`). A seam's two pcurves are given
//! to its two uses by continuity with the neighbouring uses.
//!
//! [`validate_shell`] checks a shell (indices, loops closed through shared vertices, edge curves
//! ending at their vertices, pcurves ending on the surface at the use's vertices) within
//! `TRIM_RTOL x size` (`size` the diagonal of the vertices' bounding box); the JSON reader
//! ([`crate::model`]) and [`shells_of_import`] run it, so a located error names the shell, face,
//! loop and use.
//!
//! **Limitations.** Faces on surfaces of a type not read, and edges whose curves are not read,
//! leave their shell open (warned about by the STEP reader). Faces are not split at the seam:
//! a surface's parameter box is the whole converted surface. Pcurves on angle-parametrized
//! surfaces that are not iso-lines are polylines (see above).

pub mod mesh;
pub mod sculpt;

pub use mesh::{MAX_SHELL_SAMPLES, tessellate_shell, tessellate_shell_faces};

use crate::brep::{Edge, Face, LoopItem, Shell, Vertex, closure_tolerance};
use crate::error::IoError;
use crate::step_read::{CadImport, ParamAxis, TrimEdge, TrimmedFace};
use std::collections::HashMap;
use vclay_core::Vec3;
use vclay_spline::{NurbsCurve, NurbsSurface, ParametricCurve, ParametricSurface};

/// Relative tolerance of [`validate_shell`]: points that must coincide (a curve's end and its
/// vertex, a pcurve's end on the surface and its vertex) may be `TRIM_RTOL x size` apart,
/// `size` the diagonal of the bounding box of the shell's vertices. CAD files round their
/// points to about 1e-12 relative and their precision is 1e-7 mm; 1e-6 relative accepts them
/// and still catches a loop that does not close.
pub const TRIM_RTOL: f64 = 1e-6;

/// Points of the polyline that stands for a pcurve that is not an iso-line on an
/// angle-parametrized surface (a cylinder's intersection with a plane at an angle).
pub const PCURVE_POLYLINE_POINTS: usize = 65;

/// The part `[a, b]` of a curve as a curve of its own (exact: knots inserted at `a` and `b`
/// up to the degree, Piegl & Tiller A5.1, and the control points between taken), parametrized
/// on `[a, b]` with clamped ends. `a < b` inside the curve's domain (values within the knot
/// vector's parameter tolerance of a knot or of the domain's ends are snapped to it).
pub fn curve_part(c: &NurbsCurve, a: f64, b: f64) -> Result<NurbsCurve, String> {
    let mut c = if c.knots().is_clamped() {
        c.clone()
    } else {
        c.clamped().map_err(|e| e.to_string())?
    };
    let d = c.domain();
    let tol = c.knots().parameter_tolerance();
    let snap = |x: f64, c: &NurbsCurve| -> f64 {
        c.knots()
            .as_slice()
            .iter()
            .copied()
            .find(|k| (k - x).abs() <= tol)
            .unwrap_or(x)
    };
    let (a, b) = (snap(a, &c), snap(b, &c));
    if !(a < b && a >= d.min - tol && b <= d.max + tol) {
        return Err(format!(
            "part [{a}, {b}] is not an increasing range inside the curve's domain [{}, {}]",
            d.min, d.max
        ));
    }
    let (a, b) = (a.max(d.min), b.min(d.max));
    let p = c.degree();
    for x in [a, b] {
        if x > d.min && x < d.max {
            let m = c.knots().multiplicity(x);
            if m < p {
                c = c.insert_knot(x, p - m).map_err(|e| e.to_string())?;
            }
        }
    }
    let u = c.knots().as_slice();
    // C(a) = P[s - p] with s the last index of a knot equal to a; C(b) = P[r - 1] with r the
    // first index of a knot equal to b.
    let s = u
        .iter()
        .rposition(|&k| k == a)
        .ok_or("start knot not found")?;
    let r = u.iter().position(|&k| k == b).ok_or("end knot not found")?;
    if s < p || r < s + 1 || r < 1 {
        return Err("inconsistent knots after insertion".into());
    }
    let mut knots = vec![a; p + 1];
    knots.extend_from_slice(&u[s + 1..r]);
    knots.extend(std::iter::repeat_n(b, p + 1));
    let pts = c.control_points()[s - p..r].to_vec();
    let ws = c.weights()[s - p..r].to_vec();
    NurbsCurve::new(p, knots, pts, Some(ws)).map_err(|e| e.to_string())
}

/// Makes the coordinate `axis` of the points of a sampled curve continuous across the seam of
/// a full turn `[start, end]` (each point moved by whole periods toward its neighbour, from the
/// middle point out), then moves them all by one period when that brings them inside the turn
/// (within `rtol` of the period). The samples of a pcurve on a closed surface come wrapped into
/// the turn one by one; this makes them one curve again.
pub(crate) fn unwrap_turn<P>(pts: &mut [P], axis: usize, [start, end]: [f64; 2], rtol: f64)
where
    P: std::ops::IndexMut<usize, Output = f64>,
{
    let n = pts.len();
    if n == 0 {
        return;
    }
    let period = end - start;
    let mid = n / 2;
    for k in (0..mid).rev().chain(mid + 1..n) {
        let near = if k < mid {
            pts[k + 1][axis]
        } else {
            pts[k - 1][axis]
        };
        pts[k][axis] += ((near - pts[k][axis]) / period).round() * period;
    }
    let (lo, hi) = pts.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |m, p| {
        (m.0.min(p[axis]), m.1.max(p[axis]))
    });
    let eps = rtol * period;
    let shift = if lo < start - eps {
        period
    } else if hi > end + eps {
        -period
    } else {
        0.0
    };
    if shift != 0.0 && lo + shift >= start - eps && hi + shift <= end + eps {
        pts.iter_mut().for_each(|p| p[axis] += shift);
    }
}

/// Whether every pcurve of the face is exact (not a polyline standing for a curve on an angle
/// direction; see the module documentation): true unless a pcurve is of degree 1 with more than
/// two control points.
pub fn pcurves_exact(face: &Face) -> bool {
    face.pcurves
        .iter()
        .all(|c| c.degree() > 1 || c.control_points().len() == 2)
}

/// A pcurve of a STEP face (in the surface's file parameters, over `range`) in the NURBS
/// parameters of the converted surface.
fn pcurve_in_nurbs_params(
    face: &TrimmedFace,
    pc: &NurbsCurve,
    range: [f64; 2],
) -> Result<NurbsCurve, String> {
    let linear = face.axes.iter().all(|a| matches!(a, ParamAxis::Linear));
    if linear {
        let d = pc.domain();
        return if (range[0] - d.min).abs() <= pc.knots().parameter_tolerance()
            && (range[1] - d.max).abs() <= pc.knots().parameter_tolerance()
        {
            Ok(pc.clone())
        } else {
            curve_part(pc, range[0], range[1])
        };
    }
    let n = PCURVE_POLYLINE_POINTS;
    let mut pts = Vec::with_capacity(n);
    for k in 0..n {
        let t = range[0] + (range[1] - range[0]) * k as f64 / (n - 1) as f64;
        let q = pc.point(t).map_err(|e| e.to_string())?;
        let [u, v] = face.to_nurbs_params(q.x, q.y);
        pts.push(Vec3::new(u, v, 0.0));
    }
    // `to_nurbs` wraps each point into the turn: make the curve continuous again (from its
    // middle point), then bring it into the turn as far as it goes.
    for (axis, a) in face.axes.iter().enumerate() {
        if let ParamAxis::Angle {
            start,
            end,
            periodic: true,
            ..
        } = *a
        {
            unwrap_turn(&mut pts, axis, [start, end], 1e-12);
        }
    }
    let scale = pts
        .iter()
        .fold(1.0f64, |m, p| m.max(p.x.abs()).max(p.y.abs()));
    let iso = |k: usize| {
        pts.iter()
            .all(|p| (p[k] - pts[0][k]).abs() <= 1e-12 * scale)
    };
    let pts = if iso(0) || iso(1) {
        vec![pts[0], pts[n - 1]]
    } else {
        pts
    };
    let m = pts.len();
    let mut knots = vec![range[0]; 2];
    for k in 1..m - 1 {
        knots.push(range[0] + (range[1] - range[0]) * k as f64 / (m - 1) as f64);
    }
    knots.extend([range[1]; 2]);
    NurbsCurve::new(1, knots, pts, None).map_err(|e| e.to_string())
}

/// An edge's 3D curve from its start to its end vertex: the part of a B-spline given by the
/// edge's range, or the exact arc or segment the reader built.
fn edge_curve(e: &TrimEdge) -> Result<NurbsCurve, String> {
    let d = e.curve.domain();
    let tol = e.curve.knots().parameter_tolerance();
    if (e.range[0] - d.min).abs() <= tol && (e.range[1] - d.max).abs() <= tol {
        Ok(e.curve.clone())
    } else {
        curve_part(&e.curve, e.range[0], e.range[1])
    }
}

fn structure(path: String, message: impl Into<String>) -> IoError {
    IoError::Structure {
        path,
        message: message.into(),
    }
}

/// The shells of a STEP import's B-rep faces ([`CadImport::faces`]), with their trims: see the
/// module documentation. Faces whose surface is not a surface entity are skipped. Each shell is
/// validated ([`validate_shell`]); an error names the STEP face.
pub fn shells_of_import(import: &CadImport) -> Result<Vec<Shell>, IoError> {
    let faces: Vec<&TrimmedFace> = import
        .faces
        .iter()
        .filter(|f| {
            matches!(
                import.entities.get(f.entity).map(|e| &e.entity),
                Some(crate::model::Entity::Surface(_))
            )
        })
        .collect();
    // Faces joined by shared EDGE_CURVEs (union-find).
    let mut parent: Vec<usize> = (0..faces.len()).collect();
    fn root(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    let mut first_face_of_edge: HashMap<usize, usize> = HashMap::new();
    for (k, f) in faces.iter().enumerate() {
        for e in f.loops.iter().flat_map(|l| &l.edges) {
            match first_face_of_edge.get(&e.step_id) {
                Some(&other) => {
                    let (a, b) = (root(&mut parent, k), root(&mut parent, other));
                    parent[a] = b;
                }
                None => {
                    first_face_of_edge.insert(e.step_id, k);
                }
            }
        }
    }
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut group_of: HashMap<usize, usize> = HashMap::new();
    for k in 0..faces.len() {
        let r = root(&mut parent, k);
        let g = *group_of.entry(r).or_insert_with(|| {
            groups.push(Vec::new());
            groups.len() - 1
        });
        groups[g].push(k);
    }
    let mut shells = Vec::with_capacity(groups.len());
    for g in groups {
        let members: Vec<&TrimmedFace> = g.iter().map(|&k| faces[k]).collect();
        let sh = shell_of_faces(import, &members)?;
        validate_shell(&sh).map_err(|(f, m)| {
            structure(
                format!("STEP face #{}", members[f.min(members.len() - 1)].step_id),
                m,
            )
        })?;
        shells.push(sh);
    }
    Ok(shells)
}

/// One shell of STEP faces that share edges.
fn shell_of_faces(import: &CadImport, faces: &[&TrimmedFace]) -> Result<Shell, IoError> {
    let mut vertices: Vec<Vertex> = Vec::new();
    let mut vmap: HashMap<usize, usize> = HashMap::new();
    let mut edges: Vec<Edge> = Vec::new();
    let mut emap: HashMap<usize, usize> = HashMap::new();
    let mut out_faces = Vec::with_capacity(faces.len());
    for f in faces {
        let at = |m: String| structure(format!("STEP face #{}", f.step_id), m);
        let Some(crate::model::Entity::Surface(surface)) =
            import.entities.get(f.entity).map(|e| &e.entity)
        else {
            return Err(at("its surface is not a surface entity".into()));
        };
        let surface = clamp(surface).map_err(at)?;
        let mut pcurves: Vec<NurbsCurve> = Vec::new();
        let mut loops: Vec<(bool, Vec<LoopItem>)> = Vec::new();
        for l in &f.loops {
            if l.edges.is_empty() {
                continue;
            }
            // (item, candidate pcurves in loop direction) per use.
            let mut uses: Vec<(usize, bool, Vec<NurbsCurve>)> = Vec::new();
            let order: Vec<&TrimEdge> = if l.orientation {
                l.edges.iter().collect()
            } else {
                l.edges.iter().rev().collect()
            };
            for e in order {
                let forward = e.forward == l.orientation;
                let mut vid = [0; 2];
                for (k, (sid, p)) in e.vertices.iter().enumerate() {
                    vid[k] = *vmap.entry(*sid).or_insert_with(|| {
                        vertices.push(Vertex { point: *p });
                        vertices.len() - 1
                    });
                }
                let edge = match emap.get(&e.step_id) {
                    Some(&i) => i,
                    None => {
                        let curve =
                            edge_curve(e).map_err(|m| at(format!("edge #{}: {m}", e.step_id)))?;
                        edges.push(Edge {
                            curve,
                            start: vid[0],
                            end: vid[1],
                        });
                        emap.insert(e.step_id, edges.len() - 1);
                        edges.len() - 1
                    }
                };
                let mut cands = Vec::new();
                if let Some(pc) = &e.pcurve {
                    cands.push(
                        pcurve_in_nurbs_params(f, pc, e.pcurve_range)
                            .map_err(|m| at(format!("edge #{} pcurve: {m}", e.step_id)))?,
                    );
                }
                if let Some((pc, r, _)) = &e.seam_pcurve {
                    cands.push(
                        pcurve_in_nurbs_params(f, pc, *r)
                            .map_err(|m| at(format!("edge #{} pcurve: {m}", e.step_id)))?,
                    );
                }
                uses.push((edge, forward, cands));
            }
            let chosen = choose_pcurves(&uses);
            let items = uses
                .iter()
                .zip(chosen)
                .map(|((edge, forward, _), pc)| LoopItem::Edge {
                    edge: *edge,
                    forward: *forward,
                    pcurve: pc.map(|c| {
                        pcurves.push(c);
                        pcurves.len() - 1
                    }),
                })
                .collect();
            loops.push((l.outer, items));
        }
        // The outer loop: flagged, else the one spanning the largest parameter box.
        let outer = loops.iter().position(|l| l.0).unwrap_or_else(|| {
            let area = |items: &[LoopItem]| {
                let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
                for it in items {
                    if let LoopItem::Edge {
                        pcurve: Some(k), ..
                    } = it
                    {
                        for p in pcurves[*k].control_points() {
                            for a in 0..2 {
                                lo[a] = lo[a].min(p[a]);
                                hi[a] = hi[a].max(p[a]);
                            }
                        }
                    }
                }
                ((hi[0] - lo[0]) * (hi[1] - lo[1])).max(0.0)
            };
            (0..loops.len())
                .max_by(|&a, &b| area(&loops[a].1).total_cmp(&area(&loops[b].1)))
                .unwrap_or(0)
        });
        let mut bound = Vec::new();
        let mut holes = Vec::new();
        for (k, (_, items)) in loops.into_iter().enumerate() {
            if k == outer {
                bound = items;
            } else {
                holes.push(items);
            }
        }
        out_faces.push(Face {
            surface,
            same_sense: f.same_sense,
            bound,
            holes,
            pcurves,
            entity: Some(f.entity),
        });
    }
    Ok(finish(vertices, edges, out_faces))
}

/// Gives each use one of its candidate pcurves, in loop direction: a seam's two pcurves go to
/// the use whose neighbours they continue (ends nearest in parameter space).
fn choose_pcurves(uses: &[(usize, bool, Vec<NurbsCurve>)]) -> Vec<Option<NurbsCurve>> {
    let n = uses.len();
    let ends = |c: &NurbsCurve, forward: bool| -> Option<[Vec3; 2]> {
        let d = c.domain();
        let (a, b) = (c.point(d.min).ok()?, c.point(d.max).ok()?);
        Some(if forward { [a, b] } else { [b, a] })
    };
    // Ends of the uses with a single candidate (fixed).
    let fixed: Vec<Option<[Vec3; 2]>> = uses
        .iter()
        .map(|(_, f, c)| if c.len() == 1 { ends(&c[0], *f) } else { None })
        .collect();
    let mut taken: HashMap<usize, usize> = HashMap::new();
    let mut out = Vec::with_capacity(n);
    for (k, (edge, forward, cands)) in uses.iter().enumerate() {
        if cands.len() < 2 {
            out.push(cands.first().cloned());
            continue;
        }
        let prev = fixed[(k + n - 1) % n].map(|e| e[1]);
        let next = fixed[(k + 1) % n].map(|e| e[0]);
        let cost = |c: &NurbsCurve| -> f64 {
            let Some([a, b]) = ends(c, *forward) else {
                return f64::INFINITY;
            };
            prev.map_or(0.0, |p| (p - a).norm()) + next.map_or(0.0, |q| (q - b).norm())
        };
        let pick = match taken.get(edge) {
            // The seam's other use takes the other pcurve.
            Some(&used) => 1 - used,
            None => {
                if cost(&cands[1]) < cost(&cands[0]) {
                    1
                } else {
                    0
                }
            }
        };
        taken.insert(*edge, pick);
        out.push(Some(cands[pick].clone()));
    }
    out
}

fn clamp(s: &NurbsSurface) -> Result<NurbsSurface, String> {
    let mut s = s.clone();
    for axis in 0..2 {
        if !s.knots()[axis].is_clamped() {
            s = s.clamped(axis).map_err(|e| e.to_string())?;
        }
    }
    Ok(s)
}

/// A shell of trimmed faces from its parts: closed when every edge is used exactly twice in
/// opposite directions; the tolerance is [`closure_tolerance`] of its vertices.
pub fn finish(vertices: Vec<Vertex>, edges: Vec<Edge>, faces: Vec<Face>) -> Shell {
    let pts: Vec<Vec3> = vertices.iter().map(|v| v.point).collect();
    let mut sh = Shell {
        tolerance: closure_tolerance(&pts),
        vertices,
        edges,
        faces,
        closed: false,
    };
    sh.closed = !sh.edges.is_empty() && sh.edge_uses().iter().all(|&u| u == (1, 1));
    sh
}

/// Counts of a shell's topology: vertices, edges, faces, loops.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Topology {
    /// Vertices.
    pub vertices: usize,
    /// Edges.
    pub edges: usize,
    /// Faces.
    pub faces: usize,
    /// Loops (outer and inner).
    pub loops: usize,
}

impl Topology {
    /// The counts of a shell.
    pub fn of(shell: &Shell) -> Self {
        Topology {
            vertices: shell.vertices.len(),
            edges: shell.edges.len(),
            faces: shell.faces.len(),
            loops: shell.faces.iter().map(|f| f.loops().count()).sum(),
        }
    }

    /// The Euler-Poincare characteristic `V - E + F - (L - F)` (`L - F` the inner loops), equal
    /// to `2 (1 - g)` for a closed shell of genus `g` whose faces are each one disc with holes.
    pub fn euler(&self) -> i64 {
        self.vertices as i64 - self.edges as i64 + 2 * self.faces as i64 - self.loops as i64
    }
}

/// Where a check of [`validate_shell`] failed: the face index (or the edge index for edge
/// errors, reported as face 0) and a message naming the loop and use.
pub type ShellError = (usize, String);

/// Checks a trimmed shell: every index in range, each edge curve starting and ending at its
/// vertices, every loop closed through shared vertices (each use ends where the next starts),
/// each pcurve inside its surface's domain with its ends on the surface at the use's vertices,
/// all within `TRIM_RTOL x size`. The error names the face, loop and use
/// (`face 3 loop 1 use 2 (edge 7): ...`).
pub fn validate_shell(shell: &Shell) -> Result<(), ShellError> {
    let pts: Vec<Vec3> = shell.vertices.iter().map(|v| v.point).collect();
    let size = closure_tolerance(&pts) / crate::brep::CLOSURE_RTOL;
    let tol = TRIM_RTOL * size.max(f64::MIN_POSITIVE);
    let nv = shell.vertices.len();
    for (k, e) in shell.edges.iter().enumerate() {
        let msg = |m: String| (0, format!("edge {k}: {m}"));
        if e.start >= nv || e.end >= nv {
            return Err(msg(format!(
                "vertex {} or {} out of range ({nv} vertices)",
                e.start, e.end
            )));
        }
        let d = e.curve.domain();
        for (t, v, which) in [(d.min, e.start, "start"), (d.max, e.end, "end")] {
            let p = e.curve.point(t).map_err(|x| msg(x.to_string()))?;
            let gap = (p - shell.vertices[v].point).norm();
            if gap > tol {
                return Err(msg(format!(
                    "the curve's {which} is {gap:.3e} from vertex {v} (tolerance {tol:.3e})"
                )));
            }
        }
    }
    for (fi, f) in shell.faces.iter().enumerate() {
        for (li, l) in f.loops().enumerate() {
            let n = l.len();
            let ends = |it: &LoopItem| -> Result<[usize; 2], String> {
                match *it {
                    LoopItem::Pole { vertex } if vertex < nv => Ok([vertex, vertex]),
                    LoopItem::Pole { vertex } => Err(format!("pole vertex {vertex} out of range")),
                    LoopItem::Edge { edge, forward, .. } => {
                        let e = shell
                            .edges
                            .get(edge)
                            .ok_or(format!("edge {edge} out of range"))?;
                        Ok(if forward {
                            [e.start, e.end]
                        } else {
                            [e.end, e.start]
                        })
                    }
                }
            };
            if n == 0 {
                return Err((fi, format!("loop {li} is empty")));
            }
            for (ui, it) in l.iter().enumerate() {
                let at = |m: String| {
                    let e = match it {
                        LoopItem::Edge { edge, .. } => format!(" (edge {edge})"),
                        LoopItem::Pole { .. } => " (pole)".into(),
                    };
                    (fi, format!("loop {li} use {ui}{e}: {m}"))
                };
                let [_, b] = ends(it).map_err(at)?;
                let [a2, _] = ends(&l[(ui + 1) % n]).map_err(at)?;
                if b != a2 {
                    return Err(at(format!(
                        "ends at vertex {b} but the next use starts at vertex {a2}: the loop is \
                         not closed"
                    )));
                }
                let LoopItem::Edge {
                    edge,
                    forward,
                    pcurve: Some(pk),
                } = *it
                else {
                    continue;
                };
                let pc = f
                    .pcurves
                    .get(pk)
                    .ok_or_else(|| at(format!("pcurve {pk} out of range")))?;
                let e = &shell.edges[edge];
                let d = pc.domain();
                let sd = f.surface.domain();
                let ptol = 1e-9 * (sd[0].max - sd[0].min).max(sd[1].max - sd[1].min);
                for (t, v, which) in [(d.min, e.start, "start"), (d.max, e.end, "end")] {
                    let q = pc.point(t).map_err(|x| at(x.to_string()))?;
                    let (u, w) = (q.x, q.y);
                    if u < sd[0].min - ptol
                        || u > sd[0].max + ptol
                        || w < sd[1].min - ptol
                        || w > sd[1].max + ptol
                    {
                        return Err(at(format!(
                            "the pcurve's {which} ({u}, {w}) is outside the surface's domain"
                        )));
                    }
                    let s = f
                        .surface
                        .point(u.clamp(sd[0].min, sd[0].max), w.clamp(sd[1].min, sd[1].max))
                        .map_err(|x| at(x.to_string()))?;
                    let gap = (s - shell.vertices[v].point).norm();
                    if gap > tol {
                        return Err(at(format!(
                            "the pcurve's {which} lies {gap:.3e} from vertex {v} on the \
                             surface (tolerance {tol:.3e})"
                        )));
                    }
                }
                let _ = forward;
            }
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// JSON form (docs/formats.md, "Trimmed B-rep shells")

use crate::json::{self, JsonPath};
use crate::model::NamedEntity;
use serde_json::{Map, Value};

/// Fields of a shell, an edge, a face and an edge use.
const SHELL_FIELDS: [&str; 3] = ["vertices", "edges", "faces"];
const EDGE_FIELDS: [&str; 3] = ["start", "end", "curve"];
const FACE_FIELDS: [&str; 3] = ["surface", "same_sense", "loops"];
const USE_FIELDS: [&str; 3] = ["edge", "forward", "pcurve"];
const CURVE_FIELDS: [&str; 4] = ["degree", "knots", "control_points", "weights"];

fn object<'a>(
    v: &'a Value,
    path: &JsonPath,
    what: &str,
    fields: &[&str],
) -> Result<&'a Map<String, Value>, IoError> {
    let Value::Object(o) = v else {
        return Err(path.expected(what, v));
    };
    if let Some(k) = o.keys().find(|k| !fields.contains(&k.as_str())) {
        return Err(path.error(format!(
            "unknown field {} (allowed: {})",
            crate::error::quote(k),
            fields.join(", ")
        )));
    }
    Ok(o)
}

fn field<'a>(o: &'a Map<String, Value>, k: &str, path: &JsonPath) -> Result<&'a Value, IoError> {
    o.get(k)
        .ok_or_else(|| path.error(format!("missing field \"{k}\"")))
}

fn boolean(v: &Value, path: &JsonPath) -> Result<bool, IoError> {
    v.as_bool().ok_or_else(|| path.expected("true or false", v))
}

/// A curve object `{"degree", "knots", "control_points", "weights"?}` with points of `dim`
/// coordinates (3, or 2 for a pcurve, whose z is 0).
fn curve_from_json(v: &Value, path: &JsonPath, dim: usize) -> Result<NurbsCurve, IoError> {
    let o = object(v, path, "a curve object", &CURVE_FIELDS)?;
    let degree = json::integer(field(o, "degree", path)?, &path.key("degree"))?;
    let knots = crate::model::numbers(field(o, "knots", path)?, &path.key("knots"))?;
    let cp = path.key("control_points");
    let pts = match dim {
        3 => crate::model::points1(field(o, "control_points", path)?, &cp)?,
        _ => json::array(field(o, "control_points", path)?, &cp, "an array of [u, v]")?
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let pp = cp.index(i);
                match p.as_array() {
                    Some(a) if a.len() == 2 => Ok(Vec3::new(
                        json::number(&a[0], &pp.index(0))?,
                        json::number(&a[1], &pp.index(1))?,
                        0.0,
                    )),
                    _ => Err(pp.expected("an array of 2 numbers", p)),
                }
            })
            .collect::<Result<Vec<_>, _>>()?,
    };
    let weights = o
        .get("weights")
        .map(|w| crate::model::numbers(w, &path.key("weights")))
        .transpose()?;
    NurbsCurve::new(degree, knots, pts, weights).map_err(|e| path.error(e.to_string()))
}

fn curve_to_json(c: &NurbsCurve, dim: usize) -> Value {
    use crate::model::{num, nums};
    let mut m = Map::new();
    m.insert("degree".into(), Value::from(c.degree()));
    m.insert("knots".into(), nums(c.knots().as_slice()));
    m.insert(
        "control_points".into(),
        Value::Array(
            c.control_points()
                .iter()
                .map(|p| Value::Array(p.iter().take(dim).map(|&x| num(x)).collect()))
                .collect(),
        ),
    );
    if c.weights().iter().any(|&w| w != 1.0) {
        m.insert("weights".into(), nums(c.weights()));
    }
    Value::Object(m)
}

/// The JSON object of a trimmed shell: `{"vertices": [[x, y, z], ...], "edges": [{"start",
/// "end", "curve"}], "faces": [{"surface": entity index, "same_sense", "loops": [[{"edge",
/// "forward", "pcurve"?}, ...], ...]}]}`, the outer loop first. Faces without
/// [`Face::entity`] are written with `"surface": null` (they cannot be read back).
pub fn shell_to_json(shell: &Shell) -> Value {
    let mut m = Map::new();
    m.insert(
        "vertices".into(),
        Value::Array(
            shell
                .vertices
                .iter()
                .map(|v| Value::Array(v.point.iter().map(|&x| crate::model::num(x)).collect()))
                .collect(),
        ),
    );
    let edges = shell
        .edges
        .iter()
        .map(|e| {
            let mut o = Map::new();
            o.insert("start".into(), Value::from(e.start));
            o.insert("end".into(), Value::from(e.end));
            o.insert("curve".into(), curve_to_json(&e.curve, 3));
            Value::Object(o)
        })
        .collect();
    m.insert("edges".into(), Value::Array(edges));
    let faces = shell
        .faces
        .iter()
        .map(|f| {
            let mut o = Map::new();
            o.insert("surface".into(), f.entity.map_or(Value::Null, Value::from));
            o.insert("same_sense".into(), Value::Bool(f.same_sense));
            let loops = f
                .loops()
                .map(|l| {
                    Value::Array(
                        l.iter()
                            .filter_map(|it| match *it {
                                LoopItem::Edge {
                                    edge,
                                    forward,
                                    pcurve,
                                } => {
                                    let mut u = Map::new();
                                    u.insert("edge".into(), Value::from(edge));
                                    u.insert("forward".into(), Value::Bool(forward));
                                    if let Some(k) = pcurve {
                                        u.insert("pcurve".into(), curve_to_json(&f.pcurves[k], 2));
                                    }
                                    Some(Value::Object(u))
                                }
                                LoopItem::Pole { .. } => None,
                            })
                            .collect(),
                    )
                })
                .collect();
            o.insert("loops".into(), Value::Array(loops));
            Value::Object(o)
        })
        .collect();
    m.insert("faces".into(), Value::Array(faces));
    Value::Object(m)
}

/// The shells of a model's `"shells"` array (see [`shell_to_json`]), each face's surface taken
/// from `entities` and each shell validated ([`validate_shell`]); errors are located
/// (`shells[0].faces[3].loops[1][2].edge: edge 40 out of range (12 edges)`).
pub(crate) fn shells_from_json(
    v: &Value,
    path: &JsonPath,
    entities: &[NamedEntity],
) -> Result<Vec<Shell>, IoError> {
    let list = json::array(v, path, "an array of shells")?;
    let mut out = Vec::with_capacity(list.len());
    for (si, sv) in list.iter().enumerate() {
        let sp = path.index(si);
        let o = object(sv, &sp, "a shell object", &SHELL_FIELDS)?;
        let vp = sp.key("vertices");
        let vertices: Vec<Vertex> = crate::model::points1(field(o, "vertices", &sp)?, &vp)?
            .into_iter()
            .map(|point| Vertex { point })
            .collect();
        let ep = sp.key("edges");
        let mut edges = Vec::new();
        for (ei, ev) in json::array(field(o, "edges", &sp)?, &ep, "an array of edges")?
            .iter()
            .enumerate()
        {
            let p = ep.index(ei);
            let eo = object(ev, &p, "an edge object", &EDGE_FIELDS)?;
            let mut ends = [0; 2];
            for (k, name) in ["start", "end"].into_iter().enumerate() {
                let i = json::integer(field(eo, name, &p)?, &p.key(name))?;
                if i >= vertices.len() {
                    return Err(p.key(name).error(format!(
                        "vertex {i} out of range ({} vertices)",
                        vertices.len()
                    )));
                }
                ends[k] = i;
            }
            let curve = curve_from_json(field(eo, "curve", &p)?, &p.key("curve"), 3)?;
            edges.push(Edge {
                curve,
                start: ends[0],
                end: ends[1],
            });
        }
        let fp = sp.key("faces");
        let mut faces = Vec::new();
        for (fi, fv) in json::array(field(o, "faces", &sp)?, &fp, "an array of faces")?
            .iter()
            .enumerate()
        {
            let p = fp.index(fi);
            let fo = object(fv, &p, "a face object", &FACE_FIELDS)?;
            let k = json::integer(field(fo, "surface", &p)?, &p.key("surface"))?;
            let surface = match entities.get(k).map(|e| &e.entity) {
                Some(crate::model::Entity::Surface(s)) => {
                    clamp(s).map_err(|m| p.key("surface").error(m))?
                }
                Some(e) => {
                    return Err(p.key("surface").error(format!(
                        "entity {k} is a {}, not a nurbs-surface",
                        e.type_name()
                    )));
                }
                None => {
                    return Err(p.key("surface").error(format!(
                        "entity {k} out of range ({} entities)",
                        entities.len()
                    )));
                }
            };
            let same_sense = boolean(field(fo, "same_sense", &p)?, &p.key("same_sense"))?;
            let lp = p.key("loops");
            let mut pcurves = Vec::new();
            let mut loops = Vec::new();
            for (li, lv) in json::array(field(fo, "loops", &p)?, &lp, "an array of loops")?
                .iter()
                .enumerate()
            {
                let lpp = lp.index(li);
                let mut items = Vec::new();
                for (ui, uv) in json::array(lv, &lpp, "an array of edge uses")?
                    .iter()
                    .enumerate()
                {
                    let up = lpp.index(ui);
                    let uo = object(uv, &up, "an edge use object", &USE_FIELDS)?;
                    let edge = json::integer(field(uo, "edge", &up)?, &up.key("edge"))?;
                    if edge >= edges.len() {
                        return Err(up
                            .key("edge")
                            .error(format!("edge {edge} out of range ({} edges)", edges.len())));
                    }
                    let forward = boolean(field(uo, "forward", &up)?, &up.key("forward"))?;
                    let pcurve = match uo.get("pcurve") {
                        None | Some(Value::Null) => None,
                        Some(c) => {
                            pcurves.push(curve_from_json(c, &up.key("pcurve"), 2)?);
                            Some(pcurves.len() - 1)
                        }
                    };
                    items.push(LoopItem::Edge {
                        edge,
                        forward,
                        pcurve,
                    });
                }
                if items.is_empty() {
                    return Err(lpp.error("a loop needs at least one edge use"));
                }
                loops.push(items);
            }
            if loops.is_empty() {
                return Err(lp.error("a face needs at least its outer loop"));
            }
            let bound = loops.remove(0);
            faces.push(Face {
                surface,
                same_sense,
                bound,
                holes: loops,
                pcurves,
                entity: Some(k),
            });
        }
        let sh = finish(vertices, edges, faces);
        validate_shell(&sh).map_err(|(f, m)| {
            if m.starts_with("edge ") {
                sp.key("edges").error(m)
            } else {
                fp.index(f).error(m)
            }
        })?;
        out.push(sh);
    }
    Ok(out)
}
