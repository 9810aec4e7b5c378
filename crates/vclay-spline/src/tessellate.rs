//! Tessellation of surfaces and volume boundaries into a [`MeshSink`].
//!
//! Surfaces are sampled on a parameter grid, uniform between the C0 knots and with lines exactly
//! on them ([`SurfaceSampling`]), and split into two triangles per cell, with analytic normals
//! `s_u x s_v` (where the surface is degenerate, such as at the pole of a sphere, the limit of
//! the analytic normal, or the mesh normal from the adjacent triangles, replaces it). Vertices
//! on a C0 line are written once per side with that side's one-sided normal, so sharp edges
//! (the swung cube of `d-nurbs.txt` Fig 2) stay sharp in every exporter and picture; the mesh
//! is then closed by position, not by index, as it already is along a periodic seam. Volumes are tessellated by
//! their six boundary faces, each oriented so that its normals point out of the volume
//! (checked against the volume's derivative across the face).

use crate::error::SplineError;
use crate::knots::KnotVector;
use crate::surface::NurbsSurface;
use crate::traits::ParametricVolume;
use crate::volume::NurbsVolume;
use vclay_core::{MeshSink, Parallelism, TriMesh, Vec3};

/// Relative size of `|s_u x s_v|` (against the largest on the grid) below which a surface
/// point counts as degenerate and takes the mesh normal instead of the analytic one.
pub const DEGENERATE_NORMAL_RELATIVE: f64 = 1e-8;

/// Relative parameter offset (of the domain width) at which the normal of a degenerate point is
/// evaluated instead, giving the limit of the analytic normal.
pub const NORMAL_NUDGE_RELATIVE: f64 = 1e-6;

fn grid_triangles(nu: usize, nv: usize, flip: bool, base: u32, sink: &mut dyn MeshSink) {
    for i in 0..nu - 1 {
        for j in 0..nv - 1 {
            let a = base + (i * nv + j) as u32;
            let b = base + ((i + 1) * nv + j) as u32;
            let c = base + ((i + 1) * nv + j + 1) as u32;
            let d = base + (i * nv + j + 1) as u32;
            if flip {
                sink.add_quad([a, d, c, b]);
            } else {
                sink.add_quad([a, b, c, d]);
            }
        }
    }
}

/// The parameter lines of a surface tessellation ([`tessellate_surface`]): along each axis the
/// domain is cut at the surface's C0 knots ([`KnotVector::c0_knots`]: interior knots of
/// multiplicity at least the degree, where a sharp edge can be) into pieces, and each piece is
/// sampled uniformly from its start to its end, both included.
///
/// With `n` samples on an axis cut into `P` pieces, the pieces share `n - P` intervals (at least
/// one each, the others given one by one to the piece whose spacing is widest), so the axis
/// still has exactly `n` lines (the vertex count, and the memory estimates built on it, stay
/// `n_u n_v`); a surface without C0 knots keeps the plain uniform grid, and one with C0 knots
/// gets lines exactly on its creases (a uniform grid misses them and cuts every sharp edge
/// with a chord: issue 28, the swung cube of `d-nurbs.txt` Fig 2). An axis with more than
/// `n / 2` pieces (a net finer than the tessellation) is sampled uniformly, without cuts.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceSampling {
    /// Per axis (`u`, `v`), the pieces' parameter lists, in increasing order; consecutive
    /// pieces share their end and start value (a C0 knot).
    pub pieces: [Vec<Vec<f64>>; 2],
}

impl SurfaceSampling {
    /// The sampling of `surface` with `samples[a]` (at least 2) lines along axis `a` before
    /// the cut at C0 knots.
    pub fn new(surface: &NurbsSurface, samples: [usize; 2]) -> Self {
        let knots = surface.knots();
        let pieces = [0, 1].map(|a| axis_pieces(&knots[a], samples[a].max(2)));
        Self { pieces }
    }

    /// The number of vertices [`tessellate_surface`] writes: the sum over piece pairs of
    /// their products, `n_u n_v` for `n_u x n_v` samples (at least 2 each).
    pub fn vertex_count(&self) -> usize {
        let [pu, pv] = &self.pieces;
        let nu: usize = pu.iter().map(Vec::len).sum();
        let nv: usize = pv.iter().map(Vec::len).sum();
        nu * nv
    }

