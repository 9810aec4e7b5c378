//! `TensorOperator`: the factors of a Kronecker product `S_z ⊗ S_y ⊗ S_x` are found, its
//! products agree with the sparse matrix's, and anything else is refused (issue 31).

use vclay_core::{Parallelism, Vec3};
use vclay_lattice::{SparseMatrix, TensorOperator, TensorWorkspace};

/// A one-dimensional subdivision-like operator from `c` to `f = 2c - 1` points: even rows
/// `(w, 1 - 2w, w)` (end rows interpolate), odd rows `(1/2, 1/2)`; `w` varies by row so the
/// axes differ.
fn factor_1d(c: usize, w: f64) -> Vec<Vec<(usize, f64)>> {
    (0..2 * c - 1)
        .map(|i| {
            if i % 2 == 1 {
                vec![(i / 2, 0.5), (i / 2 + 1, 0.5)]
            } else if i == 0 || i == 2 * c - 2 {
                vec![(i / 2, 1.0)]
            } else {
                let w = w * (1.0 + 0.01 * i as f64);
                vec![(i / 2 - 1, w), (i / 2, 1.0 - 2.0 * w), (i / 2 + 1, w)]
            }
        })
        .collect()
}

/// The Kronecker product as a sparse matrix (rows and columns in grid order, x fastest).
fn kron(s: &[Vec<Vec<(usize, f64)>>; 3], coarse: [usize; 3]) -> SparseMatrix {
    let fine = [s[0].len(), s[1].len(), s[2].len()];
    let mut rp = vec![0usize];
    let (mut cols, mut vals) = (Vec::new(), Vec::new());
    for k in 0..fine[2] {
        for j in 0..fine[1] {
            for i in 0..fine[0] {
                let mut row: Vec<(u32, f64)> = Vec::new();
                for &(e, wz) in &s[2][k] {
                    for &(d, wy) in &s[1][j] {
                        for &(c, wx) in &s[0][i] {
                            let col = c + coarse[0] * (d + coarse[1] * e);
                            row.push((col as u32, wx * wy * wz));
                        }
                    }
                }
                row.sort_by_key(|e| e.0);
                cols.extend(row.iter().map(|e| e.0));
                vals.extend(row.iter().map(|e| e.1));
                rp.push(cols.len());
            }
        }
    }
    SparseMatrix::from_csr(
        fine.iter().product(),
        coarse.iter().product(),
        rp,
        cols,
        vals,
    )
}

fn max_diff(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).amax())
        .fold(0.0, f64::max)
}

#[test]
fn a_kronecker_product_factors_and_its_products_agree_with_the_sparse_ones() {
    for coarse in [[5, 4, 3], [3, 3, 3], [2, 6, 4], [40, 40, 41]] {
        let s = [
            factor_1d(coarse[0], 0.125),
            factor_1d(coarse[1], 0.1),
            factor_1d(coarse[2], 0.15),
        ];
        let fine = [s[0].len(), s[1].len(), s[2].len()];
        let a = kron(&s, coarse);
        let t = TensorOperator::factor(&a, coarse, fine).expect("a Kronecker product");
        assert_eq!((t.nrows(), t.ncols()), (a.nrows(), a.ncols()));
        let x: Vec<Vec3> = (0..a.ncols())
            .map(|i| Vec3::new(i as f64, (i * i % 17) as f64, -(i as f64).sqrt()))
            .collect();
        let mut ws = TensorWorkspace::default();
        let mut y = vec![Vec3::zeros(); a.nrows()];
        t.apply_into(&x, &mut y, &mut ws, Parallelism::Sequential);
        let want = a.apply(&x);
        let scale = want.iter().map(|v| v.amax()).fold(1.0, f64::max);
        assert!(max_diff(&y, &want) < 1e-14 * scale, "{coarse:?}: A x");
        let mut y2 = vec![Vec3::zeros(); a.nrows()];
        t.apply_into(&x, &mut y2, &mut ws, Parallelism::Rayon);
        assert!(y == y2, "{coarse:?}: one thread = all threads");
        let f: Vec<Vec3> = (0..a.nrows())
            .map(|i| Vec3::new((i % 13) as f64 - 6.0, 1.0, (i % 5) as f64))
            .collect();
        let mut g = vec![Vec3::zeros(); a.ncols()];
        t.apply_transpose_into(&f, &mut g, &mut ws, Parallelism::Sequential);
        let want = a.apply_transpose(&f);
        let scale = want.iter().map(|v| v.amax()).fold(1.0, f64::max);
        assert!(max_diff(&g, &want) < 1e-14 * scale, "{coarse:?}: A^T f");
        let mut g2 = vec![Vec3::zeros(); a.ncols()];
        t.apply_transpose_into(&f, &mut g2, &mut ws, Parallelism::Rayon);
        assert!(g == g2, "{coarse:?}: A^T, one thread = all threads");
    }
}

