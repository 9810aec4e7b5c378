//! A trimmed face whose surface moves (issue 30: a CAD part's face sculpted as a D-NURBS).
//!
//! **What.** The loops of a [`Face`] live in its surface's parameter space (its pcurves), so a
//! face keeps its trims when the surface's control points move. What can break is the
//! *boundary*: the 3D edges the face shares with its neighbours are `S(c(t))`, the surface
//! along the pcurve `c`; when `S` moves there, the neighbours' edges (their own surfaces along
//! their pcurves) no longer meet it. This module gives the pieces a session needs:
//!
//! - [`refine_for_sculpting`]: the surface with enough control points to move (degree raised to
//!   at least [`SCULPT_MIN_DEGREE`], then knots inserted evenly between the surface's own knots;
//!   exact, Piegl & Tiller A5.9 and A5.1, so the surface and the pcurves' parameters are
//!   unchanged);
//! - [`boundary_control_points`]: the control points whose basis functions are non-zero
//!   somewhere on the face's pcurves. Holding them fixed keeps `S(c(t))`, and so every edge,
//!   exactly where it was, whatever the other control points do (a B-spline surface at
//!   `(u, v)` depends only on the control points whose support contains `(u, v)`);
//! - [`EdgeGap`] / [`face_edge_gaps`]: for each edge of the face, how far its new 3D edge
//!   (the new surface along the face's pcurve) is from the old edge curve and from the
//!   neighbouring face's side of it (the neighbour's surface along its pcurve), sampled at
//!   [`GAP_SAMPLES`] points;
//! - [`with_face_surface`]: the shell with the face's new surface, the 3D curves of the edges
//!   that moved by more than the tolerance recomputed from the pcurves on it (polylines through
//!   [`crate::trimmed::PCURVE_POLYLINE_POINTS`] points of `S(c(t))`, exact at those points) and
//!   their vertices moved to the new ends; edges within the tolerance keep their exact curves;
//! - [`mesh_volume`]: the volume a closed, outward oriented triangle mesh encloses (divergence
//!   theorem), vclay's own measure of a solid's volume.
//!
//! **Limitations.** The boundary set is found by sampling each pcurve densely (consecutive
//! samples closer than a quarter of the smallest knot span, supports widened by one sample
//! step), so it is a superset of the exact set; a pcurve that only grazes a support corner can
//! fix one control point more than needed. Recomputed edges are polylines, not exact curves.

use crate::brep::{Face, LoopItem, Shell};
use vclay_core::{TriMesh, Vec3};
use vclay_spline::{NurbsCurve, NurbsSurface, ParametricCurve, ParametricSurface};

/// The least degree of a face's surface made sculptable by [`refine_for_sculpting`] (a plane's
/// bilinear patch becomes a bicubic one, whose bending energy is not zero).
pub const SCULPT_MIN_DEGREE: usize = 3;
/// Points along an edge at which [`face_edge_gaps`] measures the distances.
pub const GAP_SAMPLES: usize = 65;
/// Most control points along one direction of a refined surface.
pub const MAX_SCULPT_POINTS: usize = 256;

