//! Element counts: `subdivision-solids-conference.txt` Table 1 and the level-to-level recurrences.
//!
//! Table 1's "Cube (3^3)" is the lattice of 3 x 3 x 3 *points* (its control row reads 27 points,
//! 54 edges, 36 faces, 8 cells), "Cube (4^3)" that of 4 x 4 x 4 points (64, 144, 108, 27).

use crate::common;

use common::solid;
use vclay_core::Vec3;
use vclay_lattice::{BoundaryRule, Lattice, cells, primitives};

fn counts_after(l: Lattice, levels: usize) -> [usize; 4] {
    solid(l, BoundaryRule::Smooth, levels)
        .finest()
        .counts()
        .to_array()
}

#[test]
fn table1_cube_3_cubed() {
    let l = primitives::box_lattice([3, 3, 3], Vec3::zeros(), Vec3::repeat(2.0));
    assert_eq!(l.counts().to_array(), [27, 54, 36, 8]);
    let s = solid(l, BoundaryRule::Smooth, 3);
    assert_eq!(s.lattice(2).counts().to_array(), [729, 1944, 1728, 512]);
    assert_eq!(s.lattice(3).counts().to_array(), [4913, 13872, 13056, 4096]);
}

#[test]
fn table1_cube_4_cubed() {
    let l = primitives::box_lattice([4, 4, 4], Vec3::zeros(), Vec3::repeat(3.0));
    assert_eq!(l.counts().to_array(), [64, 144, 108, 27]);
    let s = solid(l, BoundaryRule::Smooth, 2);
    assert_eq!(s.lattice(1).counts().to_array(), [343, 882, 756, 216]);
    assert_eq!(s.lattice(2).counts().to_array(), [2197, 6084, 5616, 1728]);
}

#[test]
fn table1_cylinder() {
    let l = primitives::cylinder(1.0, 2.0, 4, 2, 0);
    assert_eq!(l.counts().to_array(), [15, 34, 28, 8]);
    assert_eq!(counts_after(l, 3), [3553, 10144, 9664, 3072]);
}

#[test]
fn table1_torus() {
    let l = primitives::paper_torus(1.0, 2.0, 0.5);
    assert_eq!(l.counts().to_array(), [24, 52, 36, 8]);
    let s = solid(l, BoundaryRule::Smooth, 3);
    assert_eq!(s.lattice(2).counts().to_array(), [680, 1784, 1552, 448]);
    assert_eq!(s.lattice(3).counts().to_array(), [4464, 12464, 11584, 3584]);
}

#[test]
fn table1_gear() {
    let l = primitives::gear(1.0, 2.0, 2.6, 0.5);
    assert_eq!(l.counts().to_array(), [56, 116, 76, 16]);
    assert_eq!(counts_after(l, 2), [1480, 3864, 3344, 960]);
}

#[test]
fn table1_cube_with_holes() {
    let l = primitives::cube_with_holes(1.0);
    assert_eq!(l.counts().to_array(), [64, 144, 96, 20]);
    assert_eq!(counts_after(l, 2), [1900, 5040, 4416, 1280]);
}

#[test]
fn table1_tetrahedron_with_holes() {
    let l = primitives::tetrahedron_with_holes(2.0, 0.5);
    assert_eq!(l.counts().to_array(), [16, 42, 22, 1]);
    assert_eq!(counts_after(l, 3), [2505, 6808, 6048, 1744]);
}

/// The recurrences derived in `subdivide.rs`:
/// `P' = P + E + F + C`, `E' = 2E + sum_f k_f + sum_c faces(c)`,
/// `F' = sum_f k_f + sum_c edges(c)`, `C' = sum_c vertices(c)`.
fn predicted(l: &Lattice) -> [usize; 4] {
    let k: usize = (0..l.num_faces())
        .map(|f| l.face_vertices(vclay_lattice::FaceId(f as u32)).len())
        .sum();
    let (mut cf, mut ce, mut cv) = (0, 0, 0);
    for c in 0..l.num_cells() {
        let c = vclay_lattice::CellId(c as u32);
        cf += l.cell_faces(c).len();
        ce += l.cell_edges(c).len();
        cv += l.cell_vertices(c).len();
    }
    let [p, e, f, c] = l.counts().to_array();
    [p + e + f + c, 2 * e + k + cf, k + ce, cv]
}

