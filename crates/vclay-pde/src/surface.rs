//! Evaluating and tessellating a solved patch (`dynamic-pde-surfaces.txt` eq 5, 30-32, 36).
//!
//! A solved component is `x_i(u, v, t) = sum_j W_ij(u) g_ij(v, t)` plus the local deformation
//! terms. On a grid `us x vs` the basic functions are evaluated once per column, the
//! polynomials `W_ij` once per row (Horner), and each point costs J multiply-adds per
//! component; rows are accumulated in contiguous buffers so the inner loop vectorises.

use crate::patch::PdePatch;
use crate::solve::PatchSolution;
use vclay_core::{MeshSink, Vec3};

/// Reusable buffers for [`eval_grid`].
#[derive(Clone, Debug, Default)]
pub struct GridWork {
    /// Per component: g_ij at each column, basic-major.
    gvals: [Vec<f64>; 3],
    /// Per component: W_ij at the current row.
    wrow: [Vec<f64>; 3],
    /// Per component: the current row of values.
    row: [Vec<f64>; 3],
}

#[inline]
fn horner(p: &[f64], u: f64) -> f64 {
    p.iter().rev().fold(0.0, |acc, c| acc * u + c)
}

/// Point of a solved patch at (u, v), local deformations included.
pub fn point(patch: &PdePatch, sol: &PatchSolution, u: f64, v: f64) -> Vec3 {
    if let Some(s) = &sol.spectral {
        let [x, y, z] = s.point(patch, u, v, sol.t);
        return Vec3::new(x, y, z);
    }
    let n1 = patch.trial.n_max + 1;
    let t = sol.t;
    let mut x = [0.0; 3];
    for (i, xi) in x.iter_mut().enumerate() {
        for (j, b) in patch.components[i].basics.iter().enumerate() {
            *xi += horner(&sol.weights[i][j * n1..(j + 1) * n1], u) * b.g.eval(0.0, v, t);
        }
    }
    for l in &patch.local {
        let d = l.offset(u, v, t);
        for i in 0..3 {
            x[i] += d[i];
        }
    }
    Vec3::new(x[0], x[1], x[2])
}

/// Point and first partial derivatives `(x, x_u, x_v)` of a solved patch at (u, v), for normals
/// and continuity checks. Collocation patches are differentiated exactly (`W_ij'(u)` from the
/// polynomial coefficients, `g_v` symbolic, eq 5); local deformations and the spectral
/// solutions by central differences of step `1e-6` (one-sided at the domain's ends).
pub fn derivatives(patch: &PdePatch, sol: &PatchSolution, u: f64, v: f64) -> [Vec3; 3] {
    let p = point(patch, sol, u, v);
    let fd = |f: &dyn Fn(f64, f64) -> Vec3, lo: f64, hi: f64, x: f64, along_u: bool| {
        let h = 1e-6 * (hi - lo);
        let (a, b) = ((x - h).max(lo), (x + h).min(hi));
        let at = |y: f64| if along_u { f(y, v) } else { f(u, y) };
        (at(b) - at(a)) / (b - a)
    };
    if sol.spectral.is_some() {
        let f = |a: f64, b: f64| point(patch, sol, a, b);
        let (v0, v1) = patch.v_range;
        return [p, fd(&f, 0.0, 1.0, u, true), fd(&f, v0, v1, v, false)];
    }
    let n1 = patch.trial.n_max + 1;
    let t = sol.t;
    let (mut du, mut dv) = ([0.0; 3], [0.0; 3]);
    for i in 0..3 {
        for (j, b) in patch.components[i].basics.iter().enumerate() {
            let w = &sol.weights[i][j * n1..(j + 1) * n1];
            let wd = w
                .iter()
                .enumerate()
                .skip(1)
                .rev()
                .fold(0.0, |acc, (n, c)| acc * u + n as f64 * c);
            du[i] += wd * b.g.eval(0.0, v, t);
            dv[i] += horner(w, u) * b.g_v.eval(0.0, v, t);
        }
    }
    let (mut xu, mut xv) = (
        Vec3::new(du[0], du[1], du[2]),
        Vec3::new(dv[0], dv[1], dv[2]),
    );
    if !patch.local.is_empty() {
        let off = |a: f64, b: f64| {
            patch.local.iter().fold(Vec3::zeros(), |acc, l| {
                let d = l.offset(a, b, t);
                acc + Vec3::new(d[0], d[1], d[2])
            })
        };
        let (v0, v1) = patch.v_range;
        xu += fd(&off, 0.0, 1.0, u, true);
        xv += fd(&off, v0, v1, v, false);
    }
    [p, xu, xv]
}

