//! Level operators with their weights as one-byte or two-byte indices into a table of the
//! level's distinct values: the same matrix as a [`SparseMatrix`], in fewer bytes.
//!
//! # What
//! A subdivision level operator `A^(j)` (`subdivision-solids-journal.txt` section 4.2, eq 4)
//! has a handful of distinct weights: its rows are the rules' masks, which depend only on the
//! local topology (the 4^3 cube has 19 distinct weights on every level up to level 5, 15.6
//! million non-zeros in all). [`CompactMatrix`] stores each non-zero as its `u32` column and a
//! `u8` (up to 256 distinct values) or `u16` (up to 65,536) index into the table of distinct
//! values, and the row pointers as `u32`: 5 or 6 bytes per non-zero and 4 per row instead of
//! 12 and 8. A product through it reads a weight as `table[index]`, which is the stored `f64`
//! bit for bit, and sums in the order of [`SparseMatrix`]'s products, so every product is
//! bit-identical to the [`SparseMatrix`] one (tests compare them).
//!
//! # Why
//! The per-step products `d = A p` and `g = A^T f` of a large solid stream the whole chain
//! from memory once each per step; at level 5 they were half of the step's memory traffic
//! (`docs/performance.md`, "Solid step memory traffic", issue 31).
//!
//! # Limitations
//! A matrix with more than 65,536 distinct values, or with `u32::MAX` or more non-zeros, is not
//! compacted ([`CompactMatrix::new`] returns `None`); the chain then keeps using the
//! [`SparseMatrix`].

use std::collections::HashMap;

use vclay_core::Parallelism;

use crate::sparse::{Coord, SparseMatrix, dot_pair, each_row_pair, scatter_rows};

/// An index into a table of weights: `u8` (a 256-entry table) or `u16` (65,536 entries), so
/// that a lookup needs no bounds check.
trait WeightIndex: Copy + Send + Sync {
    /// The table type, an array over every value of the index.
    type Table: ?Sized + Sync;
    /// `table[self]`.
    fn weight(self, table: &Self::Table) -> f64;
}

impl WeightIndex for u8 {
    type Table = [f64; 256];
    #[inline(always)]
    fn weight(self, table: &[f64; 256]) -> f64 {
        table[self as usize]
    }
}

impl WeightIndex for u16 {
    type Table = [f64; 65536];
    #[inline(always)]
    fn weight(self, table: &[f64; 65536]) -> f64 {
        table[self as usize]
    }
}

/// The weight indices and the table they index.
#[derive(Clone, Debug, PartialEq)]
enum Weights {
    /// Up to 256 distinct values.
    U8 {
        idx: Vec<u8>,
        table: Box<[f64; 256]>,
    },
    /// Up to 65,536 distinct values.
    U16 {
        idx: Vec<u16>,
        table: Box<[f64; 65536]>,
    },
}

/// A CSR matrix whose values are indices into a table of its distinct values (module docs):
/// `a_ik = table[index_k]`, bit for bit the values of the [`SparseMatrix`] it was built from.
#[derive(Clone, Debug, PartialEq)]
pub struct CompactMatrix {
    nrows: usize,
    ncols: usize,
    row_ptr: Vec<u32>,
    cols: Vec<u32>,
    weights: Weights,
    /// Number of distinct values (the used part of the table).
    distinct: usize,
}

/// The distinct values of `vals` by bit pattern (`-0.0` and `0.0` stay apart) in order of
/// first appearance, with each one's index; `None` above `max` distinct values.
fn distinct_values(vals: &[f64], max: usize) -> Option<(Vec<f64>, HashMap<u64, u32>)> {
    let mut table: Vec<f64> = Vec::new();
    let mut map: HashMap<u64, u32> = HashMap::new();
    for &v in vals {
        if let std::collections::hash_map::Entry::Vacant(e) = map.entry(v.to_bits()) {
            if table.len() == max {
                return None;
            }
            e.insert(table.len() as u32);
            table.push(v);
        }
    }
    Some((table, map))
}

