//! Level operators `A^(j)` and their chain `A = A^(n) ... A^(1)`
//! (`subdivision-solids-journal.txt` section 4.2, eq 4).

use crate::common;

use common::{Rng, perturb, solid};
use vclay_core::{Parallelism, Vec3};
use vclay_lattice::{BoundaryRule, ChainWorkspace, SparseMatrix, primitives};

#[test]
fn every_row_is_an_affine_combination() {
    for rule in [
        BoundaryRule::Interior,
        BoundaryRule::Smooth,
        BoundaryRule::Sharp,
    ] {
        for l in [
            primitives::box_lattice([3, 4, 3], Vec3::zeros(), Vec3::new(2.0, 3.0, 2.0)),
            primitives::cylinder(1.0, 1.0, 5, 1, 1),
            primitives::gear(1.0, 2.0, 2.5, 0.4),
        ] {
            let s = solid(l, rule, 2);
            for a in s.map().operators() {
                for (i, sum) in a.row_sums().iter().enumerate() {
                    assert!((sum - 1.0).abs() < 1e-13, "{rule:?}: row {i} sums to {sum}");
                }
            }
        }
    }
}

#[test]
fn chain_reproduces_the_subdivided_points_and_the_product() {
    let mut l = primitives::torus(3.0, 1.0, 6, 2);
    perturb(&mut l, 3, 0.1);
    let s = solid(l, BoundaryRule::Smooth, 2);
    let p = s.control().points().to_vec();
    let d = s.map().apply(&p);
    for (a, b) in d.iter().zip(s.finest().points()) {
        assert!((a - b).norm() < 1e-12);
    }
    let a = s.map().product().unwrap();
    assert_eq!((a.nrows(), a.ncols()), (s.finest().num_points(), p.len()));
    let d2 = a.apply(&p);
    for (x, y) in d.iter().zip(&d2) {
        assert!((x - y).norm() < 1e-12);
    }
    for (i, sum) in a.row_sums().iter().enumerate() {
        assert!((sum - 1.0).abs() < 1e-12, "product row {i}");
    }
    // Affine invariance: moving all control points rigidly moves all data points.
    let shift = Vec3::new(0.3, -2.0, 1.5);
    let moved: Vec<Vec3> = p.iter().map(|q| q + shift).collect();
    for (x, y) in s.map().apply(&moved).iter().zip(&d) {
        assert!((x - (y + shift)).norm() < 1e-12);
    }
}

#[test]
fn transpose_chain_is_the_adjoint() {
    let s = solid(primitives::l_solid(2, 1, 1.0), BoundaryRule::Sharp, 2);
    let mut rng = Rng(11);
    let x: Vec<f64> = (0..s.control().num_points()).map(|_| rng.sym()).collect();
    let y: Vec<f64> = (0..s.finest().num_points()).map(|_| rng.sym()).collect();
    let ax = s.map().apply(&x);
    let aty = s.map().apply_transpose(&y);
    let lhs: f64 = ax.iter().zip(&y).map(|(a, b)| a * b).sum();
    let rhs: f64 = x.iter().zip(&aty).map(|(a, b)| a * b).sum();
    assert!(
        (lhs - rhs).abs() < 1e-10 * lhs.abs().max(1.0),
        "{lhs} vs {rhs}"
    );
    // And it equals the transpose of the product.
    let at = s.map().product().unwrap().transpose();
    let aty2 = at.apply(&y);
    for (a, b) in aty.iter().zip(&aty2) {
        assert!((a - b).abs() < 1e-12);
    }
}

#[test]
fn workspace_application_matches_and_parallel_equals_sequential() {
    let s = solid(
        primitives::box_lattice([4, 4, 4], Vec3::zeros(), Vec3::repeat(3.0)),
        BoundaryRule::Smooth,
        3,
    );
    let p = s.control().points().to_vec();
    let mut ws = ChainWorkspace::new();
    let mut d1 = vec![Vec3::zeros(); s.finest().num_points()];
    let mut d2 = d1.clone();
    s.map()
        .apply_into(&p, &mut d1, &mut ws, Parallelism::Sequential);
    s.map().apply_into(&p, &mut d2, &mut ws, Parallelism::Rayon);
    assert_eq!(d1, d2);
    let mut g1 = vec![Vec3::zeros(); p.len()];
    let mut g2 = g1.clone();
    s.map()
        .apply_transpose_into(&d1, &mut g1, &mut ws, Parallelism::Sequential);
    s.map()
        .apply_transpose_into(&d1, &mut g2, &mut ws, Parallelism::Rayon);
    for (a, b) in g1.iter().zip(&g2) {
        assert!((a - b).norm() < 1e-9 * a.norm().max(1.0));
    }
    // Transpose of a chain of affine maps: A^T 1 = column sums, total = number of data points.
    let ones = vec![1.0; s.finest().num_points()];
    let cs: f64 = s.map().apply_transpose(&ones).iter().sum();
    assert!((cs - s.finest().num_points() as f64).abs() < 1e-8);
}

