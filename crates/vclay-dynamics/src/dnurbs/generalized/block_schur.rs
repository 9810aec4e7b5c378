//! The step matrix of a homogeneous geometry split into its shared coordinate block and the
//! rest, solved through a Schur complement on the rest (issues 27/31).
//!
//! ## Structure
//! With the coordinates `p = [..., p_i, w_i, ...]` of `d-nurbs.txt` eq (4) (a control point's
//! `x, y, z`, then its weight), the Jacobian of eqs (5)-(6) and (13) is
//! `J = [..., R_i I3, w_i, ...]`: a control point's three position columns are the same scalar
//! `R_i` times the identity (and so are their parametric derivatives `R^a_i I3`). Every term of
//! the step matrix of eq (18), `2M + dt D + 2 dt^2 K` with `M`, `D` of eq (16) and `K` of eq
//! (17) (and the springs' `k J^T J` of eq (19)), is a sum of `c J^a^T J^a`, whose entry between
//! two position columns is `c R^a_i R^a_j I3`. Ordering the free coordinates as the control
//! points whose `x, y, z` are all free (`kron`, component-major in the solves) and the others
//! (`rest`: the weights and the free coordinates of partly held control points):
//!
//! ```text
//! A = [ S (x) I3   B ]      S_ij = sum_q sum_a c R^a_i R^a_j   (one scalar block for x, y, z)
//!     [ B^T        C ]      B: position-rest coupling, C: rest-rest block (+ weight diagonal)
//! ```
//!
//! The intrinsic weight inertia and the weight penalty add to `C`'s diagonal only. Solving
//! `A [u; w] = [f; g]`: `u = (S^-1 (x) I3)(f - B w)` and
//! `Sigma w = g - B^T (S^-1 (x) I3) f` with the Schur complement
//! `Sigma = C - B^T (S^-1 (x) I3) B`, which is dense (the weights couple through every
//! position). So `Sigma` is never formed: `S` (one control point per row, a sixteenth of the
//! full matrix's entries) and `C` are factored by sparse Cholesky and `Sigma w = g'` is solved by
//! conjugate gradients preconditioned with `C^-1`, each iteration one three-column solve with
//! `S`'s factor, one product with `B` and `B^T`, one with `C` and one solve with `C`'s factor.
//!
//! The blocks are summed straight from each element's Gram products (`[bb | bv]` and `vv`, `nb
//! (nb + 3 nv) + nv^2` values: `S` from `bb`'s lower triangle, `B` from `bv`, `C` from `vv` and
//! `bv`'s partly held points; the dense `nd x nd` element matrix, 4,096 values against 1,280
//! for a bicubic element, is not written on this path), on two threads over two bands of
//! entries, each entry receiving its elements' terms in element order and then the point
//! forces': the values of the CSR sum to the last bit, without summing the other two thirds of
//! the position block or `B^T` (the dense element matrices and the CSR values are written only
//! when the step falls back to the full factorization).
//!
//! ## Exactness
//! Not the same bits as the full factorization: the result of an iterative solve. The CG stops
//! at `|r| <= tolerance |b|` with `r` the Schur residual, which is the residual of the full
//! system (its position rows are solved exactly by the back-substitution), so a step's error is
//! that of the full solve with this residual; the step reports it as the CG paths report
//! theirs. [`BLOCK_SCHUR_TOLERANCE`] and the comparison against the full factorization in
//! `tests/generalized.rs` state the bound. A solve that does not reach the tolerance in
//! [`BlockSchur::max_iterations`] leaves the step to the full factorization.
//!
//! ## Limitations
//! Taken only when the structure holds, which is checked once per set of fixed coordinates,
//! not assumed: a homogeneous `(x, y, z, w)` layout, every element's position columns in `R I3`
//! blocks of whole control points (a geometry with general columns on positions, such as the
//! swung surface, keeps the full factorization), and on that step's summed matrix the `x`, `y`
//! and `z` blocks of `S` equal to the last bit and the entries between components zero (the
//! later steps' element matrices have the same shapes, written by the same `Gram` code, so
//! they keep it). Every step checks that the point forces' blocks keep it and that no diagonal
//! term falls on a position.
//!
//! ## Threads
//! The sums use two rayon threads (above). The factorizations of `S` and `C` (about the same
//! size, about 1 ms each on the 32 x 32 sheet) run side by side, and each CG iteration is
//! split over [`vclay_core::team`]'s persistent team (a few microseconds a barrier, where
//! `rayon::join` costs more per call): `B d` in two bands of control points, then the
//! three-column solve with `S`'s factor beside `C d`, then `B^T t` in two bands of rows (a
//! gather by rows, in the scatter's order), then the serial rest (the solve with `C`'s
//! factor, the dot products). Every value is computed in the same order on one thread or two:
//! the same bits as the serial solve. The `S` solve (about a third of an iteration) and the
//! `C` solve (about a fifth) stay whole: splitting the `S` solve's three columns over the two
//! threads changes the bits (faer's kernels sum differently for one, two and three columns)
//! and costs nearly as much for two columns as for three. The helper spins while the caller
//! runs the serial parts, so a step costs more CPU time than wall time saved; on a loaded
//! host the spinning competes with the other processes.

use super::{CsrPattern, ElementWork, Scratch, SolverStats, gram_index};
use faer::sparse::linalg::cholesky::SymbolicCholesky;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use vclay_core::team::{SharedSlice, TaskFn, run_phases};

/// Default relative residual of the block-Schur solve ([`BlockSchur::tolerance`]): `1e-12`,
/// two orders below the CG solver's [`super::GENERALIZED_CG_TOLERANCE`]; measured on the 10 x 10
/// benchmark sheet over 100 steps, the trajectory stays within `1e-12` of the model size of
/// the full factorization's (`docs/performance.md`, fourth pass).
pub const BLOCK_SCHUR_TOLERANCE: f64 = 1e-12;

/// Default iteration cap of the block-Schur solve ([`BlockSchur::max_iterations`]): the 32 x 32
/// benchmark sheet (`dnurbs_dynamic_weights 32 --uniform --schur`) takes about 11 a step, the
/// studio's free 32 x 32 sheet pulled by a rope 16-17.
pub const BLOCK_SCHUR_ITERATIONS: usize = 60;

/// Default [`BlockSchur::max_constraint_rows`]: `2` (one normal constraint). Each constraint
/// row is a CG run on the split path but two triangular solves with a full factor; on the
/// 32 x 32 sheet one run is about as much as the split saves on the factorization (about 9 ms
/// of CG against about 20 ms saved), so from a point constraint (3 rows) on the full
/// factorization is the faster one.
pub const BLOCK_SCHUR_CONSTRAINT_ROWS: usize = 2;

