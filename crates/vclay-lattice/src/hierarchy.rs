//! A subdivision solid: the control lattice, every subdivided level and the chain of operators.

use vclay_core::{Parallelism, Vec3};

use crate::error::LatticeError;
use crate::lattice::Lattice;
use crate::map::SubdivisionMap;
use crate::subdivide::{Features, SubdivisionRules, subdivide};

/// A MacCracken-Joy subdivision solid subdivided `n` times
/// (`subdivision-solids-journal.txt` section 4.2: `d = A p`, `A = A^(n) ... A^(1)`, eq 4).
///
/// Level 0 is the control lattice (points `p`), level `n` the data lattice (points `d`); the
/// lattices in between are kept because the dynamics and the editing tools address them.
#[derive(Clone, Debug)]
pub struct SubdivisionSolid {
    rules: SubdivisionRules,
    lattices: Vec<Lattice>,
    features: Vec<Features>,
    map: SubdivisionMap,
}

impl SubdivisionSolid {
    /// Subdivides `control` `levels` times with `rules` and feature tags `features`.
    pub fn new(
        control: Lattice,
        features: Features,
        rules: SubdivisionRules,
        levels: usize,
    ) -> Result<Self, LatticeError> {
        let mut s = Self {
            rules,
            lattices: vec![control],
            features: vec![features],
            map: SubdivisionMap::default(),
        };
        for _ in 0..levels {
            s.subdivide_once()?;
        }
        Ok(s)
    }

    /// Adds one more level.
    pub fn subdivide_once(&mut self) -> Result<(), LatticeError> {
        let r = subdivide(
            self.lattices.last().unwrap(),
            self.features.last().unwrap(),
            &self.rules,
        )?;
        self.map.push(r.operator);
        self.lattices.push(r.lattice);
        self.features.push(r.features);
        Ok(())
    }

    /// The rules used.
    pub fn rules(&self) -> &SubdivisionRules {
        &self.rules
    }

    /// Number of subdivision levels `n`.
    pub fn levels(&self) -> usize {
        self.map.levels()
    }

    /// The control lattice (level 0).
    pub fn control(&self) -> &Lattice {
        &self.lattices[0]
    }

    /// The finest lattice (level `n`): the data points `d`.
    pub fn finest(&self) -> &Lattice {
        self.lattices.last().unwrap()
    }

    /// The lattice at level `j` (0 = control).
    pub fn lattice(&self, j: usize) -> &Lattice {
        &self.lattices[j]
    }

    /// The feature tags at level `j`.
    pub fn features(&self, j: usize) -> &Features {
        &self.features[j]
    }

    /// The chain of level operators.
    pub fn map(&self) -> &SubdivisionMap {
        &self.map
    }

    /// Moves the control points and recomputes every level's points through the operators.
    ///
    /// # Panics
    /// If `points.len()` differs from the control lattice's point count.
    #[track_caller]
    pub fn set_control_points(&mut self, points: Vec<Vec3>) {
        self.lattices[0].set_points(points);
        for j in 0..self.map.levels() {
            let (lo, hi) = self.lattices.split_at_mut(j + 1);
            let src = lo[j].points();
            let op = self.map.operator(j);
            op.apply_into(src, hi[0].points_mut(), Parallelism::Auto);
        }
    }
}