/// Evaluates the patch on the grid `us x vs` (row-major: `out[r * vs.len() + c]` is at
/// `(us[r], vs[c])`), local deformations included. `out` is resized.
pub fn eval_grid(
    patch: &PdePatch,
    sol: &PatchSolution,
    us: &[f64],
    vs: &[f64],
    work: &mut GridWork,
    out: &mut Vec<Vec3>,
) {
    out.resize(us.len() * vs.len(), Vec3::zeros());
    eval_grid_into(patch, sol, us, vs, work, out);
}

/// As [`eval_grid`], into a slice of length `us.len() * vs.len()`.
///
/// # Panics
/// If `out` has the wrong length.
#[track_caller]
pub fn eval_grid_into(
    patch: &PdePatch,
    sol: &PatchSolution,
    us: &[f64],
    vs: &[f64],
    work: &mut GridWork,
    out: &mut [Vec3],
) {
    let n1 = patch.trial.n_max + 1;
    let nv = vs.len();
    let t = sol.t;
    assert_eq!(out.len(), us.len() * nv, "eval_grid_into: output length");
    if let Some(s) = &sol.spectral {
        s.eval_grid(patch, t, us, vs, out);
        return;
    }
    for i in 0..3 {
        let basics = &patch.components[i].basics;
        let g = &mut work.gvals[i];
        g.clear();
        for b in basics {
            g.extend(vs.iter().map(|&v| b.g.eval(0.0, v, t)));
        }
        work.wrow[i].resize(basics.len(), 0.0);
        work.row[i].resize(nv, 0.0);
    }
    for (r, &u) in us.iter().enumerate() {
        for i in 0..3 {
            let nb = patch.components[i].basics.len();
            let w = &mut work.wrow[i];
            for j in 0..nb {
                w[j] = horner(&sol.weights[i][j * n1..(j + 1) * n1], u);
            }
            let row = &mut work.row[i];
            if nb == 0 {
                row.iter_mut().for_each(|x| *x = 0.0);
            }
            for j in 0..nb {
                let wj = w[j];
                let g = &work.gvals[i][j * nv..(j + 1) * nv];
                if j == 0 {
                    for (x, gv) in row.iter_mut().zip(g) {
                        *x = wj * gv;
                    }
                } else {
                    for (x, gv) in row.iter_mut().zip(g) {
                        *x += wj * gv;
                    }
                }
            }
        }
        let dst = &mut out[r * nv..(r + 1) * nv];
        let [rx, ry, rz] = &work.row;
        for (c, p) in dst.iter_mut().enumerate() {
            *p = Vec3::new(rx[c], ry[c], rz[c]);
        }
    }
    for l in &patch.local {
        let (u1, u2) = l.u_range;
        let (v1, v2) = l.v_range;
        for (r, &u) in us.iter().enumerate() {
            if u <= u1 || u >= u2 {
                continue;
            }
            for (c, &v) in vs.iter().enumerate() {
                if v <= v1 || v >= v2 {
                    continue;
                }
                let d = l.offset(u, v, t);
                out[r * nv + c] += Vec3::new(d[0], d[1], d[2]);
            }
        }
    }
}

/// `n` uniform samples of `[a, b]` (both ends included; `n >= 2`).
pub fn uniform(a: f64, b: f64, n: usize) -> Vec<f64> {
    let n = n.max(2);
    (0..n)
        .map(|k| a + (b - a) * k as f64 / (n - 1) as f64)
        .collect()
}

