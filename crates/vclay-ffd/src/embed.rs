//! A mesh embedded in a lattice: precomputed knot cells and local coordinates, full and
//! incremental deformation.
//!
//! **What.** The process of `ffd-direct-manipulation.txt` section 2: "calculate the parameters
//! (u, v, w) of the points on O with reference to Q(u, v, w), deform the NURBS volume, and compute
//! the new positions of these points by substituting the computed parameters into the deformed
//! NURBS volume", i.e. `x = Q(t_x) = sum P_ijk R_ijk(t_x)` (eq 1) for every embedded vertex.
//!
//! **How.** Once, at embedding: each vertex inside the rest box gets its parameters `t_x` by the
//! linear map of section 2 (the rest lattice is the identity, so no Newton iteration), the knot
//! cell `(i, j, k)` (non-empty knot span per axis) containing them and its local coordinates
//! `(s_u, s_v, s_w) in [0, 1]^3` in that cell, `s = (t - t_i) / (t_{i+1} - t_i)`. The embedded
//! vertices are stored sorted by cell (a stable counting sort, skipped when the mesh order is
//! already the cell order), with CSR offsets per cell. The parameters themselves are not stored:
//! [`EmbeddedMesh::parameters`] recomputes them from the rest position with the same arithmetic.
//!
//! On one knot cell every B-spline `B_a(t)` of eq (2) is a polynomial of degree `p` in `s`,
//! `B_{i-p+a}(t) = sum_k M_ak s^k` (the matrix `M` of each span follows from Cox-de Boor,
//! Piegl & Tiller A2.2, carried out on polynomial coefficients), so the deformed volume is, on that
//! cell, the polynomial
//!
//! ```text
//! Q = sum_{k,l,m} C_klm s_u^k s_v^l s_w^m,
//! C_klm = sum_{a,b,c} M^u_ak M^v_bl M^w_cm P_(i-p+a)(j-q+b)(k-r+c)
//! ```
//!
//! (for a rational lattice the same with `(W P, W)` and one division). A deformation converts
//! each cell it meets to these coefficients once per parallel task (sum factorization: three
//! contractions, `3 (p+1)^4` multiply-adds per component when `p = q = r`), then evaluates the
//! cell's vertices by nested Horner: `(p+1)(q+1) r + (p+1) q + p` multiply-adds per component
//! (63 for cubics, against 84 for the tensor-product contraction with stored basis values) and
//! no basis evaluation. Vertices go [`LANES`] at a time through lane arrays, which the compiler
//! vectorizes; `pulp::Arch::dispatch` compiles that loop for the best instruction set the CPU
//! has (AVX2 on x86-64 where present; runtime detection, no `unsafe` here, and no fused
//! multiply-adds, so every instruction set rounds alike); a cell's short last group repeats its
//! last vertex, so every vertex gets bit-identical results whichever grouping, chunking or
//! thread count evaluates it. When the mesh order is the cell order (every vertex embedded; one
//! cell, or a mesh sorted by cell) positions are written in place, otherwise into a buffer in
//! cell order and gathered. An incremental update after control points `C` changed recomputes only
//! the vertices of the cells whose support meets `C` (control point `i` influences knot cells
//! `i - p ..= i` along each axis), contiguous ranges of the cell-sorted storage.
//!
//! **Limitations.** Vertices outside the rest box are never moved. Normals, when enabled, are
//! recomputed for the whole mesh ([`TriMesh::compute_normals_with`] under the call's
//! parallelism, `O(triangles)`), also after an incremental update. The power form differs from
//! the B-spline form by rounding only (about
//! `1e-16` of the box diagonal for the degrees below 8 that use it; higher degrees, whose power
//! form is worse conditioned, and [`EmbeddedMesh::set_blocked_kernel`]`(false)` use the
//! per-vertex B-spline kernel). Memory is 32 bytes per embedded vertex (local coordinates 24,
//! mesh index 4, slot 4) besides the rest and deformed positions, plus, for a mesh whose order
//! is not the cell order, a 24-byte-per-vertex buffer of deformed positions in cell order that
//! the first deformation allocates and later ones reuse.

use crate::lattice::{FfdLattice, box_parameters};
use rayon::prelude::*;
use vclay_core::{Parallelism, TriMesh, Vec3};
use vclay_spline::KnotVector;

