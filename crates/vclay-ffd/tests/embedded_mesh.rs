//! Tests of `EmbeddedMesh`: identity at rest, agreement with point-wise evaluation, vertices
//! outside the lattice untouched, incremental update equal to full recomputation, parallel equal
//! to sequential.

use crate::common;

use common::{Lcg, jiggle, lattice, specs, test_box};
use vclay_core::{Parallelism, TriMesh, Vec3};
use vclay_ffd::{
    EmbeddedMesh, FfdLattice, LatticeSpec, Manipulation, PointConstraint, SolveOptions,
    WeightChange, WeightOptions,
};

/// A random "mesh": points in a box 1.5 times the test box (so some are outside), triangles over
/// consecutive vertices.
fn random_mesh(rng: &mut Lcg, n: usize, grow: f64) -> TriMesh {
    let (lo, hi) = test_box();
    let c = 0.5 * (lo + hi);
    let h = 0.5 * (hi - lo) * grow;
    let mut m = TriMesh::new();
    m.positions = (0..n)
        .map(|_| {
            c + Vec3::new(
                rng.range(-h.x, h.x),
                rng.range(-h.y, h.y),
                rng.range(-h.z, h.z),
            )
        })
        .collect();
    m.triangles = (0..n as u32 - 2)
        .step_by(3)
        .map(|i| [i, i + 1, i + 2])
        .collect();
    m
}

fn max_diff(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max)
}

#[test]
fn rest_lattice_leaves_every_vertex_unchanged() {
    let mut rng = Lcg::new(31);
    for spec in specs() {
        let l = lattice(spec);
        let mesh = random_mesh(&mut rng, 3000, 1.0);
        let e = EmbeddedMesh::new(&l, mesh.clone(), Parallelism::Auto);
        assert_eq!(e.embedded_count(), 3000);
        assert!(max_diff(&e.mesh().positions, &mesh.positions) < 1e-12 * l.size());
        assert_eq!(e.mesh().normals.len(), 3000);
    }
}

#[test]
fn deformed_vertices_match_pointwise_evaluation_and_outside_ones_stay() {
    let mut rng = Lcg::new(32);
    for spec in specs() {
        let mut l = lattice(spec);
        let mesh = random_mesh(&mut rng, 4000, 1.5);
        let mut e = EmbeddedMesh::new(&l, mesh.clone(), Parallelism::Sequential);
        assert!(e.embedded_count() > 0 && e.embedded_count() < 4000);
        jiggle(&mut l, &mut rng, 0.2);
        for rational in [false, true] {
            if rational {
                let w = (0..l.control_point_count())
                    .map(|_| rng.range(0.5, 2.0))
                    .collect();
                l.set_weights(w).unwrap();
            }
            e.deform(&l, Parallelism::Sequential);
            for (v, (x, y)) in mesh.positions.iter().zip(&e.mesh().positions).enumerate() {
                if e.is_embedded(v) {
                    assert!((l.deform_point(x) - y).norm() < 1e-13 * l.size());
                    assert_eq!(e.parameters(v), l.parameters(x));
                } else {
                    assert_eq!(x, y, "outside vertex {v} moved");
                    assert_eq!(e.parameters(v), None);
                }
            }
        }
    }
}

#[test]
fn parallel_equals_sequential() {
    let mut rng = Lcg::new(33);
    let mut l = lattice(LatticeSpec::uniform(3, 6));
    let mesh = random_mesh(&mut rng, 40_000, 1.2);
    let mut a = EmbeddedMesh::new(&l, mesh.clone(), Parallelism::Sequential);
    let mut b = EmbeddedMesh::new(&l, mesh, Parallelism::Rayon);
    jiggle(&mut l, &mut rng, 0.2);
    a.deform(&l, Parallelism::Sequential);
    b.deform(&l, Parallelism::Rayon);
    assert_eq!(a.mesh(), b.mesh());
}

#[test]
fn incremental_update_equals_full_recomputation() {
    let mut rng = Lcg::new(34);
    for spec in specs() {
        let mut l = lattice(spec);
        jiggle(&mut l, &mut rng, 0.05);
        let mesh = random_mesh(&mut rng, 5000, 1.2);
        let mut inc = EmbeddedMesh::new(&l, mesh.clone(), Parallelism::Auto);
        for step in 0..6 {
            let changed: Vec<usize> = match step % 3 {
                0 => {
                    let c = PointConstraint::new(rng.params(), l.point_at(rng.params()).unwrap());
                    let m = Manipulation::single(&l, &c).unwrap();
                    l.apply(&m);
                    m.indices().to_vec()
                }
                1 => {
                    let cs: Vec<PointConstraint> = (0..2)
                        .map(|_| {
                            let t = rng.params();
                            PointConstraint::new(t, l.point_at(t).unwrap() + rng.vec(0.1))
                        })
                        .collect();
                    let m = Manipulation::multi(&l, &cs, &SolveOptions::least_squares()).unwrap();
                    l.apply(&m);
                    m.indices().to_vec()
                }
                _ => {
                    let t = rng.params();
                    let c = PointConstraint::new(t, l.point_at(t).unwrap() + rng.vec(0.01));
                    let w = WeightChange::single(&l, &c, &WeightOptions::default()).unwrap();
                    w.apply(&mut l).unwrap();
                    w.indices().to_vec()
                }
            };
            let recomputed = inc.update(&l, &changed, Parallelism::Auto);
            assert!(recomputed <= inc.embedded_count());
            let full = EmbeddedMesh::new(&l, mesh.clone(), Parallelism::Auto);
            // Equal to rounding: once a weight differs from 1 the lattice switches to the
            // homogeneous (rational) kernel, which rounds differently for untouched vertices.
            let diff = max_diff(&inc.mesh().positions, &full.mesh().positions);
            assert!(diff < 1e-13 * l.size(), "{spec:?} step {step}: {diff}");
            assert!(max_diff(&inc.mesh().normals, &full.mesh().normals) < 1e-12);
        }
    }
}

