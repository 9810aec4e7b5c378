//! Tessellation of surfaces and volume boundaries into a [`MeshSink`].
//!
//! Surfaces are sampled on a uniform parameter grid and split into two triangles per cell, with
//! analytic normals `s_u x s_v` (where the surface is degenerate, such as at the pole of a
//! sphere, the mesh normal from the adjacent triangles replaces it). Volumes are tessellated by
//! their six boundary faces, each oriented so that its normals point out of the volume
//! (checked against the volume's derivative across the face).

use crate::error::SplineError;
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

/// Tessellates `surface` on a `samples[0] x samples[1]` grid (each at least 2) into `sink`.
///
/// Triangles are counter-clockwise around `s_u x s_v`.
pub fn tessellate_surface(
    surface: &NurbsSurface,
    samples: [usize; 2],
    sink: &mut dyn MeshSink,
) -> Result<(), SplineError> {
    let [nu, nv] = samples.map(|n| n.max(2));
    let [du, dv] = crate::traits::ParametricSurface::domain(surface);
    let (us, vs) = (du.linspace(nu), dv.linspace(nv));
    let g = surface.eval_grid_with_derivatives(&us, &vs, Parallelism::Auto)?;
    // Mesh normals as a fallback at degenerate points.
    let mut mesh = TriMesh::new();
    mesh.positions = g.points.clone();
    grid_triangles(nu, nv, false, 0, &mut mesh);
    mesh.compute_normals();
    // A point is degenerate when its |s_u x s_v| is negligible next to the largest on the grid
    // (relative tolerance DEGENERATE_NORMAL_RELATIVE).
    let crosses: Vec<Vec3> = g.du.iter().zip(&g.dv).map(|(a, b)| a.cross(b)).collect();
    let largest = crosses.iter().map(|c| c.norm()).fold(0.0, f64::max);
    let tiny = DEGENERATE_NORMAL_RELATIVE * largest;
    sink.reserve(nu * nv, 2 * (nu - 1) * (nv - 1));
    let mut base = None;
    for k in 0..nu * nv {
        let n = crosses[k];
        let normal = if n.norm() > tiny {
            n.normalize()
        } else {
            // Limit of the analytic normal: evaluate slightly inside the domain.
            let (u, v) = (us[k / nv], vs[k % nv]);
            let nudge = |t: f64, d: vclay_core::Interval| {
                let h = NORMAL_NUDGE_RELATIVE * d.length();
                if t + h <= d.max { t + h } else { t - h }
            };
            let d = crate::traits::ParametricSurface::derivatives(
                surface,
                nudge(u, du),
                nudge(v, dv),
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
    Ok(())
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
