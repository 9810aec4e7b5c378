//! The papers' gallery: solids sculpted by extruding faces, as the papers built them.
//!
//! # What
//! * [`soccer_player`]: `subdivision-solids-conference.txt` Table 1 and Fig. 1, "Soccer player":
//!   104 points, 200 edges, 122 faces, 24 hexahedra (level 2: 2,450 / 6,320 / 5,408 / 1,536).
//! * [`cactus`]: the same table and figure, "Cactus": 108 / 212 / 131 / 26 (level 2: 2,625 /
//!   6,800 / 5,840 / 1,664).
//! * [`spiked_object`] and [`holed_object`]: `subdivision-solids-journal.txt` Table 2, "Spiked
//!   object" (75 cells, 600 at level 1) and "Holed object" (135 cells, 1,080 at level 1). The
//!   table gives only cell counts and the figures are not in the text, so these two are
//!   reconstructions that match the cell counts (all hexahedra, so the level-1 counts follow).
//!
//! # How the counts pin down the models
//! The journal (section 5.3) grows protrusions with an extrusion tool: a boundary face gets a new
//! cell glued to it ([`crate::edit::extrude_face`]). Extruding a free quadrilateral face adds 4
//! points, 8 edges, 5 faces and 1 hexahedron, and a cube has 8 / 12 / 6 / 1, so `k` extrusions
//! of one cube give `8 + 4k / 12 + 8k / 6 + 5k / 1 + k`. The cactus's 108 / 212 / 131 / 26 is
//! exactly `k = 25` from one cube. The soccer player's 104 / 200 / 122 / 24 is no single cube
//! plus extrusions (`8 + 4 * 23 = 100`), but it is exactly two cubes plus 22 extrusions
//! (`16 + 88, 24 + 176, 12 + 110, 2 + 22`): the player and the ball are two pieces (its Euler
//! characteristic `V - E + F - C = 2` says the same). For an all-hexahedral lattice one level of
//! subdivision maps `(P, E, F, C)` to `(P + E + F + C, 2E + 4F + 6C, 4F + 12C, 8C)`, which turns
//! both rows of level 0 into the table's level-2 rows, so the level-2 counts check that every
//! cell is a hexahedron.
//!
//! Each model here is one starting lattice and a fixed sequence of extrusions; after each
//! extrusion the new face is placed (moved, turned and scaled as a user would drag it) by
//! [`Sculptor::grow`]. The shapes follow the figures' descriptions (a player with arms, legs and
//! a head running at a ball; a cactus with three arms); the figures themselves give no
//! coordinates.
//!
//! # Limitations
//! Positions are chosen by hand, not taken from the papers; the tests check the counts, that every
//! cell keeps a positive volume at every subdivision level up to 3, and the rough proportions.

use vclay_core::Vec3;

use crate::cells::hexahedron;
use crate::edit::{ExtrudeParams, extrude_face, newell_normal};
use crate::error::LatticeError;
use crate::ids::{CellId, FaceId};
use crate::lattice::Lattice;

/// A lattice being sculpted by extrusions: each [`Sculptor::grow`] glues one new cell to a
/// boundary face ([`extrude_face`]) and places its far face.
#[derive(Clone, Debug)]
pub struct Sculptor {
    lattice: Lattice,
}

/// Rotation taking unit vector `a` to unit vector `b` (Rodrigues), applied to `v`.
fn rotate_between(a: Vec3, b: Vec3, v: Vec3) -> Vec3 {
    let c = a.dot(&b);
    if c > 1.0 - 1e-12 {
        return v;
    }
    if c < -1.0 + 1e-12 {
        // Half turn about any axis perpendicular to `a`.
        let helper = if a.x.abs() < 0.9 {
            Vec3::x()
        } else {
            Vec3::y()
        };
        let k = a.cross(&helper).normalize();
        return 2.0 * k * k.dot(&v) - v;
    }
    let k = a.cross(&b);
    // R v = v c + (k x v) + k (k . v) / (1 + c), with |k| = sin.
    v * c + k.cross(&v) + k * (k.dot(&v) / (1.0 + c))
}

impl Sculptor {
    /// Starts from `start` (any valid lattice).
    pub fn new(start: Lattice) -> Self {
        Self { lattice: start }
    }