/// Settings of the block-Schur solve of [`super::GeneralizedDnurbs::block_schur`] (module docs
/// of `generalized/block_schur.rs`): the step matrix `[[S (x) I3, B], [B^T, C]]` solved with
/// sparse factors of `S` and `C` and conjugate gradients on the Schur complement
/// `C - B^T (S^-1 (x) I3) B` (`d-nurbs.txt` eqs (6), (13), (16)-(18)).
///
/// It pays where the full factorization dominates a step (the 32 x 32 sheet: about 27 % less
/// CPU time a step). Every further solve of a step (one per constraint row, the Newton
/// projections) is a CG run here but only two triangular solves with a full factor, so on
/// small constrained models it is slower: the Fig 8 sharp corner (7,614 quadrature points,
/// normal constraints) took 463 ms for 30 steps against 350 ms with the full factorization.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlockSchur {
    /// Relative residual `|b - A x| / |b|` at which the iterations stop (default
    /// [`BLOCK_SCHUR_TOLERANCE`]).
    pub tolerance: f64,
    /// Iteration cap (default [`BLOCK_SCHUR_ITERATIONS`]); a solve that does not reach the
    /// tolerance falls back to the full factorization for that step. The iterations run as one
    /// phased program of seven tasks an iteration (module docs, "Threads"), so a cap above
    /// `vclay_core::team::MAX_TASKS / 7` (146) runs them on the calling thread alone: the same
    /// bits, without the second core.
    pub max_iterations: usize,
    /// Steps with more constraint rows than this (point constraints 3, normal constraints 2,
    /// ties 1 each) use the full factorization (default [`BLOCK_SCHUR_CONSTRAINT_ROWS`];
    /// `usize::MAX`: always split).
    pub max_constraint_rows: usize,
}

impl Default for BlockSchur {
    fn default() -> Self {
        Self {
            tolerance: BLOCK_SCHUR_TOLERANCE,
            max_iterations: BLOCK_SCHUR_ITERATIONS,
            max_constraint_rows: BLOCK_SCHUR_CONSTRAINT_ROWS,
        }
    }
}

/// The layout of the blocks `S` (lower triangle), `B` and `C`, where each element's entries
/// go, and the symbolic factorizations of `S` and `C`; built once per set of fixed coordinates
/// (per [`CsrPattern`]).
#[derive(Debug)]
pub(super) struct SchurPattern {
    /// Free control points of `S`: the coordinate of each one's `x` (its `y`, `z` follow).
    kron: Vec<usize>,
    /// Per control point, its index in `kron` (`u32::MAX`: not in `S`).
    kron_of: Vec<u32>,
    /// The other free coordinates, in order (`C`'s rows).
    rest: Vec<usize>,
    /// Per coordinate, its index in `rest` (`u32::MAX`: not in `C`).
    rest_of: Vec<u32>,
    /// `S`'s lower triangle, column by column (the diagonal first).
    s_col_ptr: Vec<usize>,
    s_row_idx: Vec<usize>,
    s_symbolic: SymbolicCholesky<usize>,
    /// `B` by control point: entries `b_ptr[i]..b_ptr[i + 1]` with their rest index; each
    /// entry holds the `x`, `y`, `z` rows' values.
    b_ptr: Vec<usize>,
    b_col: Vec<u32>,
    /// `B^T` by rest rows: entries `bt_ptr[r]..bt_ptr[r + 1]`, each `B`'s entry index, in
    /// ascending control points (the order in which the scatter by control points would
    /// subtract them); rows `..bt_half` and `bt_half..` hold about half the entries each.
    bt_ptr: Vec<usize>,
    bt_src: Vec<u32>,
    /// Per entry of `bt_src`, its control point (index in `kron`).
    bt_point: Vec<u32>,
    bt_half: usize,
    /// Control points `..b_half` and `b_half..` hold about half of `B`'s entries each.
    b_half: usize,
    /// `C` by rows (all entries); `c_diag[r]`: the diagonal's entry.
    c_ptr: Vec<usize>,
    c_col: Vec<u32>,
    c_diag: Vec<usize>,
    /// `C`'s lower triangle as CSC (the diagonal first), each entry's index in `C`'s rows.
    cl_col_ptr: Vec<usize>,
    cl_row_idx: Vec<usize>,
    cl_src: Vec<usize>,
    c_symbolic: SymbolicCholesky<usize>,
    /// Per element, `(entry of its Gram products, slot)` (the products `[bb | bv]`, `vv` of
    /// `d-nurbs.txt` eqs (16)-(17) per element, positions in `gram_index`; structural zeros
    /// left out): the slots are `S`'s lower entries, then
    /// `B`'s (three per entry), then `C`'s rows ([`Self::slot`]), in the element's row order;
    /// `maps[0]` for the slots below `half`, `maps[1]` for the others (summed on two threads,
    /// each slot still in element order), with about as many entries each.
    maps: [Vec<Vec<[u32; 2]>>; 2],
    half: usize,
    /// The last steps' point forces' `(columns, where each entry goes)`, per point force in
    /// order ([`Self::point_map`]): a rope's block keeps its columns while its material point
    /// stays in one element, so the lookups of [`Self::slot`] are made once.
    point_maps: std::sync::Mutex<Vec<PointMap>>,
}

/// A point force's columns and where each entry of its block is summed
/// ([`SchurPattern::point_map`]; `None`: the block breaks the structure).
type PointMap = (Vec<usize>, Option<Vec<[u32; 2]>>);

/// Where an entry `(i, j)` of an element matrix is summed ([`SchurPattern::slot`]).
enum Slot {
    /// Not read: a fixed coordinate, the `y` and `z` rows of `S` (equal to the `x` row), `S`'s
    /// upper triangle, `B^T`, the zeros between components.
    Skip,
    /// This slot of the summed values.
    At(usize),
    /// In a block whose layout lacks it (the caller takes the full factorization).
    Missing,
}

/// The CSR position of entry `(i, j)`.
fn position(pattern: &CsrPattern, i: usize, j: usize) -> Option<usize> {
    let (a, b) = (pattern.row_ptr[i], pattern.row_ptr[i + 1]);
    let k = pattern.cols[a..b].binary_search(&j).ok()?;
    Some(a + k)
}

fn symbolic(m: usize, col_ptr: &[usize], row_idx: &[usize]) -> Option<SymbolicCholesky<usize>> {
    let sym = faer::sparse::SymbolicSparseColMatRef::new_checked(m, m, col_ptr, None, row_idx);
    // Approximate minimum degree, faer's defaults (as `DirectPattern`).
    faer::sparse::linalg::cholesky::factorize_symbolic_cholesky(
        sym,
        faer::Side::Lower,
        Default::default(),
        Default::default(),
    )
    .ok()
}