/// The surface raised to degree at least [`SCULPT_MIN_DEGREE`] along each direction and given
/// at least `points[a]` control points along direction `a` by inserting knots: shared out
/// among the spans between the surface's own knots so that the longest resulting span is as
/// short as it can be, and spread evenly inside each (a surface without inner knots gets the
/// uniform grid of `points[a] - p` spans). Exact: the surface's points and parametrization do
/// not change.
pub fn refine_for_sculpting(s: &NurbsSurface, points: [usize; 2]) -> Result<NurbsSurface, String> {
    if let Some(n) = points
        .iter()
        .find(|&&n| !(2..=MAX_SCULPT_POINTS).contains(&n))
    {
        return Err(format!(
            "{n} control points along a direction: from 2 to {MAX_SCULPT_POINTS}"
        ));
    }
    let mut s = s.clone();
    for axis in 0..2 {
        let p = s.degree()[axis];
        if p < SCULPT_MIN_DEGREE {
            s = s
                .elevate_degree(axis, SCULPT_MIN_DEGREE - p)
                .map_err(|e| e.to_string())?;
        }
        let have = s.dims()[axis];
        if have >= points[axis] {
            continue;
        }
        // The knots to add are shared out among the spans between the surface's own knots,
        // one at a time to the span whose pieces would be longest (ties: the first), then
        // spread evenly inside each span; they are inserted in increasing order. A surface
        // without inner knots (a plane's patch) gets the uniform grid of `points - p` spans.
        // Filling that grid from the domain's start instead, as before, refined one end of a
        // surface that holds knots already (a circle's quarter joints): the last quarter of a
        // sphere stayed one span, all of whose control points touch the face's seam, so a
        // pull there moved nothing.
        let knots: Vec<f64> = s.knots()[axis]
            .distinct()
            .into_iter()
            .map(|(u, _)| u)
            .collect();
        let mut share = vec![0usize; knots.len().saturating_sub(1)];
        let piece = |i: usize, k: usize| (knots[i + 1] - knots[i]) / (k + 1) as f64;
        for _ in have..points[axis] {
            let i = (0..share.len())
                .max_by(|&a, &b| {
                    piece(a, share[a])
                        .total_cmp(&piece(b, share[b]))
                        .then(b.cmp(&a))
                })
                .ok_or("a knot vector without a span")?;
            share[i] += 1;
        }
        for (i, &k) in share.iter().enumerate() {
            let (a, len) = (knots[i], knots[i + 1] - knots[i]);
            for j in 1..=k {
                s = s
                    .insert_knot(axis, a + len * j as f64 / (k + 1) as f64, 1)
                    .map_err(|e| e.to_string())?;
            }
        }
    }
    Ok(s)
}

/// Samples of a pcurve as parameters `(u, v)`, dense enough that consecutive samples are
/// closer than `step` in both directions (the number of samples doubles from 64 up to 65,536).
fn pcurve_samples(c: &NurbsCurve, step: [f64; 2]) -> Result<(Vec<[f64; 2]>, [f64; 2]), String> {
    let d = c.domain();
    let mut n = 64usize;
    loop {
        let pts: Vec<[f64; 2]> = (0..=n)
            .map(|k| {
                let t = d.min + d.length() * k as f64 / n as f64;
                c.point(t).map(|q| [q.x, q.y]).map_err(|e| e.to_string())
            })
            .collect::<Result<_, _>>()?;
        let mut gap = [0.0f64; 2];
        for w in pts.windows(2) {
            gap[0] = gap[0].max((w[1][0] - w[0][0]).abs());
            gap[1] = gap[1].max((w[1][1] - w[0][1]).abs());
        }
        if (gap[0] <= step[0] && gap[1] <= step[1]) || n >= 65_536 {
            return Ok((pts, gap));
        }
        n *= 2;
    }
}