/// Marker for vertices outside the lattice.
const OUTSIDE: u32 = u32::MAX;
/// Vertices per parallel task (a multiple of [`LANES`]).
const CHUNK: usize = 8192;
/// Vertices evaluated together by the blocked kernel of [`EmbeddedMesh::deform`].
pub const LANES: usize = 4;
/// The power-form kernel is used for degrees below this; higher degrees use the per-vertex
/// B-spline kernel (the monomial form grows ill-conditioned with the degree).
const BLOCK_DEGREE: usize = 8;

/// A triangle mesh embedded in an [`FfdLattice`] (`ffd-direct-manipulation.txt` section 2): rest
/// positions, the knot cell and local coordinates of every embedded vertex, and the deformed
/// mesh `x = sum P_ijk R_ijk(t_x)` (eq 1).
#[derive(Clone, Debug)]
pub struct EmbeddedMesh {
    rest: Vec<Vec3>,
    mesh: TriMesh,
    /// Per vertex: embedded index or [`OUTSIDE`].
    slot: Vec<u32>,
    /// Per embedded vertex: mesh vertex index. Embedded vertices are sorted by knot cell (stably,
    /// so a cell's vertices keep the mesh order).
    vertex: Vec<u32>,
    /// Per embedded vertex: local coordinates `(s_u, s_v, s_w)` in its knot cell.
    local: Vec<[f64; 3]>,
    /// CSR over knot cells `(i * cells_v + j) * cells_w + k`: the embedded vertices of cell `c`
    /// are `cell_start[c]..cell_start[c+1]`.
    cell_start: Vec<u32>,
    /// Whether embedded index and mesh index coincide (every vertex embedded, already in cell
    /// order): then a deformation writes the positions directly, without a gather.
    identity: bool,
    /// Deformed positions in cell order when `identity` is false (kept between deformations).
    scratch: Vec<Vec3>,
    /// Per axis, per knot cell: the `(p+1) x (p+1)` matrix `M_ak` (row `a`) of
    /// `B_{i-p+a} = sum_k M_ak s^k`.
    power: [Vec<f64>; 3],
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
        // Cloned in parallel: the copy's cost is mostly first-touch page faults.
        let rest: Vec<Vec3> = if par.is_parallel(n) {
            mesh.positions.par_iter().copied().collect()
        } else {
            mesh.positions.clone()
        };
        let degree = lattice.degree();
        let dims = lattice.dims();
        let cells = cell_counts(degree, dims);
        let (lo, hi) = lattice.bounds();
        let knots = lattice.knots();
        // Per axis: `cells / (domain length)` for the span guess and `1 / (t_{i+1} - t_i)` per
        // cell (multiplications instead of six of the nine divisions per vertex).
        let guess_scale = [0, 1, 2].map(|a| {
            let k = knots[a].as_slice();
            cells[a] as f64 / (k[degree[a] + cells[a]] - k[degree[a]])
        });
        let inv_width: [Vec<f64>; 3] = [0, 1, 2].map(|a| {
            let k = knots[a].as_slice();
            (degree[a]..degree[a] + cells[a])
                .map(|i| 1.0 / (k[i + 1] - k[i]))
                .collect()
        });
        let locate = |x: &Vec3| -> (u32, [f64; 3]) {
            let Some(t) = box_parameters(lo, hi, x) else {
                return (OUTSIDE, [0.0; 3]);
            };
            let mut ci = [0usize; 3];
            let mut s = [0.0; 3];
            for a in 0..3 {
                let span = span_of(&knots[a], cells[a], guess_scale[a], t[a]);
                let k = knots[a].as_slice();
                ci[a] = span - degree[a];
                s[a] = (t[a] - k[span]) * inv_width[a][ci[a]];
            }
            (((ci[0] * cells[1] + ci[1]) * cells[2] + ci[2]) as u32, s)
        };
        let mut cell = Vec::new();
        let mut local = Vec::new();
        if par.is_parallel(n) {
            rest.par_iter()
                .map(locate)
                .unzip_into_vecs(&mut cell, &mut local);
        } else {
            (cell, local) = rest.iter().map(locate).unzip();
        }
        // Bucket by knot cell: a counting sort, linear in the vertices (stable, so the members
        // of a cell keep the mesh order); no sort at all when the mesh order is already the
        // cell order (one cell, or a mesh sorted that way), the common case for coarse lattices.
        let ncells: usize = cells.iter().product();
        // OUTSIDE is the largest value: a sorted `cell` that does not end with it has every
        // vertex embedded.
        let in_order = |w: &[u32]| w[0] <= w[1];
        let sorted = cell.last().is_none_or(|&c| c != OUTSIDE)
            && if par.is_parallel(n) {
                cell.par_windows(2).all(in_order)
            } else {
                cell.windows(2).all(in_order)
            };
        let cell_start: Vec<u32> = if sorted {
            (0..=ncells)
                .map(|c| cell.partition_point(|&x| (x as usize) < c) as u32)
                .collect()
        } else {
            let mut cell_start = vec![0u32; ncells + 1];
            for &c in &cell {
                if c != OUTSIDE {
                    cell_start[c as usize + 1] += 1;
                }
            }
            for c in 0..ncells {
                cell_start[c + 1] += cell_start[c];
            }
            cell_start
        };
        let m = cell_start[ncells] as usize;
        let (slot, vertex, local) = if sorted {
            let ids: Vec<u32> = (0..n as u32).collect();
            (ids.clone(), ids, local)
        } else {
            let mut fill_pos = cell_start.clone();
            let mut slot = vec![OUTSIDE; n];
            let mut vertex = vec![0u32; m];
            let mut sorted_local = vec![[0.0; 3]; m];
            for (v, &c) in cell.iter().enumerate() {
                if c != OUTSIDE {
                    let e = fill_pos[c as usize] as usize;
                    fill_pos[c as usize] += 1;
                    slot[v] = e as u32;
                    vertex[e] = v as u32;
                    sorted_local[e] = local[v];
                }
            }
            (slot, vertex, sorted_local)
        };
        drop(cell);
        let power = [0, 1, 2].map(|a| {
            (0..cells[a])
                .flat_map(|c| span_power_matrix(knots[a].as_slice(), degree[a], c + degree[a]))
                .collect()
        });
        let mut out = Self {
            rest,
            mesh,
            slot,
            vertex,
            local,
            cell_start,
            identity: sorted,
            scratch: Vec::new(),
            power,
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

    /// Whether [`EmbeddedMesh::deform`] and [`EmbeddedMesh::update`] may use the blocked
    /// power-form kernel (default true; see the module docs). Off, every vertex is evaluated by
    /// the B-spline form of eq (1) with its basis values computed on the spot (Cox-de Boor);
    /// both give the same positions up to rounding, so turning it off is for comparisons.
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
    /// Parameters of vertex `v`, `None` when it is outside (recomputed from the rest position by
    /// the linear map of section 2, identical to [`FfdLattice::parameters`]).
    pub fn parameters(&self, v: usize) -> Option<[f64; 3]> {
        let s = *self.slot.get(v)?;
        if s == OUTSIDE {
            return None;
        }
        box_parameters(self.bounds.0, self.bounds.1, &self.rest[v])
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

    /// Whether the power-form kernel applies.
    fn blocked(&self) -> bool {
        self.blocked_kernel && self.degree.iter().all(|&d| d < BLOCK_DEGREE)
    }

    /// The per-vertex B-spline kernel: parameters from the rest position, Cox-de Boor basis
    /// values, the contraction of [`FfdLattice::eval_local`].
    fn eval_bspline(&self, lattice: &FfdLattice, e: usize) -> Vec3 {
        let v = self.vertex[e] as usize;
        let t = box_parameters(self.bounds.0, self.bounds.1, &self.rest[v])
            .expect("embedded vertices are inside the box");
        lattice.point_at_unchecked(t)
    }

    /// Full deformation: every embedded vertex `x = sum P_ijk R_ijk(t_x)` (eq 1), then normals.
    ///
    /// Embedded vertices are stored by knot cell, so each cell is converted to power form once
    /// per task and its vertices are evaluated [`LANES`] at a time, lane by lane in fixed-size
    /// arrays the compiler turns into SIMD instructions. When the mesh order is the cell order
    /// the positions are written directly, otherwise through a gather. Parallel over chunks of
    /// vertices when `par` allows.
    ///
    /// # Panics
    /// If `lattice` has other dimensions, degrees or box than the one embedded in.
    #[track_caller]
    pub fn deform(&mut self, lattice: &FfdLattice, par: Parallelism) -> &TriMesh {
        self.check_lattice(lattice);
        let m = self.vertex.len();
        let ranges: Vec<(usize, usize)> = (0..m)
            .step_by(CHUNK)
            .map(|a| (a, (a + CHUNK).min(m)))
            .collect();
        self.eval_ranges(lattice, &ranges, par);
        self.finish(par);
        &self.mesh
    }

    /// Evaluates the embedded vertices of `ranges` (ascending, disjoint, each at most [`CHUNK`]
    /// long) and stores them in the mesh: in place when the mesh order is the cell order, else
    /// through the `scratch` buffer (kept between calls) and a gather (all vertices) or scatter
    /// (some).
    fn eval_ranges(&mut self, lattice: &FfdLattice, ranges: &[(usize, usize)], par: Parallelism) {
        let m = self.vertex.len();
        let count: usize = ranges.iter().map(|(a, b)| b - a).sum();
        let parallel = par.is_parallel(count);
        let mut target = if self.identity {
            std::mem::take(&mut self.mesh.positions)
        } else {
            let mut t = std::mem::take(&mut self.scratch);
            t.resize(m, Vec3::zeros());
            t
        };
        // Disjoint mutable pieces of the target, one per range.
        let mut parts = Vec::with_capacity(ranges.len());
        let mut rest = &mut target[..];
        let mut offset = 0;
        for &(a, b) in ranges {
            let (_, tail) = rest.split_at_mut(a - offset);
            let (mid, tail) = tail.split_at_mut(b - a);
            parts.push((a, mid));
            rest = tail;
            offset = b;
        }
        let this = &*self;
        let eval = |(a, xs): (usize, &mut [Vec3])| this.eval_range(lattice, a, a + xs.len(), xs);
        if parallel {
            parts.into_par_iter().for_each(eval);
        } else {
            parts.into_iter().for_each(eval);
        }
        if self.identity {
            self.mesh.positions = target;
        } else {
            if count == m {
                let gather = |(x, &s): (&mut Vec3, &u32)| {
                    if s != OUTSIDE {
                        *x = target[s as usize];
                    }
                };
                if parallel {
                    self.mesh
                        .positions
                        .par_iter_mut()
                        .zip(&self.slot)
                        .for_each(gather);
                } else {
                    self.mesh
                        .positions
                        .iter_mut()
                        .zip(&self.slot)
                        .for_each(gather);
                }
            } else {
                for &(a, b) in ranges {
                    for e in a..b {
                        self.mesh.positions[self.vertex[e] as usize] = target[e];
                    }
                }
            }
            self.scratch = target;
        }
    }

    /// Evaluates the embedded vertices `e0..e1` into `out` (length `e1 - e0`), cell by cell.
    fn eval_range(&self, lattice: &FfdLattice, e0: usize, e1: usize, out: &mut [Vec3]) {
        if !self.blocked() {
            for (x, e) in out.iter_mut().zip(e0..e1) {
                *x = self.eval_bspline(lattice, e);
            }
            return;
        }
        pulp::Arch::new().dispatch(RangeOp {
            mesh: self,
            lattice,
            e0,
            e1,
            out,
        });
    }

    #[inline(always)]
    fn eval_range_deg(
        &self,
        lattice: &FfdLattice,
        e0: usize,
        e1: usize,
        out: &mut [Vec3],
        deg: [usize; 3],
    ) {
        let rational = lattice.is_rational();
        let n: usize = deg.iter().map(|d| d + 1).product();
        let stride = n * if rational { 4 } else { 3 };
        let mut coef = vec![0.0; stride];
        let mut work = vec![0.0; 2 * n];
        let mut lanes = vec![[0.0; LANES]; stride];
        // First cell with cell_start[c + 1] > e0.
        let mut c = self.cell_start.partition_point(|&s| s as usize <= e0) - 1;
        let mut e = e0;
        while e < e1 {
            let end = (self.cell_start[c + 1] as usize).min(e1);
            if end > e {
                self.cell_coefficients(lattice, c, &mut coef, &mut work);
                for (d, &v) in lanes.iter_mut().zip(&coef) {
                    *d = [v; LANES];
                }
                let mut g = e;
                while g < end {
                    // A group of LANES vertices of cell c; a short last group repeats its last
                    // vertex (each lane's arithmetic is the same, so results do not depend on
                    // the grouping).
                    let k = (end - g).min(LANES);
                    let t: [[f64; LANES]; 3] = std::array::from_fn(|a| {
                        std::array::from_fn(|l| self.local[g + l.min(k - 1)][a])
                    });
                    let x = eval_power::<LANES>(&lanes, deg, rational, &t);
                    out[g - e0..g - e0 + k].copy_from_slice(&x[..k]);
                    g += k;
                }
                e = end;
            }
            c += 1;
        }
    }

    /// The power-form coefficients `C_klm` of knot cell `c` (module docs), component-major
    /// (`x`, `y`, `z` and, for a rational lattice, `w` of the homogeneous points), each
    /// `[k][l][m]`; `work` holds two blocks of `(p+1)(q+1)(r+1)`.
    fn cell_coefficients(&self, lattice: &FfdLattice, c: usize, out: &mut [f64], work: &mut [f64]) {
        let [p, q, r] = self.degree;
        let cells = cell_counts(self.degree, self.dims);
        let ci = [
            c / (cells[1] * cells[2]),
            (c / cells[2]) % cells[1],
            c % cells[2],
        ];
        let base = lattice.flat_index(ci[0], ci[1], ci[2]);
        let [_, nv, nw] = self.dims;
        let (pu, pv, pw) = (p + 1, q + 1, r + 1);
        let n = pu * pv * pw;
        let mu = &self.power[0][ci[0] * pu * pu..][..pu * pu];
        let mv = &self.power[1][ci[1] * pv * pv..][..pv * pv];
        let mw = &self.power[2][ci[2] * pw * pw..][..pw * pw];
        let rational = lattice.is_rational();
        let ncomp = if rational { 4 } else { 3 };
        let (t0, t1) = work.split_at_mut(n);
        for comp in 0..ncomp {
            // t0[a][b][c] = P_(base + (a, b, c)), component `comp`.
            for a in 0..pu {
                for b in 0..pv {
                    let start = base + a * nv * nw + b * nw;
                    for cc in 0..pw {
                        t0[(a * pv + b) * pw + cc] = if rational {
                            lattice.homogeneous()[start + cc][comp]
                        } else {
                            lattice.control_points()[start + cc][comp]
                        };
                    }
                }
            }
            // Contract w: t1[a][b][m] = sum_c Mw[c][m] t0[a][b][c].
            for ab in 0..pu * pv {
                for m in 0..pw {
                    t1[ab * pw + m] = (0..pw).map(|cc| mw[cc * pw + m] * t0[ab * pw + cc]).sum();
                }
            }
            // Contract v: t0[a][l][m] = sum_b Mv[b][l] t1[a][b][m].
            for a in 0..pu {
                for l in 0..pv {
                    for m in 0..pw {
                        t0[(a * pv + l) * pw + m] = (0..pv)
                            .map(|b| mv[b * pv + l] * t1[(a * pv + b) * pw + m])
                            .sum();
                    }
                }
            }
            // Contract u: C[k][l][m] = sum_a Mu[a][k] t0[a][l][m].
            let dst = &mut out[comp * n..(comp + 1) * n];
            for k in 0..pu {
                for lm in 0..pv * pw {
                    dst[k * pv * pw + lm] =
                        (0..pu).map(|a| mu[a * pu + k] * t0[a * pv * pw + lm]).sum();
                }
            }
        }
    }

    /// Incremental deformation after the control points (or weights) with flat indices `changed`
    /// were modified: recomputes only the vertices of knot cells whose support contains one of
    /// them. Returns how many vertices were recomputed. The result equals [`EmbeddedMesh::deform`]
    /// as long as nothing else in the lattice changed (bit for bit: each vertex goes through the
    /// same arithmetic).
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
        // Ranges of embedded vertices of the hit cells (cells are contiguous in the storage, so
        // neighbouring hit cells merge), cut into pieces of at most CHUNK.
        let mut merged: Vec<(usize, usize)> = Vec::new();
        for (c, _) in hit.iter().enumerate().filter(|(_, h)| **h) {
            let (a, b) = (self.cell_start[c] as usize, self.cell_start[c + 1] as usize);
            match merged.last_mut() {
                Some(last) if last.1 == a => last.1 = b,
                _ if a < b => merged.push((a, b)),
                _ => {}
            }
        }
        let ranges: Vec<(usize, usize)> = merged
            .iter()
            .flat_map(|&(a, b)| (a..b).step_by(CHUNK).map(move |s| (s, (s + CHUNK).min(b))))
            .collect();
        let count: usize = ranges.iter().map(|(a, b)| b - a).sum();
        self.eval_ranges(lattice, &ranges, par);
        if count > 0 {
            self.finish(par);
        }
        count
    }

    fn finish(&mut self, par: Parallelism) {
        if self.recompute_normals && !self.mesh.triangles.is_empty() {
            self.mesh.compute_normals_with(par);
        }
    }
}

/// [`EmbeddedMesh::eval_range`] as a [`pulp::WithSimd`] operation, so that
/// [`pulp::Arch::dispatch`] compiles the lane arithmetic for the best instruction set the CPU
/// has (AVX2 where present: one 4-lane register per lane array; runtime detection, safe code).
/// No fused multiply-adds are formed, so every instruction set gives the same bits.
struct RangeOp<'a> {
    mesh: &'a EmbeddedMesh,
    lattice: &'a FfdLattice,
    e0: usize,
    e1: usize,
    out: &'a mut [Vec3],
}

