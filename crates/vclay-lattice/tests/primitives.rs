//! Primitive lattices and boundary surface extraction.

use crate::common;

use std::collections::HashMap;

use vclay_core::{TriMesh, Vec3};
use vclay_lattice::{BoundaryRule, CellId, Lattice, boundary_mesh, primitives, write_boundary};

fn total_volume(l: &Lattice) -> f64 {
    (0..l.num_cells())
        .map(|c| l.cell_signed_volume(CellId(c as u32)))
        .sum()
}

/// Checks that the mesh is closed and consistently oriented; returns its enclosed volume.
fn closed_mesh_volume(m: &TriMesh) -> f64 {
    m.validate().unwrap();
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for t in &m.triangles {
        for i in 0..3 {
            *directed.entry((t[i], t[(i + 1) % 3])).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &directed {
        assert_eq!(n, 1, "directed edge ({a}, {b}) used {n} times");
        assert_eq!(
            directed.get(&(b, a)),
            Some(&1),
            "edge ({a}, {b}) has no twin"
        );
    }
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            a.dot(&b.cross(&c)) / 6.0
        })
        .sum()
}

#[test]
fn primitives_are_valid_with_expected_sizes_and_volumes() {
    let b = primitives::box_lattice([3, 4, 5], Vec3::zeros(), Vec3::new(2.0, 3.0, 4.0));
    assert_eq!(b.counts().to_array()[0], 60);
    assert_eq!(b.num_cells(), 2 * 3 * 4);
    assert!((total_volume(&b) - 24.0).abs() < 1e-12);

    let c = primitives::cylinder(1.0, 2.0, 8, 3, 2);
    // 8 wedges + 2 rings of 8 hexahedra, 3 layers.
    assert_eq!(c.num_cells(), 3 * (8 + 16));
    assert_eq!(c.num_points(), 4 * (1 + 3 * 8));
    let octagon = 0.5 * 8.0 * (2.0 * std::f64::consts::PI / 8.0).sin();
    assert!((total_volume(&c) - 2.0 * octagon).abs() < 1e-12);

    let t = primitives::torus(3.0, 1.0, 12, 2);
    assert_eq!(t.num_cells(), 12 * 4);
    assert_eq!(t.counts().euler_characteristic(), 0);

    let l = primitives::l_solid(2, 1, 1.0);
    assert_eq!(l.num_cells(), 5);
    let tt = primitives::t_solid(2, 1, 1.0);
    assert_eq!(tt.num_cells(), 7);
    let h = primitives::cube_with_holes(1.0);
    assert!((total_volume(&h) - 20.0).abs() < 1e-12);
    // A solid handlebody of genus g has Euler characteristic 1 - g: the cube with three crossing
    // tunnels has genus 5 (the first Menger sponge step), a solid torus genus 1.
    assert_eq!(h.counts().euler_characteristic(), -4);
    let g = primitives::gear(1.0, 2.0, 2.6, 0.5);
    assert_eq!(g.counts().euler_characteristic(), 0);
    for lat in [b, c, t, l, tt, h, g] {
        lat.validate().unwrap();
        for cell in 0..lat.num_cells() {
            assert!(lat.cell_signed_volume(CellId(cell as u32)) > 0.0);
        }
    }
}

#[test]
fn boundary_mesh_is_closed_outward_and_encloses_the_lattice() {
    for l in [
        primitives::box_lattice([3, 3, 3], Vec3::zeros(), Vec3::repeat(2.0)),
        primitives::cylinder(1.0, 1.0, 6, 2, 1),
        primitives::torus(3.0, 1.0, 8, 1),
        primitives::cube_with_holes(1.0),
        primitives::t_solid(1, 2, 0.5),
    ] {
        let m = boundary_mesh(&l);
        let v = closed_mesh_volume(&m);
        assert!((v - total_volume(&l)).abs() < 1e-10, "{v}");
        // Only boundary points are emitted.
        let used: usize = (0..l.num_points())
            .filter(|&i| l.is_boundary_vertex(vclay_lattice::VertexId(i as u32)))
            .count();
        assert_eq!(m.positions.len(), used);
    }
}

