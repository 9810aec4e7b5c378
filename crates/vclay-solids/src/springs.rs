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
//! Springs are processed in batches of 16 (gather, branch-free lane-wise arithmetic compiled
//! for AVX2/FMA by pulp's run-time dispatch, scatter). In parallel, an
//! [organized](SpringSet::organize) set runs one block of springs per thread over contiguous
//! point ranges, each writing its own slice of the force array, then the springs that straddle
//! blocks; an unorganized set scatters into one buffer per thread and sums them. The hot loop
//! has no atomics and allocates nothing. Large organized sets ([`SpringSet::INDEX_SPRINGS`])
//! read their rest lengths and stiffnesses as one-byte indices into tables of the distinct
//! values (a subdivided lattice has a few hundred at most), which are the stored `f64` values
//! bit for bit: 10 instead of 24 bytes per edge spring and 6 instead of 20 per virtual spring
//! stream through the pass (issue 31, `docs/performance.md` "Solid step memory traffic").
//!
//! When the springs are exactly the edges and quads of an `nx x ny x nz` grid (every
//! subdivided box; found combinatorially by [`SpringSet::organize`] for sets of
//! [`SpringSet::GRID_SPRINGS`] springs whose points are numbered in grid order (the boxes of
//! [`crate::model::GRID_NUMBERING_POINTS`] points and more: level 4 of the 4^3 cube and finer)
//! or number at most [`SpringSet::GRID_POINTS`], or by [`SpringSet::use_grid_kernel`]), [`SpringSet::add_forces`] and [`SpringSet::set_forces`]
//! run the structured-grid kernel of the `springs/grid.rs` module instead:
//! the z-planes of `d` as coordinate rows, each kind of spring along a row one unit-stride
//! vector, the forces added row by row, threads over ranges of planes. It sums each point's
//! terms in another order than the general kernel (agreement to rounding, about `1e-16`
//! relative; the same bits for any number of threads). The phased program's
//! `SpringSet::block_forces` and `SpringSet::straddle_forces`, the stiffness product and
//! [`SpringSet::energy`] keep the general code. `docs/performance.md` "Structured-grid spring
//! kernel".

mod grid;

use grid::{GridSprings, GridWorkspace};
use rayon::prelude::*;
use vclay_core::{CacheAligned, Parallelism, Vec3};

/// The points along each axis and the points of `lattice` in the order of a structured grid
/// (`i + nx (j + ny k)`, x the longest axis; `springs/grid.rs` module docs) when its edges and faces are exactly those of
/// an `nx x ny x nz` grid, else `None`: the data-point numbering under which the grid spring
/// kernel reads and writes the point arrays in order ([`crate::DataNumbering::Grid`]).
pub(crate) fn lattice_grid_order(
    lattice: &vclay_lattice::Lattice,
) -> Option<([usize; 3], Vec<u32>)> {
    use vclay_lattice::{EdgeId, FaceId};
    let edges: Vec<[u32; 2]> = (0..lattice.num_edges())
        .map(|e| lattice.edge_vertices(EdgeId::new(e)).map(|v| v.0))
        .collect();
    let mut offsets = Vec::with_capacity(lattice.num_faces() + 1);
    offsets.push(0u32);
    let mut verts = Vec::with_capacity(4 * lattice.num_faces());
    for f in 0..lattice.num_faces() {
        verts.extend(lattice.face_vertices(FaceId::new(f)).iter().map(|v| v.0));
        offsets.push(u32::try_from(verts.len()).ok()?);
    }
    grid::label(&edges, &offsets, &verts, lattice.num_points())
}

/// Edge springs and virtual springs of a data lattice (or of its active part).
///
/// The parameter arrays are public; after [`SpringSet::organize`] change them only through
/// [`SpringSet::reset_rest`], or organize the set again: a large organized set reads them
/// through an index built from their values (module docs).
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
    /// Thread partition from [`SpringSet::organize`] (empty: not organized).
    pub(crate) parts: Vec<Part>,
    /// The points of the straddling springs of an organized set, sorted.
    pub(crate) band: Vec<u32>,
    /// The point ranges of the blocks of an organized set.
    pub(crate) blocks: Vec<std::ops::Range<usize>>,
    /// Rest lengths and stiffnesses as one-byte indices into tables of their distinct values,
    /// read by the force kernel instead of the `f64` arrays (built by
    /// [`SpringSet::organize`] for large sets, [`SpringSet::INDEX_SPRINGS`]).
    pub(crate) index: Option<Box<SpringIndex>>,
    /// The springs in the order of a structured grid, when the set is exactly a grid's edges
    /// and quads (built by [`SpringSet::organize`]; [`grid`] module docs).
    pub(crate) grid: Option<Box<GridSprings>>,
}

/// The rest lengths and stiffnesses of a spring set as `u8` indices into tables of their
/// distinct values (issue 31): 2 bytes per spring instead of 16, the same `f64` values bit
/// for bit (`table[index]` is the stored value). A subdivided box at level 5 has 29 and 27
/// distinct edge rest lengths and stiffnesses, 185 and 176 for the virtual springs: the
/// regular masks make most springs alike. Sets with more than 256 distinct values of one
/// kind keep reading the `f64` arrays.
#[derive(Clone, Debug)]
pub(crate) struct SpringIndex {
    /// `[rest, k]` indices of each edge spring.
    edge: Vec<[u8; 2]>,
    /// `[rest, k]` indices of each face corner's virtual spring.
    corner: Vec<[u8; 2]>,
    edge_rest: [f64; 256],
    edge_k: [f64; 256],
    corner_rest: [f64; 256],
    corner_k: [f64; 256],
}

/// The distinct values of `vals` (by bit pattern) as a 256-entry table and each value's index
/// into it, or `None` above 256 distinct values.
fn byte_table(vals: &[f64]) -> Option<([f64; 256], Vec<u8>)> {
    let mut table = [0.0; 256];
    let mut n = 0;
    let mut map = std::collections::HashMap::new();
    let mut idx = Vec::with_capacity(vals.len());
    for &v in vals {
        let i = match map.entry(v.to_bits()) {
            std::collections::hash_map::Entry::Occupied(e) => *e.get(),
            std::collections::hash_map::Entry::Vacant(e) => {
                if n == 256 {
                    return None;
                }
                table[n] = v;
                n += 1;
                *e.insert((n - 1) as u8)
            }
        };
        idx.push(i);
    }
    Some((table, idx))
}