    /// The `(u, v)` of every vertex, in the order [`tessellate_surface`] writes them: for each
    /// `u` piece, for each `v` piece, the piece's grid with `v` fastest.
    pub fn vertex_params(&self) -> Vec<[f64; 2]> {
        let mut out = Vec::with_capacity(self.vertex_count());
        for us in &self.pieces[0] {
            for vs in &self.pieces[1] {
                for &u in us {
                    out.extend(vs.iter().map(|&v| [u, v]));
                }
            }
        }
        out
    }
}

/// The pieces of one axis (see [`SurfaceSampling`]).
fn axis_pieces(kv: &KnotVector, samples: usize) -> Vec<Vec<f64>> {
    let d = kv.domain();
    let mut cuts = vec![d.min];
    cuts.extend(kv.c0_knots());
    cuts.push(d.max);
    let pieces = cuts.len() - 1;
    if 2 * pieces > samples {
        // More C0 pieces than half the samples (a net finer than the tessellation): the plain
        // uniform grid, so that the mesh never has more than `samples` lines per axis.
        return vec![d.linspace(samples)];
    }
    // `samples - pieces` intervals in all (each piece's end line is also the next one's start
    // line), one per piece first, then each to the piece whose spacing is widest.
    let len: Vec<f64> = cuts.windows(2).map(|w| w[1] - w[0]).collect();
    let mut k = vec![1usize; pieces];
    for _ in pieces..samples - pieces {
        let mut widest = 0;
        for i in 1..pieces {
            if len[i] / k[i] as f64 > len[widest] / k[widest] as f64 {
                widest = i;
            }
        }
        k[widest] += 1;
    }
    (0..pieces)
        // Interval::linspace, so a surface without C0 knots keeps the old grid bit for bit.
        .map(|i| vclay_core::Interval::new(cuts[i], cuts[i + 1]).linspace(k[i] + 1))
        .collect()
}

/// Tessellates `surface` into `sink` with about `samples[0] x samples[1]` (each at least 2)
/// parameter lines, cut at the C0 knots ([`SurfaceSampling`]).
///
/// Each pair of pieces (one along `u`, one along `v`) is written as its own grid of vertices,
/// so the vertices on a C0 line are duplicated, one per side, each with the normal of its own
/// side (one-sided derivatives, [`NurbsSurface::eval_grid_with_derivatives_sided`]): a
/// crease is shaded sharp, not averaged into a bevel. Triangles are counter-clockwise around
/// `s_u x s_v`. [`SurfaceSampling::vertex_params`] gives the vertices' parameters.
pub fn tessellate_surface(
    surface: &NurbsSurface,
    samples: [usize; 2],
    sink: &mut dyn MeshSink,
) -> Result<(), SplineError> {
    let sampling = SurfaceSampling::new(surface, samples);
    let [du, dv] = crate::traits::ParametricSurface::domain(surface);
    // Every piece's grid first: the degenerate-normal threshold is relative to the largest
    // |s_u x s_v| of the whole surface.
    let mut grids = Vec::new();
    for us in &sampling.pieces[0] {
        let left_u = one_sided(us, du.max);
        for vs in &sampling.pieces[1] {
            let left_v = one_sided(vs, dv.max);
            let g = surface.eval_grid_with_derivatives_sided(
                us,
                vs,
                [&left_u, &left_v],
                Parallelism::Auto,
            )?;
            grids.push((us, vs, g));
        }
    }
    let largest = grids
        .iter()
        .flat_map(|(_, _, g)| g.du.iter().zip(&g.dv).map(|(a, b)| a.cross(b).norm()))
        .fold(0.0, f64::max);
    // A point is degenerate when its |s_u x s_v| is negligible next to the largest on the
    // surface (relative tolerance DEGENERATE_NORMAL_RELATIVE).
    let tiny = DEGENERATE_NORMAL_RELATIVE * largest;
    let triangles: usize = grids
        .iter()
        .map(|(us, vs, _)| 2 * (us.len() - 1) * (vs.len() - 1))
        .sum();
    sink.reserve(sampling.vertex_count(), triangles);
    for (us, vs, g) in &grids {
        let (nu, nv) = (us.len(), vs.len());
        // Mesh normals as a fallback at degenerate points.
        let mut mesh = TriMesh::new();
        mesh.positions = g.points.clone();
        grid_triangles(nu, nv, false, 0, &mut mesh);
        mesh.compute_normals();
        let mut base = None;
        for k in 0..nu * nv {
            let n = g.du[k].cross(&g.dv[k]);
            let normal = if n.norm() > tiny {
                n.normalize()
            } else {
                // Limit of the analytic normal: evaluate slightly inside this piece.
                let (u, v) = (us[k / nv], vs[k % nv]);
                let nudge = |t: f64, piece: &[f64], d: vclay_core::Interval| {
                    let h = NORMAL_NUDGE_RELATIVE * d.length();
                    if t + h <= piece[piece.len() - 1] {
                        t + h
                    } else {
                        t - h
                    }
                };
                let d = crate::traits::ParametricSurface::derivatives(
                    surface,
                    nudge(u, us, du),
                    nudge(v, vs, dv),
                    1,
                )?;
                let m = d[1][0].cross(&d[0][1]);
                if m.norm() > 0.0 && m.norm().is_finite() {
                    m.normalize()
                } else {
                    mesh.normals[k]
                }
            };
            let idx = sink.add_vertex(g.points[k], Some(normal));
            base.get_or_insert(idx);
        }
        grid_triangles(nu, nv, false, base.unwrap_or(0), sink);
    }
    Ok(())
}