    /// Starts from the hexahedra spanning each `(min, max)` box (disjoint pieces). Errors: the
    /// lattice's construction errors (boxes sharing corner points).
    ///
    /// # Panics
    /// If a corner is not finite or `min >= max` along some axis (a programmer error in a
    /// fixed recipe).
    #[track_caller]
    pub fn from_boxes(boxes: &[(Vec3, Vec3)]) -> Result<Self, LatticeError> {
        assert!(
            boxes
                .iter()
                .all(|(lo, hi)| (0..3)
                    .all(|a| lo[a].is_finite() && hi[a].is_finite() && lo[a] < hi[a])),
            "Sculptor::from_boxes: every box needs finite corners with min < max"
        );
        let mut points = Vec::with_capacity(8 * boxes.len());
        let mut cells = Vec::with_capacity(boxes.len());
        for (b, &(lo, hi)) in boxes.iter().enumerate() {
            for k in 0..2 {
                for (i, j) in [(0, 0), (1, 0), (1, 1), (0, 1)] {
                    let pick = |s: usize, a: f64, b: f64| if s == 0 { a } else { b };
                    points.push(Vec3::new(
                        pick(i, lo.x, hi.x),
                        pick(j, lo.y, hi.y),
                        pick(k, lo.z, hi.z),
                    ));
                }
            }
            let o = 8 * b as u32;
            cells.push(hexahedron([0, 1, 2, 3, 4, 5, 6, 7].map(|i| o + i)));
        }
        Ok(Self::new(Lattice::from_cells(points, &cells)?))
    }

    /// The lattice so far.
    pub fn lattice(&self) -> &Lattice {
        &self.lattice
    }

    /// The finished lattice.
    pub fn finish(self) -> Lattice {
        self.lattice
    }

    /// The boundary face of `cell` whose outward normal points most along `dir`.
    ///
    /// # Panics
    /// If `cell` has no boundary face (a programmer error in a fixed recipe).
    #[track_caller]
    pub fn face(&self, cell: CellId, dir: Vec3) -> FaceId {
        let l = &self.lattice;
        l.cell_faces(cell)
            .iter()
            .copied()
            .filter(|&f| l.is_boundary_face(f))
            .map(|f| {
                let n = newell_normal(l.points(), l.face_vertices(f)).unwrap_or_else(Vec3::zeros);
                (f, n.dot(&dir))
            })
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .expect("the cell has a boundary face")
            .0
    }

    /// Extrudes boundary face `face` into a new cell and places the new (far) face: the base
    /// face's loop turned so that its normal becomes `normal`, scaled by `scale` about its
    /// centroid, and moved so that its centroid is `to`. Returns the new cell and its far face.
    ///
    /// Errors ([`LatticeError::CannotExtrude`] saying why, or the extrusion's own): `face` is
    /// interior or missing, `to` or `normal` is not finite, `normal` is zero, `scale` is not
    /// positive and finite, or the placed cell has a non-positive volume (a far face behind the
    /// base face). The sculptor is unchanged after an error.
    pub fn grow(
        &mut self,
        face: FaceId,
        to: Vec3,
        normal: Vec3,
        scale: f64,
    ) -> Result<(CellId, FaceId), LatticeError> {
        if face.index() >= self.lattice.num_faces() {
            return Err(LatticeError::NoSuchFace { face });
        }
        let loop_: Vec<_> = self.lattice.face_vertices(face).to_vec();
        let base: Vec<Vec3> = loop_.iter().map(|&v| self.lattice.point(v)).collect();
        let n0 = newell_normal(self.lattice.points(), &loop_).ok_or_else(|| {
            LatticeError::CannotExtrude {
                face,
                reason: "it has zero area".into(),
            }
        })?;
        let fail = |reason: String| LatticeError::CannotExtrude { face, reason };
        if !(scale.is_finite() && scale > 0.0) {
            return Err(fail(format!(
                "the scale {scale} is not positive and finite"
            )));
        }
        if !(to.iter().all(|x| x.is_finite()) && normal.iter().all(|x| x.is_finite())) {
            return Err(fail("the target or the normal is not finite".into()));
        }
        let n1 = normal
            .try_normalize(0.0)
            .ok_or_else(|| fail("the new face's normal is zero".into()))?;
        let centroid = base.iter().sum::<Vec3>() / base.len() as f64;
        let np = self.lattice.num_points();
        let edit = extrude_face(&self.lattice, face, &ExtrudeParams::default())?;
        let mut lattice = edit.lattice;
        let cell = CellId::new(lattice.num_cells() - 1);
        {
            let pts = lattice.points_mut();
            for (i, p) in base.iter().enumerate() {
                pts[np + i] = to + rotate_between(n0, n1, (p - centroid) * scale);
            }
        }
        let far = lattice
            .cell_faces(cell)
            .iter()
            .copied()
            .find(|&f| lattice.face_vertices(f).iter().all(|v| v.index() >= np))
            .expect("an extruded cell has a far face");
        let volume = lattice.cell_signed_volume(cell);
        if volume.is_nan() || volume <= 0.0 {
            return Err(fail(format!(
                "the placed cell would have volume {volume:.3e} (its far face lies behind the base face)"
            )));
        }
        self.lattice = lattice;
        Ok((cell, far))
    }

