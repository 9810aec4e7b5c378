//! The chain of level operators: `d = A p = A^(n) ... A^(1) p` without forming the product.
//!
//! `subdivision-solids-journal.txt` section 4.2 builds the data points `d` from the control
//! points `p` level by level, `d^(j+1) = A^(j) d^(j)`, and collects the product
//! `A = A^(n) A^(n-1) ... A^(1)` (eq 4). The equations of motion (journal eqs 7-10) need both `A`
//! (control -> data) and `A^T` (forces on data points -> generalized forces on control points).
//! [`SubdivisionMap`] applies both level by level: each `A^(j)` has about 10-30 entries per row,
//! while the product's rows fill up with every control point of the support, so applying the
//! chain is far cheaper than forming `A` except for small lattices ([`SubdivisionMap::product`]).
//!
//! Fixed control points (journal section 5.2, `d = A1 p1 + A2 p2`) are a column partition of the
//! product; with the chain, apply `A` to `p` with the free entries zeroed and to `p` with the fixed
//! entries zeroed.

use std::sync::OnceLock;

use rayon::prelude::*;
use vclay_core::Parallelism;

use crate::compact::CompactMatrix;
use crate::sparse::{Coord, SparseMatrix};
use crate::tensor::{TensorOperator, TensorWorkspace};

/// The level operators `A^(1) .. A^(n)` of a subdivision hierarchy. Transposes are built only on
/// request ([`SubdivisionMap::transpose`]), or on the first `A^T` product of a small chain
/// ([`SubdivisionMap::GATHER_NNZ`]). After [`SubdivisionMap::compress`], the products read
/// each level's weights as small indices into its distinct values ([`CompactMatrix`]; same
/// bits, fewer bytes). A level given a tensor-product form ([`SubdivisionMap::set_tensor`],
/// [`TensorOperator`]) is applied one axis at a time instead (issue 31).
#[derive(Debug, Default)]
pub struct SubdivisionMap {
    ops: Vec<SparseMatrix>,
    transposes: Vec<OnceLock<SparseMatrix>>,
    /// Compact copies of `ops` used by the products (empty: not compressed; `None` for a
    /// level with too many distinct values).
    compact: Vec<Option<CompactMatrix>>,
    /// Tensor-product forms of levels used by the products instead of the sparse operators
    /// (empty: none; [`SubdivisionMap::set_tensor`]).
    tensor: Vec<Option<TensorOperator>>,
}

impl Clone for SubdivisionMap {
    fn clone(&self) -> Self {
        Self {
            ops: self.ops.clone(),
            transposes: self.transposes.clone(),
            compact: self.compact.clone(),
            tensor: self.tensor.clone(),
        }
    }
}

/// Two reusable buffers for [`SubdivisionMap::apply_into`] and
/// [`SubdivisionMap::apply_transpose_into`], so that repeated applications allocate nothing.
#[derive(Clone, Debug, Default)]
pub struct ChainWorkspace<T> {
    a: Vec<T>,
    b: Vec<T>,
    /// Per-task partial sums of the scattered transpose products.
    partials: Vec<T>,
    /// The intermediate grids of tensor-product levels.
    tensor: TensorWorkspace<T>,
}

impl<T: Coord> ChainWorkspace<T> {
    /// Empty buffers (they grow on first use).
    pub fn new() -> Self {
        Self {
            a: Vec::new(),
            b: Vec::new(),
            partials: Vec::new(),
            tensor: TensorWorkspace::default(),
        }
    }
}

impl SubdivisionMap {
    /// A chain from level operators in application order (`ops[0]` is `A^(1)`).
    ///
    /// # Panics
    /// If consecutive operators do not chain (`ops[j].ncols() != ops[j-1].nrows()`).
    #[track_caller]
    pub fn new(ops: Vec<SparseMatrix>) -> Self {
        for j in 1..ops.len() {
            assert_eq!(
                ops[j].ncols(),
                ops[j - 1].nrows(),
                "level operator {j} does not chain"
            );
        }
        let transposes = ops.iter().map(|_| OnceLock::new()).collect();
        Self {
            ops,
            transposes,
            compact: Vec::new(),
            tensor: Vec::new(),
        }
    }

