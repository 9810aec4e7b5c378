//! The spring forces of a set whose springs are exactly those of a structured grid (issue 31).
//!
//! # What
//! When the data lattice is, combinatorially, an `nx x ny x nz` hexahedral grid (every
//! subdivided box: the benchmarks' cube, the studio's cubes, the papers' box figures), its
//! edge springs are the grid's x-, y- and z-edges and its virtual springs the four corners of
//! the grid's xy-, xz- and yz-quads (`subdivision-solids-journal.txt` section 5.1: a spring on
//! every edge; for each point `m` of each face, a spring from `m` to the midpoint of its two
//! neighbours in the face loop, half its force on each of them). Labelled by grid position
//! `(i, j, k)` (`i` fastest), every kind of spring along a row of fixed `(j, k)` joins points
//! at fixed offsets, so a row's springs are computed with unit-stride vector loads from a
//! structure-of-arrays copy of two z-planes of `d`, and their forces added into the planes'
//! force rows with vector adds. Instead of about fifteen scalar gathers of `d` and
//! read-modify-write scatters into `f` per point (the general kernel, 80 % of its time in
//! session h50's measurements), a point is read once from `d` and written once to `f`: in
//! order when the points are numbered in grid order (the data points of the large boxes of
//! [`crate::model`], [`crate::DataNumbering::Grid`]), else through the permutation (hence
//! [`SpringSet::GRID_POINTS`] for grids in another numbering).
//!
//! # How
//! [`GridSprings::new`] labels the points combinatorially ([`label`]; no coordinates): a
//! point on three edges is the corner `(0, 0, 0)`, its three neighbours give the axes, each
//! axis is followed to its end (the next point on a line is the neighbour that shares no face
//! with the previous one), and the remaining points are found by completing quads; then every
//! edge and every face corner of the set must be a distinct element of the grid and the counts
//! must match ([`GridSprings::slots`]), or the set is not a grid and the general kernel runs.
//! The rest lengths and stiffnesses are stored per grid slot (one-byte indices into tables of
//! the distinct values for sets of [`SpringSet::INDEX_SPRINGS`] springs, as
//! [`super::SpringIndex`], else `f64`; a plastic reset rewrites them through
//! [`GridSprings::set_params`]).
//!
//! The kernel sweeps the z-planes. Plane `k`'s springs write their forces on plane `k` into
//! `L_k` and those on plane `k + 1` into `U_{k+1}`; the force on a point of plane `k` is
//! `L_k + U_k`, each sum accumulated in a fixed order. Threads take contiguous ranges of
//! planes; a thread's first plane gets its `U` from the previous thread after the join. The
//! energy is summed per plane in vector lanes and then over the planes in order. So the forces
//! and the energy are the same bits for any number of threads (not the bits of the general
//! kernel, which sums each point's terms in another order; they agree to rounding). The
//! arithmetic is written with `pulp`'s explicit vectors (`S::f64s`): the per-spring formula
//! with its `l = 0` selects, written as a plain loop, was compiled to scalar code.
//!
//! # Limitations
//! Only a whole grid: a lattice made of several regular blocks (other topologies) would need a
//! per-block version, with the springs between blocks done by the general kernel; not built. A
//! filtered set (fixed regions) or a set over a subset of the points uses the general kernel.
//! The one-byte parameters are decoded row by row with scalar table lookups (about a tenth of
//! the pass at level 4).

use super::{SpringSet, byte_table};
use pulp::Simd;
use rayon::prelude::*;
use vclay_core::Vec3;

/// One parameter (rest length or stiffness) per grid slot: one-byte indices into a table of
/// the distinct values (the stored `f64` values bit for bit), or the `f64` values.
#[derive(Clone, Debug)]
enum Stored {
    Bytes {
        idx: Vec<u8>,
        table: Box<[f64; 256]>,
    },
    Full(Vec<f64>),
}

impl Stored {
    /// `vals[s]` at slot `slots[s]` of a `len`-slot array (unused slots: 0); as bytes if
    /// `bytes` and there are at most 256 distinct values.
    fn new(vals: &[f64], slots: &[u32], len: usize, bytes: bool) -> Self {
        if bytes && let Some((table, idx)) = byte_table(vals) {
            let mut out = vec![0u8; len];
            for (&s, i) in slots.iter().zip(idx) {
                out[s as usize] = i;
            }
            return Stored::Bytes {
                idx: out,
                table: Box::new(table),
            };
        }
        let mut out = vec![0.0; len];
        for (&s, &v) in slots.iter().zip(vals) {
            out[s as usize] = v;
        }
        Stored::Full(out)
    }

    /// The values of slots `lo..lo + n` (decoded into `buf` if stored as bytes).
    #[inline(always)]
    fn row<'a>(&'a self, lo: usize, n: usize, buf: &'a mut [f64]) -> &'a [f64] {
        match self {
            Stored::Full(v) => &v[lo..lo + n],
            Stored::Bytes { idx, table } => {
                let buf = &mut buf[..n];
                for (b, &i) in buf.iter_mut().zip(&idx[lo..lo + n]) {
                    *b = table[i as usize];
                }
                buf
            }
        }
    }

