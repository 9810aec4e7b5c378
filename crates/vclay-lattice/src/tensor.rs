//! A level operator that is a tensor product of three one-dimensional operators (issue 31).
//!
//! # What
//! Subdividing a structured `cx x cy x cz` grid (every subdivided box; MacCracken-Joy's rules on
//! a regular hexahedral grid are the tricubic B-spline's, and the sharp boundary rules of a box
//! are those of the cubic B-spline curve along each axis) gives a `fx x fy x fz` grid whose
//! level operator, with both levels numbered in grid order (`i + nx (j + ny k)`), is the
//! Kronecker product
//!
//! `A = S_z ⊗ S_y ⊗ S_x`,  `A[(i, j, k), (c, d, e)] = S_x[i, c] S_y[j, d] S_z[k, e]`
//!
//! (`subdivision-solids-journal.txt` section 4.2, eq 4: one factor `A^(j)` of the chain). A
//! row of `A` has up to 27 entries, a row of each `S` up to 3, so applying the factors one
//! axis at a time (`x`, then `y`, then `z`; `A^T` in the reverse order with the transposed
//! factors) costs about a sixth of the multiply-adds of the sparse product, and every pass but
//! the first is a sum of whole grid rows, read and written in order.
//!
//! # How
//! [`TensorOperator::factor`] reads the factors off a given sparse operator (`S_x[i, c]` is the
//! sum of row `(i, 0, 0)`'s entries over columns `(c, *, *)`, which is `S_x[i, c]` when the rows
//! of `S_y` and `S_z` sum to one, as subdivision rows do) and then checks every entry of the
//! operator against the product of the factors (to `1e-15` absolute: the operator's weights are
//! at most 1) and that the product has no entry the operator lacks; any difference and the
//! operator is not a tensor product (`None`).
//!
//! # Limitations
//! The products sum each point's terms in another order than [`crate::SparseMatrix`]'s, so
//! their results agree with it to rounding, not bit for bit (the same bits on any number of
//! threads: each output value is computed by one task in a fixed order). Only whole grids.

use std::ops::Range;

use rayon::prelude::*;
use vclay_core::Parallelism;

use crate::map::grow;
use crate::sparse::{Coord, SparseMatrix};

/// One axis's factor: `rows[i]` lists `(column, weight)` of row `i`.
#[derive(Clone, Debug, PartialEq)]
struct Factor {
    rows: Vec<Vec<(u32, f64)>>,
}

impl Factor {
    /// The transpose of an `nrows x ncols` factor (rows of the result in column order).
    fn transpose(&self, ncols: usize) -> Factor {
        let mut rows = vec![Vec::new(); ncols];
        for (i, r) in self.rows.iter().enumerate() {
            for &(c, w) in r {
                rows[c as usize].push((i as u32, w));
            }
        }
        Factor { rows }
    }

    fn get(&self, i: usize, c: usize) -> f64 {
        self.rows[i]
            .iter()
            .find(|e| e.0 as usize == c)
            .map_or(0.0, |e| e.1)
    }
}

/// A level operator `S_z ⊗ S_y ⊗ S_x` from a `coarse` grid to a `fine` grid, both numbered in
/// grid order (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct TensorOperator {
    coarse: [usize; 3],
    fine: [usize; 3],
    /// `S_x, S_y, S_z`.
    s: [Factor; 3],
    /// Their transposes.
    st: [Factor; 3],
}

/// Buffers of [`TensorOperator`]'s products (two intermediate grids), kept between calls.
#[derive(Clone, Debug)]
pub struct TensorWorkspace<T> {
    a: Vec<T>,
    b: Vec<T>,
}

impl<T> Default for TensorWorkspace<T> {
    fn default() -> Self {
        Self {
            a: Vec::new(),
            b: Vec::new(),
        }
    }
}

/// Tolerance of [`TensorOperator::factor`]'s check of each entry (weights are at most 1).
const FACTOR_TOLERANCE: f64 = 1e-15;