    /// Appends the operator of one more level.
    ///
    /// # Panics
    /// If it does not chain with the last one.
    #[track_caller]
    pub fn push(&mut self, op: SparseMatrix) {
        if let Some(last) = self.ops.last() {
            assert_eq!(op.ncols(), last.nrows(), "level operator does not chain");
        }
        self.ops.push(op);
        self.transposes.push(OnceLock::new());
        if !self.compact.is_empty() {
            self.compact
                .push(CompactMatrix::new(self.ops.last().expect("just pushed")));
        }
    }

    /// Builds the compact form of every level ([`CompactMatrix`]: weights as `u8` or `u16`
    /// indices into the level's distinct values, `u32` row pointers), which
    /// [`SubdivisionMap::apply_into`] and the scattered [`SubdivisionMap::apply_transpose_into`]
    /// then read instead of the `f64` operators. Same results bit for bit, 5-6 instead of 12
    /// bytes per non-zero per product: meant for large chains, whose products are bound by
    /// memory traffic (issue 31). Levels with more than 65,536 distinct weights stay as they
    /// are, and levels with a tensor form ([`SubdivisionMap::set_tensor`]) get none. Costs 5-6
    /// bytes per non-zero of memory.
    pub fn compress(&mut self) {
        let tensor = &self.tensor;
        self.compact = self
            .ops
            .par_iter()
            .enumerate()
            .map(|(j, op)| match tensor.get(j) {
                // Levels with a tensor form never read their compact form.
                Some(Some(_)) => None,
                _ => CompactMatrix::new(op),
            })
            .collect();
    }

    /// Makes the products ([`SubdivisionMap::apply_into`], [`SubdivisionMap::apply_transpose_into`])
    /// apply level `j` (`A^(j+1)`) through its tensor-product form `t`
    /// ([`TensorOperator::factor`] of [`SubdivisionMap::operator`]`(j)`): about a sixth of the
    /// multiply-adds, results equal to the sparse operator's to rounding (not bit for bit; issue
    /// 31). The operator itself stays (Galerkin products, restrictions, [`SubdivisionMap::product`]).
    ///
    /// # Panics
    /// If `t`'s shape is not the operator's.
    #[track_caller]
    pub fn set_tensor(&mut self, j: usize, t: TensorOperator) {
        assert_eq!(
            (t.nrows(), t.ncols()),
            (self.ops[j].nrows(), self.ops[j].ncols()),
            "tensor form of level {j}"
        );
        self.tensor.resize(self.ops.len(), None);
        self.tensor[j] = Some(t);
        if let Some(c) = self.compact.get_mut(j) {
            *c = None;
        }
    }

    /// The tensor-product form of level `j`, if [`SubdivisionMap::set_tensor`] gave one.
    pub fn tensor(&self, j: usize) -> Option<&TensorOperator> {
        self.tensor.get(j)?.as_ref()
    }

    /// Whether [`SubdivisionMap::compress`] has been called (and the chain not changed since).
    pub fn is_compressed(&self) -> bool {
        !self.compact.is_empty()
    }

    /// The compact form of level `j`, if the chain is compressed and the level could be.
    pub fn compact(&self, j: usize) -> Option<&CompactMatrix> {
        self.compact.get(j)?.as_ref()
    }

    /// Drops the stored transposes (they are built again on the next
    /// [`SubdivisionMap::transpose`]): for large chains, whose `A^T` products scatter through
    /// the operators and never read them, after a Galerkin product has built them.
    pub fn release_transposes(&mut self) {
        for t in &mut self.transposes {
            t.take();
        }
    }

    /// Bytes that the level products of this chain hold: the operators (12 bytes per non-zero,
    /// 8 per row), the stored transposes and the compact forms.
    pub fn bytes(&self) -> usize {
        let full = |a: &SparseMatrix| a.nnz() * 12 + a.nrows() * 8;
        self.ops.iter().map(full).sum::<usize>()
            + self
                .transposes
                .iter()
                .filter_map(OnceLock::get)
                .map(full)
                .sum::<usize>()
            + self
                .compact
                .iter()
                .flatten()
                .map(CompactMatrix::bytes)
                .sum::<usize>()
            + self
                .tensor
                .iter()
                .flatten()
                .map(TensorOperator::bytes)
                .sum::<usize>()
    }

