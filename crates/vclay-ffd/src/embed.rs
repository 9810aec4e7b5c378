//! A mesh embedded in a lattice: precomputed parameters and basis values, full and incremental
//! deformation.
//!
//! **What.** The process of `ffd-direct-manipulation.txt` section 2: "calculate the parameters
//! (u, v, w) of the points on O with reference to Q(u, v, w), deform the NURBS volume, and compute
//! the new positions of these points by substituting the computed parameters into the deformed
//! NURBS volume", i.e. `x = Q(t_x) = sum P_ijk R_ijk(t_x)` (eq 1) for every embedded vertex.
//!
//! **How.** Once, at embedding: each vertex inside the rest box gets its parameters (linear map),
//! the flat index of its first support control point and its per-axis non-rational B-spline values
//! (`(p+1) + (q+1) + (r+1)` numbers; the tensor products `B_i B_j B_k` and, for a rational lattice,
//! the weights are applied at evaluation, so weight changes need no re-embedding). Vertices are
//! bucketed by knot cell (CSR arrays). A full deformation evaluates every embedded vertex with
//! the contracted tensor-product kernel (`(p+1)(q+1)(r+1) + (p+1)(q+1) + (p+1)` multiply-adds per
//! coordinate), in parallel over vertex chunks; runs of [`LANES`] consecutive vertices in the
//! same knot cell (most of them in a mesh whose vertex order is spatially coherent) go through a
//! blocked kernel that evaluates them together in lane arrays, which the compiler vectorizes
//! (no `unsafe`, no target-specific code). An incremental update after control points
//! `C` changed recomputes only the vertices of the cells whose support meets `C`: control point
//! `i` influences knot cells `i - p ..= i` along each axis.
//!
//! **Limitations.** Vertices outside the rest box are never moved. Normals, when enabled, are
//! recomputed for the whole mesh ([`TriMesh::compute_normals`] is `O(triangles)`), also after an
//! incremental update. Memory is about `8 (p + q + r + 3) + 40` bytes per embedded vertex.

use crate::lattice::FfdLattice;
use rayon::prelude::*;
use vclay_core::{Parallelism, TriMesh, Vec3};

/// Marker for vertices outside the lattice.
const OUTSIDE: u32 = u32::MAX;
/// Vertices per parallel task (a multiple of [`LANES`]).
const CHUNK: usize = 4096;
/// Vertices evaluated together by the blocked kernel of [`EmbeddedMesh::deform`].
pub const LANES: usize = 4;
/// The blocked kernel is used for degrees below this (a stack buffer of `3 * BLOCK_DEGREE`
/// lane arrays); higher degrees use the per-vertex kernel.
const BLOCK_DEGREE: usize = 8;

/// A triangle mesh embedded in an [`FfdLattice`] (`ffd-direct-manipulation.txt` section 2): rest
/// positions, precomputed `(t_x, B(t_x))` per embedded vertex, and the deformed mesh
/// `x = sum P_ijk R_ijk(t_x)` (eq 1).
#[derive(Clone, Debug)]
pub struct EmbeddedMesh {
    rest: Vec<Vec3>,
    mesh: TriMesh,
    /// Per vertex: embedded index or [`OUTSIDE`].
    slot: Vec<u32>,
    /// Per embedded vertex: mesh vertex index.
    vertex: Vec<u32>,
    params: Vec<[f64; 3]>,
    /// Per embedded vertex: flat index of the first support control point.
    base: Vec<u32>,
    /// Per embedded vertex: `B_u (p+1) | B_v (q+1) | B_w (r+1)`.
    basis: Vec<f64>,
    /// CSR over knot cells: embedded vertices of cell `c` are `cell_members[cell_start[c]..cell_start[c+1]]`.
    cell_start: Vec<u32>,
    cell_members: Vec<u32>,
    degree: [usize; 3],
    dims: [usize; 3],
    bounds: (Vec3, Vec3),
    recompute_normals: bool,
    blocked_kernel: bool,
}