impl TensorOperator {
    /// The factors of `op` as an operator from the `coarse` grid to the `fine` grid (points in
    /// grid order, x fastest), or `None` if `op` is not such a tensor product (module docs).
    pub fn factor(op: &SparseMatrix, coarse: [usize; 3], fine: [usize; 3]) -> Option<Self> {
        let [cx, cy, cz] = coarse;
        let [fx, fy, fz] = fine;
        if op.ncols() != cx * cy * cz || op.nrows() != fx * fy * fz || op.nrows() == 0 {
            return None;
        }
        let col = |c: u32| {
            let c = c as usize;
            [c % cx, (c / cx) % cy, c / (cx * cy)]
        };
        // Factor of axis a from the rows along that axis through the grid's first point.
        let factor = |a: usize| -> Factor {
            let n = fine[a];
            let stride = [1, fx, fx * fy][a];
            let rows = (0..n)
                .map(|i| {
                    let (cols, vals) = op.row(i * stride);
                    let mut sums: Vec<(u32, f64)> = Vec::new();
                    for (&c, &w) in cols.iter().zip(vals) {
                        let t = col(c)[a] as u32;
                        match sums.iter_mut().find(|e| e.0 == t) {
                            Some(e) => e.1 += w,
                            None => sums.push((t, w)),
                        }
                    }
                    sums.retain(|e| e.1 != 0.0);
                    sums.sort_unstable_by_key(|e| e.0);
                    sums
                })
                .collect();
            Factor { rows }
        };
        let s = [factor(0), factor(1), factor(2)];
        // Every entry is the product of the factors, and the product has no other entries.
        let ok = (0..op.nrows()).into_par_iter().all(|r| {
            let (i, j, k) = (r % fx, (r / fx) % fy, r / (fx * fy));
            let (cols, vals) = op.row(r);
            let expected = s[0].rows[i].len() * s[1].rows[j].len() * s[2].rows[k].len();
            cols.len() == expected
                && cols.iter().zip(vals).all(|(&c, &w)| {
                    let [c, d, e] = col(c);
                    let p = s[0].get(i, c) * s[1].get(j, d) * s[2].get(k, e);
                    (p - w).abs() <= FACTOR_TOLERANCE && p != 0.0
                })
        });
        if !ok {
            return None;
        }
        let st = [s[0].transpose(cx), s[1].transpose(cy), s[2].transpose(cz)];
        Some(Self {
            coarse,
            fine,
            s,
            st,
        })
    }

    /// Number of rows (fine points).
    pub fn nrows(&self) -> usize {
        self.fine.iter().product()
    }

    /// Number of columns (coarse points).
    pub fn ncols(&self) -> usize {
        self.coarse.iter().product()
    }

    /// Bytes held (the factors and their transposes).
    pub fn bytes(&self) -> usize {
        self.s
            .iter()
            .chain(&self.st)
            .map(|f| f.rows.iter().map(|r| 24 + 16 * r.len()).sum::<usize>())
            .sum()
    }

    /// Points along x, y and z of the coarse grid (the columns) and of the fine grid (the rows).
    pub fn dims(&self) -> ([usize; 3], [usize; 3]) {
        (self.coarse, self.fine)
    }

    /// Values per z-plane of the two intermediate grids of the plane-range products, `fx cy`
    /// and `fx fy` (each grid has one plane per coarse z-plane): `A x`'s after its x-pass and
    /// after its y-pass, `A^T y`'s after its y^T-pass and after its z^T-pass.
    pub fn intermediate_plane_lens(&self) -> [usize; 2] {
        let [_, cy, _] = self.coarse;
        let [fx, fy, _] = self.fine;
        [fx * cy, fx * fy]
    }

    /// Coarse z-planes `planes` of the x- and y-passes of `y = A x`: `t1` and `t2` receive
    /// those planes of the two intermediate grids ([`TensorOperator::intermediate_plane_lens`]
    /// values each). Each plane reads only the same plane of `x`, so tasks over disjoint plane
    /// ranges are independent; with [`TensorOperator::apply_z_planes`] over all fine planes
    /// this is [`TensorOperator::apply_into`], bit for bit (every value is summed by
    /// the same `line_sum` in the same order).
    ///
    /// # Panics
    /// If `x` is not a coarse grid or `t1`, `t2` do not hold exactly `planes`.
    #[track_caller]
    pub fn apply_xy_planes<T: Coord>(
        &self,
        x: &[T],
        planes: Range<usize>,
        t1: &mut [T],
        t2: &mut [T],
    ) {
        let [cx, cy, _] = self.coarse;
        let [l1, l2] = self.intermediate_plane_lens();
        assert_eq!(x.len(), self.ncols(), "input length");
        assert_eq!(t1.len(), planes.len() * l1, "first intermediate length");
        assert_eq!(t2.len(), planes.len() * l2, "second intermediate length");
        let x = &x[planes.start * cx * cy..planes.end * cx * cy];
        along_rows(&self.s[0], x, cx, t1, self.fine[0], 1, false);
        along_rows(&self.s[1], t1, l1, t2, l2, self.fine[0], false);
    }