/// Samples of the patch domain for tessellation: `nu x nv` uniform samples, plus 12 uniform
/// samples across every local-deformation region (its borders included, so that the border is
/// a grid line and a G0 crease stays sharp).
pub fn tessellation_samples(patch: &PdePatch, nu: usize, nv: usize) -> (Vec<f64>, Vec<f64>) {
    let (v0, v1) = patch.v_range;
    let mut us = uniform(0.0, 1.0, nu);
    let mut vs = uniform(v0, v1, nv);
    for l in &patch.local {
        let k = 12;
        us.extend(uniform(l.u_range.0, l.u_range.1, k));
        vs.extend(uniform(l.v_range.0, l.v_range.1, k));
    }
    let clean = |x: &mut Vec<f64>| {
        x.sort_by(f64::total_cmp);
        let span = x.last().copied().unwrap_or(1.0) - x.first().copied().unwrap_or(0.0);
        x.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * span.max(1.0));
    };
    if !patch.local.is_empty() {
        clean(&mut us);
        clean(&mut vs);
    }
    (us, vs)
}

/// Writes a grid of points (`nu x nv`, row-major) as quads into `sink`, with normals from
/// central differences of the grid (one-sided at the borders; where the grid degenerates,
/// e.g. at a pole, the average of the neighbouring cell normals). Triangles are
/// counter-clockwise about `x_u x x_v`.
///
/// # Panics
/// If `points.len() != nu * nv`.
#[track_caller]
pub fn grid_to_mesh(points: &[Vec3], nu: usize, nv: usize, sink: &mut dyn MeshSink) {
    assert_eq!(points.len(), nu * nv, "grid_to_mesh: point count");
    sink.reserve(nu * nv, 2 * (nu.saturating_sub(1)) * (nv.saturating_sub(1)));
    let at = |r: usize, c: usize| points[r * nv + c];
    let cell_normal = |r: usize, c: usize| -> Vec3 {
        // Cross product of the diagonals of cell (r, c) (r < nu-1, c < nv-1).
        (at(r + 1, c + 1) - at(r, c)).cross(&(at(r, c + 1) - at(r + 1, c)))
    };
    let mut base = None;
    for r in 0..nu {
        for c in 0..nv {
            let du = at((r + 1).min(nu - 1), c) - at(r.saturating_sub(1), c);
            let dv = at(r, (c + 1).min(nv - 1)) - at(r, c.saturating_sub(1));
            let mut n = du.cross(&dv);
            let scale = du.norm() * dv.norm();
            let degenerate =
                n.norm().partial_cmp(&(1e-9 * scale)) != Some(std::cmp::Ordering::Greater);
            if degenerate && nu > 1 && nv > 1 {
                n = Vec3::zeros();
                for rr in r.saturating_sub(1)..=r.min(nu - 2) {
                    for cc in c.saturating_sub(1)..=c.min(nv - 2) {
                        n += cell_normal(rr, cc);
                    }
                }
            }
            let len = n.norm();
            let n = if len > 0.0 && len.is_finite() {
                n / len
            } else {
                Vec3::z()
            };
            let idx = sink.add_vertex(at(r, c), Some(n));
            if base.is_none() {
                base = Some(idx);
            }
        }
    }
    let base = base.unwrap_or(0);
    let id = |r: usize, c: usize| base + (r * nv + c) as u32;
    for r in 0..nu.saturating_sub(1) {
        for c in 0..nv.saturating_sub(1) {
            sink.add_quad([id(r, c), id(r + 1, c), id(r + 1, c + 1), id(r, c + 1)]);
        }
    }
}

/// Tessellates a solved patch on `nu x nv` samples (see [`tessellation_samples`]) into `sink`.
pub fn tessellate(
    patch: &PdePatch,
    sol: &PatchSolution,
    nu: usize,
    nv: usize,
    sink: &mut dyn MeshSink,
) {
    let (us, vs) = tessellation_samples(patch, nu, nv);
    let mut pts = Vec::new();
    eval_grid(patch, sol, &us, &vs, &mut GridWork::default(), &mut pts);
    grid_to_mesh(&pts, us.len(), vs.len(), sink);
}