#[test]
fn incremental_update_touches_only_the_local_vertices() {
    let mut rng = Lcg::new(35);
    let mut l = lattice(LatticeSpec::uniform(3, 10));
    let mesh = random_mesh(&mut rng, 20_000, 1.0);
    let mut e = EmbeddedMesh::new(&l, mesh, Parallelism::Auto);
    let before = e.mesh().positions.clone();
    let t = [0.1, 0.1, 0.1];
    let m = Manipulation::single_displacement(&l, t, Vec3::new(0.1, 0.0, 0.0)).unwrap();
    l.apply(&m);
    let n = e.update(&l, m.indices(), Parallelism::Auto);
    // A cubic 10^3 lattice has 7 knot cells per axis. The support of t = 0.1 is control points
    // 0..=3 per axis, which influence cells 0..=3: 4^3 of the 7^3 cells, under half the volume.
    assert!(
        n > 0 && n < e.embedded_count() / 2,
        "{n} of {}",
        e.embedded_count()
    );
    let moved = e
        .mesh()
        .positions
        .iter()
        .zip(&before)
        .filter(|(a, b)| a != b)
        .count();
    assert!(moved > 0 && moved <= n);
    assert_eq!(e.update(&l, &[], Parallelism::Auto), 0);
}

#[test]
fn partial_embedding_of_a_mesh() {
    // Only the part of a mesh inside the box deforms (paper Fig. 6: "the lattice embeds only the
    // middle part of the head").
    let mut rng = Lcg::new(36);
    let mesh = random_mesh(&mut rng, 3000, 3.0);
    let (lo, hi) = test_box();
    let mut l = FfdLattice::new(LatticeSpec::default(), lo, hi).unwrap();
    let mut e = EmbeddedMesh::new(&l, mesh.clone(), Parallelism::Auto);
    let inside = mesh.positions.iter().filter(|x| l.contains(x)).count();
    assert_eq!(e.embedded_count(), inside);
    jiggle(&mut l, &mut rng, 0.3);
    e.set_recompute_normals(false);
    e.deform(&l, Parallelism::Auto);
    for (v, (x, y)) in mesh.positions.iter().zip(&e.mesh().positions).enumerate() {
        if !l.contains(x) {
            assert_eq!(x, y, "vertex {v}");
        }
    }
    assert!(e.mesh().normals.len() == 3000); // from the initial embedding, not recomputed
    assert_eq!(e.rest_positions(), &mesh.positions[..]);
}

#[test]
#[should_panic(expected = "another shape")]
fn using_another_lattice_panics() {
    let l = lattice(LatticeSpec::uniform(3, 4));
    let mut e = EmbeddedMesh::new(
        &l,
        random_mesh(&mut Lcg::new(1), 30, 1.0),
        Parallelism::Auto,
    );
    e.deform(&lattice(LatticeSpec::uniform(3, 5)), Parallelism::Auto);
}

/// The blocked kernel (groups of `LANES` vertices of one knot cell) agrees with the per-vertex
/// kernel on a mesh whose consecutive vertices are neighbours (so most groups are blocked), with
/// vertices outside the box interleaved (so some groups are not), for full and incremental
/// deformation.
#[test]
fn blocked_kernel_equals_per_vertex_kernel() {
    let mut rng = Lcg::new(35);
    let (lo, hi) = test_box();
    let mut mesh = TriMesh::new();
    let n = 13;
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                let t = Vec3::new(i as f64, j as f64, k as f64) / (n - 1) as f64;
                // Every 7th point is pushed outside the box.
                let out = if (i * n * n + j * n + k) % 7 == 3 {
                    1.2
                } else {
                    1.0
                };
                mesh.positions
                    .push(lo + (hi - lo).component_mul(&(t * out)));
            }
        }
    }
    let m = mesh.positions.len() as u32;
    mesh.triangles = (0..m - 2).step_by(3).map(|i| [i, i + 1, i + 2]).collect();
    for spec in specs() {
        let mut l = lattice(spec);
        jiggle(&mut l, &mut rng, 0.1);
        for par in [Parallelism::Sequential, Parallelism::Rayon] {
            let mut blocked = EmbeddedMesh::new(&l, mesh.clone(), par);
            let mut single = blocked.clone();
            single.set_blocked_kernel(false);
            single.deform(&l, par);
            let tol = 1e-13 * l.size();
            assert!(max_diff(&blocked.mesh().positions, &single.mesh().positions) < tol);
            let c = PointConstraint::new(rng.params(), rng.vec(1.0) + lo);
            let manip = Manipulation::single(&l, &c).unwrap();
            let mut l2 = l.clone();
            l2.apply(&manip);
            let nb = blocked.update(&l2, manip.indices(), par);
            let ns = single.update(&l2, manip.indices(), par);
            assert_eq!(nb, ns);
            assert!(max_diff(&blocked.mesh().positions, &single.mesh().positions) < tol);
        }
    }
}