impl SpringIndex {
    /// The index of `set`'s parameters, or `None` when one kind has more than 256 distinct
    /// values.
    fn new(set: &SpringSet) -> Option<Self> {
        let (edge_rest, er) = byte_table(&set.edge_rest)?;
        let (edge_k, ek) = byte_table(&set.edge_k)?;
        let (corner_rest, cr) = byte_table(&set.corner_rest)?;
        let (corner_k, ck) = byte_table(&set.corner_k)?;
        Some(Self {
            edge: er.into_iter().zip(ek).map(|(r, k)| [r, k]).collect(),
            corner: cr.into_iter().zip(ck).map(|(r, k)| [r, k]).collect(),
            edge_rest,
            edge_k,
            corner_rest,
            corner_k,
        })
    }
}

/// Where the force kernel reads rest lengths and stiffnesses: the `f64` arrays of the set or
/// its [`SpringIndex`] (the same values).
trait Params: Copy {
    /// Rest lengths and stiffnesses of edges `e..e + BATCH` (`buf` as scratch).
    fn edge_batch<'a>(self, e: usize, buf: &'a mut [[f64; BATCH]; 2]) -> (&'a [f64], &'a [f64])
    where
        Self: 'a;
    /// Rest length and stiffness of edge `i`.
    fn edge(self, i: usize) -> (f64, f64);
    /// Rest length and stiffness of face corner `i`.
    fn corner(self, i: usize) -> (f64, f64);
    /// Rest lengths and stiffnesses of face corners `lo..lo + 4` into `rest` and `k`.
    fn corners4(self, lo: usize, rest: &mut [f64], k: &mut [f64]);
}

/// The set's `f64` arrays (slices held by value, as in [`Topology`]).
#[derive(Clone, Copy)]
struct Full<'s> {
    edge_rest: &'s [f64],
    edge_k: &'s [f64],
    corner_rest: &'s [f64],
    corner_k: &'s [f64],
}

impl<'s> Full<'s> {
    fn of(set: &'s SpringSet) -> Self {
        Self {
            edge_rest: &set.edge_rest,
            edge_k: &set.edge_k,
            corner_rest: &set.corner_rest,
            corner_k: &set.corner_k,
        }
    }
}

impl<'s> Params for Full<'s> {
    #[inline(always)]
    fn edge_batch<'a>(self, e: usize, _buf: &'a mut [[f64; BATCH]; 2]) -> (&'a [f64], &'a [f64])
    where
        Self: 'a,
    {
        (&self.edge_rest[e..e + BATCH], &self.edge_k[e..e + BATCH])
    }
    #[inline(always)]
    fn edge(self, i: usize) -> (f64, f64) {
        (self.edge_rest[i], self.edge_k[i])
    }
    #[inline(always)]
    fn corner(self, i: usize) -> (f64, f64) {
        (self.corner_rest[i], self.corner_k[i])
    }
    #[inline(always)]
    fn corners4(self, lo: usize, rest: &mut [f64], k: &mut [f64]) {
        rest.copy_from_slice(&self.corner_rest[lo..lo + 4]);
        k.copy_from_slice(&self.corner_k[lo..lo + 4]);
    }
}

/// A [`SpringIndex`]'s index arrays as slices held by value (as in [`Topology`]) and its
/// tables.
#[derive(Clone, Copy)]
struct Indexed<'s> {
    edge: &'s [[u8; 2]],
    corner: &'s [[u8; 2]],
    edge_rest: &'s [f64; 256],
    edge_k: &'s [f64; 256],
    corner_rest: &'s [f64; 256],
    corner_k: &'s [f64; 256],
}

impl<'s> Indexed<'s> {
    fn of(ix: &'s SpringIndex) -> Self {
        Self {
            edge: &ix.edge,
            corner: &ix.corner,
            edge_rest: &ix.edge_rest,
            edge_k: &ix.edge_k,
            corner_rest: &ix.corner_rest,
            corner_k: &ix.corner_k,
        }
    }
}

impl Params for Indexed<'_> {
    #[inline(always)]
    fn edge_batch<'a>(self, e: usize, buf: &'a mut [[f64; BATCH]; 2]) -> (&'a [f64], &'a [f64])
    where
        Self: 'a,
    {
        let ids = &self.edge[e..e + BATCH];
        for (j, &[r, k]) in ids.iter().enumerate() {
            buf[0][j] = self.edge_rest[r as usize];
            buf[1][j] = self.edge_k[k as usize];
        }
        (&buf[0], &buf[1])
    }
    #[inline(always)]
    fn edge(self, i: usize) -> (f64, f64) {
        let [r, k] = self.edge[i];
        (self.edge_rest[r as usize], self.edge_k[k as usize])
    }
    #[inline(always)]
    fn corner(self, i: usize) -> (f64, f64) {
        let [r, k] = self.corner[i];
        (self.corner_rest[r as usize], self.corner_k[k as usize])
    }
    #[inline(always)]
    fn corners4(self, lo: usize, rest: &mut [f64], k: &mut [f64]) {
        for (j, &[ri, ki]) in self.corner[lo..lo + 4].iter().enumerate() {
            rest[j] = self.corner_rest[ri as usize];
            k[j] = self.corner_k[ki as usize];
        }
    }
}

/// One block of an organized spring set: the springs whose points all lie in `points`, or (the
/// last part) the springs that straddle blocks.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Part {
    edges: std::ops::Range<usize>,
    faces: std::ops::Range<usize>,
    points: std::ops::Range<usize>,
}

/// Per-thread force buffers.
#[derive(Clone, Debug, Default)]
pub struct ForceWorkspace {
    bufs: Vec<Vec<Vec3>>,
    grid: GridWorkspace,
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
    /// Under [`Parallelism::Auto`], sets run on one thread below this many springs: thread
    /// start-up, the straddling springs (a larger share on small lattices) and, for unorganized
    /// sets, the per-thread copies of the force array cost more than they save (measured with
    /// `examples/kernels.rs`: no gain at 218k springs, 1.5x at 1.7M on 2 cores).
    pub const PARALLEL_SPRINGS: usize = 500_000;

    /// [`SpringSet::organize`] indexes the rest lengths and stiffnesses of sets of at least
    /// this many springs (one-byte indices into tables of distinct values, when there are at
    /// most 256 of each kind): their force passes are bound by memory traffic, and the index
    /// cuts the bytes per spring from 24 to 10 (edges) and from 20 to 6 (virtual springs).
    /// Smaller sets run from cache, where the table lookups would only add work.
    pub const INDEX_SPRINGS: usize = 500_000;