    /// Fine z-planes `planes` of `y = A x` (the z-pass): `y` receives those planes, from the
    /// whole second intermediate grid `t2` of [`TensorOperator::apply_xy_planes`].
    ///
    /// # Panics
    /// If `t2` is not a whole intermediate grid or `y` does not hold exactly `planes`.
    #[track_caller]
    pub fn apply_z_planes<T: Coord>(&self, t2: &[T], planes: Range<usize>, y: &mut [T]) {
        let [fx, fy, _] = self.fine;
        assert_eq!(t2.len(), fx * fy * self.coarse[2], "intermediate length");
        assert_eq!(y.len(), planes.len() * fx * fy, "output length");
        for (line, row) in y.chunks_exact_mut(fx * fy).zip(&self.s[2].rows[planes]) {
            line_sum(row, t2, line);
        }
    }

    /// Coarse z-planes `planes` of `x = A^T y`: per plane the z^T-pass (from the fine planes
    /// around it), then the y^T- and x^T-passes within the plane, `u2` and `u1` receiving the
    /// plane's intermediate values (`[fx fy, fx cy]` per plane,
    /// [`TensorOperator::intermediate_plane_lens`]) and `x` the plane's values. Tasks over
    /// disjoint plane ranges are independent; over all planes this is
    /// [`TensorOperator::apply_transpose_into`], bit for bit.
    ///
    /// # Panics
    /// If `y` is not a fine grid or `u2`, `u1`, `x` do not hold exactly `planes`.
    #[track_caller]
    pub fn apply_transpose_planes<T: Coord>(
        &self,
        y: &[T],
        planes: Range<usize>,
        u2: &mut [T],
        u1: &mut [T],
        x: &mut [T],
    ) {
        let [cx, cy, _] = self.coarse;
        let [fx, _, _] = self.fine;
        let [l1, l2] = self.intermediate_plane_lens();
        assert_eq!(y.len(), self.nrows(), "input length");
        assert_eq!(u2.len(), planes.len() * l2, "second intermediate length");
        assert_eq!(u1.len(), planes.len() * l1, "first intermediate length");
        assert_eq!(x.len(), planes.len() * cx * cy, "output length");
        for (line, row) in u2.chunks_exact_mut(l2).zip(&self.st[2].rows[planes]) {
            line_sum(row, y, line);
        }
        along_rows(&self.st[1], u2, l2, u1, l1, fx, false);
        along_rows(&self.st[0], u1, fx, x, cx, 1, false);
    }

    /// `y = A x` (module docs: along x, then y, then z).
    ///
    /// # Panics
    /// If `x` or `y` have the wrong length.
    #[track_caller]
    pub fn apply_into<T: Coord>(
        &self,
        x: &[T],
        y: &mut [T],
        ws: &mut TensorWorkspace<T>,
        par: Parallelism,
    ) {
        assert_eq!(x.len(), self.ncols(), "input length");
        assert_eq!(y.len(), self.nrows(), "output length");
        let [cx, cy, cz] = self.coarse;
        let [fx, fy, _] = self.fine;
        let TensorWorkspace { a, b } = ws;
        grow(a, fx * cy * cz);
        grow(b, fx * fy * cz);
        let (t1, t2) = (&mut a[..fx * cy * cz], &mut b[..fx * fy * cz]);
        let parallel = par.is_parallel_from(self.nrows(), 1 << 16);
        // Along x: row (d, e) of t1 from row (d, e) of x.
        along_rows(&self.s[0], x, cx, t1, fx, 1, parallel);
        // Along y: within each z-plane e, row j from rows d of the plane.
        along_rows(&self.s[1], t1, fx * cy, t2, fx * fy, fx, parallel);
        // Along z: plane k from planes e.
        along_rows(
            &self.s[2],
            t2,
            fx * fy * cz,
            y,
            fx * fy * self.fine[2],
            fx * fy,
            parallel,
        );
    }

    /// `x = A^T y` (along z, then y, then x, with the transposed factors; gathers only).
    ///
    /// # Panics
    /// If `y` or `x` have the wrong length.
    #[track_caller]
    pub fn apply_transpose_into<T: Coord>(
        &self,
        y: &[T],
        x: &mut [T],
        ws: &mut TensorWorkspace<T>,
        par: Parallelism,
    ) {
        assert_eq!(y.len(), self.nrows(), "input length");
        assert_eq!(x.len(), self.ncols(), "output length");
        let [cx, cy, cz] = self.coarse;
        let [fx, fy, fz] = self.fine;
        let TensorWorkspace { a, b } = ws;
        grow(a, fx * fy * cz);
        grow(b, fx * cy * cz);
        let (u2, u1) = (&mut a[..fx * fy * cz], &mut b[..fx * cy * cz]);
        let parallel = par.is_parallel_from(self.nrows(), 1 << 16);
        along_rows(
            &self.st[2],
            y,
            fx * fy * fz,
            u2,
            fx * fy * cz,
            fx * fy,
            parallel,
        );
        along_rows(&self.st[1], u2, fx * fy, u1, fx * cy, fx, parallel);
        along_rows(&self.st[0], u1, fx, x, cx, 1, parallel);
    }
}

