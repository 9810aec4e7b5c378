//! Parameterised control lattices.
//!
//! The models of `subdivision-solids-conference.txt` Table 1 and Fig. 1 and the journal's Table 2
//! that can be pinned down from their element counts are reproduced exactly (tests compare the
//! counts after subdivision with the table):
//! * "Cube (3^3)" and "Cube (4^3)": [`box_lattice`] with 3 or 4 points per axis (27 points,
//!   54 edges, 36 faces, 8 cells; 64, 144, 108, 27);
//! * "Cylinder": [`cylinder`] with 4 sectors, 2 layers and no hexahedral ring (15 points,
//!   34 edges, 28 faces, 8 prisms);
//! * "Torus": [`paper_torus`], one layer over a square annulus whose corners are triangles (24
//!   points, 52 edges, 36 faces, 4 hexahedra + 4 prisms, which is why its subdivided cell counts
//!   are not multiples of 8^n);
//! * "Gear": [`gear`], the same annulus with a tooth on each of its 8 outer edges (56, 116, 76,
//!   12 hexahedra + 4 prisms);
//! * "Cube w/ holes": [`cube_with_holes`], the 3 x 3 x 3 block of cells less the centre cross (64,
//!   144, 96, 20);
//! * "Tetrahedron w/ holes": [`tetrahedron_with_holes`], a single non-convex cell (a thickened
//!   tetrahedral frame, genus 3; 16 points, 42 edges, 22 faces, 1 cell). Subdivided, that cell
//!   folds (its cell point lies in the hollow); [`tetrahedron_with_holes_split`] is the same
//!   solid as 6 prisms and 4 tetrahedra, which does not.
//!
//! The extruded models of the papers' galleries (soccer player, cactus, spiked and holed
//! objects) are in [`crate::gallery`].
//!
//! Also: [`cylinder`] with any number of wedge sectors, hexahedral rings and layers, [`torus`]
//! (a ring of hexahedra), [`l_solid`] and [`t_solid`] (branching solids).
//!
//! Builders: [`voxel_lattice`] (hexahedra on a grid, any subset), [`extrude`] (prisms over a
//! planar polygon mesh, several layers), [`revolve`] (prisms swept around the z axis, closed).
//! All return validated lattices.

use std::f64::consts::PI;

use vclay_core::Vec3;

use crate::cells::{hexahedron, prism, tetrahedron};
use crate::error::LatticeError;
use crate::lattice::Lattice;

/// A box of `n[0] x n[1] x n[2]` points (each at least 2) spanning `min..max`: a regular
/// hexahedral lattice of `(n[0]-1)(n[1]-1)(n[2]-1)` cells.
///
/// # Panics
/// If a count is below 2 (a programmer error).
#[track_caller]
pub fn box_lattice(n: [usize; 3], min: Vec3, max: Vec3) -> Lattice {
    assert!(
        n.iter().all(|&k| k >= 2),
        "box_lattice needs at least 2 points per axis"
    );
    let size = (max - min).component_div(&Vec3::new(
        (n[0] - 1) as f64,
        (n[1] - 1) as f64,
        (n[2] - 1) as f64,
    ));
    voxel_lattice([n[0] - 1, n[1] - 1, n[2] - 1], min, size, |_, _, _| true)
        .expect("a box lattice is valid")
}