#[test]
fn fixed_control_points_partition_the_columns() {
    // Journal section 5.2: d = A1 p1 + A2 p2 with the free and fixed columns.
    let s = solid(primitives::cube_with_holes(1.0), BoundaryRule::Smooth, 1);
    let p = s.control().points().to_vec();
    let fixed: Vec<bool> = p.iter().map(|q| q.z < 0.5).collect();
    let p1: Vec<Vec3> = p
        .iter()
        .zip(&fixed)
        .map(|(q, &f)| if f { Vec3::zeros() } else { *q })
        .collect();
    let p2: Vec<Vec3> = p
        .iter()
        .zip(&fixed)
        .map(|(q, &f)| if f { *q } else { Vec3::zeros() })
        .collect();
    let d = s.map().apply(&p);
    let d1 = s.map().apply(&p1);
    let d2 = s.map().apply(&p2);
    for i in 0..d.len() {
        assert!((d[i] - d1[i] - d2[i]).norm() < 1e-12);
    }
}

#[test]
fn sparse_matrix_basics() {
    let a = SparseMatrix::from_csr(2, 3, vec![0, 2, 3], vec![0, 2, 1], vec![1.0, 2.0, 3.0]);
    assert_eq!(a.to_dense(), vec![vec![1.0, 0.0, 2.0], vec![0.0, 3.0, 0.0]]);
    assert_eq!(
        a.transpose().to_dense(),
        vec![vec![1.0, 0.0], vec![0.0, 3.0], vec![2.0, 0.0]]
    );
    let i = SparseMatrix::identity(3);
    assert_eq!(a.mul(&i), a);
    assert_eq!(
        a.mul(&a.transpose()).to_dense(),
        vec![vec![5.0, 0.0], vec![0.0, 9.0]]
    );
    assert_eq!(a.apply(&[1.0, 1.0, 1.0]), vec![3.0, 3.0]);
    assert_eq!(a.get(0, 2), 2.0);
    assert_eq!(a.get(1, 2), 0.0);
}

#[test]
#[should_panic(expected = "not strictly increasing")]
fn sparse_matrix_rejects_unsorted_rows() {
    SparseMatrix::from_csr(1, 3, vec![0, 2], vec![2, 0], vec![1.0, 1.0]);
}

/// The scattered `A^T x` (no transpose formed) equals the stored transpose applied row by row,
/// sequentially and with several tasks, also with empty rows at the start and the end (which
/// the task blocks must not drop).
#[test]
fn scattered_transpose_equals_stored_transpose() {
    let mut rng = Rng(7);
    let (nrows, ncols) = (9000, 1100);
    let mut row_ptr = vec![0];
    let (mut cols, mut vals) = (Vec::new(), Vec::new());
    for i in 0..nrows {
        if i >= 5 && i < nrows - 7 {
            let mut c: Vec<u32> = (0..1 + (rng.next_u64() % 12) as usize)
                .map(|_| (rng.next_u64() % ncols as u64) as u32)
                .collect();
            c.sort_unstable();
            c.dedup();
            vals.extend(c.iter().map(|_| rng.sym()));
            cols.extend(c);
        }
        row_ptr.push(cols.len());
    }
    let a = SparseMatrix::from_csr(nrows, ncols, row_ptr, cols, vals);
    let x: Vec<Vec3> = (0..nrows).map(|_| rng.vec3(1.0)).collect();
    let expected = a.transpose().apply(&x);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap();
    for par in [Parallelism::Sequential, Parallelism::Rayon] {
        let mut y = vec![Vec3::repeat(99.0); ncols];
        let mut scratch = Vec::new();
        pool.install(|| a.apply_transpose_into(&x, &mut y, &mut scratch, par));
        for (u, v) in y.iter().zip(&expected) {
            assert!((u - v).norm() < 1e-12 * v.norm().max(1.0), "{par:?}");
        }
    }
    assert_eq!(a.apply_transpose(&x).len(), ncols);
}