/// The control points (flat indices `i * nv + j`) of `surface` whose basis functions are not
/// zero somewhere on the pcurves of `face` (every loop): holding them keeps the face's edges in
/// place (see the module documentation). `surface` must be parametrized like the face's own
/// surface (a refinement of it).
pub fn boundary_control_points(face: &Face, surface: &NurbsSurface) -> Result<Vec<usize>, String> {
    let kv = surface.knots();
    let deg = surface.degree();
    let [nu, nv] = surface.dims();
    // A quarter of the smallest non-empty knot span per direction.
    let step = [0, 1].map(|a| {
        let k = kv[a].as_slice();
        let min = k
            .windows(2)
            .map(|w| w[1] - w[0])
            .filter(|&d| d > kv[a].parameter_tolerance())
            .fold(f64::INFINITY, f64::min);
        0.25 * min
    });
    let mut marked = vec![false; nu * nv];
    let mut any = false;
    for item in face.loops().flatten() {
        let LoopItem::Edge {
            pcurve: Some(k), ..
        } = *item
        else {
            continue;
        };
        let c = face
            .pcurves
            .get(k)
            .ok_or_else(|| format!("pcurve {k} out of range"))?;
        let (pts, gap) = pcurve_samples(c, step)?;
        any = true;
        for q in pts {
            // Closed supports [t_i, t_{i+p+1}] widened by one sample step.
            let range = |a: usize| {
                let t = kv[a].as_slice();
                let p = deg[a];
                let n = [nu, nv][a];
                let eps = gap[a] + kv[a].parameter_tolerance();
                (0..n)
                    .filter(|&i| t[i] - eps <= q[a] && q[a] <= t[i + p + 1] + eps)
                    .collect::<Vec<_>>()
            };
            let (iu, iv) = (range(0), range(1));
            for &i in &iu {
                for &j in &iv {
                    marked[i * nv + j] = true;
                }
            }
        }
    }
    if !any {
        // A whole surface (no pcurves): its boundary rows and columns.
        for i in 0..nu {
            for j in 0..nv {
                if i == 0 || j == 0 || i + 1 == nu || j + 1 == nv {
                    marked[i * nv + j] = true;
                }
            }
        }
    }
    Ok((0..nu * nv).filter(|&i| marked[i]).collect())
}

/// How far one edge of a sculpted face moved ([`face_edge_gaps`]).
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeGap {
    /// The edge (index in [`Shell::edges`]).
    pub edge: usize,
    /// The other face that uses it (`None` on an open boundary; the face itself on a seam).
    pub neighbour: Option<usize>,
    /// Largest distance between the new 3D edge (the new surface along the face's pcurve) and
    /// the old edge curve.
    pub moved: f64,
    /// Largest distance between the new 3D edge and the neighbour's side of the edge (its
    /// surface along its pcurve); `moved` where there is no neighbour.
    pub gap: f64,
}

/// The uses of edge `edge` in `face` other than the use `(face, loop, item)` itself.
fn other_use(shell: &Shell, edge: usize, not: (usize, usize, usize)) -> Option<(usize, usize)> {
    for (fi, f) in shell.faces.iter().enumerate() {
        for (li, l) in f.loops().enumerate() {
            for (ii, it) in l.iter().enumerate() {
                if let LoopItem::Edge {
                    edge: e,
                    pcurve: Some(k),
                    ..
                } = *it
                    && e == edge
                    && (fi, li, ii) != not
                {
                    return Some((fi, k));
                }
            }
        }
    }
    None
}

/// The points `S(c(t))` of a pcurve `c` on a surface at `n` parameters uniform over the
/// pcurve's domain.
fn along(s: &NurbsSurface, c: &NurbsCurve, n: usize) -> Result<Vec<(f64, Vec3)>, String> {
    let d = c.domain();
    (0..n)
        .map(|k| {
            let t = d.min + d.length() * k as f64 / (n - 1) as f64;
            let q = c.point(t).map_err(|e| e.to_string())?;
            let x = s.point(q.x, q.y).map_err(|e| e.to_string())?;
            Ok((t, x))
        })
        .collect()
}

