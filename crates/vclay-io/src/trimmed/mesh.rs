//! Meshing of trimmed shells without cracks (issue 30).
//!
//! **What.** [`tessellate_shell`] turns a trimmed [`Shell`] into one triangle mesh in which
//! every edge is sampled once: the faces on both sides of an edge use the same vertices along
//! it, so a closed shell gives a closed (watertight) mesh, seams and poles included.
//!
//! **How.** Target spacing `h = size / samples` (`size` the diagonal of the bounding box of the
//! shell's vertices and edge curves' control points). Each edge's 3D curve is sampled at `max(2, ceil(L / h))` segments uniform in
//! its parameter (`L` its polyline length at 64 points); the samples are the mesh's vertices
//! along the edge. Per face, in the surface's parameter space scaled by the mean `|S_u|` and
//! `|S_v|` (so that distances are roughly lengths on the surface):
//!
//! 1. the loops become closed polygons: each use's pcurve sampled at the same number of points
//!    as its edge (uniform in the pcurve's parameter), each point tied to the edge's 3D vertex;
//!    where consecutive pcurves do not meet (a pole, the side of a seam) the gap is filled by
//!    points along the straight segment, all tied to the shared vertex (a pole's degenerate
//!    edge);
//! 2. interior points on a grid of spacing `h`, kept when inside the loops (even-odd rule) and at
//!    least `h/2` from every boundary segment; every point (boundary points too, for the
//!    triangulation and the inside test alike) slightly perturbed (deterministically, 1e-3 h) so
//!    that no four are co-circular and no three boundary points collinear;
//! 3. a Delaunay triangulation (Bowyer-Watson) of all points; triangles whose centroid lies
//!    outside the loops are dropped, as are triangles with two corners on one vertex (at poles).
//!
//! Triangles are oriented by the face's sense (`S_u x S_v`, flipped when `same_sense` is
//! false). Faces without pcurves on every use cannot be meshed this way: an error names them.
//!
//! **Limitations.** The Delaunay triangulation is not constrained: with edge samples at most
//! `h/2` apart and interior points at least `h/2` from the boundary, boundary segments are
//! Delaunay edges except where two boundary stretches come closer than about `h` (thin faces,
//! sharp corners), where a triangle may be missing or bridge the gap; a finer `samples` helps.
//! Points along an edge follow its 3D parametrization, their parameter-space places follow the
//! pcurve's; where the two parametrizations differ the triangles are slightly skewed (no crack).
//! Naive Bowyer-Watson is quadratic in the points of a face: at `samples` 48 the cut sphere of
//! the tests takes about 1 s in a debug build (measured); `vclay convert` and `vclay render` use
//! at most 64.

use crate::brep::{LoopItem, Shell};
use vclay_core::{TriMesh, Vec3};
use vclay_spline::{ParametricCurve, ParametricSurface};

/// Most samples (spacing `size / samples`) of [`tessellate_shell`].
pub const MAX_SHELL_SAMPLES: usize = 1024;

/// A point of a face's parameter-space triangulation: scaled parameters and its mesh vertex.
#[derive(Clone, Copy, Debug)]
struct P2 {
    x: f64,
    y: f64,
    vertex: u32,
}

/// Meshes a trimmed shell with shared edge samples (see the module documentation); `samples`
/// sets the spacing `size / samples` (2 to [`MAX_SHELL_SAMPLES`]). Normals are computed from
/// the triangles.
pub fn tessellate_shell(shell: &Shell, samples: usize) -> Result<TriMesh, String> {
    tessellate_shell_faces(shell, samples).map(|(mesh, _)| mesh)
}