impl SchurPattern {
    /// The split of `pattern`'s free coordinates, or `None` when the structure does not hold
    /// (module docs): `homogeneous` says the layout is `(x, y, z, w)` per control point;
    /// `works` are the elements the pattern was built from and `values` their summed matrix
    /// with the point forces (the `x`, `y`, `z` blocks of `S` are checked equal and the
    /// entries between components zero, once, here).
    pub(super) fn new(
        pattern: &CsrPattern,
        fixed: &[bool],
        homogeneous: bool,
        works: &[ElementWork],
        values: &[f64],
    ) -> Option<Self> {
        let n = fixed.len();
        if !homogeneous || !n.is_multiple_of(4) || n == 0 {
            return None;
        }
        let nc = n / 4;
        let mut shared: Vec<bool> = (0..nc).map(|c| (0..3).all(|k| !fixed[4 * c + k])).collect();
        for w in works {
            if !blocks_are_points(w) {
                return None;
            }
            // A general column on a position: that control point is not in `S`.
            let nb = w.shape.0;
            for &i in &w.dofs[3 * nb..] {
                if i % 4 != 3 {
                    shared[i / 4] = false;
                }
            }
        }
        let kron: Vec<usize> = (0..nc).filter(|&c| shared[c]).map(|c| 4 * c).collect();
        if kron.is_empty() {
            return None;
        }
        let mut kron_of = vec![u32::MAX; nc];
        for (k, &x) in kron.iter().enumerate() {
            kron_of[x / 4] = k as u32;
        }
        let rest: Vec<usize> = (0..n)
            .filter(|&i| !fixed[i] && (i % 4 == 3 || !shared[i / 4]))
            .collect();
        let mut rest_of = vec![u32::MAX; n];
        for (r, &i) in rest.iter().enumerate() {
            rest_of[i] = r as u32;
        }
        // S (lower) and B, from the x rows.
        let value = |i: usize, j: usize| position(pattern, i, j).map(|p| values[p]);
        let (mut s_col_ptr, mut s_row_idx) = (vec![0], Vec::new());
        let (mut b_ptr, mut b_col) = (vec![0], Vec::new());
        for (j, &x) in kron.iter().enumerate() {
            for p in pattern.row_ptr[x]..pattern.row_ptr[x + 1] {
                let q = pattern.cols[p];
                if fixed[q] {
                    continue;
                }
                if rest_of[q] != u32::MAX {
                    b_col.push(rest_of[q]);
                    continue;
                }
                let (c, k) = (q / 4, q % 4);
                let i = kron_of[c] as usize;
                if k != 0 || i < j {
                    continue;
                }
                let v = value(x, q)?;
                for k in 1..3 {
                    if value(x + k, q + k)?.to_bits() != v.to_bits() {
                        return None;
                    }
                }
                // Between different components: structural zeros (or absent).
                for (a, b) in [(0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)] {
                    if value(x + a, q + b).is_some_and(|z| z != 0.0) {
                        return None;
                    }
                }
                s_row_idx.push(i);
            }
            s_col_ptr.push(s_row_idx.len());
            b_ptr.push(b_col.len());
        }
        // The diagonal comes first in each column (rows ascending, all >= the column).
        let ns = kron.len();
        if (0..ns).any(|j| s_col_ptr[j] == s_col_ptr[j + 1] || s_row_idx[s_col_ptr[j]] != j) {
            return None;
        }
        // C, all rows, and its lower triangle.
        let nr = rest.len();
        let (mut c_ptr, mut c_col) = (vec![0], Vec::new());
        let mut c_diag = vec![usize::MAX; nr];
        for (r, &i) in rest.iter().enumerate() {
            for p in pattern.row_ptr[i]..pattern.row_ptr[i + 1] {
                let t = rest_of[pattern.cols[p]];
                if t == u32::MAX {
                    continue;
                }
                if t as usize == r {
                    c_diag[r] = c_col.len();
                }
                c_col.push(t);
            }
            c_ptr.push(c_col.len());
        }
        if c_diag.contains(&usize::MAX) {
            return None;
        }
        let (mut cl_col_ptr, mut cl_row_idx, mut cl_src) = (vec![0], Vec::new(), Vec::new());
        for r in 0..nr {
            for e in c_ptr[r]..c_ptr[r + 1] {
                if c_col[e] as usize >= r {
                    cl_row_idx.push(c_col[e] as usize);
                    cl_src.push(e);
                }
            }
            cl_col_ptr.push(cl_row_idx.len());
        }
        // B^T by rows (a counting sort of B's entries by rest index, control points ascending).
        let mut bt_ptr = vec![0usize; nr + 1];
        for &r in &b_col {
            bt_ptr[r as usize + 1] += 1;
        }
        for r in 0..nr {
            bt_ptr[r + 1] += bt_ptr[r];
        }
        let mut next = bt_ptr.clone();
        let mut bt_src = vec![0u32; b_col.len()];
        let mut bt_point = vec![0u32; b_col.len()];
        for i in 0..ns {
            for e in b_ptr[i]..b_ptr[i + 1] {
                let r = b_col[e] as usize;
                bt_src[next[r]] = u32::try_from(e).ok()?;
                bt_point[next[r]] = u32::try_from(i).ok()?;
                next[r] += 1;
            }
        }
        let b_half = b_ptr.partition_point(|&k| 2 * k < b_col.len()).min(ns);
        let bt_half = bt_ptr.partition_point(|&k| 2 * k < b_col.len()).min(nr);
        let s_symbolic = symbolic(ns, &s_col_ptr, &s_row_idx)?;
        let c_symbolic = symbolic(nr, &cl_col_ptr, &cl_row_idx)?;
        let mut split = Self {
            kron,
            kron_of,
            rest,
            rest_of,
            s_col_ptr,
            s_row_idx,
            s_symbolic,
            bt_ptr,
            bt_src,
            bt_point,
            bt_half,
            b_half,
            b_ptr,
            b_col,
            c_ptr,
            c_col,
            c_diag,
            cl_col_ptr,
            cl_row_idx,
            cl_src,
            c_symbolic,
            maps: [Vec::new(), Vec::new()],
            half: 0,
            point_maps: std::sync::Mutex::new(Vec::new()),
        };
        let mut maps = Vec::with_capacity(works.len());
        let mut per_slot = vec![0usize; split.slots()];
        for w in works {
            let mut map = Vec::new();
            for (a, &i) in w.dofs.iter().enumerate() {
                for (b, &j) in w.dofs.iter().enumerate() {
                    match split.slot(fixed, i, j) {
                        Slot::Skip => {}
                        Slot::At(d) => {
                            // A structural zero adds nothing (a sum from +0 never is -0).
                            let Some(g) = gram_index(w.shape, a, b) else {
                                continue;
                            };
                            per_slot[d] += 1;
                            map.push([u32::try_from(g).ok()?, u32::try_from(d).ok()?]);
                        }
                        Slot::Missing => return None,
                    }
                }
            }
            maps.push(map);
        }
        let total: usize = per_slot.iter().sum();
        let mut seen = 0;
        split.half = per_slot
            .iter()
            .position(|&k| {
                seen += k;
                2 * seen >= total
            })
            .map_or(0, |d| d + 1);
        let half = split.half as u32;
        split.maps = [
            maps.iter()
                .map(|m| m.iter().copied().filter(|e| e[1] < half).collect())
                .collect(),
            maps.iter()
                .map(|m| {
                    m.iter()
                        .filter(|e| e[1] >= half)
                        .map(|&[a, d]| [a, d - half])
                        .collect()
                })
                .collect(),
        ];
        Some(split)
    }