/// A hexahedron, a prism on its top, a pyramid on its side and a tetrahedron on the pyramid.
pub fn mixed() -> Lattice {
    let mut pts = vec![];
    for z in [0.0, 1.0] {
        for (x, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
            pts.push(Vec3::new(x, y, z));
        }
    }
    pts.push(Vec3::new(0.0, 0.5, 1.8)); // 8: prism ridge
    pts.push(Vec3::new(1.0, 0.5, 1.8)); // 9
    pts.push(Vec3::new(1.8, 0.5, 0.5)); // 10: pyramid apex on the x = 1 side
    pts.push(Vec3::new(1.6, 1.4, 1.3)); // 11: tetrahedron tip
    let mut cs = vec![cells::hexahedron([0, 1, 2, 3, 4, 5, 6, 7])];
    // Prism along x over the top face: cross-sections 4-7-8 (x = 0) and 5-6-9 (x = 1).
    cs.push(cells::prism(&[4, 7, 8], &[5, 6, 9]));
    // Pyramid on face 1-2-6-5 (counter-clockwise seen from +x), apex 10.
    cs.push(cells::pyramid([1, 2, 6, 5, 10]));
    // Tetrahedron on the pyramid's face 2-6-10.
    cs.push(cells::tetrahedron([2, 6, 10, 11]));
    Lattice::from_cells(pts, &cs).unwrap()
}

#[test]
fn recurrences_hold_for_mixed_cells() {
    let l = mixed();
    assert_eq!(l.num_cells(), 4);
    let mut cur = l;
    for level in 0..3 {
        let want = predicted(&cur);
        let s = solid(cur.clone(), BoundaryRule::Smooth, 1);
        let got = s.finest().counts().to_array();
        assert_eq!(got, want, "level {level}");
        s.finest().validate().unwrap();
        // The Euler characteristic of a subdivided complex is unchanged.
        assert_eq!(
            s.finest().counts().euler_characteristic(),
            cur.counts().euler_characteristic()
        );
        cur = s.finest().clone();
    }
}

#[test]
fn recurrences_hold_for_extruded_polygons() {
    // Pentagonal and triangular prisms side by side, two layers.
    let prof = [
        [0.0, 0.0],
        [1.0, 0.0],
        [1.3, 0.8],
        [0.5, 1.3],
        [-0.3, 0.8],
        [0.5, -0.9],
    ];
    let l = primitives::extrude(
        &prof,
        &[vec![0, 1, 2, 3, 4], vec![0, 5, 1]],
        &[0.0, 0.5, 1.0],
    )
    .unwrap();
    let want = predicted(&l);
    let s = solid(l, BoundaryRule::Sharp, 1);
    assert_eq!(s.finest().counts().to_array(), want);
    // A pentagonal prism gives 10 cells, a triangular one 6: 2 layers -> 32.
    assert_eq!(want[3], 32);
}

#[test]
fn pyramid_apex_cell_has_eight_faces() {
    // The new cell at the apex of a pyramid (4 faces meet there) is an 8-faced cell.
    let pts = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.5, 0.5, 1.0),
    ];
    let l = Lattice::from_cells(pts, &[cells::pyramid([0, 1, 2, 3, 4])]).unwrap();
    let s = solid(l, BoundaryRule::Smooth, 1);
    let f = s.finest();
    assert_eq!(f.num_cells(), 5);
    let mut sizes: Vec<usize> = (0..5)
        .map(|c| f.cell_faces(vclay_lattice::CellId(c)).len())
        .collect();
    sizes.sort();
    assert_eq!(sizes, vec![6, 6, 6, 6, 8]);
    f.validate().unwrap();
}