    /// [`Sculptor::grow`] along a chain: each step grows the previous step's far face.
    /// `steps` are `(to, normal, scale)`. Returns the cells in order and the last far face.
    pub fn chain(
        &mut self,
        mut face: FaceId,
        steps: &[(Vec3, Vec3, f64)],
    ) -> Result<(Vec<CellId>, FaceId), LatticeError> {
        let mut cells = Vec::with_capacity(steps.len());
        for &(to, normal, scale) in steps {
            let (c, f) = self.grow(face, to, normal, scale)?;
            cells.push(c);
            face = f;
        }
        Ok((cells, face))
    }
}

fn v(x: f64, y: f64, z: f64) -> Vec3 {
    Vec3::new(x, y, z)
}

/// The soccer player of `subdivision-solids-conference.txt` Table 1 and Fig. 1 (and the
/// journal's Table 2): a player running at a ball, built from two cubes (the pelvis and the
/// lower half of the ball) and 22 extrusions: the upper half of the ball; chest, neck and
/// head up from the pelvis; a shoulder, upper arm, forearm and hand on each side of the chest;
/// a hip, thigh, knee, shin and foot on each side of the pelvis. 104 points, 200 edges, 122 faces, 24 hexahedra, two pieces (player and
/// ball); `height` tall (z up, standing on `z = 0`), facing -y, the ball in front of the right
/// (kicking) foot at `x > 0`.
///
/// # Panics
/// If `height` is not positive and finite.
#[track_caller]
pub fn soccer_player(height: f64) -> Lattice {
    assert!(
        height.is_finite() && height > 0.0,
        "soccer_player height must be positive"
    );
    let mut l = soccer_player_unit().expect("the soccer player recipe is valid");
    let s = height / 2.6;
    for p in l.points_mut() {
        // Scaled, and turned half a turn about z (a rotation keeps the cells' orientation) so
        // that the player faces -y, towards the default iso view.
        *p = Vec3::new(-p.x * s, -p.y * s, p.z * s);
    }
    l
}