    fn bytes(&self) -> usize {
        match self {
            Stored::Bytes { idx, .. } => idx.len() + 256 * 8,
            Stored::Full(v) => v.len() * 8,
        }
    }
}

/// The springs of a [`SpringSet`] that is exactly the edges and quads of a structured grid, in
/// grid order (module docs).
#[derive(Clone, Debug)]
pub(crate) struct GridSprings {
    /// Points along x, y, z (x the longest axis).
    dims: [usize; 3],
    /// Number of points.
    n: usize,
    /// The point id at each grid index `i + nx (j + ny k)`; empty when that is the identity
    /// (the points are numbered in grid order, as [`crate::model`] numbers a grid's).
    points: Vec<u32>,
    /// The grid index of each point id (the inverse of `points`; empty with it).
    index: Vec<u32>,
    /// Edge rest lengths at slot `axis * N + g` (`g` the edge's lower end).
    edge_rest: Stored,
    /// Edge stiffnesses, as `edge_rest`.
    edge_k: Stored,
    /// Virtual spring rest lengths at slot `(plane * 4 + corner) * N + g`: planes xy, xz, yz;
    /// corners `(0, 0), (1, 0), (1, 1), (0, 1)` in the plane's axes from the quad's lowest
    /// point `g`.
    corner_rest: Stored,
    /// Virtual spring stiffnesses, as `corner_rest`.
    corner_k: Stored,
}

/// Adjacency lists in compressed rows.
struct Csr {
    off: Vec<u32>,
    val: Vec<u32>,
}

impl Csr {
    fn new(n: usize, pairs: impl Iterator<Item = (u32, u32)> + Clone) -> Self {
        let mut off = vec![0u32; n + 1];
        for (a, _) in pairs.clone() {
            off[a as usize + 1] += 1;
        }
        for i in 0..n {
            off[i + 1] += off[i];
        }
        let mut pos = off.clone();
        let mut val = vec![0; off[n] as usize];
        for (a, b) in pairs {
            val[pos[a as usize] as usize] = b;
            pos[a as usize] += 1;
        }
        Self { off, val }
    }

    fn row(&self, i: usize) -> &[u32] {
        &self.val[self.off[i] as usize..self.off[i + 1] as usize]
    }
}

/// The plane axes `(u, v)` of the quads of planes xy, xz, yz.
const PLANES: [(usize, usize); 3] = [(0, 1), (0, 2), (1, 2)];

impl GridSprings {
    /// The grid form of `set` over points `0..n`, or `None` if its springs are not exactly
    /// the edges and quads of a grid with at least two points along each axis.
    pub(crate) fn new(set: &SpringSet, n: usize) -> Option<Self> {
        let (dims, points) = label(&set.edges, &set.face_offsets, &set.face_verts, n)?;
        let mut index = vec![0u32; n];
        for (g, &p) in points.iter().enumerate() {
            index[p as usize] = g as u32;
        }
        let identity = points.iter().enumerate().all(|(g, &p)| p as usize == g);
        let (points, index) = if identity {
            (Vec::new(), Vec::new())
        } else {
            (points, index)
        };
        let mut grid = GridSprings {
            dims,
            n,
            points,
            index,
            edge_rest: Stored::Full(Vec::new()),
            edge_k: Stored::Full(Vec::new()),
            corner_rest: Stored::Full(Vec::new()),
            corner_k: Stored::Full(Vec::new()),
        };
        grid.set_params(set).then_some(grid)
    }

    /// Points along x, y and z.
    pub(crate) fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Whether the points are numbered in grid order (no point maps).
    pub(crate) fn in_grid_order(&self) -> bool {
        self.points.is_empty()
    }

    /// Number of points.
    pub(crate) fn len(&self) -> usize {
        self.n
    }

    /// Bytes held (point maps and parameters).
    pub(crate) fn bytes(&self) -> usize {
        4 * (self.points.len() + self.index.len())
            + self.edge_rest.bytes()
            + self.edge_k.bytes()
            + self.corner_rest.bytes()
            + self.corner_k.bytes()
    }

    /// Copies the rest lengths and stiffnesses of `set` (the set this grid was built from, in
    /// any spring order) into grid order; `false` if a spring is not a distinct element of
    /// the grid.
    pub(crate) fn set_params(&mut self, set: &SpringSet) -> bool {
        let Some((es, cs)) = self.slots(set) else {
            return false;
        };
        let n = self.n;
        let bytes = set.len() >= SpringSet::INDEX_SPRINGS;
        self.edge_rest = Stored::new(&set.edge_rest, &es, 3 * n, bytes);
        self.edge_k = Stored::new(&set.edge_k, &es, 3 * n, bytes);
        self.corner_rest = Stored::new(&set.corner_rest, &cs, 12 * n, bytes);
        self.corner_k = Stored::new(&set.corner_k, &cs, 12 * n, bytes);
        true
    }