#[test]
fn subdivided_boundary_is_closed_and_sharp_box_keeps_its_volume() {
    let s = common::solid(
        primitives::box_lattice([3, 3, 3], Vec3::zeros(), Vec3::repeat(2.0)),
        BoundaryRule::Sharp,
        2,
    );
    let mut m = TriMesh::new();
    let n = write_boundary(s.finest(), &mut m);
    // 6 sides x (2 x 2 quads) x 16 per quad after two levels, two triangles each.
    assert_eq!(n, 6 * 4 * 16 * 2);
    assert!((closed_mesh_volume(&m) - 8.0).abs() < 1e-10);
    // Smooth rounds the box: the volume shrinks, the surface stays closed.
    let s = common::solid(
        primitives::box_lattice([3, 3, 3], Vec3::zeros(), Vec3::repeat(2.0)),
        BoundaryRule::Smooth,
        2,
    );
    let v = closed_mesh_volume(&boundary_mesh(s.finest()));
    assert!(v < 8.0 && v > 4.0, "{v}");
}

#[test]
fn moving_control_points_updates_every_level() {
    let mut s = common::solid(primitives::l_solid(1, 1, 1.0), BoundaryRule::Smooth, 2);
    let moved: Vec<Vec3> = s
        .control()
        .points()
        .iter()
        .map(|p| p * 2.0 + Vec3::new(1.0, 0.0, 0.0))
        .collect();
    let before = s.finest().points().to_vec();
    s.set_control_points(moved);
    for (a, b) in s.finest().points().iter().zip(&before) {
        assert!((a - (b * 2.0 + Vec3::new(1.0, 0.0, 0.0))).norm() < 1e-12);
    }
}

/// `subdivision-solids-conference.txt` Table 1, "Tetrahedron w/ holes": one non-convex cell of
/// genus 3 whose boundary is closed and outward; its volume lies between the hollow's and the
/// tetrahedron's and shrinks as the holes grow.
#[test]
fn tetrahedron_with_holes_is_one_closed_genus_three_cell() {
    let edge = 2.0;
    let full = edge * edge * edge / (6.0 * 2f64.sqrt());
    let mut last = full;
    for hole in [0.2, 0.5, 0.8] {
        let l = primitives::tetrahedron_with_holes(edge, hole);
        l.validate().unwrap();
        assert_eq!(l.counts().to_array(), [16, 42, 22, 1]);
        let v = l.cell_signed_volume(CellId(0));
        assert!(
            v > 0.0 && v < last,
            "hole {hole}: volume {v}, previous {last}"
        );
        last = v;
        let m = boundary_mesh(&l);
        assert!((closed_mesh_volume(&m) - v).abs() < 1e-12 * full);
        // A closed surface of genus 3 has Euler characteristic 2 - 2 * 3 = -4.
        let (p, e, f) = (l.num_points(), l.num_edges(), l.num_faces());
        assert_eq!(p as i64 - e as i64 + f as i64, -4);
        // Every corner point has degree 6 (3 tetrahedron edges, 3 hole edges), every hole point 5.
        let degrees: Vec<usize> = (0..p)
            .map(|i| l.vertex_edges(vclay_lattice::VertexId(i as u32)).len())
            .collect();
        assert_eq!(degrees.iter().filter(|&&d| d == 6).count(), 4);
        assert_eq!(degrees.iter().filter(|&&d| d == 5).count(), 12);
    }
    // Subdivided, it stays closed.
    let s = common::solid(
        primitives::tetrahedron_with_holes(edge, 0.5),
        BoundaryRule::Smooth,
        2,
    );
    let v = closed_mesh_volume(&boundary_mesh(s.finest()));
    assert!(v > 0.0 && v < full, "{v}");
}