fn soccer_player_unit() -> Result<Lattice, LatticeError> {
    let z = Vec3::z();
    let mut s = Sculptor::from_boxes(&[
        // Pelvis.
        (v(-0.34, -0.19, 1.18), v(0.34, 0.19, 1.46)),
        // Lower half of the ball, in front of the right (kicking) foot.
        (v(-0.6, 0.62, 0.0), v(-0.12, 1.1, 0.24)),
    ])?;
    let pelvis = CellId::new(0);
    // Upper half of the ball. A lone cube would not do: under the smooth boundary rule every
    // corner of a cube has valence 3 and loses its own weight, so the alternating (+1, -1)
    // pattern of its 8 points subdivides to zero and `A^T M A` is singular; two cells are
    // enough to break the pattern.
    let ball_top = s.face(CellId::new(1), z);
    s.grow(ball_top, v(-0.36, 0.86, 0.48), z, 1.0)?;
    // Chest, neck and head.
    let top = s.face(pelvis, z);
    let (trunk, _) = s.chain(
        top,
        &[
            (v(0.0, 0.02, 2.08), z, 1.15),
            (v(0.0, 0.03, 2.16), z, 0.38),
            (v(0.0, 0.05, 2.62), v(0.0, 0.1, 1.0), 2.3),
        ],
    )?;
    let chest = trunk[0];
    // Arms: shoulder out along x, then down; the left arm (x > 0) swings forward, the right
    // back. The shoulder is grown from the chest's whole side, so its lower face (the upper
    // arm's base) runs from the armpit at the pelvis's top corner (z = 1.46) up to the shoulder
    // (z = 1.71): the upper arm's far face must lie below the armpit. With it at z = 1.56
    // (until issue 28) the arm's inner edges rose from the armpit, a sheared sliver of a cell
    // whose boundary layer folded from level 4 on (35 cells at level 4, 290 at level 5 with
    // the smooth rule); at or below z = 1.46 no cell folds at levels 1-5.
    for side in [1.0, -1.0] {
        let f = s.face(chest, v(side, 0.0, 0.0));
        let (shoulder, _) = s.grow(f, v(0.58 * side, 0.02, 1.94), v(side, 0.0, 0.0), 0.75)?;
        let down = s.face(shoulder, -z);
        let swing = side * 0.25;
        s.chain(
            down,
            &[
                (
                    v(0.56 * side, 0.02 + swing * 0.4, 1.36),
                    v(0.15 * side, swing, -1.0),
                    0.85,
                ),
                (
                    v(0.62 * side, 0.03 + swing, 1.06),
                    v(0.2 * side, swing * 2.0, -1.0),
                    0.85,
                ),
                (
                    v(0.64 * side, 0.04 + swing * 1.3, 0.90),
                    v(0.2 * side, swing * 2.0, -1.0),
                    0.8,
                ),
            ],
        )?;
    }
    // Legs: a hip out and down from each side of the pelvis, then thigh, knee, shin and foot;
    // the right leg (x < 0) swings forward to kick.
    for side in [1.0, -1.0] {
        let f = s.face(pelvis, v(side, 0.0, 0.0));
        let (hip, _) = s.grow(f, v(0.3 * side, 0.0, 1.06), v(side * 0.4, 0.0, -1.0), 0.8)?;
        let kick = if side < 0.0 { 1.0 } else { 0.0 };
        let far = s.face(hip, v(side * 0.4, 0.0, -1.0));
        s.chain(
            far,
            &[
                (
                    v(0.27 * side, 0.1 * kick, 0.78),
                    v(0.0, 0.3 * kick, -1.0),
                    0.95,
                ),
                (
                    v(0.26 * side, 0.18 * kick, 0.56),
                    v(0.0, 0.3 * kick, -1.0),
                    0.9,
                ),
                (
                    v(0.25 * side, 0.24 * kick, 0.26),
                    v(0.0, 0.2 * kick, -1.0),
                    0.85,
                ),
                (
                    v(0.25 * side, 0.16 + 0.26 * kick, 0.06),
                    v(0.0, 1.0, -1.0),
                    0.9,
                ),
            ],
        )?;
    }
    Ok(s.finish())
}

/// The cactus of `subdivision-solids-conference.txt` Table 1 and Fig. 1 (and the journal's
/// Table 2): a trunk of 10 cells and three arms (each out from the trunk, bending up, then
/// rising) grown from one cube by 25 extrusions: 108 points, 212 edges, 131 faces, 26
/// hexahedra; about `height` tall (z up), standing on `z = 0`.
///
/// # Panics
/// If `height` is not positive and finite.
#[track_caller]
pub fn cactus(height: f64) -> Lattice {
    assert!(
        height.is_finite() && height > 0.0,
        "cactus height must be positive"
    );
    let mut l = cactus_unit().expect("the cactus recipe is valid");
    let s = height / 4.0;
    for p in l.points_mut() {
        *p *= s;
    }
    l
}

