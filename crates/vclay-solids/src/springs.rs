//! The mass-spring lattice of `subdivision-solids-journal.txt` section 5.1: a Hookean spring on
//! every edge of the data lattice and the paper's virtual springs.
//!
//! # Edge springs
//! For an edge `(a, b)` with `x = d_b - d_a`, `l = |x|`, `u = x / l`: energy
//! `E = k/2 (l - l0)^2`, force on `b` `-k (l - l0) u` and the opposite on `a` (Hooke's law,
//! `f = -k (l - l0)`).
//!
//! # Virtual springs
//! For each point `m` of each face, with `a` and `b` its two neighbours in the face loop, the
//! virtual point is `v = (a + b) / 2`; a spring joins `m` and `v` with rest length `|m0 - v0|`.
//! With `x = m - v`: `E = k/2 (|x| - l0)^2`, force on `m` `f = -k (|x| - l0) x/|x|`, and
//! `-f/2` on each of `a` and `b` ("exactly one-half of that force is applied in the opposite
//! direction to each of the endpoints that define the virtual point", which is `-dE/da`: the
//! forces are conservative and sum to zero).
//!
//! # Stiffness for implicit integration
//! The Hessian of one spring with respect to its vector `x` is
//! `H = k [u u^T + max(0, 1 - l0/l) (I - u u^T)]`; the transverse term is clamped at zero
//! (dropped under compression) so that `H` stays positive semi-definite and conjugate gradient
//! applies (the usual choice for implicit mass-spring solvers).
//!
//! # How
//! Forces are scattered into one buffer per rayon thread (springs split into contiguous ranges),
//! then summed, so the hot loop has no atomics and allocates nothing.

use rayon::prelude::*;
use vclay_core::{Parallelism, Vec3};

/// Springs below this count run on one thread.
const PARALLEL_SPRINGS: usize = 100_000;

/// Edge springs and virtual springs of a data lattice (or of its active part).
#[derive(Clone, Debug, Default)]
pub struct SpringSet {
    /// Edge endpoints.
    pub edges: Vec<[u32; 2]>,
    /// Edge rest lengths.
    pub edge_rest: Vec<f64>,
    /// Edge stiffness `k`.
    pub edge_k: Vec<f64>,
    /// Face loop offsets (`faces + 1` entries).
    pub face_offsets: Vec<u32>,
    /// Face loop vertices, flat.
    pub face_verts: Vec<u32>,
    /// Rest length of the virtual spring at each face corner (aligned with `face_verts`).
    pub corner_rest: Vec<f64>,
    /// Virtual spring stiffness per corner (aligned with `face_verts`).
    pub corner_k: Vec<f64>,
}

/// Per-thread force buffers.
#[derive(Clone, Debug, Default)]
pub struct ForceWorkspace {
    bufs: Vec<Vec<Vec3>>,
}

#[inline]
fn corner(verts: &[u32], j: usize) -> (usize, usize, usize) {
    let k = verts.len();
    (
        verts[j] as usize,
        verts[(j + k - 1) % k] as usize,
        verts[(j + 1) % k] as usize,
    )
}

impl SpringSet {
    /// Number of faces.
    pub fn num_faces(&self) -> usize {
        self.face_offsets.len().saturating_sub(1)
    }

    /// Number of springs (edges plus virtual).
    pub fn len(&self) -> usize {
        self.edges.len() + self.face_verts.len()
    }

    /// Whether there are no springs.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Sets every rest length to the length in configuration `d` (plastic reset, journal
    /// section 5.4: both kinds of spring).
    pub fn reset_rest(&mut self, d: &[Vec3]) {
        for (e, r) in self.edges.iter().zip(&mut self.edge_rest) {
            *r = (d[e[1] as usize] - d[e[0] as usize]).norm();
        }
        for f in 0..self.num_faces() {
            let (lo, hi) = (
                self.face_offsets[f] as usize,
                self.face_offsets[f + 1] as usize,
            );
            let verts = &self.face_verts[lo..hi];
            for j in 0..verts.len() {
                let (m, a, b) = corner(verts, j);
                self.corner_rest[lo + j] = (d[m] - (d[a] + d[b]) * 0.5).norm();
            }
        }
    }

