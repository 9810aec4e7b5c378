//! The control map `d = A p` of a dynamic solid, its Galerkin products `A^T W A`, and its
//! restriction to the data points that free control points influence.
//!
//! # What
//! * Subdivision solids: `A = A^(n) ... A^(1)` (`subdivision-solids-journal.txt` eq 4), kept as
//!   the chain of level operators of [`SubdivisionMap`]; `A` itself is never formed.
//! * B-spline solids: `c = B q` (journal eq 3), one sparse level whose rows hold the
//!   `(p+1)(q+1)(r+1)` non-zero tensor-product basis values of a sample.
//!
//! Both are a [`SubdivisionMap`] (a chain of CSR matrices), so the dynamics has one code path.
//!
//! # How
//! [`galerkin`] forms `A^T W A` for a diagonal `W` (masses or damping, journal eqs 7-10) level by
//! level, `W_(j-1) = A^(j)T W_j A^(j)`, each product a sparse-sparse multiplication: the matrices
//! in between couple points of one level with their neighbours only.
//!
//! [`Restricted`] is the partition of journal section 5.2 (`d = A1 p1 + A2 p2`): rows of data
//! points that depend only on fixed control points are dropped, and from the finest level down
//! only the rows and columns that remaining rows reach are kept, so each application touches
//! the active part of every level.

use std::borrow::Cow;

use vclay_core::{Parallelism, Vec3};
use vclay_lattice::{ChainWorkspace, SparseMatrix, SubdivisionMap};

/// `A^T diag(w) A` for the chain `map` (a symmetric matrix on the control points).
///
/// # Panics
/// If `w.len()` differs from the number of data points (a programmer error).
#[track_caller]
pub fn galerkin(map: &SubdivisionMap, w: &[f64]) -> SparseMatrix {
    let n = map.levels();
    assert!(n > 0, "galerkin: empty chain");
    assert_eq!(map.data_count(), Some(w.len()), "galerkin: weight length");
    // A large chain's transposes are built for this product and dropped after it (its `A^T`
    // products scatter through the operators and never read them); a small chain keeps them
    // for its gathered `A^T` products. The same matrices either way.
    let large =
        map.operators().iter().map(SparseMatrix::nnz).sum::<usize>() > SubdivisionMap::GATHER_NNZ;
    let transpose = |j: usize| -> Cow<'_, SparseMatrix> {
        if large {
            Cow::Owned(map.operator(j).transpose())
        } else {
            Cow::Borrowed(map.transpose(j))
        }
    };
    // Finest level: A^(n)T (diag(w) A^(n)), without a scaled copy of A^(n) (the same bits).
    let top = map.operator(n - 1);
    let mut cur = transpose(n - 1).mul_scaled(w, top);
    for j in (0..n - 1).rev() {
        let a = map.operator(j);
        let wa = cur.mul(a);
        cur = transpose(j).mul(&wa);
    }
    cur
}

/// For each data point, whether it depends on at least one control point with `free[i]`
/// (structural non-zeros propagated level by level).
pub fn influenced(map: &SubdivisionMap, free: &[bool]) -> Vec<bool> {
    let mut cur = free.to_vec();
    for a in map.operators() {
        cur = (0..a.nrows())
            .map(|i| a.row(i).0.iter().any(|&c| cur[c as usize]))
            .collect();
    }
    cur
}

/// The chain restricted to the data points in `rows` (journal section 5.2): level operators
/// with only the needed rows and columns, renumbered.
#[derive(Clone, Debug)]
pub struct Restricted {
    /// Restricted level operators in application order.
    map: SubdivisionMap,
    /// Control point ids of the restricted input (level 0 columns).
    pub inputs: Vec<u32>,
    /// Data point ids of the restricted output rows.
    pub outputs: Vec<u32>,
}

impl Restricted {
    /// Restricts `map` to the data points `rows` (sorted, unique).
    pub fn new(map: &SubdivisionMap, rows: Vec<u32>) -> Self {
        let n = map.levels();
        let mut ops = Vec::with_capacity(n);
        let mut need = rows.clone();
        for j in (0..n).rev() {
            let a = map.operator(j);
            let mut pos = vec![u32::MAX; a.ncols()];
            let mut cols: Vec<u32> = Vec::new();
            for &r in &need {
                for &c in a.row(r as usize).0 {
                    if pos[c as usize] == u32::MAX {
                        pos[c as usize] = 0;
                        cols.push(c);
                    }
                }
            }
            cols.sort_unstable();
            for (k, &c) in cols.iter().enumerate() {
                pos[c as usize] = k as u32;
            }
            let mut rp = Vec::with_capacity(need.len() + 1);
            rp.push(0);
            let (mut ci, mut vi) = (Vec::new(), Vec::new());
            for &r in &need {
                let (c, v) = a.row(r as usize);
                for (&c, &v) in c.iter().zip(v) {
                    ci.push(pos[c as usize]);
                    vi.push(v);
                }
                rp.push(ci.len());
            }
            ops.push(SparseMatrix::from_csr(need.len(), cols.len(), rp, ci, vi));
            need = cols;
        }
        ops.reverse();
        Self {
            map: SubdivisionMap::new(ops),
            inputs: need,
            outputs: rows,
        }
    }

    /// The restricted chain.
    pub fn map(&self) -> &SubdivisionMap {
        &self.map
    }

    /// The restricted chain, mutable (to [compress](SubdivisionMap::compress) it or release
    /// its transposes; its operators cannot be changed through it).
    pub(crate) fn map_mut(&mut self) -> &mut SubdivisionMap {
        &mut self.map
    }
}

/// Scratch buffers for applying a (possibly restricted) chain without allocating.
#[derive(Clone, Debug, Default)]
pub struct MapWorkspace {
    chain: ChainWorkspace<Vec3>,
    input: Vec<Vec3>,
    output: Vec<Vec3>,
}

/// `d[outputs] = A_r p[inputs]`: positions of the active data points; others untouched.
pub fn apply_active(
    map: &SubdivisionMap,
    restricted: Option<&Restricted>,
    p: &[Vec3],
    d: &mut [Vec3],
    ws: &mut MapWorkspace,
    par: Parallelism,
) {
    match restricted {
        None => map.apply_into(p, d, &mut ws.chain, par),
        Some(r) => {
            ws.input.clear();
            ws.input.extend(r.inputs.iter().map(|&i| p[i as usize]));
            ws.output.resize(r.outputs.len(), Vec3::zeros());
            r.map
                .apply_into(&ws.input, &mut ws.output, &mut ws.chain, par);
            for (k, &i) in r.outputs.iter().enumerate() {
                d[i as usize] = ws.output[k];
            }
        }
    }
}

/// `g = A^T f` on the control points (entries of control points outside the restriction are
/// set to zero).
pub fn apply_transpose_active(
    map: &SubdivisionMap,
    restricted: Option<&Restricted>,
    f: &[Vec3],
    g: &mut [Vec3],
    ws: &mut MapWorkspace,
    par: Parallelism,
) {
    match restricted {
        None => map.apply_transpose_into(f, g, &mut ws.chain, par),
        Some(r) => {
            ws.output.clear();
            ws.output.extend(r.outputs.iter().map(|&i| f[i as usize]));
            ws.input.resize(r.inputs.len(), Vec3::zeros());
            r.map
                .apply_transpose_into(&ws.output, &mut ws.input, &mut ws.chain, par);
            g.fill(Vec3::zeros());
            for (k, &i) in r.inputs.iter().enumerate() {
                g[i as usize] = ws.input[k];
            }
        }
    }
}