impl pulp::WithSimd for RangeOp<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        let Self {
            mesh,
            lattice,
            e0,
            e1,
            out,
        } = self;
        // The cubic and quadratic lattices get their own instances, degrees constant-folded.
        match mesh.degree {
            [3, 3, 3] => mesh.eval_range_deg(lattice, e0, e1, out, [3, 3, 3]),
            [2, 2, 2] => mesh.eval_range_deg(lattice, e0, e1, out, [2, 2, 2]),
            d => mesh.eval_range_deg(lattice, e0, e1, out, d),
        }
    }
}

/// `L` points of one knot cell in power form (module docs): `x = sum C_klm s_u^k s_v^l s_w^m`
/// by nested Horner, every operation lane by lane; rational lattices divide by the fourth
/// component.
#[inline(always)]
fn eval_power<const L: usize>(
    coef: &[[f64; L]],
    deg: [usize; 3],
    rational: bool,
    t: &[[f64; L]; 3],
) -> [Vec3; L] {
    let n: usize = deg.iter().map(|d| d + 1).product();
    let x = horner::<L>(&coef[..n], deg, t);
    let y = horner::<L>(&coef[n..2 * n], deg, t);
    let z = horner::<L>(&coef[2 * n..3 * n], deg, t);
    if rational {
        let w = horner::<L>(&coef[3 * n..4 * n], deg, t);
        std::array::from_fn(|l| Vec3::new(x[l] / w[l], y[l] / w[l], z[l] / w[l]))
    } else {
        std::array::from_fn(|l| Vec3::new(x[l], y[l], z[l]))
    }
}