    /// `y = A^(j+1) x` through the compact form where there is one.
    fn apply_level<T: Coord>(
        &self,
        j: usize,
        x: &[T],
        y: &mut [T],
        tw: &mut TensorWorkspace<T>,
        par: Parallelism,
    ) {
        if let Some(t) = self.tensor(j) {
            return t.apply_into(x, y, tw, par);
        }
        match self.compact(j) {
            Some(c) => c.apply_into(x, y, par),
            None => self.ops[j].apply_into(x, y, par),
        }
    }

    /// Number of levels `n`.
    pub fn levels(&self) -> usize {
        self.ops.len()
    }

    /// The operator `A^(j+1)` mapping level `j` to level `j + 1` (`j` from 0).
    pub fn operator(&self, j: usize) -> &SparseMatrix {
        &self.ops[j]
    }

    /// All level operators in application order.
    pub fn operators(&self) -> &[SparseMatrix] {
        &self.ops
    }

    /// Chains with at most this many non-zeros apply `A^T` through stored transposes (see
    /// [`SubdivisionMap::apply_transpose_into`]; measured on the 4^3 cube: 20-35 % faster up to
    /// level 3, 233k non-zeros; no clear gain at level 4, 1.9M). The transposes take as much
    /// memory again as the operators, at most 12 MB at this bound.
    pub const GATHER_NNZ: usize = 1 << 20;

    /// The transpose of [`SubdivisionMap::operator`]`(j)`, built on first use and kept.
    pub fn transpose(&self, j: usize) -> &SparseMatrix {
        self.transposes[j].get_or_init(|| self.ops[j].transpose())
    }

    /// Builds all transposes now (in parallel), for callers that want `A^(j)T` as matrices
    /// ([`SubdivisionMap::apply_transpose_into`] builds them itself for small chains only).
    pub fn prepare_transposes(&self) {
        (0..self.ops.len()).into_par_iter().for_each(|j| {
            self.transpose(j);
        });
    }

    /// Number of control points (columns of `A`), or `None` for an empty chain.
    pub fn control_count(&self) -> Option<usize> {
        self.ops.first().map(|a| a.ncols())
    }

    /// Number of data points (rows of `A`), or `None` for an empty chain.
    pub fn data_count(&self) -> Option<usize> {
        self.ops.last().map(|a| a.nrows())
    }

    /// `d = A p`, allocating. An empty chain is the identity.
    ///
    /// # Panics
    /// If `p` has the wrong length.
    #[track_caller]
    pub fn apply<T: Coord>(&self, p: &[T]) -> Vec<T> {
        let mut out = vec![T::zero(); self.data_count().unwrap_or(p.len())];
        self.apply_into(p, &mut out, &mut ChainWorkspace::new(), Parallelism::Auto);
        out
    }

    /// `out = A p` level by level, using `ws` for the intermediate levels.
    ///
    /// # Panics
    /// If `p` or `out` have the wrong length.
    #[track_caller]
    pub fn apply_into<T: Coord>(
        &self,
        p: &[T],
        out: &mut [T],
        ws: &mut ChainWorkspace<T>,
        par: Parallelism,
    ) {
        let n = self.ops.len();
        if n == 0 {
            out.copy_from_slice(p);
            return;
        }
        chain(
            p,
            out,
            ws,
            n,
            |j| self.ops[j].nrows(),
            |j, x, y, tw| self.apply_level(j, x, y, tw, par),
        );
    }

    /// `g = A^T f` (forces on data points pulled back to control points), allocating.
    ///
    /// # Panics
    /// If `f` has the wrong length.
    #[track_caller]
    pub fn apply_transpose<T: Coord>(&self, f: &[T]) -> Vec<T> {
        let mut out = vec![T::zero(); self.control_count().unwrap_or(f.len())];
        self.apply_transpose_into(f, &mut out, &mut ChainWorkspace::new(), Parallelism::Auto);
        out
    }