#[test]
fn mul_scaled_equals_the_product_with_a_row_scaled_copy_bit_for_bit() {
    // Issue 31: the Galerkin product of a large level without a scaled copy of `A`.
    let s = solid(primitives::gear(1.0, 2.0, 2.5, 0.4), BoundaryRule::Sharp, 2);
    let a = s.map().operator(1);
    let mut rng = Rng(5);
    let w: Vec<f64> = (0..a.nrows()).map(|_| 1.0 + rng.sym().abs()).collect();
    let mut vals = a.values().to_vec();
    for i in 0..a.nrows() {
        for v in &mut vals[a.row_ptr()[i]..a.row_ptr()[i + 1]] {
            *v *= w[i];
        }
    }
    let scaled = SparseMatrix::from_csr(
        a.nrows(),
        a.ncols(),
        a.row_ptr().to_vec(),
        a.col_indices().to_vec(),
        vals,
    );
    let t = a.transpose();
    let expected = t.mul(&scaled);
    let got = t.mul_scaled(&w, a);
    assert_eq!(got.row_ptr(), expected.row_ptr());
    assert_eq!(got.col_indices(), expected.col_indices());
    let bits = |m: &SparseMatrix| m.values().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&got), bits(&expected));
}

fn bits(v: &[Vec3]) -> Vec<[u64; 3]> {
    v.iter()
        .map(|x| [x.x.to_bits(), x.y.to_bits(), x.z.to_bits()])
        .collect()
}

/// Issue 31 (session h50): `A x` takes rows two at a time with their entries interleaved; every
/// row must still be the one-row product's bits (rows of unequal lengths, odd and even counts,
/// a last unpaired row, sequential and parallel, `f64` and compact storage).
#[test]
fn paired_row_products_equal_one_row_products_bit_for_bit() {
    let mut rng = Rng(50);
    let s = solid(primitives::gear(1.0, 2.0, 2.5, 0.4), BoundaryRule::Sharp, 2);
    for a in s.map().operators() {
        let x: Vec<Vec3> = (0..a.ncols()).map(|_| rng.vec3(1.0)).collect();
        // Odd and even row counts: all rows, and all but the first.
        for rows in [0..a.nrows(), 1..a.nrows()] {
            let sub = a.select_rows(&rows.clone().map(|i| i as u32).collect::<Vec<_>>());
            let one: Vec<Vec3> = (0..sub.nrows())
                .map(|i| {
                    let mut v = Vec3::zeros();
                    sub.apply_rows_with(i..i + 1, |c| x[c], |_, y| v = y);
                    v
                })
                .collect();
            let compact = vclay_lattice::CompactMatrix::new(&sub).unwrap();
            for par in [Parallelism::Sequential, Parallelism::Rayon] {
                let mut y = vec![Vec3::zeros(); sub.nrows()];
                sub.apply_into(&x, &mut y, par);
                assert_eq!(bits(&y), bits(&one), "{par:?}");
                compact.apply_into(&x, &mut y, par);
                assert_eq!(bits(&y), bits(&one), "compact, {par:?}");
            }
            // Row ranges starting at odd and even rows, of odd and even lengths.
            for r in [0..sub.nrows(), 1..sub.nrows(), 3..sub.nrows() - 2] {
                let mut got = Vec::new();
                sub.apply_rows_with(r.clone(), |c| x[c], |i, v| got.push((i, v)));
                assert_eq!(got.len(), r.len());
                for (i, v) in got {
                    assert_eq!(bits(&[v]), bits(&[one[i]]), "row {i}");
                }
            }
        }
    }
}

