//! The papers' galleries (issue 19): the soccer player and the cactus of
//! `subdivision-solids-conference.txt` Table 1 / Fig. 1, the spiked and holed objects of
//! `subdivision-solids-journal.txt` Table 2, and valid cells for every primitive.

use crate::common;

use common::solid;
use vclay_core::Vec3;
use vclay_lattice::command::{PRIMITIVE_NAMES, primitive};
use vclay_lattice::gallery::{self, Sculptor};
use vclay_lattice::{BoundaryRule, CellId, Lattice, primitives};

/// Cells of `l` whose signed volume is not positive.
fn folded(l: &Lattice) -> usize {
    (0..l.num_cells())
        .filter(|&c| l.cell_signed_volume(CellId::new(c)) <= 0.0)
        .count()
}

/// Number of face-connected pieces of `l`.
fn pieces(l: &Lattice) -> usize {
    let n = l.num_cells();
    let mut label = vec![usize::MAX; n];
    let mut count = 0;
    for start in 0..n {
        if label[start] != usize::MAX {
            continue;
        }
        let mut stack = vec![start];
        label[start] = count;
        while let Some(c) = stack.pop() {
            for &f in l.cell_faces(CellId::new(c)) {
                for d in l.face_cells(f).into_iter().flatten() {
                    if label[d.index()] == usize::MAX {
                        label[d.index()] = count;
                        stack.push(d.index());
                    }
                }
            }
        }
        count += 1;
    }
    count
}

