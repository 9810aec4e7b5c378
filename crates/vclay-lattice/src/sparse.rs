//! Sparse matrices in compressed sparse row (CSR) form, applied to points or scalars.
//!
//! A subdivision level is the linear map `d^(j+1) = A^(j) d^(j)` of
//! `subdivision-solids-journal.txt` section 4.2 (eq 4 and the step list after it): row `i` of
//! `A^(j)` holds the weights of the affine combination that the subdivision rules use for new
//! point `i`, so every row sums to 1. [`SparseMatrix`] stores such a matrix; it multiplies
//! `f64` slices and `Vec3` slices alike through the [`Coord`] trait, in parallel over rows with
//! rayon when the caller's [`Parallelism`] allows, and gives the transpose (for pulling forces on
//! data points back to control points, journal eq 8: `A^T f_d`) and the product of two matrices.

use rayon::prelude::*;
use vclay_core::{Parallelism, Vec3};

/// A value that sparse matrices can combine linearly: `f64`, `Vec3`.
pub trait Coord: Copy + Send + Sync {
    /// The additive identity.
    fn zero() -> Self;
    /// `self += w * x`.
    fn add_scaled(&mut self, w: f64, x: &Self);
}

impl Coord for f64 {
    #[inline]
    fn zero() -> Self {
        0.0
    }
    #[inline]
    fn add_scaled(&mut self, w: f64, x: &Self) {
        *self += w * x;
    }
}

impl Coord for Vec3 {
    #[inline]
    fn zero() -> Self {
        Vec3::zeros()
    }
    #[inline]
    fn add_scaled(&mut self, w: f64, x: &Self) {
        self.x += w * x.x;
        self.y += w * x.y;
        self.z += w * x.z;
    }
}

/// A real sparse matrix in CSR form with sorted, unique column indices in each row: a level
/// operator `A^(j)` or the product `A` of `d = A p` (`subdivision-solids-journal.txt` eq 4).
#[derive(Clone, Debug, PartialEq)]
pub struct SparseMatrix {
    nrows: usize,
    ncols: usize,
    row_ptr: Vec<usize>,
    cols: Vec<u32>,
    vals: Vec<f64>,
}

/// Rows per rayon task when applying a matrix in parallel.
pub(crate) const MIN_ROWS_PER_TASK: usize = 2048;

impl SparseMatrix {
    /// A matrix from CSR arrays.
    ///
    /// # Panics
    /// If the arrays are inconsistent: `row_ptr` not of length `nrows + 1`, not non-decreasing,
    /// not ending at `cols.len() == vals.len()`, a column out of range, or columns of a row not
    /// strictly increasing (programmer errors: matrices are produced by this crate).
    #[track_caller]
    pub fn from_csr(
        nrows: usize,
        ncols: usize,
        row_ptr: Vec<usize>,
        cols: Vec<u32>,
        vals: Vec<f64>,
    ) -> Self {
        assert_eq!(row_ptr.len(), nrows + 1, "row_ptr length");
        assert_eq!(row_ptr[0], 0, "row_ptr[0]");
        assert_eq!(*row_ptr.last().unwrap(), cols.len(), "row_ptr end");
        assert_eq!(cols.len(), vals.len(), "cols/vals length");
        for i in 0..nrows {
            let (a, b) = (row_ptr[i], row_ptr[i + 1]);
            assert!(a <= b, "row_ptr decreases at row {i}");
            assert!(
                cols[a..b].windows(2).all(|w| w[0] < w[1]),
                "columns of row {i} not strictly increasing"
            );
            assert!(
                cols[a..b].iter().all(|&c| (c as usize) < ncols),
                "column out of range in row {i}"
            );
        }
        Self {
            nrows,
            ncols,
            row_ptr,
            cols,
            vals,
        }
    }

    /// Builds without the checks of [`SparseMatrix::from_csr`] (crate-internal producers that
    /// guarantee them).
    pub(crate) fn from_csr_unchecked(
        nrows: usize,
        ncols: usize,
        row_ptr: Vec<usize>,
        cols: Vec<u32>,
        vals: Vec<f64>,
    ) -> Self {
        debug_assert_eq!(row_ptr.len(), nrows + 1);
        debug_assert_eq!(*row_ptr.last().unwrap(), cols.len());
        Self {
            nrows,
            ncols,
            row_ptr,
            cols,
            vals,
        }
    }