impl EmbeddedMesh {
    /// Embeds `mesh` (its positions are the rest positions) in `lattice` and deforms it by the
    /// lattice's current state. Normals are recomputed on output unless disabled by
    /// [`EmbeddedMesh::set_recompute_normals`].
    ///
    /// # Panics
    /// If the mesh has more than `u32::MAX - 1` vertices.
    pub fn new(lattice: &FfdLattice, mesh: TriMesh, par: Parallelism) -> Self {
        let n = mesh.positions.len();
        assert!(n < OUTSIDE as usize, "too many vertices");
        let rest = mesh.positions.clone();
        let located: Vec<Option<[f64; 3]>> = if par.is_parallel(n) {
            rest.par_iter().map(|x| lattice.parameters(x)).collect()
        } else {
            rest.iter().map(|x| lattice.parameters(x)).collect()
        };
        let mut slot = vec![OUTSIDE; n];
        let mut vertex = Vec::new();
        let mut params = Vec::new();
        for (v, t) in located.iter().enumerate() {
            if let Some(t) = t {
                slot[v] = vertex.len() as u32;
                vertex.push(v as u32);
                params.push(*t);
            }
        }
        drop(located);
        let degree = lattice.degree();
        let stride = degree.iter().sum::<usize>() + 3;
        let m = vertex.len();
        let mut base = vec![0u32; m];
        let mut basis = vec![0.0; m * stride];
        let fill = |(t, (b, vals)): (&[f64; 3], (&mut u32, &mut [f64]))| {
            let lb = lattice.local_basis(*t);
            *b = lattice.base_flat(lb.base) as u32;
            let mut o = 0;
            for a in 0..3 {
                vals[o..o + degree[a] + 1].copy_from_slice(&lb.values[a][..=degree[a]]);
                o += degree[a] + 1;
            }
        };
        if par.is_parallel(m) {
            params
                .par_iter()
                .zip(base.par_iter_mut().zip(basis.par_chunks_mut(stride)))
                .for_each(fill);
        } else {
            params
                .iter()
                .zip(base.iter_mut().zip(basis.chunks_mut(stride)))
                .for_each(fill);
        }
        // Bucket by knot cell.
        let dims = lattice.dims();
        let cells = cell_counts(degree, dims);
        let ncells: usize = cells.iter().product();
        let cell_of = |b: u32| {
            let [i, j, k] = lattice.multi_index(b as usize);
            (i * cells[1] + j) * cells[2] + k
        };
        let mut cell_start = vec![0u32; ncells + 1];
        for &b in &base {
            cell_start[cell_of(b) + 1] += 1;
        }
        for c in 0..ncells {
            cell_start[c + 1] += cell_start[c];
        }
        let mut fill_pos = cell_start.clone();
        let mut cell_members = vec![0u32; m];
        for (e, &b) in base.iter().enumerate() {
            let c = cell_of(b);
            cell_members[fill_pos[c] as usize] = e as u32;
            fill_pos[c] += 1;
        }
        let mut out = Self {
            rest,
            mesh,
            slot,
            vertex,
            params,
            base,
            basis,
            cell_start,
            cell_members,
            degree,
            dims,
            bounds: lattice.bounds(),
            recompute_normals: true,
            blocked_kernel: true,
        };
        out.deform(lattice, par);
        out
    }

    /// Whether [`EmbeddedMesh::deform`] and [`EmbeddedMesh::update`] recompute normals (default
    /// true). Turn it off to time or use positions only.
    pub fn set_recompute_normals(&mut self, on: bool) {
        self.recompute_normals = on;
    }

    /// Whether [`EmbeddedMesh::deform`] may use the blocked (SIMD-friendly) kernel (default
    /// true). Both kernels give the same positions up to rounding; turning it off is for
    /// comparisons in benchmarks.
    pub fn set_blocked_kernel(&mut self, on: bool) {
        self.blocked_kernel = on;
    }