/// Hexahedral cells on a grid of `cells[0] x cells[1] x cells[2]` voxels of size `size` starting at
/// `origin`, keeping voxel `(i, j, k)` when `filled(i, j, k)`; points no kept voxel uses are
/// dropped. Point `(i, j, k)` of the grid (before dropping) is `origin + (i, j, k) * size`.
pub fn voxel_lattice(
    cells: [usize; 3],
    origin: Vec3,
    size: Vec3,
    filled: impl Fn(usize, usize, usize) -> bool,
) -> Result<Lattice, LatticeError> {
    let [nx, ny, nz] = cells.map(|c| c + 1);
    let gid = |i: usize, j: usize, k: usize| ((k * ny + j) * nx + i) as u32;
    let mut hexes = Vec::new();
    for k in 0..cells[2] {
        for j in 0..cells[1] {
            for i in 0..cells[0] {
                if filled(i, j, k) {
                    hexes.push([
                        gid(i, j, k),
                        gid(i + 1, j, k),
                        gid(i + 1, j + 1, k),
                        gid(i, j + 1, k),
                        gid(i, j, k + 1),
                        gid(i + 1, j, k + 1),
                        gid(i + 1, j + 1, k + 1),
                        gid(i, j + 1, k + 1),
                    ]);
                }
            }
        }
    }
    let mut remap = vec![u32::MAX; nx * ny * nz];
    let mut points = Vec::new();
    for h in &mut hexes {
        for v in h.iter_mut() {
            let g = *v as usize;
            if remap[g] == u32::MAX {
                remap[g] = points.len() as u32;
                let (i, j, k) = (g % nx, (g / nx) % ny, g / (nx * ny));
                points.push(origin + Vec3::new(i as f64, j as f64, k as f64).component_mul(&size));
            }
            *v = remap[g];
        }
    }
    let cells: Vec<Vec<Vec<u32>>> = hexes.into_iter().map(hexahedron).collect();
    Lattice::from_cells(points, &cells)
}

/// Prisms over a planar polygon mesh: `profile` points `(x, y)`, `polygons` loops of profile
/// indices (counter-clockwise seen from +z), stacked over `heights` (at least two, increasing):
/// one layer of cells between consecutive heights.
pub fn extrude(
    profile: &[[f64; 2]],
    polygons: &[Vec<u32>],
    heights: &[f64],
) -> Result<Lattice, LatticeError> {
    let np = profile.len() as u32;
    let mut points = Vec::with_capacity(profile.len() * heights.len());
    for &z in heights {
        points.extend(profile.iter().map(|p| Vec3::new(p[0], p[1], z)));
    }
    let mut cells = Vec::new();
    for layer in 0..heights.len().saturating_sub(1) as u32 {
        for poly in polygons {
            let bottom: Vec<u32> = poly.iter().map(|&i| i + layer * np).collect();
            let top: Vec<u32> = poly.iter().map(|&i| i + (layer + 1) * np).collect();
            cells.push(prism_checked(&bottom, &top)?);
        }
    }
    Lattice::from_cells(points, &cells)
}

/// Prisms swept around the z axis: `profile` points `(r, z)` with `r > 0`, `polygons` loops of
/// profile indices, `segments` (at least 3) stations around a full turn; the ring closes.
pub fn revolve(
    profile: &[[f64; 2]],
    polygons: &[Vec<u32>],
    segments: usize,
) -> Result<Lattice, LatticeError> {
    let np = profile.len() as u32;
    let mut points = Vec::with_capacity(profile.len() * segments);
    for s in 0..segments {
        let t = 2.0 * PI * s as f64 / segments as f64;
        points.extend(
            profile
                .iter()
                .map(|p| Vec3::new(p[0] * t.cos(), p[0] * t.sin(), p[1])),
        );
    }
    let mut cells = Vec::new();
    for s in 0..segments as u32 {
        let s1 = (s + 1) % segments as u32;
        for poly in polygons {
            let a: Vec<u32> = poly.iter().map(|&i| i + s * np).collect();
            let b: Vec<u32> = poly.iter().map(|&i| i + s1 * np).collect();
            cells.push(prism_checked(&a, &b)?);
        }
    }
    Lattice::from_cells(points, &cells)
}

fn prism_checked(bottom: &[u32], top: &[u32]) -> Result<Vec<Vec<u32>>, LatticeError> {
    if bottom.len() < 3 {
        return Err(LatticeError::DegenerateFace {
            cell: 0,
            face_in_cell: 0,
            vertices: bottom.to_vec(),
        });
    }
    Ok(prism(bottom, top))
}