/// `sum_k s_u^k sum_l s_v^l sum_m s_w^m c[k][l][m]`, Horner along each axis, for `L` points.
#[inline(always)]
fn horner<const L: usize>(c: &[[f64; L]], [p, q, r]: [usize; 3], t: &[[f64; L]; 3]) -> [f64; L] {
    let [su, sv, sw] = t;
    let mut x = [0.0; L];
    for k in (0..=p).rev() {
        let mut y = [0.0; L];
        for l in (0..=q).rev() {
            let row = &c[(k * (q + 1) + l) * (r + 1)..][..r + 1];
            let mut z = row[r];
            for m in (0..r).rev() {
                for i in 0..L {
                    z[i] = z[i] * sw[i] + row[m][i];
                }
            }
            if l == q {
                y = z;
            } else {
                for i in 0..L {
                    y[i] = y[i] * sv[i] + z[i];
                }
            }
        }
        if k == p {
            x = y;
        } else {
            for i in 0..L {
                x[i] = x[i] * su[i] + y[i];
            }
        }
    }
    x
}

/// The B-splines of degree `p` that are non-zero on knot span `span` (`t_span <= t < t_span+1`,
/// non-empty), as polynomials in the local coordinate `s = (t - t_span) / (t_span+1 - t_span)`:
/// row `a` holds the coefficients of `s^0 ..= s^p` of `B_{span-p+a}`. Cox-de Boor (Piegl &
/// Tiller A2.2) carried out on polynomials: `left_j = t - t_{span+1-j}` and
/// `right_j = t_{span+j} - t` are linear in `s`, the denominators are knot differences.
fn span_power_matrix(knots: &[f64], p: usize, span: usize) -> Vec<f64> {
    let h = knots[span + 1] - knots[span];
    let w = p + 1;
    let mut n = vec![0.0; w * w];
    n[0] = 1.0;
    // poly * (c0 + c1 s), degree grows by one.
    let mul_linear = |poly: &[f64], c0: f64, c1: f64, out: &mut [f64]| {
        for k in 0..w {
            out[k] = c0 * poly[k] + if k > 0 { c1 * poly[k - 1] } else { 0.0 };
        }
    };
    let mut temp = vec![0.0; w];
    let mut a = vec![0.0; w];
    let mut b = vec![0.0; w];
    for j in 1..=p {
        let mut saved = vec![0.0; w];
        for r in 0..j {
            let den = knots[span + r + 1] - knots[span + 1 + r - j];
            for k in 0..w {
                temp[k] = n[r * w + k] / den;
            }
            // right_{r+1} = (t_{span+r+1} - t_span) - h s,
            // left_{j-r} = (t_span - t_{span+1+r-j}) + h s.
            mul_linear(&temp, knots[span + r + 1] - knots[span], -h, &mut a);
            mul_linear(&temp, knots[span] - knots[span + 1 + r - j], h, &mut b);
            for k in 0..w {
                n[r * w + k] = saved[k] + a[k];
            }
            saved.copy_from_slice(&b);
        }
        n[j * w..(j + 1) * w].copy_from_slice(&saved);
    }
    n
}