/// [`tessellate_shell`] with the face of each triangle: `faces[t]` is the index in
/// `shell.faces` of the face that triangle `t` lies on (for picking a face of a part).
pub fn tessellate_shell_faces(
    shell: &Shell,
    samples: usize,
) -> Result<(TriMesh, Vec<u32>), String> {
    if !(2..=MAX_SHELL_SAMPLES).contains(&samples) {
        return Err(format!(
            "samples {samples}: must be from 2 to {MAX_SHELL_SAMPLES}"
        ));
    }
    let pts: Vec<Vec3> = shell
        .vertices
        .iter()
        .map(|v| v.point)
        .chain(
            shell
                .edges
                .iter()
                .flat_map(|e| e.curve.control_points().iter().copied()),
        )
        .collect();
    let size = crate::brep::closure_tolerance(&pts) / crate::brep::CLOSURE_RTOL;
    let size = if size.is_finite() && size > 1e-300 {
        size
    } else {
        1.0
    };
    let h = size / samples as f64;
    let mut mesh = TriMesh::new();
    for v in &shell.vertices {
        mesh.positions.push(v.point);
    }
    // Edge samples: parameters and mesh vertices (ends are the shell's vertices).
    let mut edge_samples: Vec<(Vec<f64>, Vec<u32>)> = Vec::with_capacity(shell.edges.len());
    for (k, e) in shell.edges.iter().enumerate() {
        let d = e.curve.domain();
        let at = |i: usize, n: usize| d.min + (d.max - d.min) * i as f64 / n as f64;
        let mut len = 0.0;
        let mut prev = e.curve.point(d.min).map_err(|x| format!("edge {k}: {x}"))?;
        for i in 1..=64 {
            let p = e
                .curve
                .point(at(i, 64))
                .map_err(|x| format!("edge {k}: {x}"))?;
            len += (p - prev).norm();
            prev = p;
        }
        // At most h/2 apart, so that boundary segments stay Delaunay edges.
        let n = ((2.0 * len / h).ceil() as usize).clamp(2, 64 * MAX_SHELL_SAMPLES);
        let mut ts = Vec::with_capacity(n + 1);
        let mut ids = Vec::with_capacity(n + 1);
        for i in 0..=n {
            let t = at(i, n);
            ts.push(t);
            ids.push(if i == 0 {
                e.start as u32
            } else if i == n {
                e.end as u32
            } else {
                mesh.positions
                    .push(e.curve.point(t).map_err(|x| format!("edge {k}: {x}"))?);
                (mesh.positions.len() - 1) as u32
            });
        }
        edge_samples.push((ts, ids));
    }
    let mut faces = Vec::new();
    for fi in 0..shell.faces.len() {
        face_mesh(shell, fi, &edge_samples, h, &mut mesh).map_err(|m| format!("face {fi}: {m}"))?;
        faces.resize(mesh.triangles.len(), fi as u32);
    }
    mesh.compute_normals();
    Ok((mesh, faces))
}