    /// Number of summed values: `S`'s lower entries, three per entry of `B`, `C`'s entries.
    fn slots(&self) -> usize {
        self.s_row_idx.len() + 3 * self.b_col.len() + self.c_col.len()
    }

    /// Where entry `(i, j)` of an element matrix is summed. The entries read are those a
    /// gather from the summed CSR matrix would read: `S`'s lower entry `(row k, column l)`,
    /// `k >= l`, from the `x` row of control point `l` and the `x` column of `k`; `B` from the
    /// position rows; `C` from the rest rows.
    fn slot(&self, fixed: &[bool], i: usize, j: usize) -> Slot {
        if fixed[i] || fixed[j] {
            return Slot::Skip;
        }
        let find = |range: std::ops::Range<usize>, list: &[u32], key: u32| {
            list[range.clone()]
                .binary_search(&key)
                .map_or(Slot::Missing, |k| Slot::At(range.start + k))
        };
        let (ci, ki) = (i / 4, i % 4);
        let si = self.kron_of[ci];
        let ns_lower = self.s_row_idx.len();
        if si != u32::MAX && ki < 3 {
            let si = si as usize;
            let rj = self.rest_of[j];
            if rj != u32::MAX {
                return match find(self.b_ptr[si]..self.b_ptr[si + 1], &self.b_col, rj) {
                    Slot::At(e) => Slot::At(ns_lower + 3 * e + ki),
                    other => other,
                };
            }
            let sj = self.kron_of[j / 4];
            if ki != 0 || !j.is_multiple_of(4) || sj == u32::MAX || (sj as usize) < si {
                return Slot::Skip;
            }
            let col = self.s_col_ptr[si]..self.s_col_ptr[si + 1];
            return match self.s_row_idx[col.clone()].binary_search(&(sj as usize)) {
                Ok(k) => Slot::At(col.start + k),
                Err(_) => Slot::Missing,
            };
        }
        let (ri, rj) = (self.rest_of[i], self.rest_of[j]);
        if ri == u32::MAX || rj == u32::MAX {
            return Slot::Skip;
        }
        let ri = ri as usize;
        match find(self.c_ptr[ri]..self.c_ptr[ri + 1], &self.c_col, rj) {
            Slot::At(e) => Slot::At(ns_lower + 3 * self.b_col.len() + e),
            other => other,
        }
    }

    /// Whether a point force's block `w` keeps the structure: its position columns in
    /// `R I3` blocks of whole control points, no general column on a control point of `S`.
    fn admits(&self, w: &ElementWork) -> bool {
        let nb = w.shape.0;
        blocks_are_points(w)
            && w.dofs[3 * nb..]
                .iter()
                .all(|&i| i % 4 == 3 || self.kron_of[i / 4] == u32::MAX)
    }

    /// The summed values of every slot ([`Self::slot`]): the element matrices `works[..ne]`
    /// in element order, then the point forces `works[ne..]` in order, per slot, as the CSR sum
    /// and its folding add them (the same values to the last bit: the test
    /// `summed_blocks_equal_the_csr_sum_bit_for_bit`); `false` if a point force breaks the
    /// structure.
    fn sum(&self, works: &[ElementWork], ne: usize, fixed: &[bool], sums: &mut Vec<f64>) -> bool {
        sums.clear();
        sums.resize(self.slots(), 0.0);
        // Two bands of slots side by side; every slot receives its elements' terms in element
        // order.
        let (low, high) = sums.split_at_mut(self.half);
        let band = |out: &mut [f64], maps: &[Vec<[u32; 2]>]| {
            for (w, map) in works[..ne].iter().zip(maps) {
                for &[g, d] in map {
                    out[d as usize] += w.products[g as usize];
                }
            }
        };
        rayon::join(|| band(low, &self.maps[0]), || band(high, &self.maps[1]));
        let mut cache = self
            .point_maps
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        cache.truncate(works.len() - ne);
        for (k, w) in works[ne..].iter().enumerate() {
            if cache.get(k).is_none_or(|(dofs, _)| *dofs != w.dofs) {
                let entry = (w.dofs.clone(), self.point_map(w, fixed));
                if k < cache.len() {
                    cache[k] = entry;
                } else {
                    cache.push(entry);
                }
            }
            // Entry by entry in the block's row order, as the CSR folding adds them.
            let Some(map) = &cache[k].1 else {
                return false;
            };
            for &[e, d] in map {
                sums[d as usize] += w.a[e as usize];
            }
        }
        true
    }

    /// Where each entry of a point force's block `w` (row-major `a`) is summed, in row order:
    /// `[entry, slot]` for the entries [`Self::slot`] reads; `None` if the block breaks the
    /// structure ([`Self::admits`], or a slot the layout lacks).
    fn point_map(&self, w: &ElementWork, fixed: &[bool]) -> Option<Vec<[u32; 2]>> {
        if !self.admits(w) {
            return None;
        }
        let nd = w.dofs.len();
        let mut map = Vec::new();
        for (a, &i) in w.dofs.iter().enumerate() {
            for (bc, &j) in w.dofs.iter().enumerate() {
                match self.slot(fixed, i, j) {
                    Slot::Skip => {}
                    Slot::At(d) => {
                        map.push([u32::try_from(a * nd + bc).ok()?, u32::try_from(d).ok()?])
                    }
                    Slot::Missing => return None,
                }
            }
        }
        Some(map)
    }