    /// The slot of every edge and every face corner of `set`, or `None` if one is not an
    /// element of the grid, two are the same, or the counts are not the grid's.
    fn slots(&self, set: &SpringSet) -> Option<(Vec<u32>, Vec<u32>)> {
        let [nx, ny, nz] = self.dims;
        let n = self.n;
        let nf = set.num_faces();
        let edges = (nx - 1) * ny * nz + nx * (ny - 1) * nz + nx * ny * (nz - 1);
        let faces = (nx - 1) * (ny - 1) * nz + (nx - 1) * ny * (nz - 1) + nx * (ny - 1) * (nz - 1);
        if set.edges.len() != edges || nf != faces || set.face_verts.len() != 4 * nf {
            return None;
        }
        let coord = |p: u32| -> Option<[usize; 3]> {
            let g = if self.points.is_empty() {
                (p as usize) < n
            } else {
                (p as usize) < self.index.len()
            }
            .then(|| {
                self.index
                    .get(p as usize)
                    .map_or(p as usize, |&g| g as usize)
            })?;
            Some([g % nx, (g / nx) % ny, g / (nx * ny)])
        };
        let at = |c: [usize; 3]| c[0] + nx * (c[1] + ny * c[2]);
        let mut used = vec![false; 15 * n];
        let mut take = |s: usize| !std::mem::replace(&mut used[s], true);
        let mut es = Vec::with_capacity(edges);
        for &[a, b] in &set.edges {
            let (ca, cb) = (coord(a)?, coord(b)?);
            // Exactly one coordinate differs, by one.
            let axis = (0..3).find(|&x| ca[x] != cb[x])?;
            if ca[axis].abs_diff(cb[axis]) != 1 || (0..3).any(|x| x != axis && ca[x] != cb[x]) {
                return None;
            }
            let s = axis * n + at(ca).min(at(cb));
            if !take(s) {
                return None;
            }
            es.push(s as u32);
        }
        let mut cs = Vec::with_capacity(4 * nf);
        for f in 0..nf {
            let v = &set.face_verts[4 * f..4 * f + 4];
            let c = [coord(v[0])?, coord(v[1])?, coord(v[2])?, coord(v[3])?];
            let lo: [usize; 3] = std::array::from_fn(|x| c.iter().map(|p| p[x]).min().unwrap());
            // The normal axis: the one all four corners share.
            let normal = (0..3).find(|&x| c.iter().all(|p| p[x] == lo[x]))?;
            let plane = 2 - normal;
            let (u, w) = PLANES[plane];
            let mut corner = [0usize; 4];
            for (j, p) in c.iter().enumerate() {
                let (du, dv) = (p[u] - lo[u], p[w] - lo[w]);
                corner[j] = match (du, dv) {
                    (0, 0) => 0,
                    (1, 0) => 1,
                    (1, 1) => 2,
                    (0, 1) => 3,
                    _ => return None,
                };
            }
            // A loop around the square: consecutive corners are grid neighbours.
            for j in 0..4 {
                let step = (corner[(j + 1) % 4] + 4 - corner[j]) % 4;
                if step != 1 && step != 3 {
                    return None;
                }
            }
            let base = at(lo);
            for &cj in &corner {
                let s = (plane * 4 + cj) * n + base;
                if !take(3 * n + s) {
                    return None;
                }
                cs.push(s as u32);
            }
        }
        Some((es, cs))
    }

    /// Overwrites (`overwrite`) or adds to `f` the forces of the springs in configuration
    /// `d`, on `threads` threads (ranges of z-planes); returns the energy. `d` and `f` have
    /// one entry per point of the grid ([`GridSprings::len`]).
    pub(crate) fn forces(
        &self,
        d: &[Vec3],
        f: &mut [Vec3],
        ws: &mut GridWorkspace,
        threads: usize,
        overwrite: bool,
    ) -> f64 {
        let [nx, ny, nz] = self.dims;
        let plane = nx * ny;
        let threads = threads.clamp(1, nz);
        ws.threads.resize_with(threads, Default::default);
        ws.energy.clear();
        ws.energy.resize(nz, 0.0);
        // Each thread writes its planes of the forces in grid order, contiguous: straight into
        // `f` when the points are numbered in grid order (the data lattices of
        // [`crate::model`] are), else into `ws.fg`, from which `f` is then filled in point
        // order (scattered reads: writing `f` plane by plane through the permutation, scattered
        // stores, took 30 % of the pass on a Cuthill-McKee numbering).
        let direct = self.points.is_empty();
        let GridWorkspace {
            threads: scratch,
            energy,
            fg,
        } = ws;
        let dest: &mut [Vec3] = if direct {
            &mut *f
        } else {
            fg.resize(self.n, Vec3::zeros());
            &mut fg[..]
        };
        let mode = if direct { overwrite } else { true };
        // Thread t takes planes ks(t)..ks(t + 1).
        let ks = |t: usize| nz * t / threads;
        let mut parts = Vec::with_capacity(threads);
        let (mut rest, mut en) = (&mut *dest, &mut energy[..]);
        for t in 0..threads {
            let len = ks(t + 1) - ks(t);
            let (a, b) = std::mem::take(&mut rest).split_at_mut(len * plane);
            let (ea, eb) = std::mem::take(&mut en).split_at_mut(len);
            parts.push((t, a, ea));
            rest = b;
            en = eb;
        }
        let run = |(s, (t, dst, en)): (&mut PlaneScratch, (usize, &mut [Vec3], &mut [f64]))| {
            let out = Out {
                dst,
                overwrite: mode,
                first_pending: t > 0,
            };
            self.sweep(d, ks(t)..ks(t + 1), s, en, out);
        };
        if threads == 1 {
            scratch.iter_mut().zip(parts).for_each(run);
        } else {
            scratch.par_iter_mut().zip(parts).for_each(run);
        }
        // The first plane of each later thread: `L` (kept by that thread) + `U` (the previous
        // thread's carry), the single addition the one-thread sweep makes.
        for t in 1..threads {
            let lo = ks(t) * plane;
            let (l, u) = (&scratch[t].first, &scratch[t - 1].u);
            for (g, x) in dest[lo..lo + plane].iter_mut().enumerate() {
                let v = Vec3::new(l[0][g] + u[0][g], l[1][g] + u[1][g], l[2][g] + u[2][g]);
                if mode {
                    *x = v;
                } else {
                    *x += v;
                }
            }
        }
        if !direct {
            let (fg, index) = (&*fg, &self.index);
            let copy = |(fc, ic): (&mut [Vec3], &[u32])| {
                for (x, &g) in fc.iter_mut().zip(ic) {
                    if overwrite {
                        *x = fg[g as usize];
                    } else {
                        *x += fg[g as usize];
                    }
                }
            };
            if threads == 1 {
                f.chunks_mut(8192).zip(index.chunks(8192)).for_each(copy);
            } else {
                f.par_chunks_mut(8192)
                    .zip(index.par_chunks(8192))
                    .for_each(copy);
            }
        }
        ws.energy.iter().sum()
    }

