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
//! coordinate), in parallel over vertex chunks. An incremental update after control points
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
/// Vertices per parallel task.
const CHUNK: usize = 4096;

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
        };
        out.deform(lattice, par);
        out
    }

    /// Whether [`EmbeddedMesh::deform`] and [`EmbeddedMesh::update`] recompute normals (default
    /// true). Turn it off to time or use positions only.
    pub fn set_recompute_normals(&mut self, on: bool) {
        self.recompute_normals = on;
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
    /// # Panics
    /// If `lattice` has other dimensions, degrees or box than the one embedded in.
    #[track_caller]
    pub fn deform(&mut self, lattice: &FfdLattice, par: Parallelism) -> &TriMesh {
        self.check_lattice(lattice);
        let mut positions = std::mem::take(&mut self.mesh.positions);
        let this = &*self;
        let kernel = |(xs, slots): (&mut [Vec3], &[u32])| {
            for (x, &s) in xs.iter_mut().zip(slots) {
                if s != OUTSIDE {
                    *x = this.eval(lattice, s as usize);
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
        let new: Vec<Vec3> = if par.is_parallel(affected.len()) {
            affected
                .par_iter()
                .map(|&e| this.eval(lattice, e as usize))
                .collect()
        } else {
            affected
                .iter()
                .map(|&e| this.eval(lattice, e as usize))
                .collect()
        };
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
