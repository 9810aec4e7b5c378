//! # vclay-ffd
//!
//! Free-form deformation (FFD) with NURBS-volume lattices and its direct manipulation, after
//! Hu, Zhang, Tai & Sun, *Direct manipulation of FFD: efficient explicit solutions and decomposable
//! multiple point constraints*, The Visual Computer 17(6), Springer 2001
//! (`ffd-direct-manipulation.txt`).
//!
//! **What.**
//! - [`FfdLattice`]: a NURBS volume over a box that is exactly the identity at rest; parameters of a
//!   point by a linear map (section 2, eqs 1-2).
//! - [`EmbeddedMesh`]: a mesh with precomputed knot cells and local coordinates, evaluated per
//!   cell in power form; full (parallel) and incremental deformation.
//! - [`Manipulation`]: the least-norm control-point displacement moving one source to a target
//!   (eq 7) or several (eq 12), with the commutative group laws of section 4 (compose, inverse).
//! - [`decompose()`]: a multi-point manipulation as a sequence of single-point ones (section 6, eqs
//!   13-19).
//! - [`WeightChange`]: the same through the weights (section 3, last paragraph; derived here).
//!
//! ```
//! use vclay_core::Vec3;
//! use vclay_ffd::{FfdLattice, LatticeSpec, Manipulation, PointConstraint};
//! let mut lattice = FfdLattice::new(LatticeSpec::default(), Vec3::zeros(), Vec3::repeat(1.0)).unwrap();
//! let s = Vec3::new(0.3, 0.4, 0.5);
//! let c = PointConstraint::from_rest_point(&lattice, s, Vec3::new(0.35, 0.4, 0.6)).unwrap();
//! let m = Manipulation::single(&lattice, &c).unwrap();
//! lattice.apply(&m);
//! assert!((lattice.deform_point(&s) - c.target).norm() < 1e-14);
//! lattice.apply(&m.inverse()); // undo
//! assert!((lattice.deform_point(&s) - s).norm() < 1e-14);
//! ```
//!
//! **Limitations.** Axis-aligned rest boxes with clamped uniform knots only (no arbitrary
//! lattices, no knot insertion on a live lattice); the multi-point solve is dense in the number of
//! constraints (fine for hundreds, not for hundreds of thousands).
#![warn(missing_docs)]

pub mod decompose;
pub mod embed;
pub mod error;
pub mod lattice;
pub mod manipulation;
mod solve;
pub mod weights;

pub use decompose::{DecompositionStep, decompose};
pub use embed::EmbeddedMesh;
pub use error::{ConstraintConflict, FfdError};
pub use lattice::{
    DEFAULT_CONTROL_POINTS, DEFAULT_DEGREE, DEFAULT_MARGIN, FfdLattice, LatticeSpec, SparseBasis,
};
pub use manipulation::{
    DEFAULT_CONSISTENCY_TOLERANCE, DEFAULT_RANK_TOLERANCE, Manipulation, PointConstraint,
    SolveOptions,
};
pub use solve::SolveMode;
pub use weights::{
    DEFAULT_WEIGHT_ITERATIONS, DEFAULT_WEIGHT_TOLERANCE, WeightChange, WeightOptions,
};