    /// [`SpringSet::organize`] looks for a structured grid (and then the force passes run the
    /// grid kernel) in sets of at least this many springs. Below it the steps of the
    /// benchmark cubes (levels 2 and 3) run the phased program, which calls the general
    /// kernel per block, so the grid copy would only cost memory (level 3: 770 -> 1,018 bytes
    /// per data point); at level 2 the two kernels take the same time (0.103 ms); and the
    /// small models keep the general kernel's bits, which the session layer's stored runs
    /// record (`vclay-session/tests`).
    pub const GRID_SPRINGS: usize = 500_000;

    /// [`SpringSet::organize`] keeps a structured grid whose points are *not* numbered in grid
    /// order only on up to this many points: then the grid kernel reads `d` and fills `f`
    /// through a permutation, and beyond the caches these scattered accesses cost more than
    /// the kernel saves (on the Cuthill-McKee numbering of [`vclay_lattice::Lattice::locality_order`]:
    /// the spring pass 7-14 % faster than the general kernel's at level 4, 117,649 points; 5 %
    /// slower at level 5, 912,673; `docs/performance.md` "Structured-grid spring kernel"). A
    /// grid numbered in grid order (the large box lattices of [`crate::model`],
    /// [`crate::DataNumbering::Grid`]) is kept at any size.
    pub const GRID_POINTS: usize = 1 << 18;

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

    /// The corners of face `f` (its range in `face_verts`, `corner_rest` and `corner_k`).
    #[inline]
    fn face(&self, f: usize) -> std::ops::Range<usize> {
        self.face_offsets[f] as usize..self.face_offsets[f + 1] as usize
    }

    /// A new (unorganized) set with the given edges and faces, in the given order.
    fn select(
        &self,
        edges: impl IntoIterator<Item = usize>,
        faces: impl IntoIterator<Item = usize>,
    ) -> SpringSet {
        let mut out = SpringSet {
            face_offsets: vec![0],
            ..Default::default()
        };
        for i in edges {
            out.edges.push(self.edges[i]);
            out.edge_rest.push(self.edge_rest[i]);
            out.edge_k.push(self.edge_k[i]);
        }
        for f in faces {
            let r = self.face(f);
            out.face_verts
                .extend_from_slice(&self.face_verts[r.clone()]);
            out.corner_rest
                .extend_from_slice(&self.corner_rest[r.clone()]);
            out.corner_k.extend_from_slice(&self.corner_k[r]);
            out.face_offsets.push(out.face_verts.len() as u32);
        }
        out
    }

    /// Sets every rest length to the length in configuration `d` (plastic reset, journal
    /// section 5.4: both kinds of spring).
    pub fn reset_rest(&mut self, d: &[Vec3]) {
        for (e, r) in self.edges.iter().zip(&mut self.edge_rest) {
            *r = (d[e[1] as usize] - d[e[0] as usize]).norm();
        }
        for f in 0..self.num_faces() {
            let lo = self.face(f).start;
            let verts = &self.face_verts[self.face(f)];
            for j in 0..verts.len() {
                let (m, a, b) = corner(verts, j);
                self.corner_rest[lo + j] = (d[m] - (d[a] + d[b]) * 0.5).norm();
            }
        }
        if self.index.is_some() {
            self.index = SpringIndex::new(self).map(Box::new);
        }
        if let Some(mut grid) = self.grid.take()
            && grid.set_params(self)
        {
            self.grid = Some(grid);
        }
    }

    /// The subset of springs that touch a point with `keep[i]` (journal section 5.2: springs
    /// among data points that only fixed control points define need no processing).
    pub fn filter(&self, keep: &[bool]) -> SpringSet {
        let kept = |vs: &[u32]| vs.iter().any(|&v| keep[v as usize]);
        self.select(
            (0..self.edges.len()).filter(|&i| kept(&self.edges[i])),
            (0..self.num_faces()).filter(|&f| kept(&self.face_verts[self.face(f)])),
        )
    }

    /// Reorders the springs for parallel, cache-friendly force passes on `n` points: the point
    /// ids are cut into `blocks` contiguous ranges; springs whose points all lie in one range
    /// form that range's part, the rest a final straddling part, and inside each part the
    /// springs are sorted by their smallest point id. [`SpringSet::add_forces`] then runs the
    /// parts in parallel, each writing only its own range of the force array (no per-thread
    /// copies), and the straddling part after them. Pays off when the point ids are numbered for
    /// locality (the data lattices of [`crate::model`] are, by
    /// [`vclay_lattice::Lattice::locality_order`]). The forces do not depend on the order.
    /// Large sets that are exactly a grid's edges and quads also get the structured-grid
    /// kernel ([`SpringSet::GRID_SPRINGS`], [`SpringSet::GRID_POINTS`]; module docs).
    pub fn organize(&mut self, n: usize, blocks: usize) {
        let blocks = blocks.max(1);
        let block = |v: u32| (v as usize * blocks / n.max(1)).min(blocks - 1);
        // (part, smallest point id, index) of a spring over points `vs`.
        let key = |vs: &[u32], i: usize| -> (usize, u32, usize) {
            let b = vs.first().map_or(0, |&v| block(v));
            let same = vs.iter().all(|&v| block(v) == b);
            let lo = vs.iter().copied().min().unwrap_or(0);
            (if same { b } else { blocks }, lo, i)
        };
        let mut edge_keys: Vec<_> = (0..self.edges.len())
            .map(|i| key(&self.edges[i], i))
            .collect();
        let mut face_keys: Vec<_> = (0..self.num_faces())
            .map(|f| key(&self.face_verts[self.face(f)], f))
            .collect();
        edge_keys.sort_unstable();
        face_keys.sort_unstable();
        let edge_counts = counts(edge_keys.iter().map(|k| k.0), blocks + 1);
        let face_counts = counts(face_keys.iter().map(|k| k.0), blocks + 1);
        *self = self.select(edge_keys.iter().map(|k| k.2), face_keys.iter().map(|k| k.2));
        // Freed before the band and the index are built (the peak of a large build).
        drop((edge_keys, face_keys));
        let (mut e0, mut f0) = (0, 0);
        self.parts = (0..=blocks)
            .map(|b| {
                let part = Part {
                    edges: e0..e0 + edge_counts[b],
                    faces: f0..f0 + face_counts[b],
                    points: if b == blocks {
                        0..n
                    } else {
                        // Exactly the ids `v` with `block(v) == b`.
                        (n * b).div_ceil(blocks)..(n * (b + 1)).div_ceil(blocks)
                    },
                };
                e0 += edge_counts[b];
                f0 += face_counts[b];
                part
            })
            .collect();
        let straddle = &self.parts[blocks];
        let mut band: Vec<u32> = self.edges[straddle.edges.clone()]
            .iter()
            .flatten()
            .copied()
            .chain(
                self.face_verts[self.face_offsets[straddle.faces.start] as usize
                    ..self.face_offsets[straddle.faces.end] as usize]
                    .iter()
                    .copied(),
            )
            .collect();
        band.sort_unstable();
        band.dedup();
        self.band = band;
        self.blocks = self.parts[..blocks]
            .iter()
            .map(|p| p.points.clone())
            .collect();
        self.index = None;
        self.grid = (self.len() >= Self::GRID_SPRINGS)
            .then(|| GridSprings::new(self, n))
            .flatten()
            .filter(|g| n <= Self::GRID_POINTS || g.in_grid_order())
            .map(Box::new);
        // The grid kernel reads its own copy of the parameters.
        if self.grid.is_none() && self.len() >= Self::INDEX_SPRINGS {
            self.index_parameters();
        }
    }