fn cactus_unit() -> Result<Lattice, LatticeError> {
    let z = Vec3::z();
    let mut s = Sculptor::from_boxes(&[(v(-0.3, -0.3, 0.0), v(0.3, 0.3, 0.4))])?;
    // Trunk: 9 cells up from the base cube, the last one narrowing to the crown.
    let mut steps: Vec<(Vec3, Vec3, f64)> = (1..9)
        .map(|k| (v(0.0, 0.0, 0.4 + 0.4 * k as f64), z, 1.0))
        .collect();
    steps.push((v(0.0, 0.0, 4.0), z, 0.75));
    let top = s.face(CellId::new(0), z);
    let (trunk, _) = s.chain(top, &steps)?;
    // Arms: (trunk cell, direction, cells rising after the bend).
    let arms = [
        (trunk[1], v(-1.0, 0.0, 0.0), 4),
        (trunk[3], v(1.0, 0.0, 0.0), 3),
        (trunk[4], v(0.0, 1.0, 0.0), 3),
    ];
    for (cell, dir, rise) in arms {
        let f = s.face(cell, dir);
        let c = s.lattice().face_centroid(f);
        let out = c + dir * 0.36;
        let mut steps = vec![(out, dir, 0.85), (out + dir * 0.26 + z * 0.3, z, 1.0)];
        let mut at = out + dir * 0.26 + z * 0.3;
        for k in 0..rise {
            at += z * 0.36;
            let narrow = if k + 1 == rise { 0.75 } else { 1.0 };
            steps.push((at, z, narrow));
        }
        s.chain(f, &steps)?;
    }
    Ok(s.finish())
}

/// The spiked object of `subdivision-solids-journal.txt` Table 2 (75 cells, 600 at level 1),
/// reconstructed from its cell count: a `3 x 3 x 3` block of cubes of side `cell` (27 cells,
/// centred at the origin) with a spike of two tapering cells grown from each of the 24 corner
/// squares of its faces (48 extrusions), leaning away from the centre: 75 hexahedra, 219
/// points. The four corner squares of a face share no edge, so the spikes are disjoint.
///
/// # Panics
/// If `cell` is not positive and finite.
#[track_caller]
pub fn spiked_object(cell: f64) -> Lattice {
    assert!(
        cell.is_finite() && cell > 0.0,
        "spiked_object cell size must be positive"
    );
    spiked_unit(cell).expect("the spiked object recipe is valid")
}

fn spiked_unit(cell: f64) -> Result<Lattice, LatticeError> {
    let block = crate::primitives::box_lattice(
        [4, 4, 4],
        Vec3::repeat(-1.5 * cell),
        Vec3::repeat(1.5 * cell),
    );
    let mut s = Sculptor::new(block);
    // The corner squares: boundary faces whose centroid is off-centre in both in-plane axes.
    let corners: Vec<FaceId> = s
        .lattice()
        .boundary_faces()
        .filter(|&f| {
            let c = s.lattice().face_centroid(f);
            [c.x, c.y, c.z]
                .iter()
                .filter(|x| x.abs() > 0.5 * cell && x.abs() < 1.4 * cell)
                .count()
                == 2
        })
        .collect();
    debug_assert_eq!(corners.len(), 24);
    for f in corners {
        let l = s.lattice();
        let c = l.face_centroid(f);
        let n = newell_normal(l.points(), l.face_vertices(f)).unwrap_or_else(Vec3::z);
        let dir = (2.0 * n + c.normalize()).normalize();
        s.chain(
            f,
            &[
                (c + dir * 0.7 * cell, dir, 0.6),
                (c + dir * 1.6 * cell, dir, 0.35),
            ],
        )?;
    }
    Ok(s.finish())
}

/// The holed object of `subdivision-solids-journal.txt` Table 2 (135 cells, 1,080 at level 1),
/// reconstructed from its cell count: a plate of `9 x 9 x 3` cells with four square holes of
/// `3 x 3` cells through it, leaving bars one cell wide (`243 - 4 * 27 = 135` hexahedra, genus
/// 4); cells of side `cell` across and `cell / 2` through the plate, centred at the origin.
///
/// # Panics
/// If `cell` is not positive and finite.
#[track_caller]
pub fn holed_object(cell: f64) -> Lattice {
    assert!(
        cell.is_finite() && cell > 0.0,
        "holed_object cell size must be positive"
    );
    let hole = |i: usize| (1..4).contains(&i) || (5..8).contains(&i);
    crate::primitives::voxel_lattice(
        [9, 9, 3],
        Vec3::new(-4.5 * cell, -4.5 * cell, -0.75 * cell),
        Vec3::new(cell, cell, 0.5 * cell),
        |i, j, _| !(hole(i) && hole(j)),
    )
    .expect("the holed object is valid")
}