    /// The deformed mesh.
    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }
    /// The deformed mesh, by value.
    pub fn into_mesh(self) -> TriMesh {
        self.mesh
    }
    /// Rest positions (as given at embedding).
    pub fn rest_positions(&self) -> &[Vec3] {
        &self.rest
    }
    /// Number of vertices inside the lattice.
    pub fn embedded_count(&self) -> usize {
        self.vertex.len()
    }
    /// Whether vertex `v` is inside the lattice (and deforms).
    pub fn is_embedded(&self, v: usize) -> bool {
        self.slot.get(v).is_some_and(|&s| s != OUTSIDE)
    }
    /// Parameters of vertex `v`, `None` when it is outside.
    pub fn parameters(&self, v: usize) -> Option<[f64; 3]> {
        let s = *self.slot.get(v)?;
        (s != OUTSIDE).then(|| self.params[s as usize])
    }

    #[track_caller]
    fn check_lattice(&self, lattice: &FfdLattice) {
        assert!(
            lattice.dims() == self.dims
                && lattice.degree() == self.degree
                && lattice.bounds() == self.bounds,
            "embedded mesh used with a lattice of another shape"
        );
    }

    #[inline]
    fn eval(&self, lattice: &FfdLattice, e: usize) -> Vec3 {
        let [p, q, r] = self.degree;
        let stride = p + q + r + 3;
        let b = &self.basis[e * stride..(e + 1) * stride];
        let (bu, rest) = b.split_at(p + 1);
        let (bv, bw) = rest.split_at(q + 1);
        lattice.eval_local(self.base[e] as usize, bu, bv, bw)
    }

    /// Full deformation: every embedded vertex `x = sum P_ijk R_ijk(t_x)` (eq 1), then normals.
    ///
    /// Runs of [`LANES`] consecutive mesh vertices that are all embedded in the same knot cell
    /// (the common case: neighbouring vertices are near each other) are evaluated together, lane
    /// by lane in fixed-size arrays the compiler turns into SIMD instructions; other vertices one
    /// by one. Parallel over chunks of vertices when `par` allows.
    ///
    /// # Panics
    /// If `lattice` has other dimensions, degrees or box than the one embedded in.
    #[track_caller]
    pub fn deform(&mut self, lattice: &FfdLattice, par: Parallelism) -> &TriMesh {
        self.check_lattice(lattice);
        let mut positions = std::mem::take(&mut self.mesh.positions);
        let this = &*self;
        let blocked = self.blocked_kernel
            && !lattice.is_rational()
            && self.degree.iter().all(|&d| d < BLOCK_DEGREE);
        let kernel = |(xs, slots): (&mut [Vec3], &[u32])| {
            if blocked {
                let mut xb = xs.chunks_exact_mut(LANES);
                let mut sb = slots.chunks_exact(LANES);
                for (x, s) in (&mut xb).zip(&mut sb) {
                    let s: &[u32; LANES] = s.try_into().expect("chunk of LANES");
                    let b0 = if s[0] != OUTSIDE {
                        this.base[s[0] as usize]
                    } else {
                        OUTSIDE
                    };
                    if b0 != OUTSIDE
                        && s.iter()
                            .all(|&e| e != OUTSIDE && this.base[e as usize] == b0)
                    {
                        let out = this.eval_block(lattice, s);
                        x.copy_from_slice(&out);
                    } else {
                        for (xi, &e) in x.iter_mut().zip(s) {
                            if e != OUTSIDE {
                                *xi = this.eval(lattice, e as usize);
                            }
                        }
                    }
                }
                for (xi, &e) in xb.into_remainder().iter_mut().zip(sb.remainder()) {
                    if e != OUTSIDE {
                        *xi = this.eval(lattice, e as usize);
                    }
                }
            } else {
                for (x, &s) in xs.iter_mut().zip(slots) {
                    if s != OUTSIDE {
                        *x = this.eval(lattice, s as usize);
                    }
                }
            }
        };
        if par.is_parallel(this.vertex.len()) {
            positions
                .par_chunks_mut(CHUNK)
                .zip(this.slot.par_chunks(CHUNK))
                .for_each(kernel);
        } else {
            positions
                .chunks_mut(CHUNK)
                .zip(this.slot.chunks(CHUNK))
                .for_each(kernel);
        }
        self.mesh.positions = positions;
        self.finish();
        &self.mesh
    }

    /// [`LANES`] embedded vertices of one knot cell (same support base) at once, non-rational
    /// lattice: the same contraction as [`FfdLattice::eval_local`] with every scalar replaced by
    /// a lane array (control points broadcast, basis values per lane).
    #[inline]
    fn eval_block(&self, lattice: &FfdLattice, e: &[u32; LANES]) -> [Vec3; LANES] {
        let [p, q, r] = self.degree;
        let stride = p + q + r + 3;
        let mut bl = [[0.0f64; LANES]; 3 * BLOCK_DEGREE];
        for (l, &ei) in e.iter().enumerate() {
            let b = &self.basis[ei as usize * stride..(ei as usize + 1) * stride];
            for (k, &v) in b.iter().enumerate() {
                bl[k][l] = v;
            }
        }
        let (bu, rest) = bl[..stride].split_at(p + 1);
        let (bv, bw) = rest.split_at(q + 1);
        let [_, nv, nw] = self.dims;
        let su = nv * nw;
        let base = self.base[e[0] as usize] as usize;
        let pts = lattice.control_points();
        let zero = [0.0f64; LANES];
        let (mut x, mut y, mut z) = (zero, zero, zero);
        for (a, ba) in bu.iter().enumerate() {
            let (mut xv, mut yv, mut zv) = (zero, zero, zero);
            for (c, bc) in bv.iter().enumerate() {
                let start = base + a * su + c * nw;
                let row = &pts[start..start + bw.len()];
                let (mut xw, mut yw, mut zw) = (zero, zero, zero);
                for (pt, be) in row.iter().zip(bw) {
                    for l in 0..LANES {
                        xw[l] += pt.x * be[l];
                        yw[l] += pt.y * be[l];
                        zw[l] += pt.z * be[l];
                    }
                }
                for l in 0..LANES {
                    xv[l] += xw[l] * bc[l];
                    yv[l] += yw[l] * bc[l];
                    zv[l] += zw[l] * bc[l];
                }
            }
            for l in 0..LANES {
                x[l] += xv[l] * ba[l];
                y[l] += yv[l] * ba[l];
                z[l] += zv[l] * ba[l];
            }
        }
        std::array::from_fn(|l| Vec3::new(x[l], y[l], z[l]))
    }

    /// Incremental deformation after the control points (or weights) with flat indices `changed`
    /// were modified: recomputes only the vertices of knot cells whose support contains one of
    /// them. Returns how many vertices were recomputed. The result equals [`EmbeddedMesh::deform`]
    /// as long as nothing else in the lattice changed.
    ///
    /// # Panics
    /// If `lattice` has another shape than the one embedded in, or an index is out of range.
    #[track_caller]
    pub fn update(&mut self, lattice: &FfdLattice, changed: &[usize], par: Parallelism) -> usize {
        self.check_lattice(lattice);
        let cells = cell_counts(self.degree, self.dims);
        let mut hit = vec![false; cells.iter().product()];
        let [_, nv, nw] = self.dims;
        for &c in changed {
            assert!(
                c < self.dims.iter().product(),
                "control point {c} out of range"
            );
            let ijk = [c / (nv * nw), (c / nw) % nv, c % nw];
            let range = |a: usize| ijk[a].saturating_sub(self.degree[a])..=ijk[a].min(cells[a] - 1);
            for i in range(0) {
                for j in range(1) {
                    for k in range(2) {
                        hit[(i * cells[1] + j) * cells[2] + k] = true;
                    }
                }
            }
        }
        let affected: Vec<u32> = hit
            .iter()
            .enumerate()
            .filter(|(_, h)| **h)
            .flat_map(|(c, _)| {
                let (a, b) = (self.cell_start[c] as usize, self.cell_start[c + 1] as usize);
                self.cell_members[a..b].iter().copied()
            })
            .collect();
        let this = &*self;
        let blocked = self.blocked_kernel
            && !lattice.is_rational()
            && self.degree.iter().all(|&d| d < BLOCK_DEGREE);
        // Members of one cell are consecutive in `affected` and share their support base, so
        // the blocked kernel applies to almost every group of LANES.
        let kernel = |(es, xs): (&[u32], &mut [Vec3])| {
            if blocked {
                let mut eb = es.chunks_exact(LANES);
                let mut xb = xs.chunks_exact_mut(LANES);
                for (e, x) in (&mut eb).zip(&mut xb) {
                    let e: &[u32; LANES] = e.try_into().expect("chunk of LANES");
                    let b0 = this.base[e[0] as usize];
                    if e.iter().all(|&ei| this.base[ei as usize] == b0) {
                        x.copy_from_slice(&this.eval_block(lattice, e));
                    } else {
                        for (xi, &ei) in x.iter_mut().zip(e) {
                            *xi = this.eval(lattice, ei as usize);
                        }
                    }
                }
                for (xi, &ei) in xb.into_remainder().iter_mut().zip(eb.remainder()) {
                    *xi = this.eval(lattice, ei as usize);
                }
            } else {
                for (xi, &ei) in xs.iter_mut().zip(es) {
                    *xi = this.eval(lattice, ei as usize);
                }
            }
        };
        let mut new = vec![Vec3::zeros(); affected.len()];
        if par.is_parallel(affected.len()) {
            affected
                .par_chunks(CHUNK)
                .zip(new.par_chunks_mut(CHUNK))
                .for_each(kernel);
        } else {
            affected
                .chunks(CHUNK)
                .zip(new.chunks_mut(CHUNK))
                .for_each(kernel);
        }
        for (&e, x) in affected.iter().zip(new) {
            self.mesh.positions[self.vertex[e as usize] as usize] = x;
        }
        if !affected.is_empty() {
            self.finish();
        }
        affected.len()
    }

    fn finish(&mut self) {
        if self.recompute_normals && !self.mesh.triangles.is_empty() {
            self.mesh.compute_normals();
        }
    }
}

/// Knot cells (non-empty spans) per axis of a clamped uniform lattice: `n - p`.
fn cell_counts(degree: [usize; 3], dims: [usize; 3]) -> [usize; 3] {
    [0, 1, 2].map(|a| dims[a] - degree[a])
}