    /// The identity matrix of size `n`.
    pub fn identity(n: usize) -> Self {
        Self {
            nrows: n,
            ncols: n,
            row_ptr: (0..=n).collect(),
            cols: (0..n as u32).collect(),
            vals: vec![1.0; n],
        }
    }

    /// Number of rows.
    pub fn nrows(&self) -> usize {
        self.nrows
    }

    /// Number of columns.
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.cols.len()
    }

    /// Row pointer array (`nrows + 1` entries).
    pub fn row_ptr(&self) -> &[usize] {
        &self.row_ptr
    }

    /// Column indices of all entries.
    pub fn col_indices(&self) -> &[u32] {
        &self.cols
    }

    /// Values of all entries.
    pub fn values(&self) -> &[f64] {
        &self.vals
    }

    /// Column indices and values of row `i`.
    pub fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let r = self.row_ptr[i]..self.row_ptr[i + 1];
        (&self.cols[r.clone()], &self.vals[r])
    }

    /// Entry `(i, j)` (zero when not stored).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let (c, v) = self.row(i);
        c.binary_search(&(j as u32)).map_or(0.0, |k| v[k])
    }

    /// The sum of each row (1 for every row of a subdivision operator).
    pub fn row_sums(&self) -> Vec<f64> {
        (0..self.nrows)
            .map(|i| self.row(i).1.iter().sum())
            .collect()
    }

    /// `y = A x`, allocating the result.
    ///
    /// # Panics
    /// If `x.len() != ncols`.
    #[track_caller]
    pub fn apply<T: Coord>(&self, x: &[T]) -> Vec<T> {
        let mut y = vec![T::zero(); self.nrows];
        self.apply_into(x, &mut y, Parallelism::Auto);
        y
    }

    /// `y = A x` into a caller-provided slice; rows run on rayon's pool as `par` decides.
    ///
    /// # Panics
    /// If `x.len() != ncols` or `y.len() != nrows`.
    #[track_caller]
    pub fn apply_into<T: Coord>(&self, x: &[T], y: &mut [T], par: Parallelism) {
        assert_eq!(x.len(), self.ncols, "apply: input length");
        assert_eq!(y.len(), self.nrows, "apply: output length");
        each_row_pair(
            y,
            par,
            |i| self.row_dot2(i, |c| x[c]),
            |i| self.row_dot(i, |c| x[c]),
        );
    }

    /// Rows `rows` of `y = A x`, the input read through `x(column)` and each row's value
    /// handed to `out(row, value)`: the kernel of phased programs that split a product by rows
    /// and read or write through index maps (restricted chains).
    ///
    /// # Panics
    /// If `rows` is out of bounds.
    #[inline]
    pub fn apply_rows_with<T: Coord>(
        &self,
        rows: std::ops::Range<usize>,
        x: impl Fn(usize) -> T,
        mut out: impl FnMut(usize, T),
    ) {
        let mut i = rows.start;
        while i + 1 < rows.end {
            let (a, b) = self.row_dot2(i, &x);
            out(i, a);
            out(i + 1, b);
            i += 2;
        }
        if i < rows.end {
            out(i, self.row_dot(i, &x));
        }
    }

    /// The rows listed in `rows` (any order, any subset) of `y = A x`, the input read through
    /// `x(column)`, row `rows[q]`'s value handed to `out(q, value)`: the kernel of phased
    /// programs that give each thread the rows whose inputs it wrote (issue 31). Rows are taken
    /// two at a time, as in [`SparseMatrix::apply_rows_with`]; each value is the same bits as
    /// that row's value there (every row sums its entries in the same order into the same
    /// two partial sums, whichever row it is paired with).
    ///
    /// # Panics
    /// If an entry of `rows` is out of bounds.
    #[inline]
    pub fn apply_row_list_with<T: Coord>(
        &self,
        rows: &[u32],
        x: impl Fn(usize) -> T,
        mut out: impl FnMut(usize, T),
    ) {
        let (pairs, tail) = rows.as_chunks::<2>();
        for (q, &[r0, r1]) in pairs.iter().enumerate() {
            let (a, b) = dot_pair(self.row(r0 as usize), self.row(r1 as usize), |v| v, &x);
            out(2 * q, a);
            out(2 * q + 1, b);
        }
        if let Some(&r) = tail.first() {
            out(rows.len() - 1, self.row_dot(r as usize, &x));
        }
    }

    /// Rows `i` and `i + 1` of `A x` ([`dot_pair`]: the same bits as two
    /// [`SparseMatrix::row_dot`]s).
    #[inline(always)]
    fn row_dot2<T: Coord>(&self, i: usize, x: impl Fn(usize) -> T) -> (T, T) {
        let r0 = self.row_ptr[i]..self.row_ptr[i + 1];
        let r1 = self.row_ptr[i + 1]..self.row_ptr[i + 2];
        dot_pair(
            (&self.cols[r0.clone()], &self.vals[r0]),
            (&self.cols[r1.clone()], &self.vals[r1]),
            |v| v,
            x,
        )
    }

    /// Row `i` of `A x`, `x` read through `x(column)`: two partial sums (even and odd
    /// entries), so that a row is two independent chains of additions rather than one.
    #[inline(always)]
    fn row_dot<T: Coord>(&self, i: usize, x: impl Fn(usize) -> T) -> T {
        let r = self.row_ptr[i]..self.row_ptr[i + 1];
        let (mut a, mut b) = (T::zero(), T::zero());
        let (cols, vals) = (&self.cols[r.clone()], &self.vals[r]);
        let (cp, ct) = cols.as_chunks::<2>();
        let (vp, vt) = vals.as_chunks::<2>();
        for (c, v) in cp.iter().zip(vp) {
            a.add_scaled(v[0], &x(c[0] as usize));
            b.add_scaled(v[1], &x(c[1] as usize));
        }
        if let (Some(&c), Some(&v)) = (ct.first(), vt.first()) {
            a.add_scaled(v, &x(c as usize));
        }
        b.add_scaled(1.0, &a);
        b
    }

    /// `y = A^T x` without forming the transpose, allocating scratch space as needed.
    ///
    /// # Panics
    /// If `x.len() != nrows` or `y.len() != ncols`.
    #[track_caller]
    pub fn apply_transpose<T: Coord>(&self, x: &[T]) -> Vec<T> {
        let mut y = vec![T::zero(); self.ncols];
        self.apply_transpose_into(x, &mut y, &mut Vec::new(), Parallelism::Auto);
        y
    }

    /// `y = A^T x` by scattering the rows of `A` (no transpose is formed): row `i` adds
    /// `a_ik x_i` to `y_k`. The rows are read in storage order and `x` sequentially, so the only
    /// irregular accesses go to `y`, which is the smaller (coarser) side for a subdivision
    /// operator. In parallel, each of `T` rayon tasks scatters a contiguous block of rows into
    /// its own `ncols`-long partial sum in `scratch` (grown to `T * ncols` on first use, then
    /// reused), and the partial sums are added column-parallel.
    ///
    /// # Panics
    /// If `x.len() != nrows` or `y.len() != ncols`.
    #[track_caller]
    pub fn apply_transpose_into<T: Coord>(
        &self,
        x: &[T],
        y: &mut [T],
        scratch: &mut Vec<T>,
        par: Parallelism,
    ) {
        assert_eq!(x.len(), self.nrows, "apply_transpose: input length");
        assert_eq!(y.len(), self.ncols, "apply_transpose: output length");
        let scatter = |rows: std::ops::Range<usize>, acc: &mut [T]| {
            for (i, xi) in rows.clone().zip(&x[rows]) {
                let r = self.row_ptr[i]..self.row_ptr[i + 1];
                for (&c, &v) in self.cols[r.clone()].iter().zip(&self.vals[r]) {
                    acc[c as usize].add_scaled(v, xi);
                }
            }
        };
        let first_row_at = |entry: usize| self.row_ptr.partition_point(|&p| p < entry);
        scatter_rows(
            self.nrows,
            self.nnz(),
            first_row_at,
            y,
            scratch,
            par,
            scatter,
        );
    }

    /// The matrix with its rows reordered: row `i` of the result is row `order[i]` of `self`
    /// (`P A` for the permutation `P`; rows may also be repeated or dropped).
    ///
    /// # Panics
    /// If an entry of `order` is not a row index (a programmer error).
    #[track_caller]
    pub fn select_rows(&self, order: &[u32]) -> SparseMatrix {
        let mut row_ptr = Vec::with_capacity(order.len() + 1);
        row_ptr.push(0);
        let mut cols = Vec::with_capacity(self.nnz());
        let mut vals = Vec::with_capacity(self.nnz());
        for &r in order {
            let (c, v) = self.row(r as usize);
            cols.extend_from_slice(c);
            vals.extend_from_slice(v);
            row_ptr.push(cols.len());
        }
        SparseMatrix {
            nrows: order.len(),
            ncols: self.ncols,
            row_ptr,
            cols,
            vals,
        }
    }

    /// The matrix with its columns renumbered: new column `i` is old column `order[i]` (`A P^T`
    /// for the permutation `P`). The entries of each row are sorted by their new column, so a
    /// row's terms are still summed in column order.
    ///
    /// # Panics
    /// If `order` is not a permutation of the columns (a programmer error).
    #[track_caller]
    pub fn renumber_columns(&self, order: &[u32]) -> SparseMatrix {
        assert_eq!(order.len(), self.ncols, "one new position per column");
        let mut new = vec![u32::MAX; order.len()];
        for (i, &c) in order.iter().enumerate() {
            assert_eq!(new[c as usize], u32::MAX, "column {c} appears twice");
            new[c as usize] = i as u32;
        }
        let mut row_ptr = Vec::with_capacity(self.nrows + 1);
        row_ptr.push(0);
        let mut cols = Vec::with_capacity(self.nnz());
        let mut vals = Vec::with_capacity(self.nnz());
        let mut row: Vec<(u32, f64)> = Vec::new();
        for i in 0..self.nrows {
            let (c, v) = self.row(i);
            row.clear();
            row.extend(c.iter().map(|&c| new[c as usize]).zip(v.iter().copied()));
            row.sort_unstable_by_key(|e| e.0);
            cols.extend(row.iter().map(|e| e.0));
            vals.extend(row.iter().map(|e| e.1));
            row_ptr.push(cols.len());
        }
        SparseMatrix {
            nrows: self.nrows,
            ncols: self.ncols,
            row_ptr,
            cols,
            vals,
        }
    }

    /// The transpose, as a new CSR matrix (a counting sort over columns; rows of the result
    /// stay sorted).
    pub fn transpose(&self) -> SparseMatrix {
        let mut counts = vec![0usize; self.ncols + 1];
        for &c in &self.cols {
            counts[c as usize + 1] += 1;
        }
        for j in 0..self.ncols {
            counts[j + 1] += counts[j];
        }
        let row_ptr = counts.clone();
        let mut cursor = counts;
        let mut cols = vec![0u32; self.nnz()];
        let mut vals = vec![0.0; self.nnz()];
        for i in 0..self.nrows {
            for k in self.row_ptr[i]..self.row_ptr[i + 1] {
                let c = self.cols[k] as usize;
                let dst = cursor[c];
                cols[dst] = i as u32;
                vals[dst] = self.vals[k];
                cursor[c] += 1;
            }
        }
        SparseMatrix::from_csr_unchecked(self.ncols, self.nrows, row_ptr, cols, vals)
    }

    /// The product `self * rhs` (Gustavson's row-by-row algorithm with a dense accumulator).
    ///
    /// # Panics
    /// If `self.ncols() != rhs.nrows()`.
    #[track_caller]
    pub fn mul(&self, rhs: &SparseMatrix) -> SparseMatrix {
        self.mul_with(rhs, |_, v| v)
    }

    /// The product `self * diag(w) * rhs` without forming `diag(w) rhs`: each entry of `rhs`
    /// row `k` is taken as `v * w[k]`, the value a row-scaled copy would hold, so the result is
    /// bit for bit `self.mul(&scaled)` (a Galerkin product `A^T W A` of a large level without
    /// a copy of `A`, issue 31).
    ///
    /// # Panics
    /// If `self.ncols() != rhs.nrows()` or `w.len() != rhs.nrows()`.
    #[track_caller]
    pub fn mul_scaled(&self, w: &[f64], rhs: &SparseMatrix) -> SparseMatrix {
        assert_eq!(w.len(), rhs.nrows, "mul_scaled: weight length");
        self.mul_with(rhs, |k, v| v * w[k])
    }

    /// `self * rhs` with `rhs`'s entry `v` in row `k` read as `value(k, v)`.
    #[track_caller]
    fn mul_with(
        &self,
        rhs: &SparseMatrix,
        value: impl Fn(usize, f64) -> f64 + Sync,
    ) -> SparseMatrix {
        assert_eq!(self.ncols, rhs.nrows, "mul: inner dimensions");
        let n = rhs.ncols;
        let rows: Vec<(Vec<u32>, Vec<f64>)> = (0..self.nrows)
            .into_par_iter()
            .with_min_len(256)
            .map_init(
                || (vec![0.0f64; n], vec![false; n], Vec::<u32>::new()),
                |(acc, seen, touched), i| {
                    let (c, v) = self.row(i);
                    for (&k, &w) in c.iter().zip(v) {
                        let (c2, v2) = rhs.row(k as usize);
                        for (&j, &w2) in c2.iter().zip(v2) {
                            let w2 = value(k as usize, w2);
                            let j = j as usize;
                            if !seen[j] {
                                seen[j] = true;
                                touched.push(j as u32);
                            }
                            acc[j] += w * w2;
                        }
                    }
                    touched.sort_unstable();
                    let mut oc = Vec::with_capacity(touched.len());
                    let mut ov = Vec::with_capacity(touched.len());
                    for &j in touched.iter() {
                        let j = j as usize;
                        if acc[j] != 0.0 {
                            oc.push(j as u32);
                            ov.push(acc[j]);
                        }
                        acc[j] = 0.0;
                        seen[j] = false;
                    }
                    touched.clear();
                    (oc, ov)
                },
            )
            .collect();
        let mut row_ptr = Vec::with_capacity(self.nrows + 1);
        row_ptr.push(0);
        let nnz: usize = rows.iter().map(|r| r.0.len()).sum();
        let mut cols = Vec::with_capacity(nnz);
        let mut vals = Vec::with_capacity(nnz);
        for (c, v) in rows {
            cols.extend_from_slice(&c);
            vals.extend_from_slice(&v);
            row_ptr.push(cols.len());
        }
        SparseMatrix::from_csr_unchecked(self.nrows, n, row_ptr, cols, vals)
    }

    /// The matrix as dense rows (for tests and small examples).
    pub fn to_dense(&self) -> Vec<Vec<f64>> {
        (0..self.nrows)
            .map(|i| {
                let mut r = vec![0.0; self.ncols];
                let (c, v) = self.row(i);
                for (&j, &w) in c.iter().zip(v) {
                    r[j as usize] = w;
                }
                r
            })
            .collect()
    }
}

