//! # vclay-lattice
//!
//! Polyhedral cell complexes and MacCracken-Joy subdivision solids, the volumetric
//! Catmull-Clark scheme of `subdivision-solids-conference.txt` (section 3.1, Table 1) and
//! `subdivision-solids-journal.txt` (sections 3.3, 4.2, 5.2-5.3).
//!
//! * [`Lattice`]: points, edges, faces and cells of arbitrary polyhedral shape with adjacency in
//!   both directions (radial-edge style, flat arrays with typed ids), built from cells given as
//!   face loops and validated ([`LatticeError`] names the element at fault).
//! * [`subdivide()`]: one level of subdivision, the four rules of the conference paper plus a
//!   [`BoundaryRule`] and user [`Features`] (creases, corners); returns the finer lattice and the
//!   level operator `A^(j)` as a [`SparseMatrix`] (each row an affine combination).
//! * [`SubdivisionSolid`] and [`SubdivisionMap`]: all levels, `d = A p = A^(n)...A^(1) p`
//!   (journal eq 4) and `A^T f` applied level by level without forming the product (each level's
//!   transpose product by scattering the rows of `A^(j)`, in parallel with per-task partial
//!   sums, so no transpose is stored).
//! * [`primitives`]: boxes, cylinders, tori, L and T solids, the paper's torus, gear, cube
//!   with holes and tetrahedron with holes (the paper's single cell and a split one that does not
//!   fold); [`cells`]: face lists of hexahedra, prisms, tetrahedra, pyramids.
//! * [`gallery`]: the papers' extruded models (soccer player, cactus, spiked and holed objects)
//!   built by a [`gallery::Sculptor`] from cubes and face extrusions.
//! * [`write_boundary`]: the outward boundary surface into a [`vclay_core::MeshSink`].
//! * [`limit`]: the limit position and first derivatives at any `(cell, u, v, w)`
//!   ([`LimitEvaluator`]): the tricubic B-spline on regular cells, local subdivision with a stated
//!   tolerance elsewhere; [`limit_surface`]: the boundary limit surface (limit masks, positions
//!   and normals into a sink) and its bicubic patches ([`boundary_patches`], exact in regular
//!   regions, fitted elsewhere with the error).
//! * [`edit`]: [`extrude_face`] and [`delete_cell`] return a new validated lattice with stable
//!   ids (documented there) or an error saying why the edit is refused; [`Features`] tags are
//!   edited in place and carried across edits.
//! * [`formats`]: OpenVolumeMesh `.ovm` (read/write), VTK `.vtu` (write), boundary surface as
//!   OBJ/STL/PLY (write); atomic writes, errors with file, line and element.
//! * [`command`]: the logic of the `vclay subdivide` command line.
//! * [`from_mesh`]: [`lattice_from_mesh`] builds a hexahedral control lattice inside a closed
//!   triangle mesh and fits its level-`L` boundary to the mesh (`vclay clay`); open,
//!   non-manifold or misoriented input is a [`ClayError`] naming edges and triangles.
//!
//! ```
//! use vclay_lattice::{primitives, Features, SubdivisionRules, BoundaryRule, SubdivisionSolid};
//! use vclay_core::Vec3;
//! let cube = primitives::box_lattice([4, 4, 4], Vec3::zeros(), Vec3::repeat(1.0));
//! let features = Features::none(&cube);
//! let solid = SubdivisionSolid::new(cube, features, SubdivisionRules::new(BoundaryRule::Smooth), 2).unwrap();
//! // Conference paper, Table 1, "Cube (4^3)", level 2.
//! assert_eq!(solid.finest().counts().to_array(), [2197, 6084, 5616, 1728]);
//! let d = solid.map().apply(solid.control().points());
//! assert!((d[100] - solid.finest().points()[100]).norm() < 1e-12);
//! ```
//!
//! Limitations: editing operations (extrusion, cell deletion) rebuild the lattice from cells;
//! the surface writers in [`formats::surface`] are local stand-ins until `vclay-io` unifies mesh
//! export.
#![warn(missing_docs)]

pub mod boundary;
pub mod cells;
pub mod command;
pub mod compact;
mod csr;
pub mod edit;
pub mod error;
pub mod formats;
pub mod from_mesh;
pub mod gallery;
pub mod hierarchy;
pub mod ids;
pub mod lattice;
pub mod limit;
pub mod limit_surface;
pub mod map;
pub mod primitives;
pub mod sparse;
pub mod subdivide;
pub mod tensor;

pub use boundary::{boundary_mesh, write_boundary};
pub use compact::CompactMatrix;
pub use edit::{Edit, ExtrudeParams, delete_cell, extrude_face};
pub use error::LatticeError;
pub use formats::FormatError;
pub use from_mesh::{Clay, ClayError, ClayParams, ClayReport, lattice_from_mesh};
pub use hierarchy::SubdivisionSolid;
pub use ids::{CellId, EdgeId, FaceId, VertexId};
pub use lattice::{ElementCounts, Lattice};
pub use limit::{LimitEvaluator, LimitParams, LimitPoint, LimitQuery, cell_frame};
pub use limit_surface::{LimitPatches, boundary_limits, boundary_patches, write_limit_boundary};
pub use map::{ChainWorkspace, SubdivisionMap};
pub use sparse::{Coord, SparseMatrix};
pub use subdivide::{
    BoundaryRule, Features, Refinement, SubdivisionRules, subdivide, subdivision_operator,
};
pub use tensor::{TensorOperator, TensorWorkspace};