/// Which samples of a piece take the limit from the left: its last one, unless it is the end
/// of the domain (where evaluation is from the left anyway).
fn one_sided(piece: &[f64], domain_end: f64) -> Vec<bool> {
    let last = piece.len() - 1;
    (0..piece.len())
        .map(|i| i == last && piece[i] < domain_end)
        .collect()
}

/// Tessellates the six boundary faces of `volume` with `samples` points per axis (each at least
/// 2) into `sink`, outward-oriented, with per-face smooth normals.
pub fn tessellate_volume_boundary(
    volume: &NurbsVolume,
    samples: [usize; 3],
    sink: &mut dyn MeshSink,
) -> Result<(), SplineError> {
    let samples = samples.map(|n| n.max(2));
    let dom = volume.domain();
    let params: Vec<Vec<f64>> = (0..3).map(|a| dom[a].linspace(samples[a])).collect();
    for axis in 0..3 {
        let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in [0usize, 1] {
            let fixed = if side == 0 {
                dom[axis].min
            } else {
                dom[axis].max
            };
            let mut face = TriMesh::new();
            let (n1, n2) = (samples[a1], samples[a2]);
            let mut grid_params = [params[0].clone(), params[1].clone(), params[2].clone()];
            grid_params[axis] = vec![fixed];
            let pts = volume.eval_grid(
                &grid_params[0],
                &grid_params[1],
                &grid_params[2],
                Parallelism::Auto,
            )?;
            // Reorder to an (a1, a2) grid.
            let strides = [
                grid_params[1].len() * grid_params[2].len(),
                grid_params[2].len(),
                1,
            ];
            for i in 0..n1 {
                for j in 0..n2 {
                    let mut idx = [0usize; 3];
                    idx[a1] = i;
                    idx[a2] = j;
                    let flat = idx[0] * strides[0] + idx[1] * strides[1] + idx[2] * strides[2];
                    face.positions.push(pts[flat]);
                }
            }
            grid_triangles(n1, n2, false, 0, &mut face);
            face.compute_normals();
            // Orientation: compare with the derivative across the face at its middle.
            let mid = [
                dom[0].min + 0.5 * dom[0].length(),
                dom[1].min + 0.5 * dom[1].length(),
                dom[2].min + 0.5 * dom[2].length(),
            ];
            let mut at = mid;
            at[axis] = fixed;
            let d = volume.derivatives(at[0], at[1], at[2], 1)?;
            let across = [d[1][0][0], d[0][1][0], d[0][0][1]][axis];
            let outward = if side == 0 { -across } else { across };
            let centre = (n1 / 2) * n2 + n2 / 2;
            let flip = face.normals[centre].dot(&outward) < 0.0;
            let mut base = None;
            for (p, n) in face.positions.iter().zip(&face.normals) {
                let n: Vec3 = if flip { -n } else { *n };
                let idx = sink.add_vertex(*p, Some(n));
                base.get_or_insert(idx);
            }
            grid_triangles(n1, n2, flip, base.unwrap_or(0), sink);
        }
    }
    Ok(())
}