fn extent(l: &Lattice) -> Vec3 {
    let (mut lo, mut hi) = (Vec3::repeat(f64::INFINITY), Vec3::repeat(f64::NEG_INFINITY));
    for p in l.points() {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    hi - lo
}

fn is_all_hex(l: &Lattice) -> bool {
    (0..l.num_cells()).all(|c| {
        let c = CellId::new(c);
        l.cell_faces(c).len() == 6 && l.cell_vertices(c).len() == 8
    })
}

#[test]
fn table1_soccer_player() {
    let l = gallery::soccer_player(2.0);
    assert_eq!(l.counts().to_array(), [104, 200, 122, 24]);
    assert!(is_all_hex(&l));
    // The player and the ball.
    assert_eq!(pieces(&l), 2);
    let e = extent(&l);
    assert!((e.z - 2.0).abs() < 0.05, "height {}", e.z);
    assert!(
        e.x < 0.7 * e.z && e.y < 0.7 * e.z,
        "a standing figure: {e:?}"
    );
    let s = solid(l, BoundaryRule::Smooth, 2);
    assert_eq!(s.lattice(2).counts().to_array(), [2450, 6320, 5408, 1536]);
}

#[test]
fn table1_cactus() {
    let l = gallery::cactus(4.0);
    assert_eq!(l.counts().to_array(), [108, 212, 131, 26]);
    assert!(is_all_hex(&l));
    assert_eq!(pieces(&l), 1);
    let e = extent(&l);
    assert!((e.z - 4.0).abs() < 0.05, "height {}", e.z);
    // The arms reach out on both sides of the trunk.
    assert!(e.x > 0.35 * e.z, "{e:?}");
    let s = solid(l, BoundaryRule::Smooth, 2);
    assert_eq!(s.lattice(2).counts().to_array(), [2625, 6800, 5840, 1664]);
}

#[test]
fn table2_spiked_and_holed_objects() {
    let spiked = gallery::spiked_object(1.0);
    assert_eq!(spiked.num_cells(), 75);
    assert!(is_all_hex(&spiked));
    // 27 cubes, 48 extrusions of 4 points each.
    assert_eq!(spiked.num_points(), 64 + 48 * 4);
    let holed = gallery::holed_object(1.0);
    assert_eq!(holed.num_cells(), 135);
    assert!(is_all_hex(&holed));
    // Genus 4: V - E + F - C = 1 - 4.
    assert_eq!(holed.counts().euler_characteristic(), -3);
    assert_eq!(
        solid(spiked, BoundaryRule::Smooth, 1).finest().num_cells(),
        600
    );
    assert_eq!(
        solid(holed, BoundaryRule::Smooth, 1).finest().num_cells(),
        1080
    );
}

/// Issue 19: the tetrahedron with holes folded (984 of 1,744 cells at level 3); every shipped
/// primitive now keeps every cell's volume positive at levels 1-3 (level 3 for the small ones)
/// with the smooth boundary rule (`vclay subdivide`'s default) and the sharp one.
///
/// Not covered: the sharp rule folds 32 of the level-3 cells of the paper's torus and gear
/// (their crease curves at the triangular corners), and the interior rule (volumetric rules on
/// the boundary too) folds the corner cells of every lattice with boundary corners, a box
/// included (docs/formats.md, `vclay subdivide`).
#[test]
fn no_primitive_folds() {
    for &name in PRIMITIVE_NAMES {
        if name == "tetrahedron-with-holes-paper" {
            continue;
        }
        let l = primitive(name).unwrap();
        assert_eq!(folded(&l), 0, "{name} level 0");
        let levels = if l.num_cells() <= 30 { 3 } else { 2 };
        for rule in [BoundaryRule::Smooth, BoundaryRule::Sharp] {
            if rule == BoundaryRule::Sharp && (name == "paper-torus" || name == "gear") {
                continue;
            }
            let s = solid(l.clone(), rule, levels);
            for k in 1..=levels {
                let f = folded(s.lattice(k));
                assert_eq!(f, 0, "{name} {rule:?} level {k}: {f} folded cells");
            }
        }
    }
}

/// Issue 28: `vclay subdivide --primitive soccer-player --levels 4` folded 35 cells (290 at
/// level 5), all in the boundary layer of the two upper arms at the armpit: the upper arm's far
/// face lay above the armpit corner, so the cell's inner edges rose from it (a sheared sliver).
/// The recipe now hangs the arm below the armpit; no cell folds at level 4 with the smooth
/// rule (level 5, 786,432 cells, is measured with the release CLI: docs/formats.md). The
/// worst scaled cell volume (volume over the cube of the cell's diameter) also stays above the
/// level-3 value of the folding recipe (2.6e-3; 1.3e-2 now).
#[test]
fn soccer_player_does_not_fold_at_level_4() {
    let s = solid(gallery::soccer_player(2.0), BoundaryRule::Smooth, 4);
    let quality = |l: &Lattice| {
        (0..l.num_cells())
            .map(|c| {
                let c = CellId::new(c);
                let p: Vec<Vec3> = l.cell_vertices(c).iter().map(|&v| l.point(v)).collect();
                let d = p
                    .iter()
                    .flat_map(|a| p.iter().map(move |b| (a - b).norm()))
                    .fold(0.0, f64::max);
                l.cell_signed_volume(c) / d.powi(3)
            })
            .fold(f64::INFINITY, f64::min)
    };
    assert!(quality(s.lattice(3)) > 1e-2, "{}", quality(s.lattice(3)));
    let f = folded(s.lattice(4));
    assert_eq!(
        f,
        0,
        "{f} of {} level-4 cells folded",
        s.lattice(4).num_cells()
    );
}

/// The paper's single cell folds at every hole size (its cell point is in the hollow); the split
/// lattice has the same points and boundary faces and does not fold.
#[test]
fn paper_tetrahedron_folds_and_the_split_one_does_not() {
    for hole in [0.2, 0.3, 0.4] {
        let paper = primitives::tetrahedron_with_holes(2.0, hole);
        let split = primitives::tetrahedron_with_holes_split(2.0, hole);
        assert_eq!(paper.points(), split.points());
        assert_eq!(split.counts().to_array(), [16, 42, 34, 10]);
        assert_eq!(split.counts().euler_characteristic(), -2, "genus 3");
        // The cell point is the centre of the tetrahedron, in the hollow.
        assert!(paper.cell_centroid(CellId::new(0)).norm() < 1e-12);
        let p = solid(paper, BoundaryRule::Smooth, 1);
        assert!(folded(p.lattice(1)) > 0, "hole {hole}");
        let s = solid(split, BoundaryRule::Smooth, 3);
        for k in 1..=3 {
            assert_eq!(folded(s.lattice(k)), 0, "hole {hole} level {k}");
        }
        assert_eq!(s.lattice(3).num_cells(), 52 * 64);
    }
    // The paper's counts (Table 1) still come from the single cell.
    let paper = primitive("tetrahedron-with-holes-paper").unwrap();
    assert_eq!(paper.counts().to_array(), [16, 42, 22, 1]);
}

#[test]
fn sculptor_grows_faces_where_asked() {
    let mut s = Sculptor::from_boxes(&[(Vec3::zeros(), Vec3::repeat(1.0))]).unwrap();
    let top = s.face(CellId::new(0), Vec3::z());
    let to = Vec3::new(0.5, 0.5, 2.0);
    let (cell, far) = s.grow(top, to, Vec3::new(0.0, 1.0, 1.0), 0.5).unwrap();
    let l = s.lattice();
    assert_eq!(l.counts().to_array(), [12, 20, 11, 2]);
    assert!((l.face_centroid(far) - to).norm() < 1e-12);
    assert!(l.cell_signed_volume(cell) > 0.0);
    // The far face is turned to the asked normal and scaled by one half (area 1/4).
    let vs: Vec<Vec3> = l.face_vertices(far).iter().map(|&v| l.point(v)).collect();
    let n = (vs[1] - vs[0]).cross(&(vs[2] - vs[0]));
    assert!((n.norm() - 0.25).abs() < 1e-12);
    assert!((n.normalize() - Vec3::new(0.0, 1.0, 1.0).normalize()).norm() < 1e-12);
    // Refused, with the sculptor unchanged: a far face behind the base, a bad scale, an
    // interior face, a missing face.
    let before = s.lattice().counts();
    let top2 = s.face(cell, Vec3::new(0.0, 1.0, 1.0));
    let behind = l_centroid(&s, top2) - Vec3::new(0.0, 1.0, 1.0);
    let err = s
        .grow(top2, behind, Vec3::new(0.0, 1.0, 1.0), 1.0)
        .unwrap_err();
    assert!(err.to_string().contains("volume"), "{err}");
    let err = s.grow(top2, to, Vec3::z(), f64::NAN).unwrap_err();
    assert!(err.to_string().contains("scale"), "{err}");
    let err = s.grow(top, to, Vec3::z(), 1.0).unwrap_err();
    assert!(err.to_string().contains("interior"), "{err}");
    assert!(
        s.grow(vclay_lattice::FaceId(999), to, Vec3::z(), 1.0)
            .is_err()
    );
    assert_eq!(s.lattice().counts(), before);
}

fn l_centroid(s: &Sculptor, f: vclay_lattice::FaceId) -> Vec3 {
    s.lattice().face_centroid(f)
}