fn face_mesh(
    shell: &Shell,
    fi: usize,
    edge_samples: &[(Vec<f64>, Vec<u32>)],
    h: f64,
    mesh: &mut TriMesh,
) -> Result<(), String> {
    let f = &shell.faces[fi];
    let s = &f.surface;
    let dom = s.domain();
    // Scale of the parameters: mean |S_u|, |S_v| on a 5 x 5 grid.
    let (mut su, mut sv, mut n) = (0.0, 0.0, 0.0);
    for i in 0..5 {
        for j in 0..5 {
            let u = dom[0].min + (dom[0].max - dom[0].min) * (i as f64 + 0.5) / 5.0;
            let v = dom[1].min + (dom[1].max - dom[1].min) * (j as f64 + 0.5) / 5.0;
            let d = s.derivatives(u, v, 1).map_err(|e| e.to_string())?;
            su += d[1][0].norm();
            sv += d[0][1].norm();
            n += 1.0;
        }
    }
    let (su, sv) = ((su / n).max(1e-300), (sv / n).max(1e-300));
    // Closed directions (a full turn): their period in scaled parameters. A face may cross the
    // converted surface's seam (its loop jumps by a period): the loop is made continuous and
    // points are evaluated wrapped into the domain.
    let tol = 1e-9 * h * 1e3;
    let closed = |axis: usize| -> Result<bool, String> {
        for k in 0..5 {
            let o = 1 - axis;
            let t = dom[o].min + (dom[o].max - dom[o].min) * k as f64 / 4.0;
            let (a, b) = if axis == 0 {
                (s.point(dom[0].min, t), s.point(dom[0].max, t))
            } else {
                (s.point(t, dom[1].min), s.point(t, dom[1].max))
            };
            if (a.map_err(|e| e.to_string())? - b.map_err(|e| e.to_string())?).norm() > tol {
                return Ok(false);
            }
        }
        Ok(true)
    };
    let period = [
        closed(0)?.then_some((dom[0].max - dom[0].min) * su),
        closed(1)?.then_some((dom[1].max - dom[1].min) * sv),
    ];
    let wrap = |x: f64, axis: usize, scale: f64| -> f64 {
        match period[axis] {
            Some(p) => {
                let lo = dom[axis].min * scale;
                (lo + (x - lo).rem_euclid(p)) / scale
            }
            None => x / scale,
        }
    };
    // The shift by whole periods that brings `b` nearest to `a`; none on a face with a seam
    // (an edge used twice): such a face spans the whole turn and its loop runs along both
    // sides of the seam and across poles, which a shift would fold onto each other.
    let mut seen = std::collections::HashSet::new();
    let has_seam = f.loops().flatten().any(|it| match it {
        LoopItem::Edge { edge, .. } => !seen.insert(*edge),
        LoopItem::Pole { .. } => false,
    });
    let period = if has_seam { [None, None] } else { period };
    let shift = |a: P2, b: P2| -> (f64, f64) {
        let best = |d: f64, p: Option<f64>| p.map_or(0.0, |p| (d / p).round() * p);
        (best(a.x - b.x, period[0]), best(a.y - b.y, period[1]))
    };
    // 1. Loops as polygons of scaled parameters tied to mesh vertices.
    let mut polys: Vec<Vec<P2>> = Vec::new();
    for l in f.loops() {
        let mut poly: Vec<P2> = Vec::new();
        for it in l {
            let LoopItem::Edge {
                edge,
                forward,
                pcurve,
            } = *it
            else {
                continue;
            };
            let pc = pcurve
                .and_then(|k| f.pcurves.get(k))
                .ok_or("an edge use has no pcurve")?;
            let (_, ids) = &edge_samples[edge];
            let m = ids.len() - 1;
            let d = pc.domain();
            let mut seg: Vec<P2> = (0..=m)
                .map(|i| {
                    let t = d.min + (d.max - d.min) * i as f64 / m as f64;
                    pc.point(t).map(|q| P2 {
                        x: q.x * su,
                        y: q.y * sv,
                        vertex: ids[i],
                    })
                })
                .collect::<Result<_, _>>()
                .map_err(|e| e.to_string())?;
            if !forward {
                seg.reverse();
            }
            if let Some(last) = poly.last().copied() {
                let (dx, dy) = shift(last, seg[0]);
                for p in &mut seg {
                    p.x += dx;
                    p.y += dy;
                }
                gap(&mut poly, last, seg[0], h);
                poly.pop();
            }
            poly.extend(seg);
        }
        if poly.len() < 3 {
            continue;
        }
        // Close the loop (a gap between the last and the first use), then drop the repeated
        // first point.
        let (last, first) = (poly[poly.len() - 1], poly[0]);
        gap(&mut poly, last, first, h);
        poly.pop();
        if let Some(l) = poly.last()
            && (l.x - first.x).hypot(l.y - first.y) <= 1e-9 * h
        {
            poly.pop();
        }
        polys.push(poly);
    }
    if polys.is_empty() {
        return Ok(());
    }
    // Every boundary point moved by up to 1e-3 h (deterministic) for the triangulation and the
    // inside test alike: rectangles of boundary samples are co-circular and straight edges
    // collinear, which rounding would turn into overlapping cavities. Mesh vertices keep their
    // exact places.
    let mut count = 0usize;
    for p in polys.iter_mut().flatten() {
        count += 1;
        let jit = |k: usize| ((k as f64 * 0.754_877_666_2).fract() - 0.5) * 2e-3 * h;
        p.x += jit(2 * count);
        p.y += jit(2 * count + 1);
    }
    // 2. Interior grid points.
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in polys.iter().flatten() {
        lo = [lo[0].min(p.x), lo[1].min(p.y)];
        hi = [hi[0].max(p.x), hi[1].max(p.y)];
    }
    let mut points: Vec<P2> = polys.iter().flatten().copied().collect();
    let segs: Vec<(P2, P2)> = polys
        .iter()
        .flat_map(|p| (0..p.len()).map(move |i| (p[i], p[(i + 1) % p.len()])))
        .collect();
    let nx = ((hi[0] - lo[0]) / h).ceil() as usize;
    let ny = ((hi[1] - lo[1]) / h).ceil() as usize;
    if (nx as f64) * (ny as f64) > 4e6 {
        return Err(format!(
            "{nx} x {ny} interior points: too many (lower samples)"
        ));
    }
    for i in 1..nx {
        for j in 1..ny {
            // Deterministic perturbation against co-circular grid points.
            let jit = |k: usize| ((k as f64 * 0.618_033_988_75).fract() - 0.5) * 2e-3 * h;
            let x = lo[0] + (hi[0] - lo[0]) * i as f64 / nx as f64 + jit(i * 7919 + j);
            let y = lo[1] + (hi[1] - lo[1]) * j as f64 / ny as f64 + jit(j * 104_729 + i);
            if !inside(&polys, x, y) || segs.iter().any(|(a, b)| seg_dist(a, b, x, y) < 0.5 * h) {
                continue;
            }
            let q = s
                .point(wrap(x, 0, su), wrap(y, 1, sv))
                .map_err(|e| e.to_string())?;
            mesh.positions.push(q);
            points.push(P2 {
                x,
                y,
                vertex: (mesh.positions.len() - 1) as u32,
            });
        }
    }
    // 3. Delaunay, keep the triangles inside.
    for [a, b, c] in delaunay(&points) {
        let (pa, pb, pc) = (points[a], points[b], points[c]);
        if pa.vertex == pb.vertex || pb.vertex == pc.vertex || pa.vertex == pc.vertex {
            continue;
        }
        let (cx, cy) = ((pa.x + pb.x + pc.x) / 3.0, (pa.y + pb.y + pc.y) / 3.0);
        if !inside(&polys, cx, cy) {
            continue;
        }
        // Counter-clockwise in (u, v) is the surface's normal side.
        let ccw = (pb.x - pa.x) * (pc.y - pa.y) - (pb.y - pa.y) * (pc.x - pa.x) > 0.0;
        let tri = if ccw == f.same_sense {
            [pa.vertex, pb.vertex, pc.vertex]
        } else {
            [pa.vertex, pc.vertex, pb.vertex]
        };
        mesh.triangles.push(tri);
    }
    Ok(())
}