#[test]
fn operators_that_are_not_kronecker_products_are_refused() {
    let coarse = [4, 3, 5];
    let s = [
        factor_1d(4, 0.125),
        factor_1d(3, 0.125),
        factor_1d(5, 0.125),
    ];
    let fine = [7, 5, 9];
    let a = kron(&s, coarse);
    assert!(TensorOperator::factor(&a, coarse, fine).is_some());
    // Wrong shapes.
    assert!(TensorOperator::factor(&a, [3, 4, 5], fine).is_none());
    assert!(TensorOperator::factor(&a, coarse, [5, 7, 9]).is_none());
    // One weight changed (by more than rounding), one entry dropped, one entry added.
    let (rp, cols, vals) = (
        a.row_ptr().to_vec(),
        a.col_indices().to_vec(),
        a.values().to_vec(),
    );
    let r = rp[100];
    let mut v2 = vals.clone();
    v2[r] += 1e-9;
    let changed = SparseMatrix::from_csr(a.nrows(), a.ncols(), rp.clone(), cols.clone(), v2);
    assert!(TensorOperator::factor(&changed, coarse, fine).is_none());
    let (mut rp3, mut c3, mut v3) = (rp.clone(), cols.clone(), vals.clone());
    c3.remove(r);
    v3.remove(r);
    for p in &mut rp3[101..] {
        *p -= 1;
    }
    let dropped = SparseMatrix::from_csr(a.nrows(), a.ncols(), rp3, c3, v3);
    assert!(TensorOperator::factor(&dropped, coarse, fine).is_none());
    // A row of a point in the middle that also takes a far column with a small weight.
    let row = 7 + 7 * (2 + 5 * 4);
    let (mut rp4, mut c4, mut v4) = (rp.clone(), cols.clone(), vals.clone());
    let end = rp4[row + 1];
    assert!(c4[end - 1] < (a.ncols() - 1) as u32);
    c4.insert(end, (a.ncols() - 1) as u32);
    v4.insert(end, 1e-3);
    for p in &mut rp4[row + 1..] {
        *p += 1;
    }
    let added = SparseMatrix::from_csr(a.nrows(), a.ncols(), rp4, c4, v4);
    assert!(TensorOperator::factor(&added, coarse, fine).is_none());
}

/// The plane-range products (the phased step's tasks, `vclay-solids` `solid/phased.rs`) give
/// the whole products bit for bit, however the planes are split: shapes with odd and even plane
/// counts, one to five tasks (some with empty ranges).
#[test]
fn plane_range_products_are_the_whole_products_bit_for_bit() {
    for coarse in [[5, 4, 3], [3, 3, 3], [2, 6, 4], [7, 7, 7], [4, 5, 6]] {
        let s = [
            factor_1d(coarse[0], 0.125),
            factor_1d(coarse[1], 0.1),
            factor_1d(coarse[2], 0.15),
        ];
        let fine = [s[0].len(), s[1].len(), s[2].len()];
        let a = kron(&s, coarse);
        let t = TensorOperator::factor(&a, coarse, fine).unwrap();
        assert_eq!(t.dims(), (coarse, fine));
        let [l1, l2] = t.intermediate_plane_lens();
        let x: Vec<Vec3> = (0..a.ncols())
            .map(|i| Vec3::new(i as f64, (i * i % 17) as f64, -(i as f64).sqrt()))
            .collect();
        let f: Vec<Vec3> = (0..a.nrows())
            .map(|i| Vec3::new((i % 13) as f64 - 6.0, 1.0 / (1 + i) as f64, (i % 5) as f64))
            .collect();
        let mut ws = TensorWorkspace::default();
        let mut y = vec![Vec3::zeros(); a.nrows()];
        t.apply_into(&x, &mut y, &mut ws, Parallelism::Sequential);
        let mut g = vec![Vec3::zeros(); a.ncols()];
        t.apply_transpose_into(&f, &mut g, &mut ws, Parallelism::Sequential);
        let cz = coarse[2];
        let (plane, fplane) = (coarse[0] * coarse[1], fine[0] * fine[1]);
        for tasks in 1..=5 {
            let split = |n: usize, k: usize| n * k / tasks..n * (k + 1) / tasks;
            // A x: x- and y-passes by coarse planes, then the z-pass by fine planes.
            let (mut t1, mut t2) = (vec![Vec3::zeros(); l1 * cz], vec![Vec3::zeros(); l2 * cz]);
            for k in 0..tasks {
                let e = split(cz, k);
                t.apply_xy_planes(
                    &x,
                    e.clone(),
                    &mut t1[e.start * l1..e.end * l1],
                    &mut t2[e.start * l2..e.end * l2],
                );
            }
            let mut y2 = vec![Vec3::zeros(); a.nrows()];
            for k in 0..tasks {
                let p = split(fine[2], k);
                t.apply_z_planes(&t2, p.clone(), &mut y2[p.start * fplane..p.end * fplane]);
            }
            assert!(y == y2, "{coarse:?}, {tasks} tasks: A x");
            // A^T f: every pass by coarse planes.
            let (mut u1, mut u2) = (vec![Vec3::zeros(); l1 * cz], vec![Vec3::zeros(); l2 * cz]);
            let mut g2 = vec![Vec3::zeros(); a.ncols()];
            for k in 0..tasks {
                let e = split(cz, k);
                t.apply_transpose_planes(
                    &f,
                    e.clone(),
                    &mut u2[e.start * l2..e.end * l2],
                    &mut u1[e.start * l1..e.end * l1],
                    &mut g2[e.start * plane..e.end * plane],
                );
            }
            assert!(g == g2, "{coarse:?}, {tasks} tasks: A^T f");
        }
    }
}
