//! # vclay-pde: dynamic PDE surfaces
//!
//! What: surfaces that are solutions of the fourth-order dynamic PDE of You & Zhang,
//! "Fast generation of 3-D deformable moving surfaces" (IEEE TSMC-B 2003,
//! `dynamic-pde-surfaces.txt`), eq (1):
//!
//! `[b_i d4/du4 + c_i d4/du2dv2 + d_i d4/dv4 + rho d2/dt2 + eta d/dt] x_i(u, v, t) = 0`,
//! i = x, y, z, with position and tangent conditions at u = 0 and u = 1 that change with t
//! (eq 2).
//!
//! How (the paper's method): the boundary functions, written by the user as expressions
//! ([`expr`]), are split into basic functions g_ij(v, t) and coefficients ([`basis`], eq 3); the
//! solution `x_i = sum_j W_ij(u) g_ij(v, t)` uses Hermite cubics that meet the boundary
//! conditions exactly plus trial terms `psi_n(u)` that vanish with their slope at both ends
//! ([`trial`], eq 4-5); the remaining constants minimise the squared PDE residual at M
//! collocation points by a column-pivoted QR ([`solve`], [`lsq`], eq 6-12). Animation is a solve
//! per instant ([`model::Animator`]); local deformations add a blended term of G0 or G1
//! continuity ([`patch::LocalDeformation`], eq 30-32); three- and four-sided patches add side
//! conditions as exact linear constraints ([`solve`], eq 33-37). For section III's comparison
//! a patch can instead be solved by Bloor and Wilson's Fourier series or their pseudospectral
//! method ([`spectral`], eq 19-23; the spec's `solver` key).
//!
//! Limitations: as in the paper, the constants p_ijn are treated as independent of t when the
//! PDE's time derivatives are taken (eq 7), so each instant is an independent solve rather than
//! a time integration. Derivatives of basic functions are symbolic; expressions are evaluated
//! by walking the tree (once per grid column, not per point).
//!
//! Entry points: [`PdeModel::read`] / [`PdeModel::from_json`] (spec files, see
//! `docs/formats.md`), [`PdeModel::solve`], [`PdeModel::tessellate`], [`Animator::frame`].
#![warn(missing_docs)]

pub mod basis;
pub mod builtin;
pub mod error;
pub mod expr;
pub mod lsq;
pub mod model;
pub mod patch;
pub mod solve;
pub mod spec;
pub mod spectral;
pub mod surface;
pub mod trial;

pub use error::PdeError;
pub use expr::{Expr, ExprError, Var};
pub use model::{Animator, ModelSolution, RESIDUAL_WARNING_RATIO, ResidualCheck, frame_times};
pub use patch::{Continuity, Field, LocalDeformation, PdePatch};
pub use solve::{PatchSolution, SolveStats, Solver};
pub use spec::{PdeModel, SpecFile};
pub use spectral::{Method, SpectralSolution};
pub use trial::PatchKind;