/// A cylinder about the z axis from `z = 0` to `height`: a core of `sectors` triangular prisms
/// (wedges) around the axis, `rings` rings of hexahedra around the core, `layers` layers.
/// The paper's "Cylinder" is `cylinder(r, h, 4, 2, 0)`.
///
/// # Panics
/// If `sectors < 3`, `layers < 1`, or `radius`/`height` are not positive.
#[track_caller]
pub fn cylinder(radius: f64, height: f64, sectors: usize, layers: usize, rings: usize) -> Lattice {
    assert!(
        sectors >= 3 && layers >= 1 && radius > 0.0 && height > 0.0,
        "cylinder parameters"
    );
    let nr = rings + 1;
    let mut profile = vec![[0.0, 0.0]];
    for j in 1..=nr {
        let r = radius * j as f64 / nr as f64;
        for s in 0..sectors {
            let t = 2.0 * PI * s as f64 / sectors as f64;
            profile.push([r * t.cos(), r * t.sin()]);
        }
    }
    let idx = |j: usize, s: usize| (1 + (j - 1) * sectors + s % sectors) as u32;
    let mut polys = Vec::new();
    for s in 0..sectors {
        polys.push(vec![0, idx(1, s), idx(1, s + 1)]);
    }
    for j in 1..nr {
        for s in 0..sectors {
            polys.push(vec![
                idx(j, s),
                idx(j + 1, s),
                idx(j + 1, s + 1),
                idx(j, s + 1),
            ]);
        }
    }
    let heights: Vec<f64> = (0..=layers)
        .map(|l| height * l as f64 / layers as f64)
        .collect();
    extrude(&profile, &polys, &heights).expect("a cylinder lattice is valid")
}