    /// The springs based on planes `ks` on one thread (compiled for the CPU's best
    /// instruction set by pulp's run-time dispatch), their forces sent to `out`, each plane's
    /// energy into `energy` (indexed from `ks.start`).
    fn sweep(
        &self,
        d: &[Vec3],
        ks: std::ops::Range<usize>,
        s: &mut PlaneScratch,
        energy: &mut [f64],
        mut out: Out<'_>,
    ) {
        pulp::Arch::new().dispatch(SweepOp {
            grid: self,
            d,
            ks,
            s,
            energy,
            out: &mut out,
        });
    }

    #[inline(always)]
    fn sweep_kernel<S: Simd>(
        &self,
        simd: S,
        d: &[Vec3],
        ks: std::ops::Range<usize>,
        s: &mut PlaneScratch,
        energy: &mut [f64],
        out: &mut Out<'_>,
    ) {
        let [nx, ny, nz] = self.dims;
        let plane = nx * ny;
        let n = self.n;
        s.prepare(plane, nx);
        let k0 = ks.start;
        self.gather(d, k0, &mut s.d0);
        for c in &mut s.u {
            c.fill(0.0);
        }
        for k in ks {
            let upper = k + 1 < nz;
            if upper {
                self.gather(d, k + 1, &mut s.d1);
            }
            for c in s.l.iter_mut().chain(&mut s.un) {
                c.fill(0.0);
            }
            let mut acc = simd.splat_f64s(0.0);
            let PlaneScratch {
                d0,
                d1,
                l,
                un,
                rows,
                ..
            } = &mut *s;
            let (d0, d1) = (&*d0, &*d1);
            let m = nx - 1;
            for j in 0..ny {
                let r0 = j * nx;
                let r1 = r0 + nx;
                let g0 = k * plane + r0;
                let side = j + 1 < ny;
                // Edges: the force on the first point in `rows.v[0]`, its opposite on the
                // second.
                let to = Sink::Rows;
                self.edge_row(simd, [(d0, r0), (d0, r0 + 1)], g0, m, rows, to, &mut acc);
                add_row(l, r0, &rows.v[0], m, 1.0);
                add_row(l, r0 + 1, &rows.v[0], m, -1.0);
                // The y- and z-edges add straight into rows of `L` and `U` that do not overlap
                // (the same additions in the same order as through `rows.v`).
                if side {
                    let to = Sink::Split(l, r0, r1);
                    self.edge_row(simd, [(d0, r0), (d0, r1)], n + g0, nx, rows, to, &mut acc);
                }
                if upper {
                    let to = Sink::Two(l, un, r0);
                    self.edge_row(
                        simd,
                        [(d0, r0), (d1, r0)],
                        2 * n + g0,
                        nx,
                        rows,
                        to,
                        &mut acc,
                    );
                }
                // Quads, corners (0, 0), (1, 0), (1, 1), (0, 1) in the plane's axes: the
                // total force on each corner in `rows.a`.
                if side {
                    let p = [(d0, r0), (d0, r0 + 1), (d0, r1 + 1), (d0, r1)];
                    self.quad_row(simd, p, g0, m, rows, &mut acc);
                    add_row(l, r0, &rows.a[0], m, 1.0);
                    add_row(l, r0 + 1, &rows.a[1], m, 1.0);
                    add_row(l, r1 + 1, &rows.a[2], m, 1.0);
                    add_row(l, r1, &rows.a[3], m, 1.0);
                }
                if upper {
                    let p = [(d0, r0), (d0, r0 + 1), (d1, r0 + 1), (d1, r0)];
                    self.quad_row(simd, p, 4 * n + g0, m, rows, &mut acc);
                    add_row(l, r0, &rows.a[0], m, 1.0);
                    add_row(l, r0 + 1, &rows.a[1], m, 1.0);
                    add_row(un, r0 + 1, &rows.a[2], m, 1.0);
                    add_row(un, r0, &rows.a[3], m, 1.0);
                }
                if side && upper {
                    let p = [(d0, r0), (d0, r1), (d1, r1), (d1, r0)];
                    self.quad_row(simd, p, 8 * n + g0, nx, rows, &mut acc);
                    add_row(l, r0, &rows.a[0], nx, 1.0);
                    add_row(l, r1, &rows.a[1], nx, 1.0);
                    add_row(un, r1, &rows.a[2], nx, 1.0);
                    add_row(un, r0, &rows.a[3], nx, 1.0);
                }
            }
            energy[k - k0] = simd.reduce_sum_f64s(acc);
            // Plane k is L_k + U_k; the first plane of a later thread waits for its U.
            if k == k0 && out.first_pending {
                for (dst, src) in s.first.iter_mut().zip(&s.l) {
                    dst.copy_from_slice(src);
                }
            } else {
                out.put(plane, k, k0, &s.l, &s.u);
            }
            std::mem::swap(&mut s.u, &mut s.un);
            std::mem::swap(&mut s.d0, &mut s.d1);
        }
        // `s.u` now holds U of plane `ks.end` (the next thread's first plane).
    }