/// Two rows of `A x` at once, their entries interleaved: row `r`'s entries `(cols, w)` with
/// weights `weight(w)`. Each row sums exactly as the one-row products do (even entries into one
/// partial sum, odd entries into another, the odd tail into the first, then second + first), so
/// each value is the same bits as a one-row product; the two rows give four independent chains
/// of additions instead of two (issue 31: a row of a level operator has about 15 entries, and
/// one row's two chains leave the core waiting on the additions' latency).
#[inline(always)]
pub(crate) fn dot_pair<T: Coord, W: Copy>(
    (c0, w0): (&[u32], &[W]),
    (c1, w1): (&[u32], &[W]),
    weight: impl Fn(W) -> f64,
    x: impl Fn(usize) -> T,
) -> (T, T) {
    let (cp0, ct0) = c0.as_chunks::<2>();
    let (vp0, vt0) = w0.as_chunks::<2>();
    let (cp1, ct1) = c1.as_chunks::<2>();
    let (vp1, vt1) = w1.as_chunks::<2>();
    let (mut a0, mut b0, mut a1, mut b1) = (T::zero(), T::zero(), T::zero(), T::zero());
    let both = cp0.len().min(cp1.len());
    for (((c, v), d), w) in cp0[..both]
        .iter()
        .zip(&vp0[..both])
        .zip(&cp1[..both])
        .zip(&vp1[..both])
    {
        a0.add_scaled(weight(v[0]), &x(c[0] as usize));
        a1.add_scaled(weight(w[0]), &x(d[0] as usize));
        b0.add_scaled(weight(v[1]), &x(c[1] as usize));
        b1.add_scaled(weight(w[1]), &x(d[1] as usize));
    }
    for (c, v) in cp0[both..].iter().zip(&vp0[both..]) {
        a0.add_scaled(weight(v[0]), &x(c[0] as usize));
        b0.add_scaled(weight(v[1]), &x(c[1] as usize));
    }
    for (c, v) in cp1[both..].iter().zip(&vp1[both..]) {
        a1.add_scaled(weight(v[0]), &x(c[0] as usize));
        b1.add_scaled(weight(v[1]), &x(c[1] as usize));
    }
    if let (Some(&c), Some(&v)) = (ct0.first(), vt0.first()) {
        a0.add_scaled(weight(v), &x(c as usize));
    }
    if let (Some(&c), Some(&v)) = (ct1.first(), vt1.first()) {
        a1.add_scaled(weight(v), &x(c as usize));
    }
    b0.add_scaled(1.0, &a0);
    b1.add_scaled(1.0, &a1);
    (b0, b1)
}