    /// `out = A^T f = A^(1)T ... A^(n)T f` level by level. Chains of up to
    /// [`SubdivisionMap::GATHER_NNZ`] non-zeros apply stored transposes (built on first use and
    /// kept, [`SubdivisionMap::transpose`]): each coarse point gathers its sum in registers, and
    /// everything stays in cache at these sizes. Larger chains scatter the rows of `A^(j)`
    /// ([`SparseMatrix::apply_transpose_into`]): the fine-level input is read in order and only
    /// the coarse-level output is accessed irregularly, which is no slower there than gathering
    /// from all over the fine level, and costs no memory for transposes.
    ///
    /// # Panics
    /// If `f` or `out` have the wrong length.
    #[track_caller]
    pub fn apply_transpose_into<T: Coord>(
        &self,
        f: &[T],
        out: &mut [T],
        ws: &mut ChainWorkspace<T>,
        par: Parallelism,
    ) {
        let n = self.ops.len();
        if n == 0 {
            out.copy_from_slice(f);
            return;
        }
        let gather = self.ops.iter().map(SparseMatrix::nnz).sum::<usize>() <= Self::GATHER_NNZ;
        let ChainWorkspace {
            a,
            b,
            partials,
            tensor,
        } = ws;
        let mut cur: &mut Vec<T> = a;
        let mut other: &mut Vec<T> = b;
        let mut other_len = 0;
        for j in 0..n {
            let level = n - 1 - j;
            let m = &self.ops[level];
            let src: &[T] = if j == 0 { f } else { &other[..other_len] };
            // Every product below overwrites its whole output (the scattered ones zero it
            // first), so a buffer is only grown, never cleared.
            let dst: &mut [T] = if j + 1 == n {
                out
            } else {
                grow(cur, m.ncols());
                other_len = m.ncols();
                &mut cur[..m.ncols()]
            };
            if let Some(t) = self.tensor(level) {
                t.apply_transpose_into(src, dst, tensor, par);
            } else if gather {
                self.transpose(level).apply_into(src, dst, par);
            } else if let Some(c) = self.compact(level) {
                c.apply_transpose_into(src, dst, partials, par);
            } else {
                m.apply_transpose_into(src, dst, partials, par);
            }
            if j + 1 < n {
                std::mem::swap(&mut cur, &mut other);
            }
        }
    }

    /// The product `A = A^(n) ... A^(1)` as one matrix (identity-free: `None` for an empty chain).
    ///
    /// Its rows fill with every control point in a data point's support, so this is meant for
    /// small lattices (tests, fixed-region partitions of small models).
    pub fn product(&self) -> Option<SparseMatrix> {
        let mut it = self.ops.iter();
        let first = it.next()?.clone();
        Some(it.fold(first, |acc, a| a.mul(&acc)))
    }
}

/// Applies `n` matrices in sequence: `rows(j)` is the row count of the j-th and
/// `apply(j, x, y)` computes `y = A_j x`.
fn chain<T: Coord>(
    input: &[T],
    out: &mut [T],
    ws: &mut ChainWorkspace<T>,
    n: usize,
    rows: impl Fn(usize) -> usize,
    apply: impl Fn(usize, &[T], &mut [T], &mut TensorWorkspace<T>),
) {
    let ChainWorkspace { a, b, tensor, .. } = ws;
    let mut cur: &mut Vec<T> = a;
    let mut other: &mut Vec<T> = b;
    let mut other_len = 0;
    for j in 0..n {
        let src: &[T] = if j == 0 { input } else { &other[..other_len] };
        if j + 1 == n {
            apply(j, src, out, tensor);
        } else {
            // `apply` overwrites every row: the buffer is only grown, never cleared.
            let r = rows(j);
            grow(cur, r);
            apply(j, src, &mut cur[..r], tensor);
            other_len = r;
            std::mem::swap(&mut cur, &mut other);
        }
    }
}

/// Grows `v` to at least `n` entries (new ones zero); never shrinks it, so that a workspace
/// reused for the levels of a chain is zero-filled once, not at every product (the tensor-product levels' workspaces too).
pub(crate) fn grow<T: Coord>(v: &mut Vec<T>, n: usize) {
    if v.len() < n {
        v.resize(n, T::zero());
    }
}
