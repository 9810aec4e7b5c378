//! # vclay-dynamics
//!
//! Physics on top of the geometry layers. This first part is the D-NURBS finite-element model of
//! `d-nurbs.txt` (sections 4.5-6): curves and tensor-product surfaces whose control points are
//! generalized coordinates with mass, damping and thin-plate-under-tension stiffness, integrated
//! by the implicit scheme of eq (18) with an element-by-element conjugate-gradient solver.
//!
//! Limitations of this version (documented, not hidden): weights are frozen (footnote 2 of the
//! paper: M, D, K constant and computed once); dynamic weights with the generalized inertial
//! force g_p, swung and triangular surfaces, and nonlinear constraints are not implemented yet.
#![warn(missing_docs)]

pub mod dnurbs;
pub mod error;
pub mod scenario;

pub use dnurbs::{
    Density, DnurbsClosedCurve, DnurbsCurve, DnurbsSurface, ElasticReference, ElementSystem, Force,
    Integrator, LinearSolver, Material, SolverStats, StepReport,
};
pub use error::DynamicsError;