    /// This step's blocks summed straight from the element matrices `works[..ne]` and the
    /// point forces `works[ne..]` (in that order, per entry, as the CSR sum and its folding
    /// add them, so the values are the CSR matrix's to the last bit) plus `extra_diag`, and
    /// the numeric factorizations of `S` and `C`. `None` if a point force breaks the
    /// structure, a diagonal term falls on a position or a factorization fails. `buffers` are
    /// the last step's, reused.
    pub(super) fn factor(
        self: &Arc<Self>,
        works: &[ElementWork],
        ne: usize,
        fixed: &[bool],
        extra_diag: &[f64],
        buffers: &mut SchurBuffers,
    ) -> Option<SchurFactor> {
        for &x in &self.kron {
            if extra_diag[x..x + 3].iter().any(|&d| d != 0.0) {
                return None;
            }
        }
        let SchurBuffers {
            sums,
            c_lower,
            scratch,
            scratch_c,
            b,
            c,
            ..
        } = buffers;
        if !self.sum(works, ne, fixed, sums) {
            return None;
        }
        let (s_values, rest) = sums.split_at(self.s_row_idx.len());
        let (b_values, c_values) = rest.split_at(3 * self.b_col.len());
        b.clear();
        b.extend(b_values.chunks_exact(3).map(|v| [v[0], v[1], v[2]]));
        c.clear();
        c.extend_from_slice(c_values);
        for (r, &e) in self.c_diag.iter().enumerate() {
            c[e] += extra_diag[self.rest[r]];
        }
        c_lower.clear();
        c_lower.extend(self.cl_src.iter().map(|&e| c[e]));
        // S and C side by side (a phased program of two tasks, each with its own scratch).
        let jobs = [
            Mutex::new((std::mem::take(&mut buffers.s_factor), Some(scratch))),
            Mutex::new((std::mem::take(&mut buffers.c_factor), Some(scratch_c))),
        ];
        let task = |_: usize, k: usize| {
            let mut job = jobs[k].lock().unwrap_or_else(PoisonError::into_inner);
            let (out, scratch) = &mut *job;
            let Some(scratch) = scratch.take() else {
                return;
            };
            let (col_ptr, row_idx, values, symbolic) = if k == 0 {
                (&self.s_col_ptr, &self.s_row_idx, s_values, &self.s_symbolic)
            } else {
                (
                    &self.cl_col_ptr,
                    &self.cl_row_idx,
                    &c_lower[..],
                    &self.c_symbolic,
                )
            };
            // An empty factor marks a failure.
            *out = numeric(
                symbolic,
                col_ptr,
                row_idx,
                values,
                std::mem::take(out),
                scratch,
            )
            .unwrap_or_default();
        };
        run_phases(&[2], &task);
        let [s_factor, c_factor] =
            jobs.map(|j| j.into_inner().unwrap_or_else(PoisonError::into_inner).0);
        if s_factor.is_empty() || c_factor.is_empty() {
            return None;
        }
        Some(SchurFactor {
            pattern: self.clone(),
            s_factor,
            c_factor,
            b: std::mem::take(b),
            c: std::mem::take(c),
        })
    }
}

/// Whether every block column of `w` is a whole control point's `x, y, z` (`4c, 4c+1, 4c+2`).
fn blocks_are_points(w: &ElementWork) -> bool {
    let nb = w.shape.0;
    w.dofs[..3 * nb]
        .chunks_exact(3)
        .all(|b| b[0] % 4 == 0 && b[1] == b[0] + 1 && b[2] == b[0] + 2)
}

/// The numeric factor of the lower triangle `(col_ptr, row_idx, values)` with `symbolic`,
/// into `out` (sequential, as the full factorization).
fn numeric(
    symbolic: &SymbolicCholesky<usize>,
    col_ptr: &[usize],
    row_idx: &[usize],
    values: &[f64],
    mut out: Vec<f64>,
    scratch: &mut Scratch,
) -> Option<Vec<f64>> {
    let m = col_ptr.len() - 1;
    let sym = faer::sparse::SymbolicSparseColMatRef::new_checked(m, m, col_ptr, None, row_idx);
    let mat = faer::sparse::SparseColMatRef::new(sym, values);
    out.resize(symbolic.len_val(), 0.0);
    let par = faer::Par::Seq;
    let req = symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default());
    symbolic
        .factorize_numeric_llt::<f64>(
            &mut out,
            mat,
            faer::Side::Lower,
            Default::default(),
            par,
            faer::dyn_stack::MemStack::new(scratch.get(req)),
            Default::default(),
        )
        .ok()?;
    Some(out)
}

/// Buffers of the block-Schur factorization kept between steps (scratch; no state).
#[derive(Default)]
pub(super) struct SchurBuffers {
    sums: Vec<f64>,
    c_lower: Vec<f64>,
    s_factor: Vec<f64>,
    c_factor: Vec<f64>,
    b: Vec<[f64; 3]>,
    c: Vec<f64>,
    scratch: Scratch,
    scratch_c: Scratch,
}

impl SchurBuffers {
    /// Takes back a step's factor buffers.
    pub(super) fn keep(&mut self, f: SchurFactor) {
        self.s_factor = f.s_factor;
        self.c_factor = f.c_factor;
        self.b = f.b;
        self.c = f.c;
    }
}

/// One step's factors of `S` and `C` and the values of `B` and `C` (see the module docs).
pub(super) struct SchurFactor {
    pattern: Arc<SchurPattern>,
    s_factor: Vec<f64>,
    c_factor: Vec<f64>,
    /// `B`'s values in [`SchurPattern::b_col`]'s order: the `x`, `y`, `z` rows' entries.
    b: Vec<[f64; 3]>,
    /// `C`'s values by rows ([`SchurPattern::c_ptr`]).
    c: Vec<f64>,
}

impl SchurFactor {
    /// Solves `(S (x) I3) u = f` in place for the `f.len() / ns` columns of `f`
    /// (component-major: `x` of every control point, then `y`, then `z`): one pass over `S`'s
    /// factor for the columns.
    fn solve_s(&self, f: &mut [f64]) {
        let ns = self.pattern.kron.len();
        let rhs = faer::MatMut::from_column_major_slice_mut(f, ns, f.len() / ns);
        solve_with(&self.pattern.s_symbolic, &self.s_factor, rhs);
    }

    /// Solves `C z = r` in place.
    fn solve_c(&self, r: &mut [f64]) {
        let nr = r.len();
        let rhs = faer::MatMut::from_column_major_slice_mut(r, nr, 1);
        solve_with(&self.pattern.c_symbolic, &self.c_factor, rhs);
    }

    /// `out = B w` (component-major, as [`Self::solve_s`]).
    fn b_times(&self, w: &[f64], out: &mut [f64]) {
        let p = &self.pattern;
        let ns = p.kron.len();
        for i in 0..ns {
            let mut s = [0.0; 3];
            for e in p.b_ptr[i]..p.b_ptr[i + 1] {
                let we = w[p.b_col[e] as usize];
                for k in 0..3 {
                    s[k] += self.b[e][k] * we;
                }
            }
            for k in 0..3 {
                out[k * ns + i] = s[k];
            }
        }
    }

    /// `B w` on the control points `rows` (`out[k]`: component `k` of those rows); each
    /// entry summed as in [`Self::b_times`].
    fn b_times_rows(&self, w: &[f64], rows: Range<usize>, out: [&mut [f64]; 3]) {
        let p = &self.pattern;
        let [ox, oy, oz] = out;
        for (j, i) in rows.enumerate() {
            let mut s = [0.0; 3];
            for e in p.b_ptr[i]..p.b_ptr[i + 1] {
                let we = w[p.b_col[e] as usize];
                for k in 0..3 {
                    s[k] += self.b[e][k] * we;
                }
            }
            (ox[j], oy[j], oz[j]) = (s[0], s[1], s[2]);
        }
    }

    /// `out -= B^T u` (`u` component-major).
    fn sub_bt_times(&self, u: &[f64], out: &mut [f64]) {
        self.sub_bt_rows(u, 0..out.len(), out);
    }

