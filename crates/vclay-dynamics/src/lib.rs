//! # vclay-dynamics
//!
//! Physics on top of the geometry layers. This first part is the D-NURBS finite-element model of
//! `d-nurbs.txt` (sections 4.5-6): curves and tensor-product surfaces whose control points are
//! generalized coordinates with mass, damping and thin-plate-under-tension stiffness, integrated
//! by the implicit scheme of eq (18) with an element-by-element conjugate-gradient solver.
//!
//! Two engines: [`Dnurbs`](dnurbs::Dnurbs) with frozen weights (footnote 2: M, D, K constant,
//! factored once) and [`GeneralizedDnurbs`](dnurbs::GeneralizedDnurbs), where control points
//! **and weights** (and a swung surface's profile curves and scale, eq 7) are dynamic, with the
//! generalized inertial force `g_p`, weight positivity and point/normal constraints by Lagrange
//! multipliers. Scenario files of the D-NURBS kinds are read by `vclay-session`.
//!
//! Not yet: triangular D-NURBS (a later issue; they plug in as a
//! [`GeneralizedGeometry`](dnurbs::GeneralizedGeometry)).
#![warn(missing_docs)]

pub mod dnurbs;
pub mod error;

pub use dnurbs::{
    Density, DnurbsClosedCurve, DnurbsCurve, DnurbsSurface, ElasticReference, ElementSystem, Force,
    Integrator, LinearSolver, Material, SolverStats, StepReport,
};
pub use error::DynamicsError;