/// `y[i] = row i` for every row, two rows at a time: `two(i)` gives rows `i` and `i + 1`
/// (kernels that interleave two rows, [`dot_pair`]), `one(i)` the last row of an odd count.
/// In parallel (tasks of at least
/// [`MIN_ROWS_PER_TASK`] rows) when `par` says so for `y.len()` rows. The kernel of `A x` for
/// every storage of `A` ([`SparseMatrix`], [`crate::CompactMatrix`]); each row's value does not
/// depend on the split or the pairing, so the result is the same bits either way.
pub(crate) fn each_row_pair<T: Send>(
    y: &mut [T],
    par: Parallelism,
    two: impl Fn(usize) -> (T, T) + Sync,
    one: impl Fn(usize) -> T + Sync,
) {
    let pair = |k: usize, ys: &mut [T]| match ys {
        [y0, y1] => (*y0, *y1) = two(2 * k),
        [y0] => *y0 = one(2 * k),
        _ => {}
    };
    if par.is_parallel(y.len()) {
        y.par_chunks_mut(2)
            .enumerate()
            .with_min_len(MIN_ROWS_PER_TASK / 2)
            .for_each(|(k, ys)| pair(k, ys));
    } else {
        y.chunks_mut(2).enumerate().for_each(|(k, ys)| pair(k, ys));
    }
}