    /// `out -= (B^T u)[rows]` (`out`: those rows of the result): per row, the entries in
    /// ascending control points, each `b_x u_x + b_y u_y + b_z u_z` subtracted in turn.
    fn sub_bt_rows(&self, u: &[f64], rows: Range<usize>, out: &mut [f64]) {
        let p = &self.pattern;
        let ns = p.kron.len();
        for (o, r) in out.iter_mut().zip(rows) {
            let mut v = *o;
            for k in p.bt_ptr[r]..p.bt_ptr[r + 1] {
                let b = &self.b[p.bt_src[k] as usize];
                let i = p.bt_point[k] as usize;
                v -= b[0] * u[i] + b[1] * u[ns + i] + b[2] * u[2 * ns + i];
            }
            *o = v;
        }
    }

    /// `out = C w`.
    fn c_times(&self, w: &[f64], out: &mut [f64]) {
        let p = &self.pattern;
        for (r, o) in out.iter_mut().enumerate() {
            let mut s = 0.0;
            for e in p.c_ptr[r]..p.c_ptr[r + 1] {
                s += self.c[e] * w[p.c_col[e] as usize];
            }
            *o = s;
        }
    }

    /// `out = Sigma w = C w - B^T (S^-1 (x) I3) B w`; `t` is scratch of `3 ns`.
    fn schur_times(&self, w: &[f64], out: &mut [f64], t: &mut [f64]) {
        self.b_times(w, t);
        self.solve_s(t);
        self.c_times(w, out);
        self.sub_bt_times(t, out);
    }

    /// Solves `A x = b` on the free coordinates (fixed entries of `x` become 0), starting the
    /// iterations from `x`'s rest entries; returns the iterations and the relative residual of
    /// the last iterate (the Schur residual: module docs).
    ///
    /// The iterations run as one phased program ([`vclay_core::team`]), four phases an
    /// iteration (module docs, "Threads"): (1) `t = B d` in two bands of control points; (2)
    /// `t = (S^-1 (x) I3) t` (one three-column solve) beside `q = C d`; (3) `q -= B^T t` in
    /// two bands of rows; (4) one task: the step along `d`, the residual, the solve with `C`'s
    /// factor and the next direction. Each task writes its own part and every value is summed
    /// in the same order whatever thread runs it, so the result is the same to the last bit
    /// on one thread or two (test `two_threads_solve_as_one`) and as the serial loop's.
    pub(super) fn solve(&self, b: &[f64], x: &mut [f64], max_it: usize, tol: f64) -> SolverStats {
        self.solve_on(b, x, max_it, tol, &run_phases)
    }

    /// [`Self::solve`] with the phased program run by `run` (tests: one thread or a team).
    fn solve_on(
        &self,
        b: &[f64],
        x: &mut [f64],
        max_it: usize,
        tol: f64,
        run: &dyn Fn(&[usize], &TaskFn<'_>),
    ) -> SolverStats {
        let p = &self.pattern;
        let (ns, nr) = (p.kron.len(), p.rest.len());
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        // f (component-major) and y = (S^-1 (x) I3) f.
        let mut f = vec![0.0; 3 * ns];
        for (i, &c) in p.kron.iter().enumerate() {
            for k in 0..3 {
                f[k * ns + i] = b[c + k];
            }
        }
        let gr: Vec<f64> = p.rest.iter().map(|&i| b[i]).collect();
        let bnorm = (dot(&f, &f) + dot(&gr, &gr)).sqrt();
        let mut y = f.clone();
        self.solve_s(&mut y);
        // g' = g - B^T y; r = g' - Sigma w for the starting w.
        let mut r = gr;
        self.sub_bt_times(&y, &mut r);
        let mut w: Vec<f64> = p.rest.iter().map(|&i| x[i]).collect();
        let mut t = vec![0.0; 3 * ns];
        let mut q = vec![0.0; nr];
        if w.iter().any(|&v| v != 0.0) {
            self.schur_times(&w, &mut q, &mut t[..3 * ns]);
            for (ri, qi) in r.iter_mut().zip(&q) {
                *ri -= qi;
            }
        }
        let rel = move |r: &[f64]| {
            let rn = dot(r, r).sqrt();
            if bnorm > 0.0 { rn / bnorm } else { rn }
        };
        let stats = SolverStats {
            iterations: 0,
            relative_residual: rel(&r),
        };
        let mut z = r.clone();
        self.solve_c(&mut z);
        let mut d = z.clone();
        let rz = dot(&r, &z);
        let done = AtomicBool::new(max_it == 0 || stats.relative_residual <= tol);
        let serial = Mutex::new(CgState {
            w: &mut w,
            r: &mut r,
            z: &mut z,
            rz,
            stats,
        });
        {
            let (ts, qs, ds) = (
                SharedSlice::new(&mut t),
                SharedSlice::new(&mut q),
                SharedSlice::new(&mut d),
            );
            let counts: Vec<usize> = (0..max_it).flat_map(|_| [2, 2, 2, 1]).collect();
            let task = |phase: usize, task: usize| {
                // The phase barriers order this load after the store of an earlier phase.
                if done.load(Ordering::Relaxed) {
                    return;
                }
                match (phase % 4, task) {
                    (0, k) => {
                        let rows = if k == 0 { 0..p.b_half } else { p.b_half..ns };
                        let d = ds.read();
                        let at = |c: usize| c * ns + rows.start..c * ns + rows.end;
                        let (mut x, mut y, mut z) =
                            (ts.range(at(0)), ts.range(at(1)), ts.range(at(2)));
                        self.b_times_rows(&d, rows.clone(), [&mut x, &mut y, &mut z]);
                    }
                    (1, 0) => self.solve_s(&mut ts.range(0..3 * ns)),
                    (1, _) => self.c_times(&ds.read(), &mut qs.range(0..nr)),
                    (2, k) => {
                        let rows = if k == 0 { 0..p.bt_half } else { p.bt_half..nr };
                        let t = ts.read();
                        self.sub_bt_rows(&t, rows.clone(), &mut qs.range(rows));
                    }
                    _ => {
                        let mut st = serial.lock().unwrap_or_else(PoisonError::into_inner);
                        let (q, mut d) = (qs.read(), ds.range(0..nr));
                        if st.iterate(&q, &mut d, tol, self, &dot, &rel) {
                            done.store(true, Ordering::Relaxed);
                        }
                    }
                }
            };
            run(&counts, &task);
        }
        let stats = serial
            .into_inner()
            .unwrap_or_else(PoisonError::into_inner)
            .stats;
        // u = (S^-1 (x) I3)(f - B w).
        self.b_times(&w, &mut t[..3 * ns]);
        for (fi, ti) in f.iter_mut().zip(&t) {
            *fi -= ti;
        }
        self.solve_s(&mut f);
        x.iter_mut().for_each(|v| *v = 0.0);
        for (i, &c) in p.kron.iter().enumerate() {
            for k in 0..3 {
                x[c + k] = f[k * ns + i];
            }
        }
        for (r, &i) in p.rest.iter().enumerate() {
            x[i] = w[r];
        }
        stats
    }
}

/// The iterate of [`SchurFactor::solve`]'s conjugate gradients that only the serial phase
/// touches.
struct CgState<'a> {
    w: &'a mut [f64],
    r: &'a mut [f64],
    z: &'a mut [f64],
    rz: f64,
    stats: SolverStats,
}

