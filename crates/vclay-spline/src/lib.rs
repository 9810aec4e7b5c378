//! # vclay-spline
//!
//! Spline geometry, with no notion of time or physics: validated knot vectors, B-spline basis
//! functions and their derivatives, NURBS curves, tensor-product surfaces and trivariate volumes
//! with derivatives of any order, the D-NURBS Jacobians (`d-nurbs.txt` eqs 3-6), batched grid
//! evaluation, exact knot insertion and degree elevation, exact primitives and tessellation.
//!
//! Everything follows Piegl & Tiller, *The NURBS Book* (2nd ed.), whose algorithm numbers are
//! cited at each function, and the D-NURBS paper for the Jacobians.
//!
//! ```
//! use vclay_spline::{NurbsCurve, ParametricCurve};
//! use vclay_core::Vec3;
//! let c = NurbsCurve::circle(Vec3::zeros(), Vec3::x(), Vec3::y(), 2.0).unwrap();
//! let p = c.point(0.3).unwrap();
//! assert!((p.norm() - 2.0).abs() < 1e-14);
//! ```
//!
//! Limitations: degrees up to [`MAX_DEGREE`]; degree elevation clamps unclamped knot vectors
//! first; no knot removal yet.
#![warn(missing_docs)]

pub mod curve;
pub mod error;
pub mod grid;
pub mod jacobian;
pub mod knots;
pub mod primitives;
pub mod refine;
pub mod simplex;
pub mod surface;
pub mod tessellate;
pub mod traits;
pub mod triangular;
mod util;
pub mod volume;

pub use curve::NurbsCurve;
pub use error::{KnotError, NetIndex, SplineError};
pub use grid::{AxisBasis, SurfaceGrid};
pub use jacobian::{SparseJacobian, generalized_coordinates};
pub use knots::{BasisWorkspace, KnotVector, MAX_DEGREE, MAX_DERIVATIVE_ORDER};
pub use simplex::{SimplexError, SimplexSpline};
pub use surface::NurbsSurface;
pub use tessellate::{SurfaceSampling, tessellate_surface, tessellate_volume_boundary};
pub use traits::{ParametricCurve, ParametricSurface, ParametricVolume};
pub use triangular::{
    KnotClouds, TriangularBasis, TriangularError, TriangularNurbs, TriangularPoint, Triangulation,
};
pub use volume::NurbsVolume;