/// The index of each value of `vals` in `map`, narrowed by `narrow` (`map` has every value).
fn indices<I>(vals: &[f64], map: &HashMap<u64, u32>, narrow: impl Fn(u32) -> I) -> Vec<I> {
    let mut last: Option<(u64, u32)> = None;
    vals.iter()
        .map(|v| {
            let bits = v.to_bits();
            let i = match last {
                Some((b, i)) if b == bits => i,
                _ => map[&bits],
            };
            last = Some((bits, i));
            narrow(i)
        })
        .collect()
}

impl CompactMatrix {
    /// `a` with its values as indices into its distinct values (`u8` indices for up to 256
    /// distinct values, `u16` for up to 65,536); `None` for more distinct values or for
    /// `u32::MAX` non-zeros or more.
    pub fn new(a: &SparseMatrix) -> Option<Self> {
        if u32::try_from(a.nnz()).is_err() {
            return None;
        }
        let (table, map) = distinct_values(a.values(), 1 << 16)?;
        let distinct = table.len();
        let weights = if distinct <= 256 {
            let mut t = Box::new([0.0; 256]);
            t[..distinct].copy_from_slice(&table);
            Weights::U8 {
                idx: indices(a.values(), &map, |i| i as u8),
                table: t,
            }
        } else {
            let mut t: Box<[f64; 65536]> = vec![0.0; 65536]
                .into_boxed_slice()
                .try_into()
                .expect("65,536 entries");
            t[..distinct].copy_from_slice(&table);
            Weights::U16 {
                idx: indices(a.values(), &map, |i| i as u16),
                table: t,
            }
        };
        Some(Self {
            nrows: a.nrows(),
            ncols: a.ncols(),
            row_ptr: a.row_ptr().iter().map(|&p| p as u32).collect(),
            cols: a.col_indices().to_vec(),
            weights,
            distinct,
        })
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

    /// Number of distinct values (entries of the table in use).
    pub fn distinct_values(&self) -> usize {
        self.distinct
    }

    /// Bytes of the arrays a product reads: row pointers, columns, indices and the used part
    /// of the table.
    pub fn bytes(&self) -> usize {
        let per = match self.weights {
            Weights::U8 { .. } => 1,
            Weights::U16 { .. } => 2,
        };
        self.row_ptr.len() * 4 + self.cols.len() * (4 + per) + self.distinct * 8
    }

    /// The matrix as a [`SparseMatrix`] (the values looked up; for tests and rebuilding).
    pub fn to_sparse(&self) -> SparseMatrix {
        let vals: Vec<f64> = match &self.weights {
            Weights::U8 { idx, table } => idx.iter().map(|&i| i.weight(table)).collect(),
            Weights::U16 { idx, table } => idx.iter().map(|&i| i.weight(table)).collect(),
        };
        SparseMatrix::from_csr_unchecked(
            self.nrows,
            self.ncols,
            self.row_ptr.iter().map(|&p| p as usize).collect(),
            self.cols.clone(),
            vals,
        )
    }

    /// `y = A x`, rows on rayon's pool as `par` decides: the same sums in the same order as
    /// [`SparseMatrix::apply_into`], so the same bits.
    ///
    /// # Panics
    /// If `x.len() != ncols` or `y.len() != nrows`.
    #[track_caller]
    pub fn apply_into<T: Coord>(&self, x: &[T], y: &mut [T], par: Parallelism) {
        assert_eq!(x.len(), self.ncols, "apply: input length");
        assert_eq!(y.len(), self.nrows, "apply: output length");
        match &self.weights {
            Weights::U8 { idx, table } => self.apply_with(idx, &**table, x, y, par),
            Weights::U16 { idx, table } => self.apply_with(idx, &**table, x, y, par),
        }
    }

    fn apply_with<T: Coord, I: WeightIndex>(
        &self,
        idx: &[I],
        table: &I::Table,
        x: &[T],
        y: &mut [T],
        par: Parallelism,
    ) {
        each_row_pair(
            y,
            par,
            |i| self.row_dot2(i, idx, table, |c| x[c]),
            |i| self.row_dot(i, idx, table, |c| x[c]),
        );
    }

    /// Rows `i` and `i + 1` of `A x` ([`dot_pair`]: the same bits as two
    /// [`CompactMatrix::row_dot`]s).
    #[inline(always)]
    fn row_dot2<T: Coord, I: WeightIndex>(
        &self,
        i: usize,
        idx: &[I],
        table: &I::Table,
        x: impl Fn(usize) -> T,
    ) -> (T, T) {
        let r0 = self.row_ptr[i] as usize..self.row_ptr[i + 1] as usize;
        let r1 = self.row_ptr[i + 1] as usize..self.row_ptr[i + 2] as usize;
        dot_pair(
            (&self.cols[r0.clone()], &idx[r0]),
            (&self.cols[r1.clone()], &idx[r1]),
            |v| v.weight(table),
            x,
        )
    }

    /// Rows `rows` of `y = A x`, as [`SparseMatrix::apply_rows_with`] (same bits).
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
        match &self.weights {
            Weights::U8 { idx, table } => {
                for i in rows {
                    out(i, self.row_dot(i, idx, &**table, &x));
                }
            }
            Weights::U16 { idx, table } => {
                for i in rows {
                    out(i, self.row_dot(i, idx, &**table, &x));
                }
            }
        }
    }