/// Issue 31 (session h54): the phased step takes the rows of its first `A^T` level as a list
/// (each thread the rows whose forces it wrote); every row must be the one-row product's bits,
/// whatever row it is paired with (shuffled lists, odd and even lengths, a row repeated).
#[test]
fn row_list_products_equal_one_row_products_bit_for_bit() {
    let mut rng = Rng(54);
    let s = solid(primitives::gear(1.0, 2.0, 2.5, 0.4), BoundaryRule::Sharp, 2);
    for a in s
        .map()
        .operators()
        .iter()
        .chain([&s.map().operator(1).transpose()])
    {
        let x: Vec<Vec3> = (0..a.ncols()).map(|_| rng.vec3(1.0)).collect();
        let one = |i: usize| {
            let mut v = Vec3::zeros();
            a.apply_rows_with(i..i + 1, |c| x[c], |_, y| v = y);
            v
        };
        // A shuffled order of all rows, its odd-length tail, and a list with a repeated row.
        let mut order: Vec<u32> = (0..a.nrows() as u32).collect();
        for i in (1..order.len()).rev() {
            order.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
        }
        let repeated = [order[0], order[1], order[0]];
        for list in [&order[..], &order[1..], &repeated[..]] {
            let mut got = vec![None; list.len()];
            a.apply_row_list_with(list, |c| x[c], |q, v| got[q] = Some(v));
            for (q, v) in got.into_iter().enumerate() {
                let row = list[q] as usize;
                assert_eq!(bits(&[v.unwrap()]), bits(&[one(row)]), "row {row}");
            }
        }
    }
}

/// Issue 31 (session h50): a chain workspace keeps its buffers at their largest size instead of
/// clearing them before every product, so one workspace reused for chains of other sizes must
/// give the bits of a fresh one.
#[test]
fn a_workspace_reused_across_chains_gives_the_bits_of_a_fresh_one() {
    let mut rng = Rng(5);
    let big = solid(
        primitives::box_lattice([3, 3, 3], Vec3::zeros(), Vec3::repeat(1.0)),
        BoundaryRule::Sharp,
        3,
    );
    let small = solid(primitives::gear(1.0, 2.0, 2.5, 0.4), BoundaryRule::Sharp, 2);
    let mut shared = ChainWorkspace::new();
    for (round, s) in [&big, &small, &big, &small].into_iter().enumerate() {
        let map = s.map();
        let p: Vec<Vec3> = (0..map.control_count().unwrap())
            .map(|_| rng.vec3(1.0))
            .collect();
        let f: Vec<Vec3> = (0..map.data_count().unwrap())
            .map(|_| rng.vec3(1.0))
            .collect();
        for par in [Parallelism::Sequential, Parallelism::Rayon] {
            let (mut d0, mut d1) = (vec![Vec3::zeros(); f.len()], vec![Vec3::zeros(); f.len()]);
            map.apply_into(&p, &mut d0, &mut ChainWorkspace::new(), par);
            map.apply_into(&p, &mut d1, &mut shared, par);
            assert_eq!(bits(&d0), bits(&d1), "round {round}, A p, {par:?}");
            let (mut g0, mut g1) = (vec![Vec3::zeros(); p.len()], vec![Vec3::zeros(); p.len()]);
            map.apply_transpose_into(&f, &mut g0, &mut ChainWorkspace::new(), par);
            map.apply_transpose_into(&f, &mut g1, &mut shared, par);
            assert_eq!(bits(&g0), bits(&g1), "round {round}, A^T f, {par:?}");
        }
    }
}

#[test]
fn renumbered_columns_take_the_renumbered_input() {
    // A level operator of a gear (unsorted neighbourhoods) and a scrambled column order:
    // `A P^T` applied to `P x` is `A x`, each row's terms summed in the new column order.
    let s = solid(primitives::gear(1.0, 2.0, 2.5, 0.4), BoundaryRule::Sharp, 2);
    let a = &s.map().operators()[1];
    let n = a.ncols();
    let mut rng = Rng(7);
    let mut order: Vec<u32> = (0..n as u32).collect();
    for i in (1..n).rev() {
        order.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
    }
    let b = a.renumber_columns(&order);
    assert_eq!((b.nrows(), b.ncols(), b.nnz()), (a.nrows(), n, a.nnz()));
    for i in 0..b.nrows() {
        let (c, _) = b.row(i);
        assert!(c.windows(2).all(|w| w[0] < w[1]), "row {i} not sorted");
    }
    let x: Vec<Vec3> = (0..n).map(|_| rng.vec3(1.0)).collect();
    let px: Vec<Vec3> = order.iter().map(|&c| x[c as usize]).collect();
    for (u, v) in a.apply(&x).iter().zip(b.apply(&px)) {
        assert!((u - v).norm() < 1e-13, "{u} against {v}");
    }
}