impl CgState<'_> {
    /// One iteration's serial part, given `q = Sigma d`: the step along `d`, the residual and
    /// (unless it stops) the preconditioned residual and the next direction into `d`; `true`
    /// when the iterations stop (the tolerance reached, the cap, or a non-positive curvature).
    fn iterate(
        &mut self,
        q: &[f64],
        d: &mut [f64],
        tol: f64,
        f: &SchurFactor,
        dot: &dyn Fn(&[f64], &[f64]) -> f64,
        rel: &dyn Fn(&[f64]) -> f64,
    ) -> bool {
        let dq = dot(d, q);
        if dq <= 0.0 {
            return true;
        }
        let alpha = self.rz / dq;
        for i in 0..d.len() {
            self.w[i] += alpha * d[i];
            self.r[i] -= alpha * q[i];
        }
        self.stats.iterations += 1;
        self.stats.relative_residual = rel(self.r);
        if self.stats.relative_residual <= tol {
            return true;
        }
        self.z.copy_from_slice(self.r);
        f.solve_c(self.z);
        let rz_new = dot(self.r, self.z);
        let beta = rz_new / self.rz;
        self.rz = rz_new;
        for i in 0..d.len() {
            d[i] = self.z[i] + beta * d[i];
        }
        false
    }
}

/// `rhs = (L L^T)^-1 rhs` with a factor of `symbolic` (sequential).
fn solve_with(symbolic: &SymbolicCholesky<usize>, values: &[f64], rhs: faer::MatMut<'_, f64>) {
    let par = faer::Par::Seq;
    let mut mem =
        faer::dyn_stack::MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(rhs.ncols(), par));
    faer::sparse::linalg::cholesky::LltRef::<'_, usize, f64>::new(symbolic, values)
        .solve_in_place_with_conj(
            faer::Conj::No,
            rhs,
            par,
            faer::dyn_stack::MemStack::new(&mut mem),
        );
}

#[cfg(test)]
mod tests {
    use super::super::{GeneralizedDnurbs, fold_extras, same_bits};
    use super::*;
    use crate::dnurbs::{RationalGeometry, benchmarks};
    use crate::{Force, Integrator};
    use vclay_core::Vec3;

    impl SchurPattern {
        /// The CSR position each slot would be gathered from (see [`Self::slot`]).
        fn csr_positions(&self, pattern: &CsrPattern) -> Vec<usize> {
            let at = |i: usize, j: usize| position(pattern, i, j).expect("in the pattern");
            let mut out = Vec::with_capacity(self.slots());
            for col in 0..self.kron.len() {
                for e in self.s_col_ptr[col]..self.s_col_ptr[col + 1] {
                    out.push(at(self.kron[col], self.kron[self.s_row_idx[e]]));
                }
            }
            for i in 0..self.kron.len() {
                for e in self.b_ptr[i]..self.b_ptr[i + 1] {
                    for k in 0..3 {
                        out.push(at(self.kron[i] + k, self.rest[self.b_col[e] as usize]));
                    }
                }
            }
            for r in 0..self.rest.len() {
                for e in self.c_ptr[r]..self.c_ptr[r + 1] {
                    out.push(at(self.rest[r], self.rest[self.c_col[e] as usize]));
                }
            }
            out
        }
    }

    /// The blocks summed straight from the element matrices (two bands of slots, point forces
    /// after the elements) are the summed CSR matrix's entries with the point forces folded
    /// in, to the last bit: an 8 x 8 benchmark sheet with one control point held in `x` only
    /// (its `y`, `z` in `C`), a moving spring and a data spring, after a few steps.
    /// The element matrices of `m`'s last block-Schur step with its point forces appended
    /// (as the step adds them), the number of element matrices, and the split it used.
    pub(super) fn last_step(
        m: &mut GeneralizedDnurbs<RationalGeometry>,
    ) -> (Vec<ElementWork>, usize, Arc<SchurPattern>) {
        let mut works = std::mem::take(&mut m.work_pool);
        let ne = works.len();
        let ck = 2.0 * benchmarks::DT * benchmarks::DT;
        m.add_point_forces(&mut works, ck, ck).unwrap();
        let split = m
            .schur
            .as_ref()
            .unwrap()
            .1
            .clone()
            .expect("structure holds");
        (works, ne, split)
    }

    #[test]
    fn summed_blocks_equal_the_csr_sum_bit_for_bit() {
        let mut m: GeneralizedDnurbs<RationalGeometry> = benchmarks::dynamic_sheet(8).unwrap();
        m.block_schur = Some(BlockSchur::default());
        m.set_fixed_coordinate(4 * (3 * 8 + 4), true).unwrap();
        m.forces_mut().push(Force::DataPoint {
            point: Vec3::new(0.3, 0.6, 0.2),
            stiffness: 5.0,
        });
        for _ in 0..4 {
            m.step(Integrator::Implicit { dt: benchmarks::DT }).unwrap();
        }
        assert!(
            m.work_pool.iter().all(|w| !w.dense),
            "the block-Schur steps never wrote the dense element matrices"
        );
        let (mut works, ne, split) = last_step(&mut m);
        assert!(works.len() > ne, "point forces present");
        let pattern = m.pattern.clone().unwrap();
        assert!(
            split.kron.len() < 8 * 7,
            "the held row and the partly held point are out"
        );
        assert!(
            split.rest.len() > 8 * 8 - 1,
            "the partly held point's y, z are in C"
        );
        super::super::densify(&mut works[..ne]);
        let mut values = pattern.values(&works[..ne]);
        assert!(fold_extras(&pattern, &mut values, &works[ne..], &m.fixed));
        let mut sums = Vec::new();
        assert!(split.sum(&works, ne, &m.fixed, &mut sums));
        let at = split.csr_positions(&pattern);
        assert_eq!(sums.len(), at.len());
        assert!(0 < split.half && split.half < sums.len());
        for (d, (&v, &p)) in sums.iter().zip(&at).enumerate() {
            assert_eq!(v.to_bits(), values[p].to_bits(), "slot {d}");
        }
        // The point forces' maps kept from the steps (above) and made afresh give the same
        // sums.
        assert_eq!(split.point_maps.lock().unwrap().len(), works.len() - ne);
        split.point_maps.lock().unwrap().clear();
        let mut fresh = Vec::new();
        assert!(split.sum(&works, ne, &m.fixed, &mut fresh));
        assert!(same_bits(&fresh, &sums));
    }
}