    /// Plane `k` of `d` as coordinate rows.
    #[inline(always)]
    fn gather(&self, d: &[Vec3], k: usize, out: &mut [Vec<f64>; 3]) {
        let plane = self.dims[0] * self.dims[1];
        let [x, y, z] = out;
        let (x, y, z) = (&mut x[..plane], &mut y[..plane], &mut z[..plane]);
        if self.points.is_empty() {
            for (g, q) in d[k * plane..(k + 1) * plane].iter().enumerate() {
                x[g] = q.x;
                y[g] = q.y;
                z[g] = q.z;
            }
        } else {
            let ids = &self.points[k * plane..(k + 1) * plane];
            for (g, &p) in ids.iter().enumerate() {
                let q = d[p as usize];
                x[g] = q.x;
                y[g] = q.y;
                z[g] = q.z;
            }
        }
    }

    /// `m` edge springs from the points of row `p[0]` to those of row `p[1]` (coordinate
    /// planes and offsets), parameters at edge slots `lo..lo + m`: the force `g` on the first
    /// point (`-g` on the second) into `rows.v[0]`, the energies into `acc`.
    #[inline(always)]
    fn edge_row<S: Simd>(
        &self,
        simd: S,
        p: [(&[Vec<f64>; 3], usize); 2],
        lo: usize,
        m: usize,
        rows: &mut Rows,
        to: Sink<'_>,
        acc: &mut S::f64s,
    ) {
        let [(pa, oa), (pb, ob)] = p;
        let Rows { v, pr, pk, .. } = rows;
        let rest = self.edge_rest.row(lo, m, &mut pr[0]);
        let k = self.edge_k.row(lo, m, &mut pk[0]);
        let [gx, gy, gz] = &mut v[0];
        let mut to = to;
        let lanes_n = S::F64_LANES;
        let mut i = 0;
        while i < m {
            let r = i..(i + lanes_n).min(m);
            // (No closures here: they would not inherit the dispatched instruction set.)
            let (ra, rb) = (oa + r.start..oa + r.end, ob + r.start..ob + r.end);
            let mut x = simd.sub_f64s(ld(simd, &pb[0][rb.clone()]), ld(simd, &pa[0][ra.clone()]));
            let mut y = simd.sub_f64s(ld(simd, &pb[1][rb.clone()]), ld(simd, &pa[1][ra.clone()]));
            let mut z = simd.sub_f64s(ld(simd, &pb[2][rb]), ld(simd, &pa[2][ra]));
            let (r0, k0) = (ld(simd, &rest[r.clone()]), ld(simd, &k[r.clone()]));
            lanes(simd, &mut x, &mut y, &mut z, r0, k0, acc);
            match &mut to {
                Sink::Rows => {
                    st(simd, &mut gx[r.clone()], x);
                    st(simd, &mut gy[r.clone()], y);
                    st(simd, &mut gz[r], z);
                }
                Sink::Split(dst, a, b) => {
                    for (c, g) in [x, y, z].into_iter().enumerate() {
                        add_lanes(simd, &mut dst[c][*a + r.start..*a + r.end], g, false);
                        add_lanes(simd, &mut dst[c][*b + r.start..*b + r.end], g, true);
                    }
                }
                Sink::Two(da, db, a) => {
                    for (c, g) in [x, y, z].into_iter().enumerate() {
                        add_lanes(simd, &mut da[c][*a + r.start..*a + r.end], g, false);
                        add_lanes(simd, &mut db[c][*a + r.start..*a + r.end], g, true);
                    }
                }
            }
            i += lanes_n;
        }
    }