/// Fills the parameter-space gap from `a` to `b` (a pole, the side of a seam: both ends are one
/// vertex) with points at most `h/2` apart tied to `b`'s vertex, then pushes `b`.
fn gap(poly: &mut Vec<P2>, a: P2, b: P2, h: f64) {
    let d = (b.x - a.x).hypot(b.y - a.y);
    if d > 1e-9 * h {
        let n = ((2.0 * d / h).ceil() as usize).max(1);
        for k in 1..n {
            let t = k as f64 / n as f64;
            poly.push(P2 {
                x: a.x + (b.x - a.x) * t,
                y: a.y + (b.y - a.y) * t,
                vertex: b.vertex,
            });
        }
    }
    poly.push(b);
}

/// Even-odd rule over all loops.
fn inside(polys: &[Vec<P2>], x: f64, y: f64) -> bool {
    let mut inside = false;
    for poly in polys {
        let m = poly.len();
        for i in 0..m {
            let (a, b) = (poly[i], poly[(i + 1) % m]);
            if (a.y > y) != (b.y > y) {
                let xc = a.x + (y - a.y) / (b.y - a.y) * (b.x - a.x);
                if x < xc {
                    inside = !inside;
                }
            }
        }
    }
    inside
}

fn seg_dist(a: &P2, b: &P2, x: f64, y: f64) -> f64 {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((x - a.x) * dx + (y - a.y) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a.x + t * dx - x).hypot(a.y + t * dy - y)
}