    /// The subset of springs that touch a point with `keep[i]` (journal section 5.2: springs
    /// among data points that only fixed control points define need no processing).
    pub fn filter(&self, keep: &[bool]) -> SpringSet {
        let mut out = SpringSet {
            face_offsets: vec![0],
            ..Default::default()
        };
        for (i, e) in self.edges.iter().enumerate() {
            if keep[e[0] as usize] || keep[e[1] as usize] {
                out.edges.push(*e);
                out.edge_rest.push(self.edge_rest[i]);
                out.edge_k.push(self.edge_k[i]);
            }
        }
        for f in 0..self.num_faces() {
            let (lo, hi) = (
                self.face_offsets[f] as usize,
                self.face_offsets[f + 1] as usize,
            );
            if self.face_verts[lo..hi].iter().any(|&v| keep[v as usize]) {
                out.face_verts.extend_from_slice(&self.face_verts[lo..hi]);
                out.corner_rest.extend_from_slice(&self.corner_rest[lo..hi]);
                out.corner_k.extend_from_slice(&self.corner_k[lo..hi]);
                out.face_offsets.push(out.face_verts.len() as u32);
            }
        }
        out
    }

    /// Potential energy `sum k/2 (l - l0)^2` in configuration `d`.
    pub fn energy(&self, d: &[Vec3]) -> f64 {
        let mut e = 0.0;
        for (i, s) in self.edges.iter().enumerate() {
            let l = (d[s[1] as usize] - d[s[0] as usize]).norm();
            e += 0.5 * self.edge_k[i] * (l - self.edge_rest[i]).powi(2);
        }
        for f in 0..self.num_faces() {
            let (lo, hi) = (
                self.face_offsets[f] as usize,
                self.face_offsets[f + 1] as usize,
            );
            let verts = &self.face_verts[lo..hi];
            for j in 0..verts.len() {
                let (m, a, b) = corner(verts, j);
                let l = (d[m] - (d[a] + d[b]) * 0.5).norm();
                e += 0.5 * self.corner_k[lo + j] * (l - self.corner_rest[lo + j]).powi(2);
            }
        }
        e
    }

    /// Adds the spring forces in configuration `d` to `f` and returns the potential energy.
    pub fn add_forces(
        &self,
        d: &[Vec3],
        f: &mut [Vec3],
        ws: &mut ForceWorkspace,
        par: Parallelism,
    ) -> f64 {
        let threads = if par.is_parallel(self.len()) && self.len() >= PARALLEL_SPRINGS {
            rayon::current_num_threads().max(1)
        } else {
            1
        };
        if threads == 1 {
            return self.forces_range(d, f, 0..self.edges.len(), 0..self.num_faces());
        }
        ws.bufs.resize_with(threads, Vec::new);
        let (ne, nf) = (self.edges.len(), self.num_faces());
        let energy: f64 = ws
            .bufs
            .par_iter_mut()
            .enumerate()
            .map(|(t, buf)| {
                buf.clear();
                buf.resize(d.len(), Vec3::zeros());
                let er = ne * t / threads..ne * (t + 1) / threads;
                let fr = nf * t / threads..nf * (t + 1) / threads;
                self.forces_range(d, buf, er, fr)
            })
            .sum();
        let bufs = &ws.bufs;
        f.par_chunks_mut(8192).enumerate().for_each(|(c, chunk)| {
            let base = c * 8192;
            for b in bufs {
                for (k, x) in chunk.iter_mut().enumerate() {
                    *x += b[base + k];
                }
            }
        });
        energy
    }