/// `y = A^T x` by scattering the rows of `A` (`nrows` rows, `nnz` entries): `scatter(rows,
/// acc)` adds rows `rows`' terms into `acc`. On one thread, straight into the zeroed `y`; in
/// parallel, each of `T` tasks scatters a block of rows of about equal entry counts (the block
/// bounds from `first_row_at(entry)`, the first row whose entries start at or after `entry`)
/// into its own partial sum in `scratch` (grown to `T * y.len()`), and the partial sums are
/// added in task order, column-parallel. Shared by [`SparseMatrix::apply_transpose_into`]
/// and [`crate::CompactMatrix`]'s, so both give the same bits for the same thread count.
pub(crate) fn scatter_rows<T: Coord>(
    nrows: usize,
    nnz: usize,
    first_row_at: impl Fn(usize) -> usize,
    y: &mut [T],
    scratch: &mut Vec<T>,
    par: Parallelism,
    scatter: impl Fn(std::ops::Range<usize>, &mut [T]) + Sync,
) {
    let tasks = rayon::current_num_threads().min(nrows / MIN_ROWS_PER_TASK);
    if !par.is_parallel(nrows) || tasks < 2 {
        y.iter_mut().for_each(|v| *v = T::zero());
        scatter(0..nrows, y);
        return;
    }
    let n = y.len();
    scratch.clear();
    scratch.resize(tasks * n, T::zero());
    // Blocks of equal entry counts (rows differ in length).
    let mut bounds: Vec<usize> = (0..=tasks)
        .map(|t| first_row_at(nnz * t / tasks).min(nrows))
        .collect();
    bounds[tasks] = nrows;
    scratch
        .par_chunks_mut(n)
        .enumerate()
        .for_each(|(t, acc)| scatter(bounds[t]..bounds[t + 1], acc));
    let partials: &[T] = scratch;
    y.par_iter_mut()
        .enumerate()
        .with_min_len(MIN_ROWS_PER_TASK)
        .for_each(|(c, v)| {
            let mut s = partials[c];
            for t in 1..tasks {
                s.add_scaled(1.0, &partials[t * n + c]);
            }
            *v = s;
        });
}