    /// The virtual springs of `m` quads whose corners `(0, 0), (1, 0), (1, 1), (0, 1)` are
    /// the rows `p`, parameters of corner `c` at slots `lo + c N..lo + c N + m`: the total force
    /// on each corner into `rows.a`, the energies into `acc`. As in the general kernel, corners
    /// 0 and 2 share the virtual point `(p1 + p3) / 2`, corners 1 and 3 `(p0 + p2) / 2`, and
    /// corner `j` takes `-g_j` and `g_{j±1} / 2`.
    #[inline(always)]
    fn quad_row<S: Simd>(
        &self,
        simd: S,
        p: [(&[Vec<f64>; 3], usize); 4],
        lo: usize,
        m: usize,
        rows: &mut Rows,
        acc: &mut S::f64s,
    ) {
        let n = self.n;
        let Rows { a, pr, pk, .. } = rows;
        let [pr0, pr1, pr2, pr3] = pr.each_mut();
        let [pk0, pk1, pk2, pk3] = pk.each_mut();
        let rest = [
            self.corner_rest.row(lo, m, pr0),
            self.corner_rest.row(lo + n, m, pr1),
            self.corner_rest.row(lo + 2 * n, m, pr2),
            self.corner_rest.row(lo + 3 * n, m, pr3),
        ];
        let k = [
            self.corner_k.row(lo, m, pk0),
            self.corner_k.row(lo + n, m, pk1),
            self.corner_k.row(lo + 2 * n, m, pk2),
            self.corner_k.row(lo + 3 * n, m, pk3),
        ];
        let half = simd.splat_f64s(0.5);
        let lanes_n = S::F64_LANES;
        let mut i = 0;
        while i < m {
            let r = i..(i + lanes_n).min(m);
            // v[corner][coordinate]: the spring vectors, then the forces g.
            let mut v = [[simd.splat_f64s(0.0); 3]; 4];
            for c in 0..3 {
                let q = [
                    ld(simd, &p[0].0[c][p[0].1 + r.start..p[0].1 + r.end]),
                    ld(simd, &p[1].0[c][p[1].1 + r.start..p[1].1 + r.end]),
                    ld(simd, &p[2].0[c][p[2].1 + r.start..p[2].1 + r.end]),
                    ld(simd, &p[3].0[c][p[3].1 + r.start..p[3].1 + r.end]),
                ];
                let mid02 = simd.mul_f64s(simd.add_f64s(q[1], q[3]), half);
                let mid13 = simd.mul_f64s(simd.add_f64s(q[0], q[2]), half);
                v[0][c] = simd.sub_f64s(q[0], mid02);
                v[1][c] = simd.sub_f64s(q[1], mid13);
                v[2][c] = simd.sub_f64s(q[2], mid02);
                v[3][c] = simd.sub_f64s(q[3], mid13);
            }
            for j in 0..4 {
                let [x, y, z] = &mut v[j];
                let (rj, kj) = (ld(simd, &rest[j][r.clone()]), ld(simd, &k[j][r.clone()]));
                lanes(simd, x, y, z, rj, kj, acc);
            }
            for c in 0..3 {
                let g = [v[0][c], v[1][c], v[2][c], v[3][c]];
                for j in 0..4 {
                    let t = simd.mul_f64s(simd.add_f64s(g[(j + 1) & 3], g[(j + 3) & 3]), half);
                    st(simd, &mut a[j][c][r.clone()], simd.sub_f64s(t, g[j]));
                }
            }
            i += lanes_n;
        }
    }
}

/// Where [`GridSprings::edge_row`] puts the force `g` on the first point of each spring.
enum Sink<'a> {
    /// `g` into `rows.v[0]` (the callers add it to overlapping, shifted rows).
    Rows,
    /// `+g` at offset `.1` and `-g` at offset `.2` of the same planes (rows that do not
    /// overlap).
    Split(&'a mut [Vec<f64>; 3], usize, usize),
    /// `+g` into the first planes and `-g` into the second, both at offset `.2`.
    Two(&'a mut [Vec<f64>; 3], &'a mut [Vec<f64>; 3], usize),
}

/// `s += v` (`s -= v` if `sub`) on the first `s.len()` lanes (at most one vector's): the
/// additions of [`add_row`], lane by lane.
#[inline(always)]
fn add_lanes<S: Simd>(simd: S, s: &mut [f64], v: S::f64s, sub: bool) {
    let old = ld(simd, s);
    let new = if sub {
        simd.sub_f64s(old, v)
    } else {
        simd.add_f64s(old, v)
    };
    st(simd, s, new);
}

/// The values of `s` (at most one vector's lanes; missing lanes are zero) as a vector.
#[inline(always)]
fn ld<S: Simd>(simd: S, s: &[f64]) -> S::f64s {
    if s.len() == S::F64_LANES {
        S::as_simd_f64s(s).0[0]
    } else {
        simd.partial_load_f64s(s)
    }
}

/// Stores the first `s.len()` lanes of `v` into `s` (at most one vector's lanes).
#[inline(always)]
fn st<S: Simd>(simd: S, s: &mut [f64], v: S::f64s) {
    if s.len() == S::F64_LANES {
        S::as_mut_simd_f64s(s).0[0] = v;
    } else {
        simd.partial_store_f64s(s, v);
    }
}

/// `dst[c][off..off + m] += sign * src[c][..m]` for the three coordinates (`sign` is 1 or -1).
#[inline(always)]
fn add_row(dst: &mut [Vec<f64>; 3], off: usize, src: &[Vec<f64>; 3], m: usize, sign: f64) {
    for (d, s) in dst.iter_mut().zip(src) {
        let (d, s) = (&mut d[off..off + m], &s[..m]);
        if sign > 0.0 {
            for (d, &s) in d.iter_mut().zip(s) {
                *d += s;
            }
        } else {
            for (d, &s) in d.iter_mut().zip(s) {
                *d -= s;
            }
        }
    }
}

