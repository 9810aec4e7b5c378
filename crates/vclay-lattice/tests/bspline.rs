//! On a regular hexahedral lattice one level of MacCracken-Joy subdivision is uniform tricubic
//! B-spline refinement (`subdivision-solids-journal.txt` section 3.3: "the subdivision solid of a
//! regular lattice reduces to a standard tri-cubic B-spline solid"): new vertex points use the
//! mask `(1,6,1)/8` in all three directions, edge points `(1,1)/2` along the edge and `(1,6,1)/8`
//! across it, face points `(1,1)/2 x (1,1)/2 x (1,6,1)/8`, cell points `(1,1)/2` cubed. The
//! boundary surface under `Smooth` is bicubic (Catmull-Clark) refinement of the boundary net.

use crate::common;

use std::collections::HashMap;

use common::{perturb, solid};
use vclay_core::Vec3;
use vclay_lattice::{BoundaryRule, Lattice, VertexId, primitives};

const N: usize = 7;

/// The 7 x 7 x 7 grid, perturbed, and the map grid index -> point id.
fn grid() -> (Lattice, HashMap<[usize; 3], VertexId>) {
    let mut l = primitives::box_lattice([N, N, N], Vec3::zeros(), Vec3::repeat((N - 1) as f64));
    let mut ids = HashMap::new();
    for (v, p) in l.points().iter().enumerate() {
        ids.insert(
            [p.x, p.y, p.z].map(|c| c.round() as usize),
            VertexId(v as u32),
        );
    }
    perturb(&mut l, 7, 0.3);
    (l, ids)
}

const W3: [f64; 3] = [0.125, 0.75, 0.125];

/// Tensor-product mask: per axis, (offset, weight) pairs.
fn mask(
    l: &Lattice,
    ids: &HashMap<[usize; 3], VertexId>,
    at: [usize; 3],
    axes: [&[(isize, f64)]; 3],
) -> Vec3 {
    let mut s = Vec3::zeros();
    for &(a, wa) in axes[0] {
        for &(b, wb) in axes[1] {
            for &(c, wc) in axes[2] {
                let g = [
                    (at[0] as isize + a) as usize,
                    (at[1] as isize + b) as usize,
                    (at[2] as isize + c) as usize,
                ];
                s += l.point(ids[&g]) * (wa * wb * wc);
            }
        }
    }
    s
}

const CUBIC: [(isize, f64); 3] = [(-1, W3[0]), (0, W3[1]), (1, W3[2])];
const HALF: [(isize, f64); 2] = [(0, 0.5), (1, 0.5)];
const ONE: [(isize, f64); 1] = [(0, 1.0)];