    fn forces_range(
        &self,
        d: &[Vec3],
        f: &mut [Vec3],
        edges: std::ops::Range<usize>,
        faces: std::ops::Range<usize>,
    ) -> f64 {
        let mut energy = 0.0;
        for i in edges {
            let [a, b] = self.edges[i];
            let (a, b) = (a as usize, b as usize);
            let x = d[b] - d[a];
            let l = x.norm();
            let s = l - self.edge_rest[i];
            if s == 0.0 || l == 0.0 {
                continue;
            }
            let k = self.edge_k[i];
            energy += 0.5 * k * s * s;
            let g = x * (k * s / l);
            f[a] += g;
            f[b] -= g;
        }
        for fc in faces {
            let (lo, hi) = (
                self.face_offsets[fc] as usize,
                self.face_offsets[fc + 1] as usize,
            );
            let verts = &self.face_verts[lo..hi];
            if let [i0, i1, i2, i3] = *verts {
                // Quads (every face of a subdivided lattice): corners 0 and 2 share the virtual
                // point (p1 + p3) / 2, corners 1 and 3 share (p0 + p2) / 2; four scatters.
                let idx = [i0 as usize, i1 as usize, i2 as usize, i3 as usize];
                let p = idx.map(|i| d[i]);
                let mid = [(p[1] + p[3]) * 0.5, (p[0] + p[2]) * 0.5];
                let mut acc = [Vec3::zeros(); 4];
                let rest = &self.corner_rest[lo..hi];
                let ks = &self.corner_k[lo..hi];
                for j in 0..4 {
                    let x = p[j] - mid[j & 1];
                    let l = x.norm();
                    let s = l - rest[j];
                    if l == 0.0 {
                        continue;
                    }
                    energy += 0.5 * ks[j] * s * s;
                    let g = x * (ks[j] * s / l);
                    acc[j] -= g;
                    let h = g * 0.5;
                    acc[(j + 1) & 3] += h;
                    acc[(j + 3) & 3] += h;
                }
                for j in 0..4 {
                    f[idx[j]] += acc[j];
                }
                continue;
            }
            for j in 0..verts.len() {
                let (m, a, b) = corner(verts, j);
                let x = d[m] - (d[a] + d[b]) * 0.5;
                let l = x.norm();
                let s = l - self.corner_rest[lo + j];
                if s == 0.0 || l == 0.0 {
                    continue;
                }
                let k = self.corner_k[lo + j];
                energy += 0.5 * k * s * s;
                let g = x * (k * s / l);
                f[m] -= g;
                let h = g * 0.5;
                f[a] += h;
                f[b] += h;
            }
        }
        energy
    }

    /// `out += K y`, with `K` the clamped (positive semi-definite) stiffness matrix of the
    /// springs at configuration `d` (see the [module docs](self)). Sequential.
    pub fn add_stiffness_product(&self, d: &[Vec3], y: &[Vec3], out: &mut [Vec3]) {
        for (i, e) in self.edges.iter().enumerate() {
            let (a, b) = (e[0] as usize, e[1] as usize);
            let h =
                spring_hessian_apply(d[b] - d[a], self.edge_k[i], self.edge_rest[i], y[b] - y[a]);
            out[b] += h;
            out[a] -= h;
        }
        for fc in 0..self.num_faces() {
            let (lo, hi) = (
                self.face_offsets[fc] as usize,
                self.face_offsets[fc + 1] as usize,
            );
            let verts = &self.face_verts[lo..hi];
            for j in 0..verts.len() {
                let (m, a, b) = corner(verts, j);
                let x = d[m] - (d[a] + d[b]) * 0.5;
                let yx = y[m] - (y[a] + y[b]) * 0.5;
                let h =
                    spring_hessian_apply(x, self.corner_k[lo + j], self.corner_rest[lo + j], yx);
                out[m] += h;
                out[a] -= h * 0.5;
                out[b] -= h * 0.5;
            }
        }
    }

    /// A bound on the largest eigenvalue of `K` at rest, per point: Gershgorin row sums
    /// (`sum` of the stiffnesses a point takes part in, each counted with its coupling weight).
    pub fn gershgorin(&self, n: usize) -> Vec<f64> {
        let mut g = vec![0.0; n];
        for (i, e) in self.edges.iter().enumerate() {
            g[e[0] as usize] += 2.0 * self.edge_k[i];
            g[e[1] as usize] += 2.0 * self.edge_k[i];
        }
        for fc in 0..self.num_faces() {
            let (lo, hi) = (
                self.face_offsets[fc] as usize,
                self.face_offsets[fc + 1] as usize,
            );
            let verts = &self.face_verts[lo..hi];
            for j in 0..verts.len() {
                let (m, a, b) = corner(verts, j);
                let k = self.corner_k[lo + j];
                g[m] += 2.0 * k;
                g[a] += k;
                g[b] += k;
            }
        }
        g
    }
}

/// `H y` for one spring with vector `x`, stiffness `k`, rest length `l0` (clamped Hessian).
#[inline]
pub(crate) fn spring_hessian_apply(x: Vec3, k: f64, l0: f64, y: Vec3) -> Vec3 {
    let l = x.norm();
    if l == 0.0 {
        return y * k;
    }
    let u = x / l;
    let along = u * u.dot(&y);
    let t = (1.0 - l0 / l).max(0.0);
    (along + (y - along) * t) * k
}