    /// Row `i` of `A x`: two partial sums (even and odd entries), then their sum, exactly as
    /// `SparseMatrix`'s row product.
    #[inline(always)]
    fn row_dot<T: Coord, I: WeightIndex>(
        &self,
        i: usize,
        idx: &[I],
        table: &I::Table,
        x: impl Fn(usize) -> T,
    ) -> T {
        let r = self.row_ptr[i] as usize..self.row_ptr[i + 1] as usize;
        let (mut a, mut b) = (T::zero(), T::zero());
        let (cols, ids) = (&self.cols[r.clone()], &idx[r]);
        let (cp, ct) = cols.as_chunks::<2>();
        let (vp, vt) = ids.as_chunks::<2>();
        for (c, v) in cp.iter().zip(vp) {
            a.add_scaled(v[0].weight(table), &x(c[0] as usize));
            b.add_scaled(v[1].weight(table), &x(c[1] as usize));
        }
        if let (Some(&c), Some(&v)) = (ct.first(), vt.first()) {
            a.add_scaled(v.weight(table), &x(c as usize));
        }
        b.add_scaled(1.0, &a);
        b
    }

    /// `y = A^T x` by scattering the rows, as [`SparseMatrix::apply_transpose_into`] (the same
    /// row blocks per task and the same order of additions, so the same bits).
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
        match &self.weights {
            Weights::U8 { idx, table } => {
                self.apply_transpose_with(idx, &**table, x, y, scratch, par)
            }
            Weights::U16 { idx, table } => {
                self.apply_transpose_with(idx, &**table, x, y, scratch, par)
            }
        }
    }

    fn apply_transpose_with<T: Coord, I: WeightIndex>(
        &self,
        idx: &[I],
        table: &I::Table,
        x: &[T],
        y: &mut [T],
        scratch: &mut Vec<T>,
        par: Parallelism,
    ) {
        let scatter = |rows: std::ops::Range<usize>, acc: &mut [T]| {
            for (i, xi) in rows.clone().zip(&x[rows]) {
                let r = self.row_ptr[i] as usize..self.row_ptr[i + 1] as usize;
                for (&c, &v) in self.cols[r.clone()].iter().zip(&idx[r]) {
                    acc[c as usize].add_scaled(v.weight(table), xi);
                }
            }
        };
        // The same blocks and order of sums as `SparseMatrix::apply_transpose_into`.
        let first_row_at = |entry: usize| self.row_ptr.partition_point(|&p| (p as usize) < entry);
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
}
