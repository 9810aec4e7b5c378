//! # vclay
//!
//! Physics-based free-form modeling ("virtual clay") in Rust. This facade re-exports the layers:
//!
//! - [`core`]: math types, tolerances, parallelism policy, the mesh sink.
//! - [`spline`]: knots, basis functions, NURBS curves, surfaces and volumes, D-NURBS Jacobians,
//!   refinement, primitives, tessellation.
//! - [`lattice`]: polyhedral cell complexes and MacCracken-Joy subdivision solids.
//! - [`ffd`]: direct manipulation of free-form deformation.
//! - [`dynamics`]: D-NURBS (dynamic NURBS curves and surfaces).
//! - [`pde`]: dynamic PDE surfaces (boundary basis functions, collocation least squares).
//! - [`io`]: the JSON model format and mesh files.
//! - [`render`]: headless pictures (PNG, GIF turntables, SVG plots).
//! - [`solids`]: dynamic B-spline and subdivision solids (virtual clay), tools, scenarios.
//!
//! See `docs/architecture.md` in the repository for the map of the layers.
#![warn(missing_docs)]

pub use vclay_core as core;
pub use vclay_dynamics as dynamics;
pub use vclay_ffd as ffd;
pub use vclay_fit as fit;
pub use vclay_io as io;
pub use vclay_lattice as lattice;
pub use vclay_pde as pde;
pub use vclay_render as render;
pub use vclay_session as session;
pub use vclay_solids as solids;
pub use vclay_spline as spline;

pub use vclay_core::{Interval, Parallelism, TriMesh, Vec3, Vec4};
pub use vclay_spline::{
    KnotVector, NurbsCurve, NurbsSurface, NurbsVolume, ParametricCurve, ParametricSurface,
    ParametricVolume, SplineError,
};
