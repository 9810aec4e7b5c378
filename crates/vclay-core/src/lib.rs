//! # vclay-core
//!
//! The bottom layer of vclay. It fixes the scalar and vector types (everything is `f64`), the
//! tolerance policy, the parallelism policy and the [`mesh::MeshSink`] trait through which every
//! tessellation, exporter and viewer receives triangles.
//!
//! It knows nothing of splines, lattices, time or files. Every other vclay crate depends on it.
#![warn(missing_docs)]

pub mod math;
pub mod mesh;
pub mod par;
pub mod plasticity;
pub mod quadrature;
pub mod team;
pub mod testing;
pub mod text;
pub mod tolerance;
pub mod triangle_rule;
pub mod yardstick;

pub use math::{Interval, Vec3, Vec4};
pub use mesh::{MeshError, MeshSink, TriMesh};
pub use par::{CacheAligned, Parallelism};
pub use plasticity::Plasticity;
pub use quadrature::GaussLegendre;
pub use tolerance::Tolerance;
pub use triangle_rule::TriangleRule;