#[cfg(test)]
mod solve_tests {
    use super::super::GeneralizedDnurbs;
    use super::*;
    use crate::Integrator;
    use crate::dnurbs::{RationalGeometry, benchmarks};
    use vclay_core::team::Team;

    /// An `n x n` benchmark sheet after a few block-Schur steps, this step's factor (with a
    /// weight diagonal, as the weight inertia adds) and a right-hand side.
    fn factored(n: usize) -> (SchurFactor, Vec<f64>, SchurBuffers) {
        let mut m: GeneralizedDnurbs<RationalGeometry> = benchmarks::dynamic_sheet(n).unwrap();
        m.block_schur = Some(BlockSchur::default());
        for _ in 0..3 {
            m.step(Integrator::Implicit { dt: benchmarks::DT }).unwrap();
        }
        let (works, ne, split) = super::tests::last_step(&mut m);
        let nd = m.fixed.len();
        let extra: Vec<f64> = (0..nd)
            .map(|i| if i % 4 == 3 { 0.5 } else { 0.0 })
            .collect();
        let mut buffers = SchurBuffers::default();
        let f = split
            .factor(&works, ne, &m.fixed, &extra, &mut buffers)
            .expect("factors");
        let b = (0..nd)
            .map(|i| ((i * 7919) % 1013) as f64 / 1013.0 - 0.5)
            .collect();
        (f, b, buffers)
    }

    /// Runs a phased program on the calling thread alone, in order.
    fn alone(counts: &[usize], run: &TaskFn<'_>) {
        for (phase, &c) in counts.iter().enumerate() {
            for task in 0..c {
                run(phase, task);
            }
        }
    }

    /// The block-Schur CG run as a phased program on a team of two gives the same iterate to
    /// the last bit as on one thread (every value is summed in one order whoever runs it).
    #[test]
    fn two_threads_solve_as_one() {
        let (f, b, _) = factored(12);
        let team = Team::new(2);
        let (mut x1, mut x2) = (vec![0.0; b.len()], vec![0.0; b.len()]);
        let s1 = f.solve_on(&b, &mut x1, 60, 1e-12, &alone);
        let s2 = f.solve_on(&b, &mut x2, 60, 1e-12, &|c, t| team.run(c, t));
        assert!(s1.iterations > 3 && s1.relative_residual <= 1e-12, "{s1:?}");
        assert_eq!(s1.iterations, s2.iterations);
        assert_eq!(
            s1.relative_residual.to_bits(),
            s2.relative_residual.to_bits()
        );
        assert!(x1.iter().zip(&x2).all(|(a, b)| a.to_bits() == b.to_bits()));
    }

    /// `B^T` by rows subtracts in the scatter's order: the same bits as the scatter by
    /// control points; the two bands of rows cover every row.
    #[test]
    fn transpose_by_rows_equals_the_scatter() {
        let (f, _, _) = factored(8);
        let p = &f.pattern;
        let (ns, nr) = (p.kron.len(), p.rest.len());
        let u: Vec<f64> = (0..3 * ns).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut scatter: Vec<f64> = (0..nr).map(|r| r as f64).collect();
        let mut rows = scatter.clone();
        for i in 0..ns {
            for e in p.b_ptr[i]..p.b_ptr[i + 1] {
                let b = &f.b[e];
                scatter[p.b_col[e] as usize] -=
                    b[0] * u[i] + b[1] * u[ns + i] + b[2] * u[2 * ns + i];
            }
        }
        let (lo, hi) = rows.split_at_mut(p.bt_half);
        f.sub_bt_rows(&u, 0..p.bt_half, lo);
        f.sub_bt_rows(&u, p.bt_half..nr, hi);
        assert!(0 < p.bt_half && p.bt_half < nr);
        assert!(
            scatter
                .iter()
                .zip(&rows)
                .all(|(a, b)| a.to_bits() == b.to_bits())
        );
    }

    /// Timings of the CG's pieces on the 32 x 32 sheet (`cargo test --release -p
    /// vclay-dynamics schur_piece_timings -- --ignored --nocapture`).
    #[test]
    #[ignore = "timing, prints"]
    fn schur_piece_timings() {
        let (f, _, mut buffers) = factored(32);
        let p = &f.pattern;
        let (ns, nr) = (p.kron.len(), p.rest.len());
        let reps = 400;
        let time = |name: &str, g: &mut dyn FnMut()| {
            let t0 = std::time::Instant::now();
            for _ in 0..reps {
                g();
            }
            let us = t0.elapsed().as_secs_f64() * 1e6 / reps as f64;
            println!("{name}: {us:.1} us");
        };
        let d: Vec<f64> = (0..nr).map(|i| (i as f64 * 0.1).cos()).collect();
        let mut t = vec![0.0; 3 * ns];
        let mut q = vec![0.0; nr];
        println!("ns {ns}, nr {nr}, B entries {}", p.b_col.len());
        time("b_times (3)", &mut || f.b_times(&d, &mut t));
        time("b_times_rows (half)", &mut || {
            let (x, yz) = t.split_at_mut(ns);
            let (y, z) = yz.split_at_mut(ns);
            let h = p.b_half;
            f.b_times_rows(&d, 0..h, [&mut x[..h], &mut y[..h], &mut z[..h]])
        });
        time("sub_bt scatter", &mut || {
            for i in 0..ns {
                for e in p.b_ptr[i]..p.b_ptr[i + 1] {
                    let b = &f.b[e];
                    q[p.b_col[e] as usize] -= b[0] * t[i] + b[1] * t[ns + i] + b[2] * t[2 * ns + i];
                }
            }
        });
        time("solve_s (3)", &mut || f.solve_s(&mut t));
        time("solve_s (2)", &mut || f.solve_s(&mut t[..2 * ns]));
        time("solve_s (1)", &mut || f.solve_s(&mut t[..ns]));
        time("solve_c", &mut || f.solve_c(&mut q));
        time("c_times", &mut || f.c_times(&d, &mut q));
        time("sub_bt_times", &mut || f.sub_bt_times(&t, &mut q));
        let mut scratch = Scratch::default();
        let sv = buffers.sums[..p.s_row_idx.len()].to_vec();
        let cl = buffers.c_lower.clone();
        time("numeric S", &mut || {
            let out = std::mem::take(&mut buffers.s_factor);
            buffers.s_factor = numeric(
                &p.s_symbolic,
                &p.s_col_ptr,
                &p.s_row_idx,
                &sv,
                out,
                &mut scratch,
            )
            .unwrap();
        });
        time("numeric C", &mut || {
            let out = std::mem::take(&mut buffers.c_factor);
            buffers.c_factor = numeric(
                &p.c_symbolic,
                &p.cl_col_ptr,
                &p.cl_row_idx,
                &cl,
                out,
                &mut scratch,
            )
            .unwrap();
        });
        println!(
            "factor values: S {}, C {}",
            p.s_symbolic.len_val(),
            p.c_symbolic.len_val()
        );
    }
}