/// For spring vectors `(x, y, z)` (one vector of lanes) with rest lengths and stiffnesses:
/// replaces the vectors by the forces `g = k (l - l0) x / l` (zero where `l = 0`) and adds the
/// energies `k/2 (l - l0)^2` to the lanes of `acc`. The same operations per spring as the
/// general kernel's `spring_batch` (no fused multiply-adds), on explicit vectors: a plain loop
/// with the `l = 0` selects was compiled to scalar code with branches.
#[inline(always)]
fn lanes<S: Simd>(
    simd: S,
    x: &mut S::f64s,
    y: &mut S::f64s,
    z: &mut S::f64s,
    rest: S::f64s,
    k: S::f64s,
    acc: &mut S::f64s,
) {
    let zero = simd.splat_f64s(0.0);
    let sq = simd.add_f64s(
        simd.add_f64s(simd.mul_f64s(*x, *x), simd.mul_f64s(*y, *y)),
        simd.mul_f64s(*z, *z),
    );
    let l = simd.sqrt_f64s(sq);
    let s = simd.sub_f64s(l, rest);
    let pos = simd.greater_than_f64s(l, zero);
    let inv = simd.select_f64s(pos, simd.div_f64s(simd.splat_f64s(1.0), l), zero);
    let c = simd.mul_f64s(simd.mul_f64s(k, s), inv);
    let half_k = simd.mul_f64s(simd.splat_f64s(0.5), k);
    let e = simd.mul_f64s(simd.mul_f64s(half_k, s), s);
    *acc = simd.add_f64s(*acc, simd.select_f64s(pos, e, zero));
    *x = simd.mul_f64s(*x, c);
    *y = simd.mul_f64s(*y, c);
    *z = simd.mul_f64s(*z, c);
}

/// Where a sweep puts the finished planes: its planes of the forces in grid order, overwritten
/// or added to; the first plane is kept in the scratch's `first` instead if `first_pending`
/// (its `U` comes from the previous thread).
struct Out<'a> {
    dst: &'a mut [Vec3],
    overwrite: bool,
    first_pending: bool,
}

impl Out<'_> {
    /// Plane `k` (of a sweep from `k0`): `l + u`.
    #[inline(always)]
    fn put(&mut self, plane: usize, k: usize, k0: usize, l: &[Vec<f64>; 3], u: &[Vec<f64>; 3]) {
        let lo = (k - k0) * plane;
        let out = &mut self.dst[lo..lo + plane];
        let [lx, ly, lz] = l.each_ref().map(|c| &c[..plane]);
        let [ux, uy, uz] = u.each_ref().map(|c| &c[..plane]);
        if self.overwrite {
            for (g, x) in out.iter_mut().enumerate() {
                *x = Vec3::new(lx[g] + ux[g], ly[g] + uy[g], lz[g] + uz[g]);
            }
        } else {
            for (g, x) in out.iter_mut().enumerate() {
                *x += Vec3::new(lx[g] + ux[g], ly[g] + uy[g], lz[g] + uz[g]);
            }
        }
    }
}

/// The sweep as a [`pulp::WithSimd`] operation (see [`GridSprings::sweep`]).
struct SweepOp<'a, 'o> {
    grid: &'a GridSprings,
    d: &'a [Vec3],
    ks: std::ops::Range<usize>,
    s: &'a mut PlaneScratch,
    energy: &'a mut [f64],
    out: &'a mut Out<'o>,
}

impl pulp::WithSimd for SweepOp<'_, '_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        self.grid
            .sweep_kernel(simd, self.d, self.ks, self.s, self.energy, self.out);
    }
}

/// Row buffers of one thread: spring vectors (then forces) and corner force totals per quad
/// corner, and decoded parameters.
#[derive(Clone, Debug, Default)]
struct Rows {
    v: [[Vec<f64>; 3]; 4],
    a: [[Vec<f64>; 3]; 4],
    pr: [Vec<f64>; 4],
    pk: [Vec<f64>; 4],
}

/// One thread's planes: `d` on planes `k` and `k + 1`, the forces `L_k`, `U_k`, `U_{k+1}`
/// (module docs), and row buffers.
#[derive(Clone, Debug, Default)]
pub(crate) struct PlaneScratch {
    d0: [Vec<f64>; 3],
    d1: [Vec<f64>; 3],
    l: [Vec<f64>; 3],
    u: [Vec<f64>; 3],
    un: [Vec<f64>; 3],
    /// `L` of the first plane of a sweep that waits for its `U`.
    first: [Vec<f64>; 3],
    rows: Rows,
}

impl PlaneScratch {
    /// Grows the buffers to planes of `plane` points and rows of `nx` (no allocation once
    /// grown).
    fn prepare(&mut self, plane: usize, nx: usize) {
        for c in [
            &mut self.d0,
            &mut self.d1,
            &mut self.l,
            &mut self.u,
            &mut self.un,
            &mut self.first,
        ]
        .into_iter()
        .flatten()
        {
            c.resize(plane, 0.0);
        }
        let r = &mut self.rows;
        for c in
            r.v.iter_mut()
                .chain(&mut r.a)
                .flatten()
                .chain(&mut r.pr)
                .chain(&mut r.pk)
        {
            c.resize(nx, 0.0);
        }
    }
}