/// The super-triangle's corners around the points (`20 d` from the centre of their bounding
/// box of side `d`), after the points, and the incircle test: `d` strictly inside the
/// circumcircle of the counter-clockwise triangle `t` (the incircle determinant relative to
/// `d`, Guibas & Stolfi).
fn with_super_triangle(points: &[P2]) -> Vec<[f64; 2]> {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in points {
        lo = [lo[0].min(p.x), lo[1].min(p.y)];
        hi = [hi[0].max(p.x), hi[1].max(p.y)];
    }
    let d = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-300);
    let (mx, my) = ((lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0);
    let mut xy: Vec<[f64; 2]> = points.iter().map(|p| [p.x, p.y]).collect();
    xy.push([mx - 20.0 * d, my - d]);
    xy.push([mx, my + 20.0 * d]);
    xy.push([mx + 20.0 * d, my - d]);
    xy
}

fn cross(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

fn incircle(t: [usize; 3], d: [f64; 2], xy: &[[f64; 2]]) -> bool {
    let r = |k: usize| {
        let (x, y) = (xy[t[k]][0] - d[0], xy[t[k]][1] - d[1]);
        (x, y, x * x + y * y)
    };
    let ((ax, ay, a2), (bx, by, b2), (cx, cy, c2)) = (r(0), r(1), r(2));
    ax * (by * c2 - b2 * cy) - ay * (bx * c2 - b2 * cx) + a2 * (bx * cy - by * cx) > 0.0
}

/// No neighbour (the super-triangle's outside).
const NONE: usize = usize::MAX;

/// Delaunay triangulation of the points, as counter-clockwise index triples: Bowyer-Watson with
/// a super-triangle, as before session 23, but each point's cavity (the triangles whose
/// circumcircle holds it, by the same incircle test) is found by walking to the triangle that
/// holds the point and spreading to neighbours, instead of testing every triangle: about
/// `n^1.5` instead of `n^2` (a face of 1,500 points: 18 ms to 1-2 ms). The triangles are the
/// same (`delaunay_reference` in the tests); their order is not.
fn delaunay(points: &[P2]) -> Vec<[usize; 3]> {
    let n = points.len();
    if n < 3 {
        return Vec::new();
    }
    let xy = with_super_triangle(points);
    // Triangle k: corners (counter-clockwise) and the neighbour across edge (c[i], c[i + 1]).
    let mut corners: Vec<[usize; 3]> = Vec::with_capacity(2 * n + 8);
    let mut nbr: Vec<[usize; 3]> = Vec::with_capacity(2 * n + 8);
    let mut alive: Vec<bool> = Vec::with_capacity(2 * n + 8);
    let first = if cross(xy[n], xy[n + 1], xy[n + 2]) < 0.0 {
        [n, n + 2, n + 1]
    } else {
        [n, n + 1, n + 2]
    };
    corners.push(first);
    nbr.push([NONE; 3]);
    alive.push(true);
    let mut last = 0;
    let mut cavity: Vec<usize> = Vec::new();
    let mut in_cavity: Vec<bool> = vec![false];
    let mut stack: Vec<usize> = Vec::new();
    // (a, b, outside neighbour, the edge's index in that neighbour) of the cavity's boundary.
    let mut boundary: Vec<(usize, usize, usize)> = Vec::new();
    for i in 0..n {
        let p = xy[i];
        // Walk from the last new triangle towards p (a step crosses an edge that p is strictly
        // beyond); bounded, with a scan of all triangles as the fallback.
        let mut t = last;
        let mut steps = 0;
        let found = loop {
            let c = corners[t];
            let next = (0..3).find_map(|e| {
                let (a, b) = (c[e], c[(e + 1) % 3]);
                (cross(xy[a], xy[b], p) < 0.0 && nbr[t][e] != NONE).then_some(nbr[t][e])
            });
            match next {
                Some(u) if steps < corners.len() => {
                    t = u;
                    steps += 1;
                }
                Some(_) => break None,
                None => break Some(t),
            }
        };
        let seed = match found.filter(|&t| incircle(corners[t], p, &xy)) {
            Some(t) => Some(t),
            None => (0..corners.len()).find(|&t| alive[t] && incircle(corners[t], p, &xy)),
        };
        let Some(seed) = seed else {
            // On a vertex already there (no circumcircle holds it strictly): as before, the
            // point adds nothing.
            continue;
        };
        // The cavity: the connected triangles whose circumcircle holds p.
        cavity.clear();
        stack.clear();
        stack.push(seed);
        in_cavity[seed] = true;
        while let Some(t) = stack.pop() {
            cavity.push(t);
            for &u in &nbr[t] {
                if u != NONE && !in_cavity[u] && incircle(corners[u], p, &xy) {
                    in_cavity[u] = true;
                    stack.push(u);
                }
            }
        }
        boundary.clear();
        for &t in &cavity {
            for e in 0..3 {
                let u = nbr[t][e];
                if u == NONE || !in_cavity[u] {
                    boundary.push((corners[t][e], corners[t][(e + 1) % 3], u));
                }
            }
        }
        for &t in &cavity {
            alive[t] = false;
            in_cavity[t] = false;
        }
        // The new triangles (a, b, p), counter-clockwise as their cavity edge was.
        let base = corners.len();
        for (k, &(a, b, u)) in boundary.iter().enumerate() {
            corners.push([a, b, i]);
            nbr.push([u, NONE, NONE]);
            alive.push(true);
            in_cavity.push(false);
            if u != NONE {
                // The outside neighbour's edge (b, a) now faces the new triangle.
                let e = (0..3)
                    .find(|&e| corners[u][e] == b && corners[u][(e + 1) % 3] == a)
                    .expect("the neighbour shares the edge");
                nbr[u][e] = base + k;
            }
        }
        // Around p: the edge (b, p) of (a, b, p) meets the edge (p, b) of (b, c, p).
        for k in 0..boundary.len() {
            let b = boundary[k].1;
            if let Some(j) = (0..boundary.len()).find(|&j| boundary[j].0 == b) {
                nbr[base + k][1] = base + j;
                nbr[base + j][2] = base + k;
            }
        }
        last = base;
    }
    (0..corners.len())
        .filter(|&t| alive[t] && corners[t].iter().all(|&k| k < n))
        .map(|t| corners[t])
        .collect()
}

/// The Bowyer-Watson triangulation as it was until session 23: every triangle tested for every
/// point (quadratic). [`delaunay`] must give the same triangles; kept to check that.
#[cfg(test)]
fn delaunay_reference(points: &[P2]) -> Vec<[usize; 3]> {
    let n = points.len();
    if n < 3 {
        return Vec::new();
    }
    let xy = with_super_triangle(points);
    let orient = |t: [usize; 3], xy: &[[f64; 2]]| -> [usize; 3] {
        if cross(xy[t[0]], xy[t[1]], xy[t[2]]) < 0.0 {
            [t[0], t[2], t[1]]
        } else {
            t
        }
    };
    let mut tris: Vec<[usize; 3]> = vec![orient([n, n + 1, n + 2], &xy)];
    let mut edges: Vec<[usize; 2]> = Vec::new();
    for i in 0..n {
        let p = xy[i];
        edges.clear();
        let mut k = 0;
        while k < tris.len() {
            let t = tris[k];
            if incircle(t, p, &xy) {
                for e in [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]] {
                    edges.push(e);
                }
                tris.swap_remove(k);
            } else {
                k += 1;
            }
        }
        // The cavity's boundary: edges seen once.
        let mut boundary: Vec<[usize; 2]> = Vec::new();
        for e in &edges {
            let twice = edges
                .iter()
                .filter(|f| (f[0] == e[1] && f[1] == e[0]) || (f[0] == e[0] && f[1] == e[1]))
                .count()
                > 1;
            if !twice {
                boundary.push(*e);
            }
        }
        for e in boundary {
            tris.push(orient([e[0], e[1], i], &xy));
        }
    }
    tris.into_iter()
        .filter(|t| t.iter().all(|&k| k < n))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same triangles as the quadratic Bowyer-Watson (as rotated to start at their least
    /// corner, sorted) on jittered grids with a ring of boundary points, as the face mesher
    /// makes them, and on scattered points.
    #[test]
    fn the_fast_delaunay_gives_the_reference_triangles() {
        let canon = |ts: Vec<[usize; 3]>| {
            let mut v: Vec<[usize; 3]> = ts
                .into_iter()
                .map(|t| {
                    let k = (0..3).min_by_key(|&k| t[k]).unwrap();
                    [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
                })
                .collect();
            v.sort_unstable();
            v
        };
        let jit = |k: usize| (k as f64 * 0.618_033_988_75).fract() - 0.5;
        // Twice the area of the triangles (counter-clockwise: all positive).
        let area = |ts: &[[usize; 3]], pts: &[P2]| {
            ts.iter()
                .map(|t| {
                    let [a, b, c] = t.map(|k| [pts[k].x, pts[k].y]);
                    let x = cross(a, b, c);
                    assert!(x > 0.0, "a triangle turns clockwise: {t:?}");
                    x
                })
                .sum::<f64>()
        };
        for (m, scatter) in [(3, false), (10, false), (25, false), (40, true), (12, true)] {
            let ring = |pts: &mut Vec<P2>, wobble: f64| {
                // A ring, as a trim loop (off the circle by `wobble`: the reference is only
                // trustworthy away from co-circular points).
                for k in 0..4 * m {
                    let a = std::f64::consts::TAU * k as f64 / (4 * m) as f64;
                    let r = 0.5 + wobble * jit(k * 613);
                    pts.push(P2 {
                        x: 0.5 + r * a.cos(),
                        y: 0.5 + r * a.sin(),
                        vertex: 0,
                    });
                }
            };
            let mut circle = Vec::new();
            ring(&mut circle, 0.0);
            let mut pts = Vec::new();
            ring(&mut pts, 1e-3);
            for i in 1..m {
                for j in 1..m {
                    let (x, y) = if scatter {
                        (0.5 + jit(i * 31 + j * 7), 0.5 + jit(j * 131 + i * 17))
                    } else {
                        (
                            i as f64 / m as f64 + 2e-3 / m as f64 * jit(i * 7919 + j),
                            j as f64 / m as f64 + 2e-3 / m as f64 * jit(j * 104_729 + i),
                        )
                    };
                    pts.push(P2 { x, y, vertex: 0 });
                }
            }
            let fast = canon(delaunay(&pts));
            let slow = canon(delaunay_reference(&pts));
            assert!(!fast.is_empty());
            assert_eq!(fast, slow, "{m} x {m}, scattered {scatter}");
            // On the exact circle (every ring point co-circular) the quadratic version made
            // overlapping triangles; this one covers the polygon once: its area.
            // (Twice the convex hull's area, Andrew's monotone chain.)
            circle.extend_from_slice(&pts[4 * m..]);
            let mut q: Vec<[f64; 2]> = circle.iter().map(|p| [p.x, p.y]).collect();
            q.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
            let mut hull: Vec<[f64; 2]> = Vec::new();
            for pass in 0..2 {
                let start = hull.len();
                let it: Vec<[f64; 2]> = if pass == 0 {
                    q.clone()
                } else {
                    q.iter().rev().copied().collect()
                };
                for p in it {
                    while hull.len() >= start + 2
                        && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
                    {
                        hull.pop();
                    }
                    hull.push(p);
                }
                hull.pop();
            }
            let hull2: f64 = (0..hull.len())
                .map(|k| {
                    let (a, b) = (hull[k], hull[(k + 1) % hull.len()]);
                    a[0] * b[1] - a[1] * b[0]
                })
                .sum();
            // No overlap: counter-clockwise triangles, each directed edge used once at most,
            // covering no more than the hull (and nearly all of it: a finite super-triangle
            // can cost a sliver along the hull, as it always did).
            let ts = delaunay(&circle);
            let twice = area(&ts, &circle);
            let mut edges: Vec<[usize; 2]> = ts
                .iter()
                .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]])
                .collect();
            let all = edges.len();
            edges.sort_unstable();
            edges.dedup();
            assert_eq!(edges.len(), all, "{m}: an edge is used twice the same way");
            assert!(
                twice <= hull2 + 1e-9 && twice > 0.99 * hull2,
                "{m}: the triangles cover {twice} of the hull's {hull2} (twice the areas)"
            );
        }
        // Fewer than three points, and a repeated point.
        assert!(
            delaunay(&[P2 {
                x: 0.0,
                y: 0.0,
                vertex: 0
            }])
            .is_empty()
        );
        let tri =
            [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 0.0)].map(|(x, y)| P2 { x, y, vertex: 0 });
        assert_eq!(canon(delaunay(&tri)), canon(delaunay_reference(&tri)));
    }
}