/// `line = sum_c w_c src_c` over the `(c, w)` of `row`, where `src_c` is line `c` of `input`
/// (lines of `line.len()` values), summed from zero in the order of `row`; zero for an empty
/// row. Rows of up to five entries (every row of a subdivision factor and of its transpose)
/// write each value once.
#[inline]
fn line_sum<T: Coord>(row: &[(u32, f64)], input: &[T], line: &mut [T]) {
    let inner = line.len();
    let src = |c: u32| &input[c as usize * inner..(c as usize + 1) * inner];
    match *row {
        [(a, wa)] => {
            for (d, x) in line.iter_mut().zip(src(a)) {
                let mut v = T::zero();
                v.add_scaled(wa, x);
                *d = v;
            }
        }
        [(a, wa), (b, wb)] => {
            for ((d, x), y) in line.iter_mut().zip(src(a)).zip(src(b)) {
                let mut v = T::zero();
                v.add_scaled(wa, x);
                v.add_scaled(wb, y);
                *d = v;
            }
        }
        [(a, wa), (b, wb), (c, wc)] => {
            for (((d, x), y), z) in line.iter_mut().zip(src(a)).zip(src(b)).zip(src(c)) {
                let mut v = T::zero();
                v.add_scaled(wa, x);
                v.add_scaled(wb, y);
                v.add_scaled(wc, z);
                *d = v;
            }
        }
        [(a, wa), (b, wb), (c, wc), (e, we)] => {
            for ((((d, x), y), z), u) in line
                .iter_mut()
                .zip(src(a))
                .zip(src(b))
                .zip(src(c))
                .zip(src(e))
            {
                let mut v = T::zero();
                v.add_scaled(wa, x);
                v.add_scaled(wb, y);
                v.add_scaled(wc, z);
                v.add_scaled(we, u);
                *d = v;
            }
        }
        [(a, wa), (b, wb), (c, wc), (e, we), (g, wg)] => {
            for (((((d, x), y), z), u), t) in line
                .iter_mut()
                .zip(src(a))
                .zip(src(b))
                .zip(src(c))
                .zip(src(e))
                .zip(src(g))
            {
                let mut v = T::zero();
                v.add_scaled(wa, x);
                v.add_scaled(wb, y);
                v.add_scaled(wc, z);
                v.add_scaled(we, u);
                v.add_scaled(wg, t);
                *d = v;
            }
        }
        _ => {
            line.fill(T::zero());
            for &(c, w) in row {
                for (d, v) in line.iter_mut().zip(src(c)) {
                    d.add_scaled(w, v);
                }
            }
        }
    }
}

/// Applies factor `s` along one axis: the input is made of blocks of `in_block` values and the
/// output of blocks of `out_block` (one block per position on the slower axes, in order);
/// within a block, a line of the axis is `inner` consecutive values (the faster axes), and
/// output line `i` of a block is `sum_c s[i, c]` input line `c` of the same block.
fn along_rows<T: Coord>(
    s: &Factor,
    input: &[T],
    in_block: usize,
    out: &mut [T],
    out_block: usize,
    inner: usize,
    parallel: bool,
) {
    let blocks = input.len() / in_block;
    let out = &mut out[..blocks * out_block];
    let block = |(o, i): (&mut [T], &[T])| {
        for (line, row) in o.chunks_exact_mut(inner).zip(&s.rows) {
            line_sum(row, i, line);
        }
    };
    if !parallel {
        out.chunks_mut(out_block)
            .zip(input.chunks(in_block))
            .for_each(block);
    } else if blocks == 1 {
        // One block (the slowest axis): tasks take ranges of its output lines.
        let lines = out_block / inner;
        let per = lines
            .div_ceil(4 * rayon::current_num_threads().max(1))
            .max(1);
        out.par_chunks_mut(inner * per)
            .enumerate()
            .for_each(|(t, o)| {
                for (l, line) in o.chunks_exact_mut(inner).enumerate() {
                    line_sum(&s.rows[t * per + l], input, line);
                }
            });
    } else {
        // Several blocks per task when they are short.
        let per = (4096 / out_block.max(1)).max(1);
        out.par_chunks_mut(out_block * per)
            .zip(input.par_chunks(in_block * per))
            .for_each(|(o, i)| {
                o.chunks_mut(out_block)
                    .zip(i.chunks(in_block))
                    .for_each(block)
            });
    }
}