/// [`KnotVector::find_span`] (the same span), found by a guess from a uniform spacing of the
/// `cells` spans (`scale = cells / domain length`) and one check against the knots; the binary
/// search only where the check fails (non-uniform knots, parameters on the domain ends).
#[inline]
fn span_of(kv: &KnotVector, cells: usize, scale: f64, u: f64) -> usize {
    let k = kv.as_slice();
    let p = kv.degree();
    let (a, b) = (k[p], k[p + cells]);
    let guess = p + (((u - a) * scale) as usize).min(cells - 1);
    if u > a && u < b && k[guess] <= u && u < k[guess + 1] {
        guess
    } else {
        kv.find_span(u)
    }
}

/// Knot cells (non-empty spans) per axis of a clamped uniform lattice: `n - p`.
fn cell_counts(degree: [usize; 3], dims: [usize; 3]) -> [usize; 3] {
    [0, 1, 2].map(|a| dims[a] - degree[a])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The guessed span is the binary search's, at and between the knots and on the ends.
    #[test]
    fn span_of_equals_find_span() {
        for (p, n) in [(1, 2), (2, 3), (2, 5), (3, 4), (3, 7), (3, 20), (5, 9)] {
            let kv = KnotVector::clamped_uniform(p, n).unwrap();
            let cells = n - p;
            let mut us: Vec<f64> = (0..=1000).map(|i| i as f64 / 1000.0).collect();
            for &k in kv.as_slice() {
                us.extend([k, k.next_down(), k.next_up()]);
            }
            for u in us.into_iter().filter(|u| (0.0..=1.0).contains(u)) {
                let scale = cells as f64;
                assert_eq!(
                    span_of(&kv, cells, scale, u),
                    kv.find_span(u),
                    "p {p} n {n} u {u}"
                );
            }
        }
    }

    /// The power form of each span reproduces Cox-de Boor (Piegl & Tiller A2.2) on that span.
    #[test]
    fn span_power_matrix_matches_cox_de_boor() {
        for (p, n) in [(1, 2), (2, 3), (2, 5), (3, 4), (3, 7), (5, 9)] {
            let kv = KnotVector::clamped_uniform(p, n).unwrap();
            let k = kv.as_slice();
            for span in p..n {
                let mat = span_power_matrix(k, p, span);
                for i in 0..=10 {
                    let s = i as f64 / 10.0;
                    let t = k[span] + s * (k[span + 1] - k[span]);
                    let mut want = vec![0.0; p + 1];
                    kv.basis(span, t, &mut want);
                    for a in 0..=p {
                        let got: f64 = (0..=p)
                            .map(|j| mat[a * (p + 1) + j] * s.powi(j as i32))
                            .sum();
                        assert!(
                            (got - want[a]).abs() < 1e-14,
                            "p {p} span {span} s {s} a {a}"
                        );
                    }
                }
            }
        }
    }
}