/// For each edge use of face `face` of `shell` with a pcurve, how far the edge moved and how
/// far it is from its neighbour when the face's surface is `surface` (see [`EdgeGap`]). Both
/// sides of an edge run over the edge curve's parameter interval in its direction, so they
/// are compared at equal parameters.
pub fn face_edge_gaps(
    shell: &Shell,
    face: usize,
    surface: &NurbsSurface,
) -> Result<Vec<EdgeGap>, String> {
    let f = shell
        .faces
        .get(face)
        .ok_or_else(|| format!("face {face} out of range ({} faces)", shell.faces.len()))?;
    let mut out = Vec::new();
    for (li, l) in f.loops().enumerate() {
        for (ii, it) in l.iter().enumerate() {
            let LoopItem::Edge {
                edge,
                pcurve: Some(k),
                ..
            } = *it
            else {
                continue;
            };
            let pc = f.pcurves.get(k).ok_or("pcurve out of range")?;
            let curve = &shell.edges.get(edge).ok_or("edge out of range")?.curve;
            let new = along(surface, pc, GAP_SAMPLES)?;
            let cd = curve.domain();
            let pd = pc.domain();
            let mut moved = 0.0f64;
            for (t, x) in &new {
                // The edge curve at the same fraction of its interval.
                let s = cd.min + cd.length() * (t - pd.min) / pd.length().max(f64::MIN_POSITIVE);
                let y = curve.point(s).map_err(|e| e.to_string())?;
                moved = moved.max((x - y).norm());
            }
            let nb = other_use(shell, edge, (face, li, ii));
            let gap = match nb {
                Some((g, kg)) => {
                    let gs = if g == face {
                        surface
                    } else {
                        &shell.faces[g].surface
                    };
                    let pcg = shell.faces[g]
                        .pcurves
                        .get(kg)
                        .ok_or("pcurve out of range")?;
                    let theirs = along(gs, pcg, GAP_SAMPLES)?;
                    new.iter()
                        .zip(&theirs)
                        .map(|((_, a), (_, b))| (a - b).norm())
                        .fold(0.0, f64::max)
                }
                None => moved,
            };
            out.push(EdgeGap {
                edge,
                neighbour: nb.map(|n| n.0),
                moved,
                gap,
            });
        }
    }
    Ok(out)
}

/// The shell with face `face`'s surface replaced by `surface`: the 3D curves of its edges that
/// moved by more than `tolerance` ([`face_edge_gaps`]) recomputed from the pcurves on the new
/// surface (polylines, see the module documentation) and their vertices moved to the new ends;
/// the other edges keep their exact curves. The neighbours' surfaces and pcurves are not
/// touched, so a moved edge leaves a gap on their side ([`EdgeGap::gap`]).
pub fn with_face_surface(
    shell: &Shell,
    face: usize,
    surface: &NurbsSurface,
    tolerance: f64,
) -> Result<Shell, String> {
    let gaps = face_edge_gaps(shell, face, surface)?;
    let mut out = shell.clone();
    out.faces[face].surface = surface.clone();
    let f = &shell.faces[face];
    for g in gaps.iter().filter(|g| g.moved > tolerance) {
        // The first use of the edge in this face gives its pcurve (pcurves run in the edge's
        // direction whichever way the loop uses it).
        let Some(k) = f.loops().flatten().find_map(|it| match *it {
            LoopItem::Edge {
                edge,
                pcurve: Some(k),
                ..
            } if edge == g.edge => Some(k),
            _ => None,
        }) else {
            continue;
        };
        let pc = &f.pcurves[k];
        let pts = along(surface, pc, crate::trimmed::PCURVE_POLYLINE_POINTS)?;
        let d = shell.edges[g.edge].curve.domain();
        let m = pts.len();
        let mut knots = vec![d.min; 2];
        for i in 1..m - 1 {
            knots.push(d.min + d.length() * i as f64 / (m - 1) as f64);
        }
        knots.extend([d.max; 2]);
        let curve = NurbsCurve::new(1, knots, pts.iter().map(|p| p.1).collect(), None)
            .map_err(|e| e.to_string())?;
        let e = &mut out.edges[g.edge];
        e.curve = curve;
        let (a, b) = (pts[0].1, pts[m - 1].1);
        out.vertices[e.start].point = a;
        out.vertices[e.end].point = b;
    }
    Ok(out)
}

/// The volume enclosed by a closed triangle mesh oriented outward: `sum (a . (b x c)) / 6`
/// over its triangles (divergence theorem); negative for an inward mesh, meaningless for an
/// open one.
pub fn mesh_volume(mesh: &TriMesh) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            a.dot(&b.cross(&c))
        })
        .sum::<f64>()
        / 6.0
}
