//! # vclay-solids
//!
//! Dynamic free-form solids as virtual clay, after McDonnell & Qin,
//! `subdivision-solids-journal.txt` sections 4-5: B-spline solids sampled on a grid (eq 3,
//! `c = B q`) and MacCracken-Joy subdivision solids (eq 4, `d = A p`) share one dynamic core,
//! [`DynamicSolid`]:
//!
//! * data points `d = A p` carry lumped masses and damping and are joined by a Hookean spring
//!   on every lattice edge plus the paper's virtual springs (section 5.1, [`springs`]);
//! * the control points move by eq (10), `A^T M A p'' = A^T f_d - A^T D A p' - A^T f_int`, with
//!   `A^T M A` factored once (sparse Cholesky) and `A` applied level by level, never formed
//!   ([`map`]);
//! * integrators: the paper's explicit scheme (section 4.4), symplectic Euler (default) and a
//!   linearized implicit Euler solved by preconditioned conjugate gradient; divergence stops a
//!   run with the step and a suggested time step; explicit and symplectic steps of models
//!   from [`PHASED_POINTS`] data points run as one phased program on a persistent thread team
//!   ([`vclay_core::team`]; see [`SolidParams::parallelism`]);
//! * tools (section 5.4, [`tools`]): rope, point and region forces, gravity, inflation; run-time
//!   fixing and freeing of control points (section 5.2, with the free/fixed partition
//!   `d = A1 p1 + A2 p2`), plastic reset, material changes, extrusion and cell deletion
//!   mid-run;
//! * scenarios, commands, undo and session files live one layer up, in `vclay-session`,
//!   which drives [`DynamicSolid`] through [`DynamicSolid::state`] /
//!   [`DynamicSolid::set_state`] / [`DynamicSolid::from_parts`] (bitwise snapshots).
//!
//! ```
//! use vclay_solids::{DynamicSolid, Material, SolidParams, SolidSource};
//! use vclay_lattice::{primitives, BoundaryRule, Features, SubdivisionRules};
//! use vclay_core::Vec3;
//! let cube = primitives::box_lattice([2, 2, 2], Vec3::zeros(), Vec3::repeat(1.0));
//! let p = cube.points().to_vec();
//! let source = SolidSource::Subdivision {
//!     features: Features::none(&cube),
//!     control: cube,
//!     rules: SubdivisionRules::new(BoundaryRule::Sharp),
//!     levels: 1,
//! };
//! let mut solid = DynamicSolid::new(source, p, Material::default(), SolidParams::default()).unwrap();
//! solid.attach_rope(Vec3::new(1.5, 1.5, 1.5), 50.0, 0.0).unwrap();
//! solid.run(100).unwrap();
//! // The corner control point at (1, 1, 1) follows the cursor.
//! let corner = solid.control_points_where(|x| x.min() > 0.99)[0];
//! assert!(solid.control_points()[corner].x > 1.1);
//! println!("energy {:?}", solid.energy());
//! ```
//!
//! * [`metric`]: for B-spline solids, the metric-tensor energy of section 4.3 by Gauss
//!   quadrature, selectable instead of the springs ([`DynamicSolid::use_metric_energy`]).
//!
//! Limitations: damping acts on absolute point velocities; B-spline solids cannot be edited
//! topologically.
#![warn(missing_docs)]

pub mod benchmarks;
pub mod error;
pub mod figures;
pub mod map;
pub mod material;
pub mod metric;
pub mod model;
pub mod solid;
pub mod springs;
pub mod tools;

pub use error::SolidsError;
pub use material::{Material, MaterialField};
pub use model::{DataNumbering, Discretization, SolidSource};
pub use solid::{
    DynamicSolid, Energy, Integrator, PHASED_POINTS, SolidParams, SolidRest, SolidState,
    SolidStats, StepReport, ToolId,
};
pub use tools::{Falloff, Tool};