    /// The points along x, y and z of the grid whose edges and quads this set's springs
    /// are, when [`SpringSet::organize`] found one (`None` otherwise): then
    /// [`SpringSet::add_forces`] and [`SpringSet::set_forces`] run the structured-grid kernel.
    pub fn grid_dims(&self) -> Option<[usize; 3]> {
        self.grid.as_ref().map(|g| g.dims())
    }

    /// Looks for a structured grid over points `0..n` whatever the set's size
    /// ([`SpringSet::GRID_SPRINGS`], [`SpringSet::GRID_POINTS`]), so that the force passes run
    /// the grid kernel if one is found (for comparisons and tests); returns whether one was.
    pub fn use_grid_kernel(&mut self, n: usize) -> bool {
        self.grid = GridSprings::new(self, n).map(Box::new);
        self.grid.is_some()
    }

    /// Drops the grid form, so that the general kernel runs (for comparisons; the parameter
    /// index of a large set is built as [`SpringSet::organize`] builds it for a set that is
    /// not a grid).
    pub fn drop_grid(&mut self) {
        if self.grid.take().is_some() && !self.parts.is_empty() && self.len() >= Self::INDEX_SPRINGS
        {
            self.index_parameters();
        }
    }

    /// Builds the one-byte index of the rest lengths and stiffnesses that the force kernel
    /// then reads ([`SpringSet::INDEX_SPRINGS`]); returns whether every kind has at most 256
    /// distinct values (otherwise the kernel keeps reading the `f64` arrays). The forces are
    /// the same bits either way. Changing the parameter arrays afterwards other than through
    /// [`SpringSet::reset_rest`] requires calling this again (or [`SpringSet::organize`]).
    pub(crate) fn index_parameters(&mut self) -> bool {
        self.index = SpringIndex::new(self).map(Box::new);
        self.index.is_some()
    }

    /// Bytes of the spring arrays: endpoints, rest lengths and stiffnesses (24 per edge, 20
    /// per face corner) and the parameter index (face offsets excluded).
    pub fn bytes(&self) -> usize {
        self.edges.len() * 24
            + self.face_verts.len() * 20
            + self
                .index
                .as_ref()
                .map_or(0, |ix| 2 * (ix.edge.len() + ix.corner.len()) + 4 * 256 * 8)
            + self.grid.as_ref().map_or(0, |g| g.bytes())
    }

    /// The point blocks of a set [organized](SpringSet::organize) for `n` points (`None`
    /// otherwise): block `b` owns the forces on the points of its range, for phased programs
    /// ([`SpringSet::block_forces`], then [`SpringSet::straddle_forces`]).
    pub(crate) fn blocks_for(&self, n: usize) -> Option<&[std::ops::Range<usize>]> {
        (self.blocks.len() > 1 && self.blocks.last()?.end == n).then_some(&self.blocks[..])
    }

    /// Overwrites `f_block` (the forces on the points of block `b`) with the forces of the
    /// springs inside the block; returns their energy.
    pub(crate) fn block_forces(&self, b: usize, d: &[Vec3], f_block: &mut [Vec3]) -> f64 {
        let part = &self.parts[b];
        f_block.fill(Vec3::zeros());
        self.forces_range(
            d,
            f_block,
            part.points.start,
            part.edges.clone(),
            part.faces.clone(),
        )
    }

    /// Adds the forces of part `k` of `parts` (equal shares) of the springs that straddle
    /// blocks to `f` (they act on the points of [`SpringSet::band`] only); returns their
    /// energy.
    pub(crate) fn straddle_forces(
        &self,
        d: &[Vec3],
        f: &mut [Vec3],
        k: usize,
        parts: usize,
    ) -> f64 {
        let part = self.parts.last().expect("organized spring set");
        let share = |r: &std::ops::Range<usize>| {
            r.start + r.len() * k / parts..r.start + r.len() * (k + 1) / parts
        };
        self.forces_range(d, f, 0, share(&part.edges), share(&part.faces))
    }

    /// Number of springs in the straddling part of an organized set (all springs if the set is
    /// not organized): the springs [`SpringSet::add_forces`] processes on one thread.
    pub fn straddling(&self) -> usize {
        match self.parts.last() {
            Some(p) => {
                p.edges.len()
                    + (self.face_offsets[p.faces.end] - self.face_offsets[p.faces.start]) as usize
            }
            None => self.len(),
        }
    }

    /// Potential energy `sum k/2 (l - l0)^2` in configuration `d`.
    pub fn energy(&self, d: &[Vec3]) -> f64 {
        let mut e = 0.0;
        for (i, s) in self.edges.iter().enumerate() {
            let l = (d[s[1] as usize] - d[s[0] as usize]).norm();
            e += 0.5 * self.edge_k[i] * (l - self.edge_rest[i]).powi(2);
        }
        for f in 0..self.num_faces() {
            let lo = self.face(f).start;
            let verts = &self.face_verts[self.face(f)];
            for j in 0..verts.len() {
                let (m, a, b) = corner(verts, j);
                let l = (d[m] - (d[a] + d[b]) * 0.5).norm();
                e += 0.5 * self.corner_k[lo + j] * (l - self.corner_rest[lo + j]).powi(2);
            }
        }
        e
    }