/// A torus about the z axis: a ring of `segments` stations whose square cross-section of side
/// `2 * minor` centred at radius `major` is split into `cross x cross` hexahedra.
///
/// # Panics
/// If `segments < 3`, `cross < 1`, or not `0 < minor < major`.
#[track_caller]
pub fn torus(major: f64, minor: f64, segments: usize, cross: usize) -> Lattice {
    assert!(
        segments >= 3 && cross >= 1 && minor > 0.0 && minor < major,
        "torus parameters"
    );
    let n = cross + 1;
    let mut profile = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            let u = -minor + 2.0 * minor * i as f64 / cross as f64;
            let v = -minor + 2.0 * minor * j as f64 / cross as f64;
            profile.push([major + u, v]);
        }
    }
    let id = |i: usize, j: usize| (j * n + i) as u32;
    let mut polys = Vec::new();
    for j in 0..cross {
        for i in 0..cross {
            polys.push(vec![id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    revolve(&profile, &polys, segments).expect("a torus lattice is valid")
}

/// The square annulus of the paper's torus and gear: inner square `i_k` (radius `inner`, angles
/// 45 + 90k degrees), outer octagon `o_m` (radius `outer`, angles 22.5 + 45(m-1) degrees);
/// triangles `(i_k, o_2k, o_2k+1)` at the corners and quads `(i_k, o_2k+1, o_2k+2, i_k+1)`.
fn annulus(inner: f64, outer: f64) -> (Vec<[f64; 2]>, Vec<Vec<u32>>) {
    let deg = PI / 180.0;
    let mut pts = Vec::new();
    for k in 0..4 {
        let t = (45.0 + 90.0 * k as f64) * deg;
        pts.push([inner * t.cos(), inner * t.sin()]);
    }
    for m in 0..8 {
        let t = (22.5 + 45.0 * (m as f64 - 1.0)) * deg;
        pts.push([outer * t.cos(), outer * t.sin()]);
    }
    let i = |k: u32| k % 4;
    let o = |m: u32| 4 + m % 8;
    let mut polys = Vec::new();
    for k in 0..4u32 {
        polys.push(vec![i(k), o(2 * k), o(2 * k + 1)]);
        polys.push(vec![i(k), o(2 * k + 1), o(2 * k + 2), i(k + 1)]);
    }
    (pts, polys)
}

/// The torus-like solid of the conference paper's Table 1 and Fig. 2: one layer of cells of
/// thickness `height` over a square annulus (inner radius `inner`, outer radius `outer`) whose
/// four corners are triangles: 4 hexahedra and 4 prisms, 24 points, 52 edges, 36 faces.
///
/// # Panics
/// If not `0 < inner < outer` or `height <= 0`.
#[track_caller]
pub fn paper_torus(inner: f64, outer: f64, height: f64) -> Lattice {
    assert!(
        0.0 < inner && inner < outer && height > 0.0,
        "paper_torus parameters"
    );
    let (pts, polys) = annulus(inner, outer);
    extrude(&pts, &polys, &[0.0, height]).expect("the paper torus is valid")
}

/// The gear-like solid of the conference paper's Table 1 and Fig. 1: [`paper_torus`]'s annulus
/// with one tooth (a quad reaching out to radius `tip`) on each of the 8 outer edges, one layer
/// thick: 12 hexahedra + 4 prisms, 56 points, 116 edges, 76 faces.
///
/// # Panics
/// If not `0 < inner < outer < tip` or `height <= 0`.
#[track_caller]
pub fn gear(inner: f64, outer: f64, tip: f64, height: f64) -> Lattice {
    assert!(
        0.0 < inner && inner < outer && outer < tip && height > 0.0,
        "gear parameters"
    );
    let (mut pts, mut polys) = annulus(inner, outer);
    for m in 0..8u32 {
        let (a, b) = (4 + m, 4 + (m + 1) % 8);
        let (pa, pb) = (pts[a as usize], pts[b as usize]);
        // Tooth tip points: the edge's points pushed out to radius `tip`, narrowed by a third.
        let mid = [(pa[0] + pb[0]) / 2.0, (pa[1] + pb[1]) / 2.0];
        let tip_of = |p: [f64; 2]| {
            let q = [
                mid[0] + (p[0] - mid[0]) * 0.6,
                mid[1] + (p[1] - mid[1]) * 0.6,
            ];
            let r = (q[0] * q[0] + q[1] * q[1]).sqrt();
            [q[0] * tip / r, q[1] * tip / r]
        };
        let (ta, tb) = (pts.len() as u32, pts.len() as u32 + 1);
        pts.push(tip_of(pa));
        pts.push(tip_of(pb));
        // Outer edge a -> b runs counter-clockwise around the annulus; the tooth lies outside
        // it, so its counter-clockwise loop runs b -> a along the shared edge.
        polys.push(vec![a, ta, tb, b]);
    }
    extrude(&pts, &polys, &[0.0, height]).expect("the gear is valid")
}

/// The cube with holes of the conference paper's Table 1 and Fig. 1: the `3 x 3 x 3` block of
/// cells of size `cell` without the centre cell and the six cells at the face centres (a
/// Menger-sponge step): 20 hexahedra, 64 points, 144 edges, 96 faces.
pub fn cube_with_holes(cell: f64) -> Lattice {
    voxel_lattice([3, 3, 3], Vec3::zeros(), Vec3::repeat(cell), |i, j, k| {
        [i, j, k].iter().filter(|&&x| x == 1).count() < 2
    })
    .expect("the cube with holes is valid")
}

/// An L-shaped solid: two arms of `arm` cells each (plus the shared corner cell) with a square
/// cross-section of `width x width` cells of size `cell`, along +x and +y.
///
/// # Panics
/// If `arm < 1` or `width < 1`.
#[track_caller]
pub fn l_solid(arm: usize, width: usize, cell: f64) -> Lattice {
    assert!(arm >= 1 && width >= 1, "l_solid parameters");
    let n = arm + width;
    voxel_lattice(
        [n, n, width],
        Vec3::zeros(),
        Vec3::repeat(cell),
        |i, j, _| i < width || j < width,
    )
    .expect("the L solid is valid")
}

/// A T-shaped branching solid: a bar of `2 * arm + width` cells along x and a stem of `arm` cells
/// along +y from its middle, square cross-section of `width x width` cells of size `cell`.
///
/// # Panics
/// If `arm < 1` or `width < 1`.
#[track_caller]
pub fn t_solid(arm: usize, width: usize, cell: f64) -> Lattice {
    assert!(arm >= 1 && width >= 1, "t_solid parameters");
    let nx = 2 * arm + width;
    voxel_lattice(
        [nx, width + arm, width],
        Vec3::zeros(),
        Vec3::repeat(cell),
        |i, j, _| j < width || (i >= arm && i < arm + width),
    )
    .expect("the T solid is valid")
}

/// The tetrahedron with holes of the conference paper's Table 1 and Fig. 1: a single non-convex
/// cell, the regular tetrahedron of edge length `edge` (centred at the origin) with a triangular
/// hole through each face, all four meeting in a hollow centre, so that what remains is a
/// thickened tetrahedral frame (genus 3): 16 points, 42 edges, 22 faces, 1 cell, as in the
/// table.
///
/// The 16 points are the 4 corners `X` and, on each face `f`, the inner triangle `X_f = c_f +
/// hole (X - c_f)` (`c_f` the face centroid). The 22 faces: per tetrahedron face the 3 trapezoids
/// `X Y Y_f X_f` around its hole (12), per tetrahedron edge `XY` between faces `f` and `g` the
/// inner wall `X_f Y_f Y_g X_g` of the bar along it (6), and per corner the triangle `X_f X_g
/// X_h` facing the hollow (4). `hole` in `(0, 1)` is the size of the holes relative to the faces.
///
/// Subdivided, the interior folds: the first level's cell point is the centroid of the 16
/// points, inside the hollow, so about half the cells of every level have non-positive volume
/// (984 of 1,744 at level 3 by [`Lattice::cell_signed_volume`]; 936 of the 1,680 hexahedra by
/// VTK's `vtkCellSizeFilter`, `bench/check_vtk.sh`). The boundary surface is not affected.
/// This is what MacCracken-Joy's rules do with the paper's single-cell model, whatever the hole
/// size (see [`tetrahedron_with_holes_split`] for why, and for the variant that does not fold).
///
/// # Panics
/// If `edge <= 0` or `hole` is not in `(0, 1)`, or if the lattice is degenerate (a hole so
/// small or so large that points coincide, such as `hole = 1e-300`); use
/// [`try_tetrahedron_with_holes`] for sizes that come from user input.
#[track_caller]
pub fn tetrahedron_with_holes(edge: f64, hole: f64) -> Lattice {
    assert!(
        edge > 0.0 && hole > 0.0 && hole < 1.0,
        "tetrahedron_with_holes parameters"
    );
    try_tetrahedron_with_holes(edge, hole).expect("the tetrahedron with holes is valid")
}

/// [`tetrahedron_with_holes`] that returns the lattice's validation error (a degenerate edge,
/// coinciding points) instead of panicking, for parameters that come from user input.
///
/// # Panics
/// If `edge <= 0` or `hole` is not in `(0, 1)` (check these first).
#[track_caller]
pub fn try_tetrahedron_with_holes(edge: f64, hole: f64) -> Result<Lattice, LatticeError> {
    assert!(
        edge > 0.0 && hole > 0.0 && hole < 1.0,
        "tetrahedron_with_holes parameters"
    );
    let (points, faces, inner) = tet_frame_points(edge, hole);
    let corners: Vec<Vec3> = points[..4].to_vec();
    let mut cell: Vec<Vec<u32>> = Vec::with_capacity(22);
    for (f, loop_) in faces.iter().enumerate() {
        for i in 0..3 {
            let (x, y) = (loop_[i], loop_[(i + 1) % 3]);
            cell.push(vec![x as u32, y as u32, inner[f][y], inner[f][x]]);
        }
    }
    // Bars: the edge x -> y runs this way in face f and the other way in face g.
    for x in 0..4 {
        for y in 0..4 {
            if x == y {
                continue;
            }
            let Some(f) = (0..4).find(|&f| {
                let l = faces[f];
                (0..3).any(|i| l[i] == x && l[(i + 1) % 3] == y)
            }) else {
                continue;
            };
            if x < y {
                let g = (0..4)
                    .find(|&g| g != f && g != x && g != y)
                    .expect("two faces");
                cell.push(vec![inner[f][x], inner[f][y], inner[g][y], inner[g][x]]);
            }
        }
    }
    // Corners: the triangle of the three hole points near corner x, facing away from x.
    let centre = Vec3::zeros();
    for x in 0..4 {
        let mut tri: Vec<u32> = (0..4).filter(|&f| f != x).map(|f| inner[f][x]).collect();
        let [a, b, c] = [0, 1, 2].map(|i| points[tri[i] as usize]);
        if (b - a).cross(&(c - a)).dot(&(centre - corners[x])) < 0.0 {
            tri.swap(1, 2);
        }
        cell.push(tri);
    }
    Lattice::from_cells(points, &[cell])
}

/// The 16 points of the tetrahedron with holes (4 corners, then 3 hole points per face), the
/// faces' corner loops (face `f` opposite corner `f`, counter-clockwise seen from outside) and
/// `inner[f][v]`, the point of face `f`'s hole near corner `v`.
fn tet_frame_points(edge: f64, hole: f64) -> (Vec<Vec3>, Vec<[usize; 3]>, [[u32; 4]; 4]) {
    // Regular tetrahedron with edge length 2 sqrt(2) * (edge / (2 sqrt(2))) = edge.
    let s = edge / (2.0 * 2f64.sqrt());
    let corners = [
        Vec3::new(1.0, 1.0, 1.0) * s,
        Vec3::new(1.0, -1.0, -1.0) * s,
        Vec3::new(-1.0, 1.0, -1.0) * s,
        Vec3::new(-1.0, -1.0, 1.0) * s,
    ];
    // Face f is opposite corner f; its loop counter-clockwise seen from outside.
    let faces: Vec<[usize; 3]> = (0..4)
        .map(|f| {
            let mut loop_: Vec<usize> = (0..4).filter(|&v| v != f).collect();
            let [a, b, c] = [0, 1, 2].map(|i| corners[loop_[i]]);
            let centroid = (a + b + c) / 3.0;
            if (b - a).cross(&(c - a)).dot(&(centroid - corners[f])) < 0.0 {
                loop_.swap(1, 2);
            }
            [loop_[0], loop_[1], loop_[2]]
        })
        .collect();
    let mut points = corners.to_vec();
    // inner[f][v]: the point of face f's hole near corner v.
    let mut inner = [[u32::MAX; 4]; 4];
    for (f, loop_) in faces.iter().enumerate() {
        let c = loop_.iter().map(|&v| corners[v]).sum::<Vec3>() / 3.0;
        for &v in loop_ {
            inner[f][v] = points.len() as u32;
            points.push(c + (corners[v] - c) * hole);
        }
    }
    (points, faces, inner)
}

/// Default relative hole size of [`tetrahedron_with_holes_split`] (`vclay subdivide --primitive
/// tetrahedron-with-holes`): the largest round value at which no cell folds up to level 3.
/// Larger holes make the bars thin and triangular: at `0.45` 32 of 3,328 level-3 cells fold,
/// at `0.5` 4 of 416 at level 2 and 128 at level 3.
pub const DEFAULT_SPLIT_HOLE: f64 = 0.4;

/// The tetrahedron with holes of [`tetrahedron_with_holes`] (the same 16 points, the same
/// boundary) split into convex cells: a triangular prism along each of the 6 bars (cross-section
/// `X X_f X_g` at corner `X`, the triangle between the corner and the two hole points beside
/// it) and a tetrahedron `X X_f X_g X_h` at each of the 4 corners: 10 cells, 16 points, 42
/// edges, 34 faces (the 22 of the single cell and the 12 triangles where bars meet corners).
///
/// Why: the paper's single cell (Table 1) is not convex, and its cell point (the centroid of its
/// 16 points, the tetrahedron's centre) lies in the hollow where the four holes meet, outside
/// the material, on the outer side of every face that faces the hollow. Each level-1 cell of a
/// point on those faces joins that point to the cell point, so it spans the face the wrong way
/// round: it is inverted, whatever the hole size (984 of 1,744 cells have non-positive volume
/// at level 3 with `hole = 0.5`). The paper's Fig. 1 shows only the smooth boundary, which the
/// rules compute from boundary points alone and which is the same for both lattices at level 0.
/// Split into convex cells, every cell's point lies inside its own cell, and with holes up to
/// [`DEFAULT_SPLIT_HOLE`] no cell folds (tests check levels 1 to 3; larger holes leave bars so
/// thin that the smooth boundary rule folds a few cells near the corners). The prisms subdivide into 6 hexahedra and the
/// tetrahedra into 4, so level 1 has 52 hexahedra (3,328 at level 3).
///
/// # Panics
/// If `edge <= 0` or `hole` is not in `(0, 1)`, or if the lattice is degenerate; use
/// [`try_tetrahedron_with_holes_split`] for sizes that come from user input.
#[track_caller]
pub fn tetrahedron_with_holes_split(edge: f64, hole: f64) -> Lattice {
    assert!(
        edge > 0.0 && hole > 0.0 && hole < 1.0,
        "tetrahedron_with_holes_split parameters"
    );
    try_tetrahedron_with_holes_split(edge, hole).expect("the split tetrahedron with holes is valid")
}

/// [`tetrahedron_with_holes_split`] that returns the lattice's validation error instead of
/// panicking.
///
/// # Panics
/// If `edge <= 0` or `hole` is not in `(0, 1)` (check these first).
#[track_caller]
pub fn try_tetrahedron_with_holes_split(edge: f64, hole: f64) -> Result<Lattice, LatticeError> {
    assert!(
        edge > 0.0 && hole > 0.0 && hole < 1.0,
        "tetrahedron_with_holes_split parameters"
    );
    let (points, faces, inner) = tet_frame_points(edge, hole);
    // Orients a cell's loops outward (its signed volume positive).
    let outward = |mut cell: Vec<Vec<u32>>| -> Vec<Vec<u32>> {
        let mut vol = 0.0;
        for l in &cell {
            let o = points[l[0] as usize];
            for i in 1..l.len() - 1 {
                let a = points[l[i] as usize] - o;
                let b = points[l[i + 1] as usize] - o;
                vol += o.dot(&a.cross(&b));
            }
        }
        if vol < 0.0 {
            for l in &mut cell {
                l.reverse();
            }
        }
        cell
    };
    let mut cells = Vec::with_capacity(10);
    for x in 0..4usize {
        for y in x + 1..4 {
            // The two faces containing edge xy are those opposite the other two corners.
            let [f, g]: [usize; 2] = {
                let mut it = (0..4).filter(|&k| k != x && k != y);
                [it.next().expect("two"), it.next().expect("two")]
            };
            debug_assert!(faces[f].contains(&x) && faces[g].contains(&y));
            let bottom = [x as u32, inner[f][x], inner[g][x]];
            let top = [y as u32, inner[f][y], inner[g][y]];
            cells.push(outward(prism(&bottom, &top)));
        }
    }
    for x in 0..4usize {
        let others: Vec<u32> = (0..4).filter(|&f| f != x).map(|f| inner[f][x]).collect();
        cells.push(outward(tetrahedron([
            others[0], others[1], others[2], x as u32,
        ])));
    }
    Lattice::from_cells(points, &cells)
}
