//! The error type of the lattice layer.

use crate::ids::{CellId, EdgeId, FaceId, VertexId};
use thiserror::Error;

/// Problems found while building or validating a [`crate::Lattice`].
///
/// Every variant names the offending element: cells by their index in the input, faces by their
/// index inside the cell (`face_in_cell`) and by their vertex loop, so a message reads
/// "cell 3, face 2 [4, 5, 9, 8]: ...".
#[derive(Clone, Debug, Error, PartialEq)]
pub enum LatticeError {
    /// A point has a NaN or infinite coordinate.
    #[error("{point} has a non-finite coordinate")]
    NonFinitePoint {
        /// The point.
        point: VertexId,
    },
    /// A face refers to a point index that does not exist.
    #[error(
        "cell {cell}, face {face_in_cell}: vertex index {index} is out of range ({points} points)"
    )]
    VertexOutOfRange {
        /// Input index of the cell.
        cell: usize,
        /// Index of the face inside the cell.
        face_in_cell: usize,
        /// The offending index.
        index: u32,
        /// Number of points.
        points: usize,
    },
    /// A face has fewer than three vertices.
    #[error("cell {cell}, face {face_in_cell} {vertices:?}: a face needs at least 3 vertices")]
    DegenerateFace {
        /// Input index of the cell.
        cell: usize,
        /// Index of the face inside the cell.
        face_in_cell: usize,
        /// The face's vertex loop.
        vertices: Vec<u32>,
    },
    /// A vertex occurs twice in one face loop.
    #[error("cell {cell}, face {face_in_cell} {vertices:?}: vertex {vertex} occurs more than once")]
    RepeatedVertex {
        /// Input index of the cell.
        cell: usize,
        /// Index of the face inside the cell.
        face_in_cell: usize,
        /// The face's vertex loop.
        vertices: Vec<u32>,
        /// The repeated vertex.
        vertex: u32,
    },
    /// An edge joins two points that coincide (within the geometric tolerance).
    #[error("edge ({a}, {b}) is degenerate: its end points are {length:e} apart")]
    DegenerateEdge {
        /// First end point.
        a: VertexId,
        /// Second end point.
        b: VertexId,
        /// Distance between the end points.
        length: f64,
    },
    /// Two distinct points coincide (within the geometric tolerance).
    #[error("{a} and {b} coincide ({distance:e} apart)")]
    DuplicatePoint {
        /// Lower point id.
        a: VertexId,
        /// Higher point id.
        b: VertexId,
        /// Their distance.
        distance: f64,
    },
    /// A point is not a vertex of any face.
    #[error("{point} is not used by any cell")]
    UnusedPoint {
        /// The point.
        point: VertexId,
    },
    /// The lattice has no cells.
    #[error("the lattice has no cells")]
    Empty,
    /// A cell lists the same face twice.
    #[error("cell {cell} uses face {vertices:?} twice")]
    RepeatedFaceInCell {
        /// Input index of the cell.
        cell: usize,
        /// The face's vertex loop.
        vertices: Vec<u32>,
    },
    /// Two faces have the same vertex set but their loops visit the vertices in different orders.
    #[error("faces {first:?} and {second:?} have the same vertices in a different cyclic order")]
    FaceLoopMismatch {
        /// The loop as first seen.
        first: Vec<u32>,
        /// The conflicting loop.
        second: Vec<u32>,
    },
    /// More than two cells share a face.
    #[error("face {vertices:?} is used by {} cells {cells:?} (at most 2 allowed)", cells.len())]
    FaceUsedByMoreThanTwoCells {
        /// The face's vertex loop.
        vertices: Vec<u32>,
        /// Input indices of all cells using it.
        cells: Vec<usize>,
    },
    /// Two cells traverse their shared face in the same direction: one of them is inside out.
    #[error("cells {cells:?} traverse their shared face {vertices:?} in the same direction")]
    FaceOrientationConflict {
        /// The face's vertex loop.
        vertices: Vec<u32>,
        /// Input indices of the two cells.
        cells: [usize; 2],
    },
    /// An edge of a cell is not used by exactly two of the cell's faces: the cell is not closed.
    #[error(
        "cell {cell} is not closed: edge ({a}, {b}) is used by {uses} of its faces (must be 2)"
    )]
    OpenCell {
        /// Input index of the cell.
        cell: usize,
        /// First end point.
        a: VertexId,
        /// Second end point.
        b: VertexId,
        /// Number of the cell's faces using the edge.
        uses: usize,
    },
    /// Two faces of one cell traverse a shared edge in the same direction.
    #[error("cell {cell} has inconsistent face orientation at edge ({a}, {b})")]
    InconsistentOrientation {
        /// Input index of the cell.
        cell: usize,
        /// First end point.
        a: VertexId,
        /// Second end point.
        b: VertexId,
    },
    /// The faces of a cell around one of its vertices form more than one fan (the cell is pinched
    /// at the vertex), so the vertex has no single corner in the cell.
    #[error("cell {cell} is pinched at {vertex}: its faces there form more than one fan")]
    NonManifoldCellVertex {
        /// Input index of the cell.
        cell: usize,
        /// The vertex.
        vertex: VertexId,
    },
    /// An internal consistency check of a built lattice failed (a bug, reported rather than
    /// panicking so that callers can show it).
    #[error("lattice invariant violated at {element}: {message}")]
    Invariant {
        /// The element, e.g. "face 12".
        element: String,
        /// What is wrong.
        message: String,
    },
    /// Element counts no longer fit the `u32` ids.
    #[error("the subdivided lattice would have {count} {what}, more than u32 ids can address")]
    TooLarge {
        /// Kind of element.
        what: &'static str,
        /// Required count.
        count: usize,
    },
    /// A tagged element does not exist in the lattice.
    #[error("feature tag refers to {element}, which does not exist")]
    BadTag {
        /// The element, e.g. "edge 99".
        element: String,
    },
    /// A face id given to an operation does not exist.
    #[error("{face} does not exist")]
    NoSuchFace {
        /// The face.
        face: FaceId,
    },
    /// A cell id given to an operation does not exist.
    #[error("{cell} does not exist")]
    NoSuchCell {
        /// The cell.
        cell: CellId,
    },
    /// An edit would remove the last cell of the lattice.
    #[error("cannot delete {cell}: it is the only cell of the lattice")]
    LastCell {
        /// The cell.
        cell: CellId,
    },
    /// Deleting a cell would split the lattice into more face-connected pieces.
    #[error(
        "cannot delete {cell}: the lattice would fall apart into {after} pieces (now {before})"
    )]
    WouldDisconnect {
        /// The cell.
        cell: CellId,
        /// Face-connected components before the edit.
        before: usize,
        /// Face-connected components after the edit.
        after: usize,
    },
    /// Deleting a cell would leave a boundary edge in other than two boundary faces.
    #[error(
        "cannot delete {cell}: {edge} (points {a}, {b}) would lie in {boundary_faces} boundary faces (a non-manifold edge)"
    )]
    WouldCreateNonManifoldEdge {
        /// The cell.
        cell: CellId,
        /// The edge, with its id before the edit.
        edge: EdgeId,
        /// First end point (id before the edit).
        a: VertexId,
        /// Second end point (id before the edit).
        b: VertexId,
        /// Number of boundary faces the edge would lie in.
        boundary_faces: usize,
    },
    /// Deleting a cell would pinch the boundary surface at a vertex (its boundary faces there
    /// would form more than one fan).
    #[error(
        "cannot delete {cell}: the boundary would be pinched at {vertex} ({fans} separate fans of boundary faces)"
    )]
    WouldCreateNonManifoldVertex {
        /// The cell.
        cell: CellId,
        /// The vertex, with its id before the edit.
        vertex: VertexId,
        /// Number of fans.
        fans: usize,
    },
    /// A face cannot be extruded.
    #[error("cannot extrude {face}: {reason}")]
    CannotExtrude {
        /// The face.
        face: FaceId,
        /// Why.
        reason: String,
    },
    /// A limit query addresses a cell that is not a hexahedron (limit parameters `(u, v, w)`
    /// are defined on hexahedra; every cell from level 1 on is one).
    #[error(
        "{cell} is not a hexahedron ({vertices} vertices, {faces} faces): limit parameters (u, v, w) address hexahedral cells; subdivide once and address its children"
    )]
    NotHexahedral {
        /// The cell.
        cell: CellId,
        /// Its number of vertices.
        vertices: usize,
        /// Its number of faces.
        faces: usize,
    },
    /// A limit query is invalid (cell out of range, parameter outside `[0, 1]` or not finite).
    #[error("limit query {index}: {message}")]
    LimitQuery {
        /// Index of the query in its list.
        index: usize,
        /// What is wrong.
        message: String,
    },
    /// A limit evaluation parameter is invalid.
    #[error("limit evaluation: {message}")]
    LimitParameter {
        /// What is wrong.
        message: String,
    },
}