    /// Adds the spring forces in configuration `d` to `f` and returns the potential energy.
    ///
    /// In parallel ([`Parallelism::Rayon`], or `Auto` from [`SpringSet::PARALLEL_SPRINGS`]
    /// springs): an [organized](SpringSet::organize) set runs its blocks side by side, each
    /// writing its own range of `f`, then its straddling springs; an unorganized one splits the
    /// springs evenly and sums per-thread copies of `f` kept in `ws`.
    pub fn add_forces(
        &self,
        d: &[Vec3],
        f: &mut [Vec3],
        ws: &mut ForceWorkspace,
        par: Parallelism,
    ) -> f64 {
        self.forces(d, f, ws, par, false)
    }

    /// Overwrites `f` with the spring forces in configuration `d` and returns the potential
    /// energy: [`SpringSet::add_forces`] on a zeroed `f`, the same bits, but an
    /// [organized](SpringSet::organize) set running in parallel zeroes each block's range in
    /// the task that then fills it, instead of a separate pass over `f` on one thread.
    pub fn set_forces(
        &self,
        d: &[Vec3],
        f: &mut [Vec3],
        ws: &mut ForceWorkspace,
        par: Parallelism,
    ) -> f64 {
        self.forces(d, f, ws, par, true)
    }

    /// [`SpringSet::add_forces`], on a zeroed `f` if `overwrite`.
    fn forces(
        &self,
        d: &[Vec3],
        f: &mut [Vec3],
        ws: &mut ForceWorkspace,
        par: Parallelism,
        overwrite: bool,
    ) -> f64 {
        let threads = if par.is_parallel_from(self.len(), Self::PARALLEL_SPRINGS) {
            rayon::current_num_threads().max(1)
        } else {
            1
        };
        if let Some(grid) = &self.grid
            && d.len() == grid.len()
            && f.len() == grid.len()
        {
            return grid.forces(d, f, &mut ws.grid, threads, overwrite);
        }
        let organized = self.parts.len() > 2
            && self.parts[self.parts.len() - 2].points.end == f.len()
            && d.len() == f.len();
        if threads == 1 {
            if overwrite {
                f.fill(Vec3::zeros());
            }
            return self.forces_range(d, f, 0, 0..self.edges.len(), 0..self.num_faces());
        }
        if organized && let Some((straddle, blocks)) = self.parts.split_last() {
            // Organized: each block writes its own range of `f`, then the straddling springs.
            let mut chunks = Vec::with_capacity(blocks.len());
            let mut rest = &mut *f;
            let mut at = 0;
            for b in blocks {
                let (head, tail) = std::mem::take(&mut rest).split_at_mut(b.points.end - at);
                chunks.push(head);
                rest = tail;
                at = b.points.end;
            }
            let energy: f64 = blocks
                .par_iter()
                .zip(chunks)
                .map(|(b, chunk)| {
                    if overwrite {
                        chunk.fill(Vec3::zeros());
                    }
                    self.forces_range(d, chunk, b.points.start, b.edges.clone(), b.faces.clone())
                })
                .sum();
            return energy
                + self.forces_range(d, f, 0, straddle.edges.clone(), straddle.faces.clone());
        }
        if overwrite {
            f.fill(Vec3::zeros());
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
                self.forces_range(d, buf, 0, er, fr)
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

    /// Forces of the edges and faces in the given ranges, added to `f`, whose entry `i` is the
    /// force on point `base + i`.
    fn forces_range(
        &self,
        d: &[Vec3],
        f: &mut [Vec3],
        base: usize,
        edges: std::ops::Range<usize>,
        faces: std::ops::Range<usize>,
    ) -> f64 {
        // Compiled once per instruction set (AVX2 + FMA where the CPU has it, else the
        // baseline); the batched arithmetic below vectorizes in either.
        pulp::Arch::new().dispatch(ForcesOp {
            set: self,
            d,
            f,
            base,
            edges,
            faces,
        })
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
            let (lo, hi) = (self.face(fc).start, self.face(fc).end);
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
            let (lo, hi) = (self.face(fc).start, self.face(fc).end);
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

/// The index arrays the force kernel reads, as slices held by value: the kernel's loop then
/// keeps their addresses in registers or its own stack frame instead of reloading them from
/// the [`SpringSet`] (a fixed heap address that every thread's batch stores can 4K-alias
/// with, the spring phase's stack lottery in `docs/performance.md`, session 21 (h59)).
#[derive(Clone, Copy)]
struct Topology<'s> {
    edges: &'s [[u32; 2]],
    face_offsets: &'s [u32],
    face_verts: &'s [u32],
}

impl<'s> Topology<'s> {
    fn of(set: &'s SpringSet) -> Self {
        Self {
            edges: &set.edges,
            face_offsets: &set.face_offsets,
            face_verts: &set.face_verts,
        }
    }

    /// The corners of face `f` (see [`SpringSet::face`]).
    #[inline(always)]
    fn face(self, f: usize) -> std::ops::Range<usize> {
        self.face_offsets[f] as usize..self.face_offsets[f + 1] as usize
    }

    /// The force kernel (see [`ForcesOp`]): springs in batches of [`BATCH`], each batch
    /// gathered (spring vectors `x`), then `g = k (1 - l0/|x|) x` and the energy computed
    /// lane-wise without branches, then scattered.
    #[inline(always)]
    fn forces_kernel<P: Params>(
        self,
        params: P,
        d: &[Vec3],
        f: &mut [Vec3],
        base: usize,
        edges: std::ops::Range<usize>,
        faces: std::ops::Range<usize>,
    ) -> f64 {
        let mut energy = 0.0;
        // Batch arrays on cache lines of their own, wherever the thread's stack lies: no vector
        // access splits a line or a page ([`CacheAligned`]; the same bits).
        let mut x = CacheAligned([[0.0; BATCH]; 3]);
        let mut buf = CacheAligned([[0.0; BATCH]; 2]);
        // Edge springs.
        let mut e = edges.start;
        while e + BATCH <= edges.end {
            let idx = &self.edges[e..e + BATCH];
            for (j, &[a, b]) in idx.iter().enumerate() {
                let v = d[b as usize] - d[a as usize];
                x[0][j] = v.x;
                x[1][j] = v.y;
                x[2][j] = v.z;
            }
            let (rest, k) = params.edge_batch(e, &mut buf);
            energy += spring_batch(&mut x, rest, k);
            for (j, &[a, b]) in idx.iter().enumerate() {
                let g = Vec3::new(x[0][j], x[1][j], x[2][j]);
                f[a as usize - base] += g;
                f[b as usize - base] -= g;
            }
            e += BATCH;
        }
        for i in e..edges.end {
            let [a, b] = self.edges[i];
            let (a, b) = (a as usize, b as usize);
            let x = d[b] - d[a];
            let l = x.norm();
            if l == 0.0 {
                continue;
            }
            let (rest, k) = params.edge(i);
            let s = l - rest;
            energy += 0.5 * k * s * s;
            let g = x * (k * s / l);
            f[a - base] += g;
            f[b - base] -= g;
        }
        // Virtual springs: quads (every face of a subdivided lattice) in batches of
        // `BATCH / 4`; corners 0 and 2 share the virtual point (p1 + p3) / 2, corners 1 and 3
        // share (p0 + p2) / 2. Other faces corner by corner.
        const Q: usize = BATCH / 4;
        let mut quads = [0usize; Q];
        let mut starts = [0usize; Q];
        let mut rest = CacheAligned([0.0; BATCH]);
        let mut ks = CacheAligned([0.0; BATCH]);
        let mut nq = 0;
        for fc in faces {
            let (lo, hi) = (self.face(fc).start, self.face(fc).end);
            if hi - lo == 4 {
                quads[nq] = fc;
                starts[nq] = lo;
                nq += 1;
                if nq == Q {
                    energy +=
                        self.quad_batch(params, d, f, base, &starts, &mut x, &mut rest, &mut ks);
                    nq = 0;
                }
                continue;
            }
            energy += self.face_scalar(params, d, f, base, lo, hi);
        }
        for &lo in &starts[..nq] {
            energy += self.face_scalar(params, d, f, base, lo, lo + 4);
        }
        energy
    }

    /// One batch of `BATCH / 4` quads starting at corner offsets `starts`.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn quad_batch<P: Params>(
        self,
        params: P,
        d: &[Vec3],
        f: &mut [Vec3],
        base: usize,
        starts: &[usize; BATCH / 4],
        x: &mut [[f64; BATCH]; 3],
        rest: &mut [f64; BATCH],
        ks: &mut [f64; BATCH],
    ) -> f64 {
        for (q, &lo) in starts.iter().enumerate() {
            let v = &self.face_verts[lo..lo + 4];
            let p = [
                d[v[0] as usize],
                d[v[1] as usize],
                d[v[2] as usize],
                d[v[3] as usize],
            ];
            let mid = [(p[1] + p[3]) * 0.5, (p[0] + p[2]) * 0.5];
            for j in 0..4 {
                let y = p[j] - mid[j & 1];
                x[0][4 * q + j] = y.x;
                x[1][4 * q + j] = y.y;
                x[2][4 * q + j] = y.z;
            }
            params.corners4(lo, &mut rest[4 * q..4 * q + 4], &mut ks[4 * q..4 * q + 4]);
        }
        let energy = spring_batch(x, rest, ks);
        for (q, &lo) in starts.iter().enumerate() {
            let v = &self.face_verts[lo..lo + 4];
            let g: [Vec3; 4] = std::array::from_fn(|j| {
                Vec3::new(x[0][4 * q + j], x[1][4 * q + j], x[2][4 * q + j])
            });
            // Corner j: -g_j on its point, +g_j / 2 on each neighbour.
            for j in 0..4 {
                let acc = (g[(j + 1) & 3] + g[(j + 3) & 3]) * 0.5 - g[j];
                f[v[j] as usize - base] += acc;
            }
        }
        energy
    }

    /// The virtual springs of one face (corners `lo..hi` of `face_verts`), one by one.
    #[inline(always)]
    fn face_scalar<P: Params>(
        self,
        params: P,
        d: &[Vec3],
        f: &mut [Vec3],
        base: usize,
        lo: usize,
        hi: usize,
    ) -> f64 {
        let verts = &self.face_verts[lo..hi];
        let mut energy = 0.0;
        for j in 0..verts.len() {
            let (m, a, b) = corner(verts, j);
            let x = d[m] - (d[a] + d[b]) * 0.5;
            let l = x.norm();
            if l == 0.0 {
                continue;
            }
            let (rest, k) = params.corner(lo + j);
            let s = l - rest;
            energy += 0.5 * k * s * s;
            let g = x * (k * s / l);
            f[m - base] -= g;
            let h = g * 0.5;
            f[a - base] += h;
            f[b - base] += h;
        }
        energy
    }
}

/// How many items of each value `0..n` the iterator yields.
fn counts(it: impl Iterator<Item = usize>, n: usize) -> Vec<usize> {
    let mut c = vec![0; n];
    for i in it {
        c[i] += 1;
    }
    c
}

/// Springs per batch of the force kernel.
const BATCH: usize = 16;

/// The force kernel as a [`pulp::WithSimd`] operation, so that [`pulp::Arch::dispatch`]
/// compiles it with the best instruction set the CPU has (runtime detection, safe code).
struct ForcesOp<'a> {
    set: &'a SpringSet,
    d: &'a [Vec3],
    f: &'a mut [Vec3],
    base: usize,
    edges: std::ops::Range<usize>,
    faces: std::ops::Range<usize>,
}

impl pulp::WithSimd for ForcesOp<'_> {
    type Output = f64;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) -> f64 {
        let set = self.set;
        match &set.index {
            Some(ix) => Topology::of(set).forces_kernel(
                Indexed::of(ix),
                self.d,
                self.f,
                self.base,
                self.edges,
                self.faces,
            ),
            None => Topology::of(set).forces_kernel(
                Full::of(set),
                self.d,
                self.f,
                self.base,
                self.edges,
                self.faces,
            ),
        }
    }
}

