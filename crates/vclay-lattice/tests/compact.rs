//! Compact level operators ([`CompactMatrix`]: weights as indices into each level's distinct
//! values, issue 31): every product equals the [`SparseMatrix`] one bit for bit, on several
//! levels of a box and of non-box primitives, and so does the compressed chain.

use crate::common;

use common::{Rng, perturb, solid};
use vclay_core::{Parallelism, Vec3};
use vclay_lattice::{
    BoundaryRule, ChainWorkspace, CompactMatrix, SparseMatrix, SubdivisionMap, primitives,
};

fn bits(v: &[Vec3]) -> Vec<[u64; 3]> {
    v.iter()
        .map(|x| [x.x.to_bits(), x.y.to_bits(), x.z.to_bits()])
        .collect()
}

fn points(rng: &mut Rng, n: usize) -> Vec<Vec3> {
    (0..n).map(|_| rng.vec3(1.0)).collect()
}

/// Products of `a` and of its compact form, sequential and parallel, compared bit for bit.
fn same_products(a: &SparseMatrix, rng: &mut Rng) {
    let c = CompactMatrix::new(a).expect("a subdivision operator has few distinct weights");
    assert_eq!(c.to_sparse(), *a);
    assert_eq!(
        (c.nrows(), c.ncols(), c.nnz()),
        (a.nrows(), a.ncols(), a.nnz())
    );
    assert!(c.bytes() < a.nnz() * 12 + a.nrows() * 8);
    let x = points(rng, a.ncols());
    let fx = points(rng, a.nrows());
    for par in [Parallelism::Sequential, Parallelism::Rayon] {
        let mut y0 = vec![Vec3::zeros(); a.nrows()];
        let mut y1 = vec![Vec3::zeros(); a.nrows()];
        a.apply_into(&x, &mut y0, par);
        c.apply_into(&x, &mut y1, par);
        assert_eq!(bits(&y0), bits(&y1), "A x, {par:?}");
        let (mut g0, mut g1) = (
            vec![Vec3::zeros(); a.ncols()],
            vec![Vec3::zeros(); a.ncols()],
        );
        a.apply_transpose_into(&fx, &mut g0, &mut Vec::new(), par);
        c.apply_transpose_into(&fx, &mut g1, &mut Vec::new(), par);
        assert_eq!(bits(&g0), bits(&g1), "A^T f, {par:?}");
    }
    let (mut r0, mut r1) = (Vec::new(), Vec::new());
    let rows = a.nrows() / 3..a.nrows();
    a.apply_rows_with(rows.clone(), |k| x[k], |i, v| r0.push((i, v)));
    c.apply_rows_with(rows, |k| x[k], |i, v| r1.push((i, v)));
    assert_eq!(r0.len(), r1.len());
    for ((i0, v0), (i1, v1)) in r0.iter().zip(&r1) {
        assert_eq!((i0, bits(&[*v0])), (i1, bits(&[*v1])));
    }
}

#[test]
fn compact_operators_multiply_like_the_sparse_ones_bit_for_bit() {
    let mut rng = Rng(31);
    let mut torus = primitives::torus(3.0, 1.0, 6, 2);
    perturb(&mut torus, 5, 0.1);
    for (l, rule, levels) in [
        (
            primitives::box_lattice([4, 4, 4], Vec3::zeros(), Vec3::repeat(1.0)),
            BoundaryRule::Sharp,
            3,
        ),
        (primitives::gear(1.0, 2.0, 2.5, 0.4), BoundaryRule::Sharp, 2),
        (torus, BoundaryRule::Smooth, 2),
        (
            primitives::cylinder(1.0, 1.0, 5, 1, 1),
            BoundaryRule::Interior,
            2,
        ),
    ] {
        let s = solid(l, rule, levels);
        for a in s.map().operators() {
            same_products(a, &mut rng);
        }
    }
}

#[test]
fn a_compressed_chain_gives_the_same_bits_and_releases_its_transposes() {
    let mut rng = Rng(7);
    for l in [
        primitives::box_lattice([4, 4, 4], Vec3::zeros(), Vec3::repeat(1.0)),
        primitives::gear(1.0, 2.0, 2.5, 0.4),
    ] {
        let s = solid(l, BoundaryRule::Sharp, 3);
        let full = s.map().clone();
        let mut small = full.clone();
        small.compress();
        assert!(small.is_compressed());
        assert!((0..small.levels()).all(|j| small.compact(j).is_some()));
        let p = points(&mut rng, full.control_count().unwrap());
        let f = points(&mut rng, full.data_count().unwrap());
        for par in [Parallelism::Sequential, Parallelism::Rayon] {
            let mut ws = ChainWorkspace::new();
            let (mut d0, mut d1) = (vec![Vec3::zeros(); f.len()], vec![Vec3::zeros(); f.len()]);
            full.apply_into(&p, &mut d0, &mut ws, par);
            small.apply_into(&p, &mut d1, &mut ws, par);
            assert_eq!(bits(&d0), bits(&d1));
            // Above `GATHER_NNZ` the transpose products scatter through the operators (compact
            // or not); below, both chains gather through the stored transposes.
            let (mut g0, mut g1) = (vec![Vec3::zeros(); p.len()], vec![Vec3::zeros(); p.len()]);
            full.apply_transpose_into(&f, &mut g0, &mut ws, par);
            small.apply_transpose_into(&f, &mut g1, &mut ws, par);
            assert_eq!(bits(&g0), bits(&g1));
        }
        // The gathered products above built the transposes of these small chains.
        small.release_transposes();
        let before = small.bytes();
        small.prepare_transposes();
        assert!(small.bytes() > before);
        small.release_transposes();
        assert_eq!(small.bytes(), before);
    }
}

#[test]
fn many_distinct_values_take_two_byte_indices_or_stay_uncompressed() {
    // 300 distinct values: u16 indices.
    let n = 300;
    let a = SparseMatrix::from_csr(
        n,
        n,
        (0..=n).collect(),
        (0..n as u32).collect(),
        (0..n).map(|i| 1.0 + i as f64).collect(),
    );
    let c = CompactMatrix::new(&a).unwrap();
    assert_eq!(c.distinct_values(), n);
    assert_eq!(c.to_sparse(), a);
    let x: Vec<f64> = (0..n).map(|i| 0.5 - i as f64).collect();
    let (mut y0, mut y1) = (vec![0.0; n], vec![0.0; n]);
    a.apply_into(&x, &mut y0, Parallelism::Sequential);
    c.apply_into(&x, &mut y1, Parallelism::Sequential);
    assert_eq!(y0, y1);
    // 70,000 distinct values: not compacted.
    let n = 70_000;
    let b = SparseMatrix::from_csr(
        1,
        n,
        vec![0, n],
        (0..n as u32).collect(),
        (0..n).map(|i| i as f64).collect(),
    );
    assert!(CompactMatrix::new(&b).is_none());
    let mut m = SubdivisionMap::new(vec![b]);
    m.compress();
    assert!(m.compact(0).is_none());
    let x = vec![1.0; n];
    assert_eq!(m.apply(&x), vec![(n * (n - 1) / 2) as f64]);
}