/// Buffers of the grid kernel, kept between passes ([`super::ForceWorkspace`]).
#[derive(Clone, Debug, Default)]
pub(crate) struct GridWorkspace {
    threads: Vec<PlaneScratch>,
    /// Energy per z-plane.
    energy: Vec<f64>,
    /// The forces in grid order (parallel passes).
    fg: Vec<Vec3>,
}

/// The grid labelling of points `0..n` with the given edges and face loops (`face_offsets`
/// has one more entry than there are faces; module docs): the dimensions (x the longest; axes
/// of equal length in the order of the corner's neighbour ids) and the point id at each grid
/// index, or `None` if the edges and faces do not lay out a grid. Only the labelling is
/// checked; [`GridSprings::slots`] checks that every edge and face is a grid element.
pub(crate) fn label(
    edges: &[[u32; 2]],
    face_offsets: &[u32],
    face_verts: &[u32],
    n: usize,
) -> Option<([usize; 3], Vec<u32>)> {
    let nf = face_offsets.len().saturating_sub(1);
    if n < 8 || edges.is_empty() || face_verts.len() != 4 * nf {
        return None;
    }
    if (0..nf).any(|f| face_offsets[f + 1].checked_sub(face_offsets[f]) != Some(4))
        || edges
            .iter()
            .flatten()
            .chain(face_verts)
            .any(|&v| v as usize >= n)
    {
        return None;
    }
    let quad = |f: u32| &face_verts[4 * f as usize..4 * f as usize + 4];
    let adj = Csr::new(n, edges.iter().flat_map(|&[a, b]| [(a, b), (b, a)]));
    let faces = Csr::new(
        n,
        (0..nf as u32).flat_map(|f| quad(f).iter().map(move |&v| (v, f))),
    );
    // The point after `p` on the grid line from `q`: the neighbour of `p` that no face through
    // `q` and `p` contains (`Some(None)` at the end of the line, `None` if not unique).
    let next = |q: u32, p: u32| -> Option<Option<u32>> {
        let mut found = None;
        for &r in adj.row(p as usize) {
            let beside = faces.row(p as usize).iter().any(|&f| {
                let v = quad(f);
                v.contains(&q) && v.contains(&r)
            });
            if r != q && !beside {
                if found.is_some() {
                    return None;
                }
                found = Some(r);
            }
        }
        Some(found)
    };
    let corner = (0..n).find(|&v| adj.row(v).len() == 3)? as u32;
    let mut lines: Vec<Vec<u32>> = Vec::with_capacity(3);
    for &a in adj.row(corner as usize) {
        let mut line = vec![corner, a];
        while let Some(r) = next(line[line.len() - 2], line[line.len() - 1])? {
            if line.len() >= n {
                return None;
            }
            line.push(r);
        }
        lines.push(line);
    }
    lines.sort_by_key(|l| (std::cmp::Reverse(l.len()), l[1]));
    let dims = [lines[0].len(), lines[1].len(), lines[2].len()];
    let [nx, ny, nz] = dims;
    if nx.checked_mul(ny)?.checked_mul(nz)? != n {
        return None;
    }
    let at = |i: usize, j: usize, k: usize| i + nx * (j + ny * k);
    let mut points = vec![u32::MAX; n];
    let mut seen = vec![false; n];
    let mut put = |points: &mut [u32], g: usize, p: u32| -> Option<()> {
        if std::mem::replace(&mut seen[p as usize], true) {
            return None;
        }
        points[g] = p;
        Some(())
    };
    put(&mut points, 0, corner)?;
    for (axis, line) in lines.iter().enumerate() {
        for (t, &p) in line.iter().enumerate().skip(1) {
            let g = match axis {
                0 => at(t, 0, 0),
                1 => at(0, t, 0),
                _ => at(0, 0, t),
            };
            put(&mut points, g, p)?;
        }
    }
    // The fourth corner of the quad with corner `a` between `b` and `c`.
    let complete = |a: u32, b: u32, c: u32| -> Option<u32> {
        let mut found = None;
        for &f in faces.row(a as usize) {
            let v = quad(f);
            let i = v.iter().position(|&x| x == a)?;
            let (prev, next) = (v[(i + 3) % 4], v[(i + 1) % 4]);
            if (prev == b && next == c) || (prev == c && next == b) {
                if found.is_some() {
                    return None;
                }
                found = Some(v[(i + 2) % 4]);
            }
        }
        found
    };
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let g = at(i, j, k);
                if points[g] != u32::MAX {
                    continue; // on an axis
                }
                let (a, b, c) = if k == 0 {
                    (at(i - 1, j - 1, 0), at(i, j - 1, 0), at(i - 1, j, 0))
                } else if j == 0 {
                    (at(i - 1, 0, k - 1), at(i, 0, k - 1), at(i - 1, 0, k))
                } else {
                    (at(i, j - 1, k - 1), at(i, j, k - 1), at(i, j - 1, k))
                };
                let p = complete(points[a], points[b], points[c])?;
                put(&mut points, g, p)?;
            }
        }
    }
    Some((dims, points))
}