/// For a batch of spring vectors `x` (rows x, y, z), rest lengths and stiffnesses: replaces
/// `x` by the force `g = k (l - l0) x / l` (zero where `l = 0`) and returns the energy
/// `sum k/2 (l - l0)^2`. Straight-line arithmetic over arrays, so it vectorizes.
#[inline(always)]
fn spring_batch(x: &mut [[f64; BATCH]; 3], rest: &[f64], k: &[f64]) -> f64 {
    let (rest, k) = (&rest[..BATCH], &k[..BATCH]);
    let mut e = CacheAligned([0.0; BATCH]);
    let mut c = CacheAligned([0.0; BATCH]);
    for j in 0..BATCH {
        let l = (x[0][j] * x[0][j] + x[1][j] * x[1][j] + x[2][j] * x[2][j]).sqrt();
        let s = l - rest[j];
        let inv = if l > 0.0 { 1.0 / l } else { 0.0 };
        c[j] = k[j] * s * inv;
        e[j] = if l > 0.0 { 0.5 * k[j] * s * s } else { 0.0 };
    }
    for row in x.iter_mut() {
        for j in 0..BATCH {
            row[j] *= c[j];
        }
    }
    e.iter().sum()
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{SolidParams, benchmarks};

    fn bits(v: &[Vec3]) -> Vec<[u64; 3]> {
        v.iter()
            .map(|x| [x.x.to_bits(), x.y.to_bits(), x.z.to_bits()])
            .collect()
    }

    fn forces(set: &SpringSet, d: &[Vec3], par: Parallelism) -> (Vec<Vec3>, u64) {
        let mut f = vec![Vec3::new(1.0, 2.0, 3.0); d.len()];
        let e = set.set_forces(d, &mut f, &mut ForceWorkspace::default(), par);
        (f, e.to_bits())
    }

    #[test]
    fn indexed_parameters_give_the_same_forces_bit_for_bit() {
        for level in [1, 2] {
            let mut s = benchmarks::cube(level, SolidParams::default()).unwrap();
            benchmarks::pull(&mut s).unwrap();
            let d = s.data_points().to_vec();
            // The general kernel (a box's set is a grid, whose kernel has its own copy).
            let mut plain = s.springs().clone();
            plain.drop_grid();
            assert!(plain.index.is_none(), "small sets read the f64 arrays");
            let mut indexed = plain.clone();
            assert!(indexed.index_parameters());
            let ix: &SpringIndex = indexed.index.as_deref().unwrap();
            // Every looked-up value is the stored one.
            for i in 0..plain.edges.len() {
                let (r, k) = Params::edge(Indexed::of(ix), i);
                assert_eq!(
                    (r.to_bits(), k.to_bits()),
                    (plain.edge_rest[i].to_bits(), plain.edge_k[i].to_bits())
                );
            }
            for i in 0..plain.face_verts.len() {
                let (r, k) = Params::corner(Indexed::of(ix), i);
                assert_eq!(
                    (r.to_bits(), k.to_bits()),
                    (plain.corner_rest[i].to_bits(), plain.corner_k[i].to_bits())
                );
            }
            assert!(indexed.bytes() > plain.bytes());
            for par in [Parallelism::Sequential, Parallelism::Rayon] {
                let (f0, e0) = forces(&plain, &d, par);
                let (f1, e1) = forces(&indexed, &d, par);
                assert_eq!(bits(&f0), bits(&f1), "level {level} {par:?}");
                assert_eq!(e0, e1);
                // `set_forces` is `add_forces` on zeroed forces.
                let mut f2 = vec![Vec3::zeros(); d.len()];
                let e2 = indexed.add_forces(&d, &mut f2, &mut ForceWorkspace::default(), par);
                assert_eq!(bits(&f1), bits(&f2));
                assert_eq!(e1, e2.to_bits());
            }
            // A plastic reset makes every rest length different: the index is dropped (more
            // than 256 values) or rebuilt, and the forces still match the plain set's.
            let mut plain2 = plain.clone();
            let mut indexed2 = indexed.clone();
            plain2.reset_rest(&d);
            indexed2.reset_rest(&d);
            let moved: Vec<Vec3> = d.iter().map(|x| x * 1.01).collect();
            assert_eq!(
                bits(&forces(&plain2, &moved, Parallelism::Sequential).0),
                bits(&forces(&indexed2, &moved, Parallelism::Sequential).0)
            );
        }
    }

    #[test]
    fn more_than_256_distinct_stiffnesses_keep_the_f64_arrays() {
        let mut set = SpringSet {
            face_offsets: vec![0],
            ..Default::default()
        };
        for i in 0..300u32 {
            set.edges.push([i, i + 1]);
            set.edge_rest.push(1.0);
            set.edge_k.push(1.0 + f64::from(i));
        }
        assert!(!set.index_parameters());
        assert!(set.index.is_none());
    }

    /// The largest difference between the forces of the grid kernel and of the general
    /// kernel, relative to the largest force, and the energies' relative difference.
    fn grid_vs_general(set: &SpringSet, d: &[Vec3], par: Parallelism) -> (f64, f64) {
        assert!(set.grid.is_some(), "a grid");
        let mut general = set.clone();
        general.drop_grid();
        let (fg, eg) = forces(set, d, par);
        let (fs, es) = forces(&general, d, par);
        let scale = fs.iter().map(|x| x.amax()).fold(0.0, f64::max);
        let df = fg
            .iter()
            .zip(&fs)
            .map(|(a, b)| (a - b).amax())
            .fold(0.0, f64::max);
        let (eg, es) = (f64::from_bits(eg), f64::from_bits(es));
        (df / scale, (eg - es).abs() / es.abs())
    }

    #[test]
    fn grid_kernel_agrees_with_the_general_kernel() {
        for level in [1, 2, 3] {
            let mut s = benchmarks::cube(level, SolidParams::default()).unwrap();
            benchmarks::pull(&mut s).unwrap();
            let d = s.data_points().to_vec();
            let mut set = s.springs().clone();
            assert!(set.use_grid_kernel(d.len()));
            let set = &set;
            let n = [4, 7, 13, 25][level];
            assert_eq!(set.grid_dims(), Some([n, n, n]));
            for par in [Parallelism::Sequential, Parallelism::Rayon] {
                let (df, de) = grid_vs_general(set, &d, par);
                eprintln!("level {level} {par:?}: {df:e} {de:e}");
                assert!(df < 1e-12 && de < 1e-12, "level {level}: {df:e} {de:e}");
            }
        }
    }

    /// A solid on a subdivided box of `n` control points, `levels` levels.
    fn boxed(n: [usize; 3], levels: usize) -> crate::DynamicSolid {
        let control = vclay_lattice::primitives::box_lattice(n, Vec3::zeros(), Vec3::repeat(1.0));
        let (source, p) =
            crate::SolidSource::subdivision(control, vclay_lattice::BoundaryRule::Sharp, levels);
        crate::DynamicSolid::new(
            source,
            p,
            crate::Material::default(),
            SolidParams::default(),
        )
        .unwrap()
    }

    /// `d` moved by a seeded pseudo-random amount of up to `amp` per coordinate.
    fn perturbed(d: &[Vec3], amp: f64, seed: u64) -> Vec<Vec3> {
        let mut x = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        let mut next = || {
            // xorshift64
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        d.iter()
            .map(|p| p + Vec3::new(next(), next(), next()) * amp)
            .collect()
    }

    #[test]
    fn grid_kernel_agrees_on_perturbed_boxes_and_after_a_plastic_reset() {
        // Odd and even grid sizes, cubic and not: (control points, levels) -> grid points.
        for (n, levels, dims) in [
            ([4, 4, 4], 1, [7, 7, 7]),
            ([4, 4, 4], 3, [25, 25, 25]),
            ([3, 5, 4], 2, [17, 13, 9]),
            ([4, 6, 5], 0, [6, 5, 4]),
        ] {
            let s = boxed(n, levels);
            let mut set = s.springs().clone();
            assert_eq!(set.grid_dims(), None, "a small set: the general kernel");
            assert!(set.use_grid_kernel(s.data_points().len()));
            assert_eq!(set.grid_dims(), Some(dims), "{n:?} level {levels}");
            let d0 = s.data_points().to_vec();
            let d = perturbed(&d0, 0.02 / (1 << levels) as f64, 7);
            for par in [Parallelism::Sequential, Parallelism::Rayon] {
                let (df, de) = grid_vs_general(&set, &d, par);
                assert!(df < 1e-12 && de < 1e-12, "{n:?} {levels}: {df:e} {de:e}");
            }
            // The returned energy is `energy()`'s.
            let (_, e) = forces(&set, &d, Parallelism::Sequential);
            let e2 = set.energy(&d);
            assert!(
                (f64::from_bits(e) - e2).abs() <= 1e-12 * e2,
                "{n:?} {levels}"
            );
            // A plastic reset rewrites every rest length; the grid copy follows.
            set.reset_rest(&d);
            assert!(set.grid.is_some());
            let moved = perturbed(&d, 0.01 / (1 << levels) as f64, 11);
            let (df, de) = grid_vs_general(&set, &moved, Parallelism::Sequential);
            assert!(
                df < 1e-12 && de < 1e-12,
                "{n:?} {levels} reset: {df:e} {de:e}"
            );
            let (f, e) = forces(&set, &d, Parallelism::Sequential);
            assert_eq!(e, 0.0f64.to_bits(), "at the reset shape: no energy");
            assert!(f.iter().all(|x| x.amax() < 1e-12));
        }
    }

    #[test]
    fn grid_kernel_gives_the_same_bits_on_any_number_of_threads() {
        let s = boxed([4, 4, 4], 3);
        let mut set = s.springs().clone();
        assert!(set.use_grid_kernel(s.data_points().len()));
        let set = &set;
        let d = perturbed(s.data_points(), 0.002, 3);
        let (f1, e1) = forces(set, &d, Parallelism::Sequential);
        for threads in [2, 3, 5] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let (f, e) = pool.install(|| forces(set, &d, Parallelism::Rayon));
            assert!(bits(&f) == bits(&f1), "{threads} threads");
            assert_eq!(e, e1);
            // add_forces adds the same values.
            let mut g = vec![Vec3::new(1.0, 2.0, 3.0); d.len()];
            let mut h = g.clone();
            let mut ws = ForceWorkspace::default();
            pool.install(|| set.add_forces(&d, &mut g, &mut ws, Parallelism::Rayon));
            set.add_forces(&d, &mut h, &mut ws, Parallelism::Sequential);
            assert!(bits(&g) == bits(&h));
            let f_plus: Vec<Vec3> = f1.iter().map(|x| x + Vec3::new(1.0, 2.0, 3.0)).collect();
            assert!(bits(&g) == bits(&f_plus));
        }
    }

    #[test]
    fn sets_that_are_not_grids_keep_the_general_kernel() {
        // A torus and a gear (other topologies), a set filtered to part of the points (fixed
        // regions), and a grid's set with one quad removed.
        for control in [
            vclay_lattice::primitives::paper_torus(0.25, 0.5, 0.25),
            vclay_lattice::primitives::gear(0.25, 0.5, 0.65, 0.25),
        ] {
            let (source, p) =
                crate::SolidSource::subdivision(control, vclay_lattice::BoundaryRule::Sharp, 1);
            let s = crate::DynamicSolid::new(
                source,
                p,
                crate::Material::default(),
                SolidParams::default(),
            )
            .unwrap();
            let mut set = s.springs().clone();
            assert!(!set.use_grid_kernel(s.data_points().len()));
        }
        let s = boxed([4, 4, 4], 2);
        let n = s.data_points().len();
        let keep: Vec<bool> = s.data_points().iter().map(|p| p.z > 0.5).collect();
        let mut part = s.springs().filter(&keep);
        part.organize(n, 2);
        assert!(!part.use_grid_kernel(n));
        let mut whole = s.springs().clone();
        let last = whole.num_faces() - 1;
        let mut cut = whole.select(0..whole.edges.len(), 0..last);
        cut.organize(n, 2);
        assert!(!cut.use_grid_kernel(n));
        let mut cut = whole.select(1..whole.edges.len(), 0..whole.num_faces());
        cut.organize(n, 2);
        assert!(!cut.use_grid_kernel(n));
        assert!(whole.use_grid_kernel(n));
        assert_eq!(whole.grid_dims(), Some([13, 13, 13]));
    }

    #[test]
    fn grid_kernel_on_points_not_numbered_in_grid_order() {
        // The same box with its points renumbered by a seeded shuffle: the grid is found
        // through the permutation, and the forces still agree.
        let s = boxed([3, 5, 4], 2);
        let n = s.data_points().len();
        let mut perm: Vec<u32> = (0..n as u32).collect();
        let mut x = 12345u64;
        for i in (1..n).rev() {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            perm.swap(i, (x % (i as u64 + 1)) as usize);
        }
        let set = s.springs();
        let mut moved = set.select(0..set.edges.len(), 0..set.num_faces());
        for v in moved
            .edges
            .iter_mut()
            .flatten()
            .chain(&mut moved.face_verts)
        {
            *v = perm[*v as usize];
        }
        moved.organize(n, 2);
        assert!(moved.use_grid_kernel(n));
        assert_eq!(moved.grid_dims(), Some([17, 13, 9]));
        let d0 = perturbed(s.data_points(), 0.004, 5);
        let mut d = vec![Vec3::zeros(); n];
        for (i, &p) in perm.iter().enumerate() {
            d[p as usize] = d0[i];
        }
        for par in [Parallelism::Sequential, Parallelism::Rayon] {
            let (df, de) = grid_vs_general(&moved, &d, par);
            assert!(df < 1e-12 && de < 1e-12, "{par:?}: {df:e} {de:e}");
        }
    }
}
