//! Compressed sparse row adjacency lists and the parallel builders used for them.

use rayon::prelude::*;

/// A list of lists stored flat: the entries of list `i` are `data[offsets[i]..offsets[i + 1]]`.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Csr<T> {
    pub offsets: Vec<u32>,
    pub data: Vec<T>,
}

/// Number of items per parallel block in [`par_build`].
const BLOCK: usize = 4096;

impl<T: Copy + Send + Sync> Csr<T> {
    /// The list of item `i`.
    #[inline]
    pub fn get(&self, i: usize) -> &[T] {
        &self.data[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }

    /// Number of lists.
    #[inline]
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Builds `n` lists; `fill(i, out)` appends the entries of list `i`. Runs blocks of items in
    /// parallel when `parallel`.
    pub fn par_build<F>(n: usize, parallel: bool, fill: F) -> Self
    where
        F: Fn(usize, &mut Vec<T>) + Sync,
    {
        let run_block = |b: usize| {
            let lo = b * BLOCK;
            let hi = (lo + BLOCK).min(n);
            let mut lens = Vec::with_capacity(hi - lo);
            let mut data = Vec::with_capacity((hi - lo) * 4);
            for i in lo..hi {
                let before = data.len();
                fill(i, &mut data);
                lens.push((data.len() - before) as u32);
            }
            (lens, data)
        };
        let blocks = n.div_ceil(BLOCK);
        let parts: Vec<(Vec<u32>, Vec<T>)> = if parallel && blocks > 1 {
            (0..blocks).into_par_iter().map(run_block).collect()
        } else {
            (0..blocks).map(run_block).collect()
        };
        concat(n, parts)
    }

    /// Groups `(key, value)` pairs produced by `pairs` by key (a counting sort): list `k` holds
    /// the values of key `k` in the order they were produced.
    pub fn group<I>(keys: usize, count: usize, pairs: impl Fn() -> I) -> Self
    where
        I: Iterator<Item = (u32, T)>,
        T: Default,
    {
        let mut offsets = vec![0u32; keys + 1];
        for (k, _) in pairs() {
            offsets[k as usize + 1] += 1;
        }
        for i in 0..keys {
            offsets[i + 1] += offsets[i];
        }
        debug_assert_eq!(offsets[keys] as usize, count);
        let mut cursor: Vec<u32> = offsets[..keys].to_vec();
        let mut data = vec![T::default(); count];
        for (k, v) in pairs() {
            let c = &mut cursor[k as usize];
            data[*c as usize] = v;
            *c += 1;
        }
        Csr { offsets, data }
    }
}

/// Concatenates per-block `(lengths, data)` parts into one CSR.
pub(crate) fn concat<T: Copy>(n: usize, parts: Vec<(Vec<u32>, Vec<T>)>) -> Csr<T> {
    let total: usize = parts.iter().map(|p| p.1.len()).sum();
    assert!(
        total <= u32::MAX as usize,
        "adjacency list overflows u32 offsets"
    );
    let mut offsets = Vec::with_capacity(n + 1);
    offsets.push(0u32);
    let mut data = Vec::with_capacity(total);
    let mut acc = 0u32;
    for (lens, d) in parts {
        for l in lens {
            acc += l;
            offsets.push(acc);
        }
        data.extend_from_slice(&d);
    }
    Csr { offsets, data }
}

/// Builds two CSR lists per item at once (`fill(i, a, b)` appends to both).
pub(crate) fn par_build2<A, B, F>(n: usize, parallel: bool, fill: F) -> (Csr<A>, Csr<B>)
where
    A: Copy + Send + Sync,
    B: Copy + Send + Sync,
    F: Fn(usize, &mut Vec<A>, &mut Vec<B>) + Sync,
{
    type Part<A, B> = ((Vec<u32>, Vec<A>), (Vec<u32>, Vec<B>));
    let run_block = |blk: usize| -> Part<A, B> {
        let lo = blk * BLOCK;
        let hi = (lo + BLOCK).min(n);
        let (mut la, mut lb) = (Vec::with_capacity(hi - lo), Vec::with_capacity(hi - lo));
        let (mut da, mut db) = (Vec::new(), Vec::new());
        for i in lo..hi {
            let (ba, bb) = (da.len(), db.len());
            fill(i, &mut da, &mut db);
            la.push((da.len() - ba) as u32);
            lb.push((db.len() - bb) as u32);
        }
        ((la, da), (lb, db))
    };
    let blocks = n.div_ceil(BLOCK);
    let parts: Vec<Part<A, B>> = if parallel && blocks > 1 {
        (0..blocks).into_par_iter().map(run_block).collect()
    } else {
        (0..blocks).map(run_block).collect()
    };
    let (pa, pb): (Vec<_>, Vec<_>) = parts.into_iter().unzip();
    (concat(n, pa), concat(n, pb))
}