fn check_interior(rule: BoundaryRule) {
    let (l, ids) = grid();
    let s = solid(l.clone(), rule, 1);
    let fine = s.finest();
    let (np, ne, nf) = (l.num_points(), l.num_edges(), l.num_faces());
    let tol = 1e-12;
    let inner = 1..N - 1;
    let mut checked = [0usize; 4];
    // Vertex points.
    for (g, &v) in &ids {
        if g.iter().all(|x| inner.contains(x)) {
            let want = mask(&l, &ids, *g, [&CUBIC, &CUBIC, &CUBIC]);
            assert!((fine.point(v) - want).norm() < tol, "vertex {g:?}");
            checked[0] += 1;
        }
    }
    // Edge points: along axis `d` from grid point g, the two other indices interior.
    for e in 0..ne {
        let [a, b] = l.edge_vertices(vclay_lattice::EdgeId(e as u32));
        let (ga, gb) = (grid_of(&ids, a), grid_of(&ids, b));
        let d = (0..3).find(|&k| ga[k] != gb[k]).unwrap();
        let lo = if ga[d] < gb[d] { ga } else { gb };
        if (0..3).filter(|&k| k != d).all(|k| inner.contains(&lo[k])) {
            let mut axes: [&[(isize, f64)]; 3] = [&CUBIC, &CUBIC, &CUBIC];
            axes[d] = &HALF;
            let want = mask(&l, &ids, lo, axes);
            assert!(
                (fine.points()[np + e] - want).norm() < tol,
                "edge {lo:?} axis {d}"
            );
            checked[1] += 1;
        }
    }
    // Face points: normal axis `d` interior.
    for f in 0..nf {
        let vs = l.face_vertices(vclay_lattice::FaceId(f as u32));
        let gs: Vec<[usize; 3]> = vs.iter().map(|&v| grid_of(&ids, v)).collect();
        let d = (0..3)
            .find(|&k| gs.iter().all(|g| g[k] == gs[0][k]))
            .unwrap();
        let lo = [0, 1, 2].map(|k| gs.iter().map(|g| g[k]).min().unwrap());
        if inner.contains(&lo[d]) {
            let mut axes: [&[(isize, f64)]; 3] = [&HALF, &HALF, &HALF];
            axes[d] = &CUBIC;
            let want = mask(&l, &ids, lo, axes);
            assert!(
                (fine.points()[np + ne + f] - want).norm() < tol,
                "face {lo:?}"
            );
            checked[2] += 1;
        }
    }
    // Cell points: all cells.
    for c in 0..l.num_cells() {
        let vs = l.cell_vertices(vclay_lattice::CellId(c as u32));
        let lo = [0, 1, 2].map(|k| vs.iter().map(|&v| grid_of(&ids, v)[k]).min().unwrap());
        let want = mask(&l, &ids, lo, [&HALF, &HALF, &HALF]);
        assert!((fine.points()[np + ne + nf + c] - want).norm() < tol);
        checked[3] += 1;
    }
    // 5^3 interior vertices; 3 * 6 * 5 * 5 edges; 3 * 5 * 6 * 6 faces; 6^3 cells.
    assert_eq!(checked, [125, 450, 540, 216]);
}

fn grid_of(ids: &HashMap<[usize; 3], VertexId>, v: VertexId) -> [usize; 3] {
    *ids.iter().find(|(_, id)| **id == v).unwrap().0
}

#[test]
fn interior_points_are_tricubic_bspline_refinement_interior_rule() {
    check_interior(BoundaryRule::Interior);
}

#[test]
fn interior_points_are_tricubic_bspline_refinement_smooth_rule() {
    check_interior(BoundaryRule::Smooth);
}

#[test]
fn smooth_boundary_is_bicubic_refinement_of_the_boundary_net() {
    let (l, ids) = grid();
    let s = solid(l.clone(), BoundaryRule::Smooth, 1);
    let fine = s.finest();
    let np = l.num_points();
    let inner = 1..N - 1;
    let mut n = 0;
    // Boundary vertices in the interior of the z = 0 side.
    for (g, &v) in &ids {
        if g[2] == 0 && inner.contains(&g[0]) && inner.contains(&g[1]) {
            let want = mask(&l, &ids, *g, [&CUBIC, &CUBIC, &ONE]);
            assert!((fine.point(v) - want).norm() < 1e-12, "vertex {g:?}");
            n += 1;
        }
    }
    // Boundary edges along x in the z = 0 side, y interior: (1,1)/2 x (1,6,1)/8.
    for e in 0..l.num_edges() {
        let [a, b] = l.edge_vertices(vclay_lattice::EdgeId(e as u32));
        let (ga, gb) = (grid_of(&ids, a), grid_of(&ids, b));
        if ga[2] == 0 && gb[2] == 0 && ga[1] == gb[1] && inner.contains(&ga[1]) {
            let lo = if ga[0] < gb[0] { ga } else { gb };
            let want = mask(&l, &ids, lo, [&HALF, &CUBIC, &ONE]);
            assert!((fine.points()[np + e] - want).norm() < 1e-12, "edge {lo:?}");
            n += 1;
        }
    }
    assert_eq!(n, 25 + 30);
}
