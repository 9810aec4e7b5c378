//! The cell complex: points, edges, faces and cells with adjacency in both directions.
//!
//! # What
//! A [`Lattice`] is the control (or subdivided) lattice of a subdivision solid
//! (`subdivision-solids-journal.txt` section 3.3 and 5.3; `subdivision-solids-conference.txt`
//! section 3.1): "a set of closed cells that are defined by a collection of their constituent
//! faces. The faces ... are comprised of an ordered list of edges that are defined by their end
//! vertices." Cells are arbitrary closed polyhedra (hexahedra, prisms, tetrahedra, pyramids,
//! non-convex many-faced cells, even cells with handles); faces are arbitrary polygons (planar or
//! not).
//!
//! # How
//! In the spirit of the radial-edge structure the papers use (Weiler 1986; journal section 5.3),
//! but as flat arrays with integer ids instead of pointer graphs:
//! * downward: cell -> faces, face -> vertex loop and edge loop, edge -> two vertices; cell ->
//!   edges and cell -> vertices (sorted by id);
//! * upward: vertex -> edges, faces, cells; edge -> faces **in radial order** and the cells
//!   between them; face -> the cells on its two sides.
//!
//! Every list is a compressed sparse row array (`offsets` + `data`), so a 900k-cell lattice is a
//! handful of allocations.
//!
//! ## Conventions (invariants kept by every constructor)
//! * Edge `e` is stored as `[a, b]` with `a < b`; "the direction of `e`" is `a -> b`.
//! * Face `f` has a stored vertex loop `v_0 .. v_{k-1}`; its edge loop has `e_i = (v_i, v_{i+1})`.
//! * `face_cells(f) = [front, back]`: the front cell sees the stored loop counter-clockwise from
//!   outside (the right-hand normal of the loop points out of the front cell); the back cell uses
//!   the face reversed. The front cell always exists, so a boundary face's stored loop is oriented
//!   outward.
//! * Each cell's faces, taken with the orientation the cell uses, are oriented outward: every edge
//!   of the cell is used by exactly two of its faces, once in each direction.
//! * `edge_faces(e)` lists the faces around `e` counter-clockwise about the direction `a -> b`
//!   (right-hand rule); `edge_cells(e)` lists the cells met on that walk: for a closed fan cell
//!   `k` lies between faces `k` and `k+1` (cyclically), for an open (boundary) fan between faces
//!   `k` and `k+1`, and an edge where several fans meet lists them one after the other.
//!
//! # Limitations
//! * Faces are not checked for planarity or zero area; cells are not checked for
//!   self-intersection. Orientation is decided combinatorially, then each connected component is
//!   flipped as a whole if its total signed volume is negative (so inside-out input is accepted).
//! * The structure is immutable apart from point positions; editing operations (extrude, delete)
//!   rebuild it.

use std::collections::HashMap;
use std::sync::OnceLock;

use vclay_core::{Tolerance, Vec3};

use crate::csr::{Csr, par_build2};
use crate::error::LatticeError;
use crate::ids::{CellId, EdgeId, FaceId, VertexId};

/// Element counts of a lattice: points, edges, faces, cells (the columns of the conference
/// paper's Table 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct ElementCounts {
    /// Number of points (vertices).
    pub points: usize,
    /// Number of edges.
    pub edges: usize,
    /// Number of faces.
    pub faces: usize,
    /// Number of cells.
    pub cells: usize,
}

impl ElementCounts {
    /// Counts as an array `[points, edges, faces, cells]`.
    pub fn to_array(self) -> [usize; 4] {
        [self.points, self.edges, self.faces, self.cells]
    }

    /// Euler characteristic `P - E + F - C` of the complex.
    pub fn euler_characteristic(self) -> i64 {
        self.points as i64 - self.edges as i64 + self.faces as i64 - self.cells as i64
    }
}

/// A polyhedral cell complex: the control or subdivided lattice of a subdivision solid
/// (`subdivision-solids-conference.txt` section 3.1; radial-edge adjacency as in
/// `subdivision-solids-journal.txt` section 5.3). See the [module docs](self) for conventions.
#[derive(Clone, Debug)]
pub struct Lattice {
    pub(crate) points: Vec<Vec3>,
    pub(crate) edges: Vec<[VertexId; 2]>,
    pub(crate) face_offsets: Vec<u32>,
    pub(crate) face_vertices: Vec<VertexId>,
    pub(crate) face_edges: Vec<EdgeId>,
    pub(crate) face_cells: Vec<[CellId; 2]>,
    pub(crate) cell_faces: Csr<FaceId>,
    /// Upward adjacency and cell -> edges / vertices, built on first use.
    derived: OnceLock<Derived>,
}

/// The adjacency lists derived from the primary (downward) topology.
#[derive(Clone, Debug)]
pub(crate) struct Derived {
    pub vertex_edges: Csr<EdgeId>,
    pub vertex_faces: Csr<FaceId>,
    pub vertex_cells: Csr<CellId>,
    pub edge_faces: Csr<FaceId>,
    pub edge_cells: Csr<CellId>,
    pub cell_edges: Csr<EdgeId>,
    pub cell_vertices: Csr<VertexId>,
}

/// Topology without the derived (upward) adjacency; [`Lattice::assemble`] completes it.
pub(crate) struct Primary {
    pub points: Vec<Vec3>,
    pub edges: Vec<[VertexId; 2]>,
    pub face_offsets: Vec<u32>,
    pub face_vertices: Vec<VertexId>,
    pub face_edges: Vec<EdgeId>,
    pub face_cells: Vec<[CellId; 2]>,
    pub cell_faces: Csr<FaceId>,
}

/// Whether a batch of `n` items should be split over threads.
#[inline]
pub(crate) fn par_for(n: usize) -> bool {
    n >= 8192
}

/// Sorts `v[start..]` and removes duplicates there.
fn sort_dedup_tail<T: Ord + Copy>(v: &mut Vec<T>, start: usize) {
    v[start..].sort_unstable();
    let mut w = start;
    for r in start..v.len() {
        if w == start || v[r] != v[w - 1] {
            v[w] = v[r];
            w += 1;
        }
    }
    v.truncate(w);
}

impl Lattice {
    // ----------------------------------------------------------------------------------------
    // Construction
    // ----------------------------------------------------------------------------------------

    /// Builds and validates a lattice from points and cells, each cell a list of faces and each
    /// face a vertex loop (indices into `points`), using [`Tolerance::GEOMETRIC`] for the
    /// coincident-point checks. See [`Lattice::from_cells_with`].
    pub fn from_cells(points: Vec<Vec3>, cells: &[Vec<Vec<u32>>]) -> Result<Self, LatticeError> {
        Self::from_cells_with(points, cells, Tolerance::GEOMETRIC)
    }

    /// Builds and validates a lattice from points and cells (faces as vertex loops).
    ///
    /// Faces shared by two cells are recognised by their vertex set; their loops must agree up to
    /// rotation and reversal. Face loops of a cell should be counter-clockwise seen from outside
    /// the cell; a connected component given entirely inside out is flipped (its total signed
    /// volume decides). `tolerance` is relative to the largest absolute coordinate and decides when
    /// two points coincide.
    ///
    /// Checks, in this order, each reported with the element it concerns: non-finite
    /// coordinates, no cells, vertex index out of range, faces with fewer than 3 vertices or a
    /// repeated vertex, a face used twice by one cell, faces with equal vertex sets but different
    /// loops, a face used by more than two cells, two cells using a shared face in the same
    /// direction, zero-length edges, coincident points, unused points, cells that are not closed
    /// (an edge used by other than two of the cell's faces), inconsistent orientation inside a
    /// cell, and cells pinched at a vertex.
    pub fn from_cells_with(
        points: Vec<Vec3>,
        cells: &[Vec<Vec<u32>>],
        tolerance: Tolerance,
    ) -> Result<Self, LatticeError> {
        if let Some(i) = points.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(LatticeError::NonFinitePoint {
                point: VertexId::new(i),
            });
        }
        if cells.is_empty() {
            return Err(LatticeError::Empty);
        }
        let np = points.len();
        // Per-face checks.
        for (c, cell) in cells.iter().enumerate() {
            for (j, face) in cell.iter().enumerate() {
                if let Some(&bad) = face.iter().find(|&&v| v as usize >= np) {
                    return Err(LatticeError::VertexOutOfRange {
                        cell: c,
                        face_in_cell: j,
                        index: bad,
                        points: np,
                    });
                }
                if face.len() < 3 {
                    return Err(LatticeError::DegenerateFace {
                        cell: c,
                        face_in_cell: j,
                        vertices: face.clone(),
                    });
                }
                for (a, &va) in face.iter().enumerate() {
                    if face[a + 1..].contains(&va) {
                        return Err(LatticeError::RepeatedVertex {
                            cell: c,
                            face_in_cell: j,
                            vertices: face.clone(),
                            vertex: va,
                        });
                    }
                }
            }
        }

        // Shared faces by vertex set.
        struct FaceRec {
            lp: Vec<u32>,
            uses: Vec<(usize, bool)>, // (cell, reversed relative to lp)
        }
        let mut face_index: HashMap<Vec<u32>, usize> = HashMap::new();
        let mut faces: Vec<FaceRec> = Vec::new();
        let mut cell_face_ids: Vec<Vec<usize>> = Vec::with_capacity(cells.len());
        for (c, cell) in cells.iter().enumerate() {
            let mut ids = Vec::with_capacity(cell.len());
            for face in cell {
                let mut key = face.clone();
                key.sort_unstable();
                match face_index.get(&key) {
                    None => {
                        face_index.insert(key, faces.len());
                        ids.push(faces.len());
                        faces.push(FaceRec {
                            lp: face.clone(),
                            uses: vec![(c, false)],
                        });
                    }
                    Some(&fi) => {
                        let rec = &mut faces[fi];
                        let reversed = match same_cycle(&rec.lp, face) {
                            Some(r) => r,
                            None => {
                                return Err(LatticeError::FaceLoopMismatch {
                                    first: rec.lp.clone(),
                                    second: face.clone(),
                                });
                            }
                        };
                        if rec.uses.iter().any(|u| u.0 == c) {
                            return Err(LatticeError::RepeatedFaceInCell {
                                cell: c,
                                vertices: face.clone(),
                            });
                        }
                        rec.uses.push((c, reversed));
                        ids.push(fi);
                    }
                }
            }
            cell_face_ids.push(ids);
        }
        for rec in &faces {
            if rec.uses.len() > 2 {
                return Err(LatticeError::FaceUsedByMoreThanTwoCells {
                    vertices: rec.lp.clone(),
                    cells: rec.uses.iter().map(|u| u.0).collect(),
                });
            }
            if rec.uses.len() == 2 && !rec.uses[1].1 {
                return Err(LatticeError::FaceOrientationConflict {
                    vertices: rec.lp.clone(),
                    cells: [rec.uses[0].0, rec.uses[1].0],
                });
            }
        }

        // Edges, in order of first appearance.
        let mut edge_index: HashMap<(u32, u32), u32> = HashMap::new();
        let mut edges: Vec<[VertexId; 2]> = Vec::new();
        let mut face_edge_ids: Vec<Vec<u32>> = Vec::with_capacity(faces.len());
        for rec in &faces {
            let k = rec.lp.len();
            let mut fe = Vec::with_capacity(k);
            for i in 0..k {
                let (a, b) = (rec.lp[i], rec.lp[(i + 1) % k]);
                let key = (a.min(b), a.max(b));
                let id = *edge_index.entry(key).or_insert_with(|| {
                    edges.push([VertexId(key.0), VertexId(key.1)]);
                    (edges.len() - 1) as u32
                });
                fe.push(id);
            }
            face_edge_ids.push(fe);
        }

        // Geometry: zero-length edges, coincident points, unused points.
        let scale = points
            .iter()
            .flat_map(|p| p.iter().map(|c| c.abs()))
            .fold(0.0f64, f64::max);
        let tol = tolerance.scaled(scale);
        for &[a, b] in &edges {
            let length = (points[a.index()] - points[b.index()]).norm();
            if length <= tol {
                return Err(LatticeError::DegenerateEdge { a, b, length });
            }
        }
        if let Some((a, b, distance)) = find_coincident(&points, tol) {
            return Err(LatticeError::DuplicatePoint { a, b, distance });
        }
        let mut used = vec![false; np];
        for rec in &faces {
            for &v in &rec.lp {
                used[v as usize] = true;
            }
        }
        if let Some(i) = used.iter().position(|u| !u) {
            return Err(LatticeError::UnusedPoint {
                point: VertexId::new(i),
            });
        }

        // Per cell: closed, consistently oriented, not pinched at a vertex.
        for (c, cell) in cells.iter().enumerate() {
            check_cell(c, cell)?;
        }

        // Orientation of connected components by signed volume.
        let nc = cells.len();
        let mut parent: Vec<usize> = (0..nc).collect();
        fn find(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        for rec in &faces {
            if rec.uses.len() == 2 {
                let (ra, rb) = (
                    find(&mut parent, rec.uses[0].0),
                    find(&mut parent, rec.uses[1].0),
                );
                parent[ra] = rb;
            }
        }
        let mut volume = vec![0.0f64; nc];
        for (c, cell) in cells.iter().enumerate() {
            let r = find(&mut parent, c);
            volume[r] += loops_signed_volume(&points, cell.iter().map(|f| f.as_slice()), false);
        }
        let flip: Vec<bool> = (0..nc)
            .map(|c| {
                let r = find(&mut parent, c);
                volume[r] < 0.0
            })
            .collect();

        // Assemble the primary arrays.
        let nf = faces.len();
        let mut face_offsets = Vec::with_capacity(nf + 1);
        face_offsets.push(0u32);
        let mut face_vertices = Vec::new();
        let mut face_edges = Vec::new();
        let mut face_cells = Vec::with_capacity(nf);
        for (fi, rec) in faces.iter().enumerate() {
            let k = rec.lp.len();
            let c0 = rec.uses[0].0;
            if flip[c0] {
                // Reverse the loop v0, v_{k-1}, ..., v1; edge i of the reversed loop joins
                // v_{-i} and v_{-i-1}, i.e. the old edge (k - 1 - i).
                face_vertices.push(VertexId(rec.lp[0]));
                face_vertices.extend(rec.lp[1..].iter().rev().map(|&v| VertexId(v)));
                face_edges.extend((0..k).map(|i| EdgeId(face_edge_ids[fi][(2 * k - 1 - i) % k])));
            } else {
                face_vertices.extend(rec.lp.iter().map(|&v| VertexId(v)));
                face_edges.extend(face_edge_ids[fi].iter().map(|&e| EdgeId(e)));
            }
            face_offsets.push(face_vertices.len() as u32);
            let back = rec.uses.get(1).map_or(CellId::NONE, |u| CellId::new(u.0));
            face_cells.push([CellId::new(c0), back]);
        }
        let cell_faces = Csr::par_build(nc, false, |c, out| {
            out.extend(cell_face_ids[c].iter().map(|&f| FaceId::new(f)));
        });
        Ok(Self::assemble(Primary {
            points,
            edges,
            face_offsets,
            face_vertices,
            face_edges,
            face_cells,
            cell_faces,
        }))
    }

    /// Wraps primary topology; the derived adjacency is built on first use.
    pub(crate) fn assemble(p: Primary) -> Self {
        Lattice {
            points: p.points,
            edges: p.edges,
            face_offsets: p.face_offsets,
            face_vertices: p.face_vertices,
            face_edges: p.face_edges,
            face_cells: p.face_cells,
            cell_faces: p.cell_faces,
            derived: OnceLock::new(),
        }
    }

    /// The derived adjacency, building it on first use.
    #[inline]
    pub(crate) fn d(&self) -> &Derived {
        self.derived.get_or_init(|| self.build_derived())
    }

    /// Builds the upward adjacency (vertex -> edges, faces, cells; edge -> faces in radial order
    /// and cells; cell -> edges, vertices) now instead of on first use. Accessors that need it
    /// call this implicitly; it is cached, so this only moves the cost (useful before timing or
    /// before handing the lattice to many threads).
    pub fn build_adjacency(&self) {
        self.d();
    }

    /// Whether the upward adjacency has been built (see [`Lattice::build_adjacency`]).
    pub fn has_adjacency(&self) -> bool {
        self.derived.get().is_some()
    }

    fn build_derived(&self) -> Derived {
        let np = self.points.len();
        let ne = self.edges.len();
        let nf = self.face_cells.len();
        let nc = self.cell_faces.len();
        let par = par_for(ne);
        let edges = &self.edges;
        let face_offsets = &self.face_offsets;
        let face_vertices = &self.face_vertices;
        let face_edges = &self.face_edges;
        let face_cells = &self.face_cells;
        let cell_faces = &self.cell_faces;
        let ((vertex_edges, vertex_faces), (edge_faces, (cell_edges, cell_vertices))) = rayon::join(
            || {
                rayon::join(
                    || {
                        Csr::group(np, 2 * ne, || {
                            edges.iter().enumerate().flat_map(|(e, &[a, b])| {
                                [(a.0, EdgeId(e as u32)), (b.0, EdgeId(e as u32))]
                            })
                        })
                    },
                    || {
                        Csr::group(np, face_vertices.len(), || {
                            (0..nf).flat_map(move |f| {
                                face_vertices
                                    [face_offsets[f] as usize..face_offsets[f + 1] as usize]
                                    .iter()
                                    .map(move |v| (v.0, FaceId(f as u32)))
                            })
                        })
                    },
                )
            },
            || {
                rayon::join(
                    || {
                        let unordered: Csr<FaceId> = Csr::group(ne, face_edges.len(), || {
                            (0..nf).flat_map(move |f| {
                                face_edges[face_offsets[f] as usize..face_offsets[f + 1] as usize]
                                    .iter()
                                    .map(move |e| (e.0, FaceId(f as u32)))
                            })
                        });
                        radial_order(
                            edges,
                            face_offsets,
                            face_vertices,
                            face_edges,
                            face_cells,
                            &unordered,
                            par,
                        )
                    },
                    || {
                        par_build2(
                            nc,
                            par_for(nc),
                            |c, ev: &mut Vec<EdgeId>, vv: &mut Vec<VertexId>| {
                                let (se, sv) = (ev.len(), vv.len());
                                for &f in cell_faces.get(c) {
                                    let r = face_offsets[f.index()] as usize
                                        ..face_offsets[f.index() + 1] as usize;
                                    ev.extend_from_slice(&face_edges[r.clone()]);
                                    vv.extend_from_slice(&face_vertices[r]);
                                }
                                sort_dedup_tail(ev, se);
                                sort_dedup_tail(vv, sv);
                            },
                        )
                    },
                )
            },
        );
        let (edge_faces, edge_cells) = edge_faces;
        let vertex_cells = Csr::group(np, cell_vertices.data.len(), || {
            (0..nc).flat_map(|c| {
                cell_vertices
                    .get(c)
                    .iter()
                    .map(move |v| (v.0, CellId(c as u32)))
            })
        });
        Derived {
            vertex_edges,
            vertex_faces,
            vertex_cells,
            edge_faces,
            edge_cells,
            cell_edges,
            cell_vertices,
        }
    }

    // ----------------------------------------------------------------------------------------
    // Counts and geometry
    // ----------------------------------------------------------------------------------------

    /// Element counts.
    pub fn counts(&self) -> ElementCounts {
        ElementCounts {
            points: self.points.len(),
            edges: self.edges.len(),
            faces: self.face_cells.len(),
            cells: self.cell_faces.len(),
        }
    }

    /// Number of points.
    pub fn num_points(&self) -> usize {
        self.points.len()
    }

    /// Number of edges.
    pub fn num_edges(&self) -> usize {
        self.edges.len()
    }

    /// Number of faces.
    pub fn num_faces(&self) -> usize {
        self.face_cells.len()
    }

    /// Number of cells.
    pub fn num_cells(&self) -> usize {
        self.cell_faces.len()
    }

    /// All point positions, indexed by [`VertexId`].
    pub fn points(&self) -> &[Vec3] {
        &self.points
    }

    /// Mutable point positions (the topology is unaffected; no validation is repeated).
    pub fn points_mut(&mut self) -> &mut [Vec3] {
        &mut self.points
    }

    /// Replaces all point positions.
    ///
    /// # Panics
    /// If `points.len()` differs from [`Lattice::num_points`] (a programmer error).
    #[track_caller]
    pub fn set_points(&mut self, points: Vec<Vec3>) {
        assert_eq!(
            points.len(),
            self.points.len(),
            "set_points: wrong number of points"
        );
        self.points = points;
    }

    /// Position of a point.
    pub fn point(&self, v: VertexId) -> Vec3 {
        self.points[v.index()]
    }

    /// Midpoint of an edge.
    pub fn edge_midpoint(&self, e: EdgeId) -> Vec3 {
        let [a, b] = self.edges[e.index()];
        (self.points[a.index()] + self.points[b.index()]) * 0.5
    }

    /// Centroid (vertex average) of a face.
    pub fn face_centroid(&self, f: FaceId) -> Vec3 {
        let vs = self.face_vertices(f);
        vs.iter().map(|v| self.points[v.index()]).sum::<Vec3>() / vs.len() as f64
    }

    /// Centroid (vertex average) of a cell: the cell point of the subdivision rules.
    pub fn cell_centroid(&self, c: CellId) -> Vec3 {
        let vs = self.cell_vertices(c);
        vs.iter().map(|v| self.points[v.index()]).sum::<Vec3>() / vs.len() as f64
    }

    /// Signed volume of a cell, with each face fan-triangulated around its centroid (exact for
    /// planar faces). Positive for the outward orientation this structure keeps.
    pub fn cell_signed_volume(&self, c: CellId) -> f64 {
        let faces = self.cell_faces(c);
        let mut loops: Vec<Vec<u32>> = Vec::with_capacity(faces.len());
        for &f in faces {
            let mut l: Vec<u32> = self.face_vertices(f).iter().map(|v| v.0).collect();
            if self.face_cells[f.index()][1] == c {
                l.reverse();
            }
            loops.push(l);
        }
        loops_signed_volume(&self.points, loops.iter().map(|l| l.as_slice()), false)
    }

    // ----------------------------------------------------------------------------------------
    // Downward adjacency
    // ----------------------------------------------------------------------------------------

    /// All edges as `[a, b]` with `a < b`.
    pub fn edges(&self) -> &[[VertexId; 2]] {
        &self.edges
    }

    /// End points `[a, b]` of an edge, `a < b`.
    pub fn edge_vertices(&self, e: EdgeId) -> [VertexId; 2] {
        self.edges[e.index()]
    }

    /// The stored vertex loop of a face (counter-clockwise seen from its front cell's outside).
    pub fn face_vertices(&self, f: FaceId) -> &[VertexId] {
        &self.face_vertices
            [self.face_offsets[f.index()] as usize..self.face_offsets[f.index() + 1] as usize]
    }

    /// The edge loop of a face: edge `i` joins vertices `i` and `i + 1` of [`Lattice::face_vertices`].
    pub fn face_edges(&self, f: FaceId) -> &[EdgeId] {
        &self.face_edges
            [self.face_offsets[f.index()] as usize..self.face_offsets[f.index() + 1] as usize]
    }

    /// The faces of a cell, in input order (subdivided cells: face quads first, then the cell's
    /// interior quads).
    pub fn cell_faces(&self, c: CellId) -> &[FaceId] {
        self.cell_faces.get(c.index())
    }

    /// Whether cell `c` uses face `f` opposite to the face's stored loop (i.e. `c` is the back cell).
    pub fn cell_uses_face_reversed(&self, c: CellId, f: FaceId) -> bool {
        self.face_cells[f.index()][1] == c
    }

    /// The edges of a cell, sorted by id.
    pub fn cell_edges(&self, c: CellId) -> &[EdgeId] {
        self.d().cell_edges.get(c.index())
    }

    /// The vertices of a cell, sorted by id.
    pub fn cell_vertices(&self, c: CellId) -> &[VertexId] {
        self.d().cell_vertices.get(c.index())
    }

    // ----------------------------------------------------------------------------------------
    // Upward adjacency
    // ----------------------------------------------------------------------------------------

    /// The edges that contain a vertex (sorted by id).
    pub fn vertex_edges(&self, v: VertexId) -> &[EdgeId] {
        self.d().vertex_edges.get(v.index())
    }

    /// The faces that contain a vertex (sorted by id).
    pub fn vertex_faces(&self, v: VertexId) -> &[FaceId] {
        self.d().vertex_faces.get(v.index())
    }

    /// The cells that contain a vertex (sorted by id).
    pub fn vertex_cells(&self, v: VertexId) -> &[CellId] {
        self.d().vertex_cells.get(v.index())
    }

    /// The faces around an edge in radial order (see the module conventions).
    pub fn edge_faces(&self, e: EdgeId) -> &[FaceId] {
        self.d().edge_faces.get(e.index())
    }

    /// The cells around an edge in radial order (see the module conventions).
    pub fn edge_cells(&self, e: EdgeId) -> &[CellId] {
        self.d().edge_cells.get(e.index())
    }

    /// The cells on the two sides of a face: `[front, back]`; `back` is `None` on the boundary.
    pub fn face_cells(&self, f: FaceId) -> [Option<CellId>; 2] {
        let [a, b] = self.face_cells[f.index()];
        [a.get(), b.get()]
    }

    /// The edge joining `a` and `b`, if any.
    pub fn edge_between(&self, a: VertexId, b: VertexId) -> Option<EdgeId> {
        let key = [a.min(b), a.max(b)];
        self.vertex_edges(a)
            .iter()
            .copied()
            .find(|e| self.edges[e.index()] == key)
    }

    /// The face whose vertex set equals `vertices` (any order), if any.
    pub fn face_with_vertices(&self, vertices: &[VertexId]) -> Option<FaceId> {
        let first = *vertices.first()?;
        let mut want = vertices.to_vec();
        want.sort_unstable();
        self.vertex_faces(first).iter().copied().find(|&f| {
            let mut have = self.face_vertices(f).to_vec();
            have.sort_unstable();
            have == want
        })
    }

    /// Whether a face lies on the boundary (has one cell).
    pub fn is_boundary_face(&self, f: FaceId) -> bool {
        !self.face_cells[f.index()][1].is_some()
    }

    /// Whether an edge lies on the boundary (is contained in a boundary face).
    pub fn is_boundary_edge(&self, e: EdgeId) -> bool {
        self.edge_faces(e).iter().any(|&f| self.is_boundary_face(f))
    }

    /// Whether a vertex lies on the boundary (is contained in a boundary face).
    pub fn is_boundary_vertex(&self, v: VertexId) -> bool {
        self.vertex_faces(v)
            .iter()
            .any(|&f| self.is_boundary_face(f))
    }

    /// The boundary faces, in id order.
    pub fn boundary_faces(&self) -> impl Iterator<Item = FaceId> + '_ {
        (0..self.num_faces())
            .map(|f| FaceId(f as u32))
            .filter(|&f| self.is_boundary_face(f))
    }

    /// The same lattice with its points renumbered: new point `i` is old point `order[i]`.
    /// Edge, face and cell ids, every face loop's start and direction, and the geometry stay;
    /// edges are re-stored as `[a, b]` with `a < b` in the new ids (so an edge's direction may
    /// flip). Errors with [`LatticeError::Invariant`] naming the first bad entry if `order` is
    /// not a permutation of the point ids.
    pub fn renumber_points(&self, order: &[u32]) -> Result<Lattice, LatticeError> {
        let np = self.num_points();
        let bad = |i: usize, message: &str| LatticeError::Invariant {
            element: format!("order[{i}]"),
            message: message.to_string(),
        };
        if order.len() != np {
            return Err(bad(
                order.len(),
                "order length differs from the point count",
            ));
        }
        let mut new_of_old = vec![u32::MAX; np];
        for (i, &o) in order.iter().enumerate() {
            let slot = new_of_old
                .get_mut(o as usize)
                .ok_or_else(|| bad(i, "point id out of range"))?;
            if *slot != u32::MAX {
                return Err(bad(i, "point id repeated"));
            }
            *slot = i as u32;
        }
        let map = |v: VertexId| VertexId(new_of_old[v.index()]);
        Ok(Lattice::assemble(Primary {
            points: order.iter().map(|&o| self.points[o as usize]).collect(),
            edges: self
                .edges
                .iter()
                .map(|&[a, b]| {
                    let (a, b) = (map(a), map(b));
                    [a.min(b), a.max(b)]
                })
                .collect(),
            face_offsets: self.face_offsets.clone(),
            face_vertices: self.face_vertices.iter().map(|&v| map(v)).collect(),
            face_edges: self.face_edges.clone(),
            face_cells: self.face_cells.clone(),
            cell_faces: self.cell_faces.clone(),
        }))
    }

    /// A cache-friendly numbering of the points from the topology alone (the same for every
    /// placement of the points): Cuthill-McKee, a breadth-first sweep along the edges that
    /// starts at a pseudo-peripheral point (the last one reached by a sweep from point 0) and
    /// visits each point's unnumbered neighbours by increasing valence; each connected component
    /// in turn. Neighbours end up at nearby ids, so passes over springs or stencils touch a
    /// narrow moving window of memory (a breadth-first front), and contiguous id ranges are
    /// compact regions with small boundaries. Feed it to [`Lattice::renumber_points`].
    pub fn locality_order(&self) -> Vec<u32> {
        let n = self.num_points();
        let d = self.d();
        let neighbours = |v: usize| {
            d.vertex_edges.get(v).iter().map(move |e| {
                let [a, b] = self.edges[e.index()];
                if a.index() == v { b.0 } else { a.0 }
            })
        };
        let valence = |v: u32| d.vertex_edges.get(v as usize).len();
        let mut mark = vec![u32::MAX; n];
        let mut order: Vec<u32> = Vec::with_capacity(n);
        // Breadth-first sweep of the component of `start`, appending to `out` and marking
        // with `tag`; neighbours by increasing valence.
        let sweep = |start: u32, tag: u32, mark: &mut [u32], out: &mut Vec<u32>| {
            let first = out.len();
            mark[start as usize] = tag;
            out.push(start);
            let mut head = first;
            let mut next: Vec<u32> = Vec::new();
            while head < out.len() {
                let v = out[head] as usize;
                head += 1;
                next.clear();
                next.extend(neighbours(v).filter(|&w| mark[w as usize] != tag));
                next.sort_unstable_by_key(|&w| (valence(w), w));
                for &w in &next {
                    if mark[w as usize] != tag {
                        mark[w as usize] = tag;
                        out.push(w);
                    }
                }
            }
            out.len() - first
        };
        let mut probe = Vec::new();
        for s in 0..n as u32 {
            if mark[s as usize] != u32::MAX {
                continue;
            }
            // Pseudo-peripheral start: the last point reached from `s` (tagged 0, then the
            // real sweep overwrites the tags with 1).
            probe.clear();
            sweep(s, 0, &mut mark, &mut probe);
            let start = *probe.last().unwrap_or(&s);
            sweep(start, 1, &mut mark, &mut order);
        }
        order
    }

    // ----------------------------------------------------------------------------------------
    // Validation
    // ----------------------------------------------------------------------------------------

    /// Re-checks every invariant of the stored structure (the module's conventions, closedness
    /// and orientation of cells, uniqueness of edges and faces, and the consistency of all upward
    /// lists with the downward ones). Constructors guarantee these; this is for tests and for
    /// lattices whose points or topology came from elsewhere. Costs a few passes over all arrays.
    pub fn validate(&self) -> Result<(), LatticeError> {
        let inv = |element: String, message: &str| LatticeError::Invariant {
            element,
            message: message.to_string(),
        };
        let np = self.num_points();
        if let Some(i) = self
            .points
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(LatticeError::NonFinitePoint {
                point: VertexId::new(i),
            });
        }
        // Edges.
        let mut sorted = self.edges.clone();
        for (e, &[a, b]) in self.edges.iter().enumerate() {
            if !(a < b && b.index() < np) {
                return Err(inv(
                    format!("edge {e}"),
                    "end points not ordered or out of range",
                ));
            }
        }
        sorted.sort_unstable();
        if sorted.windows(2).any(|w| w[0] == w[1]) {
            return Err(inv("edges".into(), "duplicate edge"));
        }
        // Faces.
        let mut keys: Vec<Vec<VertexId>> = Vec::with_capacity(self.num_faces());
        for f in 0..self.num_faces() {
            let fid = FaceId(f as u32);
            let vs = self.face_vertices(fid);
            let es = self.face_edges(fid);
            let k = vs.len();
            if k < 3 || es.len() != k {
                return Err(inv(format!("face {f}"), "fewer than 3 vertices"));
            }
            for i in 0..k {
                let (a, b) = (vs[i], vs[(i + 1) % k]);
                if self.edges[es[i].index()] != [a.min(b), a.max(b)] {
                    return Err(inv(
                        format!("face {f}"),
                        "edge loop does not match vertex loop",
                    ));
                }
            }
            let mut key = vs.to_vec();
            key.sort_unstable();
            if key.windows(2).any(|w| w[0] == w[1]) {
                return Err(inv(format!("face {f}"), "repeated vertex"));
            }
            keys.push(key);
            let [c0, c1] = self.face_cells[f];
            if !c0.is_some() {
                return Err(inv(format!("face {f}"), "no front cell"));
            }
            for c in [c0, c1].into_iter().filter(|c| c.is_some()) {
                if !self.cell_faces(c).contains(&fid) {
                    return Err(inv(format!("face {f}"), "side cell does not list the face"));
                }
            }
        }
        keys.sort_unstable();
        if keys.windows(2).any(|w| w[0] == w[1]) {
            return Err(inv("faces".into(), "two faces with the same vertex set"));
        }
        // Cells: closed and consistently oriented.
        for c in 0..self.num_cells() {
            let cid = CellId(c as u32);
            let mut directed: Vec<(EdgeId, bool)> = Vec::new();
            for &f in self.cell_faces(cid) {
                let [c0, c1] = self.face_cells[f.index()];
                if c0 != cid && c1 != cid {
                    return Err(inv(
                        format!("cell {c}"),
                        "lists a face that does not list it",
                    ));
                }
                let rev = c1 == cid;
                let vs = self.face_vertices(f);
                for (i, &e) in self.face_edges(f).iter().enumerate() {
                    let forward = (vs[i] == self.edges[e.index()][0]) != rev;
                    directed.push((e, forward));
                }
            }
            directed.sort_unstable();
            if !directed.len().is_multiple_of(2) {
                return Err(inv(format!("cell {c}"), "not closed"));
            }
            for pair in directed.chunks(2) {
                if pair[0].0 != pair[1].0 || pair[0].1 == pair[1].1 {
                    return Err(inv(
                        format!("cell {c}"),
                        "not closed or inconsistently oriented",
                    ));
                }
            }
            let mut ce: Vec<EdgeId> = directed.iter().map(|d| d.0).collect();
            ce.dedup();
            if ce != self.cell_edges(cid) {
                return Err(inv(format!("cell {c}"), "cell_edges mismatch"));
            }
        }
        // Upward lists.
        for (e, &[a, b]) in self.edges.iter().enumerate() {
            let eid = EdgeId(e as u32);
            if !self.vertex_edges(a).contains(&eid) || !self.vertex_edges(b).contains(&eid) {
                return Err(inv(format!("edge {e}"), "missing from vertex_edges"));
            }
            let faces = self.edge_faces(eid);
            for &f in faces {
                if !self.face_edges(f).contains(&eid) {
                    return Err(inv(
                        format!("edge {e}"),
                        "edge_faces lists a face without it",
                    ));
                }
            }
            // Radial order: consecutive faces share the listed cell.
            let cells = self.edge_cells(eid);
            for &cc in cells {
                if !self.cell_edges(cc).contains(&eid) {
                    return Err(inv(
                        format!("edge {e}"),
                        "edge_cells lists a cell without it",
                    ));
                }
            }
        }
        let total_vf: usize = self.face_offsets.last().map_or(0, |&x| x as usize);
        if self.d().vertex_faces.data.len() != total_vf
            || self.d().edge_faces.data.len() != total_vf
        {
            return Err(inv(
                "lattice".into(),
                "upward face lists have the wrong size",
            ));
        }
        if self.d().vertex_edges.data.len() != 2 * self.num_edges() {
            return Err(inv("lattice".into(), "vertex_edges has the wrong size"));
        }
        for v in 0..np {
            if self.d().vertex_cells.get(v).is_empty() {
                return Err(LatticeError::UnusedPoint {
                    point: VertexId::new(v),
                });
            }
        }
        Ok(())
    }
}

/// Whether `b` is the same cycle as `a`: `Some(false)` same direction, `Some(true)` reversed,
/// `None` if not the same cycle.
fn same_cycle(a: &[u32], b: &[u32]) -> Option<bool> {
    let k = a.len();
    if b.len() != k {
        return None;
    }
    let s = b.iter().position(|&x| x == a[0])?;
    if (0..k).all(|i| a[i] == b[(s + i) % k]) {
        Some(false)
    } else if (0..k).all(|i| a[i] == b[(s + k - i) % k]) {
        Some(true)
    } else {
        None
    }
}

/// Signed volume of a closed polyhedral surface given as vertex loops, faces fan-triangulated
/// around their centroids (divergence theorem: V = (1/6) sum det(a - o, b - o, c - o)).
fn loops_signed_volume<'a>(
    points: &[Vec3],
    loops: impl Iterator<Item = &'a [u32]>,
    reverse: bool,
) -> f64 {
    let mut origin: Option<Vec3> = None;
    let mut vol = 0.0;
    for l in loops {
        let o = *origin.get_or_insert(points[l[0] as usize]);
        let g = l.iter().map(|&v| points[v as usize]).sum::<Vec3>() / l.len() as f64 - o;
        for i in 0..l.len() {
            let a = points[l[i] as usize] - o;
            let b = points[l[(i + 1) % l.len()] as usize] - o;
            vol += g.dot(&a.cross(&b));
        }
    }
    if reverse { -vol / 6.0 } else { vol / 6.0 }
}

/// Checks that one input cell is closed, consistently oriented and not pinched at a vertex.
fn check_cell(c: usize, cell: &[Vec<u32>]) -> Result<(), LatticeError> {
    // Directed edges (from, to, face).
    let mut directed: Vec<(u32, u32, usize)> = Vec::new();
    for (j, face) in cell.iter().enumerate() {
        for i in 0..face.len() {
            directed.push((face[i], face[(i + 1) % face.len()], j));
        }
    }
    let mut undirected: Vec<((u32, u32), bool)> = directed
        .iter()
        .map(|&(a, b, _)| ((a.min(b), a.max(b)), a < b))
        .collect();
    undirected.sort_unstable();
    let mut i = 0;
    while i < undirected.len() {
        let mut j = i;
        while j < undirected.len() && undirected[j].0 == undirected[i].0 {
            j += 1;
        }
        let (a, b) = undirected[i].0;
        if j - i != 2 {
            return Err(LatticeError::OpenCell {
                cell: c,
                a: VertexId(a),
                b: VertexId(b),
                uses: j - i,
            });
        }
        if undirected[i].1 == undirected[i + 1].1 {
            return Err(LatticeError::InconsistentOrientation {
                cell: c,
                a: VertexId(a),
                b: VertexId(b),
            });
        }
        i = j;
    }
    // Fans: rotate around each vertex v: from the face containing directed edge (v, w), continue
    // with the face containing (w, v), whose outgoing edge at v is the next one.
    let mut verts: Vec<u32> = cell.iter().flatten().copied().collect();
    verts.sort_unstable();
    verts.dedup();
    for &v in &verts {
        let at_v = cell.iter().filter(|f| f.contains(&v)).count();
        // Outgoing edge of v in face j.
        let out = |j: usize| -> u32 {
            let f = &cell[j];
            let p = f.iter().position(|&x| x == v).unwrap();
            f[(p + 1) % f.len()]
        };
        let start = cell.iter().position(|f| f.contains(&v)).unwrap();
        let mut j = start;
        let mut steps = 0;
        loop {
            let w = out(j);
            // Face containing directed edge (w, v).
            let next = directed
                .iter()
                .find(|&&(a, b, _)| a == w && b == v)
                .map(|d| d.2)
                .unwrap();
            steps += 1;
            j = next;
            if j == start || steps > at_v {
                break;
            }
        }
        if steps != at_v {
            return Err(LatticeError::NonManifoldCellVertex {
                cell: c,
                vertex: VertexId(v),
            });
        }
    }
    Ok(())
}

/// Finds two points closer than `tol` (grid hashing with cell size `tol`).
fn find_coincident(points: &[Vec3], tol: f64) -> Option<(VertexId, VertexId, f64)> {
    let h = tol.max(f64::MIN_POSITIVE);
    let key = |p: &Vec3| -> [i64; 3] { [0, 1, 2].map(|k| (p[k] / h).floor() as i64) };
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::with_capacity(points.len());
    for (i, p) in points.iter().enumerate() {
        grid.entry(key(p)).or_default().push(i as u32);
    }
    let mut best: Option<(VertexId, VertexId, f64)> = None;
    for (i, p) in points.iter().enumerate() {
        let k = key(p);
        for dx in -1..=1i64 {
            for dy in -1..=1i64 {
                for dz in -1..=1i64 {
                    let kk = [
                        k[0].saturating_add(dx),
                        k[1].saturating_add(dy),
                        k[2].saturating_add(dz),
                    ];
                    if let Some(list) = grid.get(&kk) {
                        for &j in list {
                            if (j as usize) > i {
                                let d = (points[j as usize] - p).norm();
                                if d <= tol && best.is_none_or(|b| (b.0.0, b.1.0) > (i as u32, j)) {
                                    best = Some((VertexId(i as u32), VertexId(j), d));
                                }
                            }
                        }
                    }
                }
            }
        }
        if best.is_some() {
            return best;
        }
    }
    best
}

/// Orders the faces around each edge radially and lists the cells between them.
fn radial_order(
    edges: &[[VertexId; 2]],
    face_offsets: &[u32],
    face_vertices: &[VertexId],
    face_edges: &[EdgeId],
    face_cells: &[[CellId; 2]],
    unordered: &Csr<FaceId>,
    parallel: bool,
) -> (Csr<FaceId>, Csr<CellId>) {
    par_build2(
        edges.len(),
        parallel,
        |e, fo: &mut Vec<FaceId>, co: &mut Vec<CellId>| {
            let s = unordered.get(e);
            let a = edges[e][0];
            let eid = EdgeId(e as u32);
            // Direction of face f along the edge: true if its stored loop runs a -> b.
            let dir = |f: FaceId| -> bool {
                let lo = face_offsets[f.index()] as usize;
                let hi = face_offsets[f.index() + 1] as usize;
                let p = face_edges[lo..hi].iter().position(|&x| x == eid).unwrap();
                face_vertices[lo + p] == a
            };
            // Turning counter-clockwise about a -> b, a cell is entered through the face it uses
            // b -> a and left through the face it uses a -> b. The front cell uses the stored loop.
            let next = |f: FaceId| -> CellId {
                let [c0, c1] = face_cells[f.index()];
                if dir(f) { c1 } else { c0 }
            };
            let prev = |f: FaceId| -> CellId {
                let [c0, c1] = face_cells[f.index()];
                if dir(f) { c0 } else { c1 }
            };
            let start_len = fo.len();
            while fo.len() - start_len < s.len() {
                let done = |f: &FaceId, fo: &Vec<FaceId>| fo[start_len..].contains(f);
                let first = s
                    .iter()
                    .copied()
                    .find(|f| !done(f, fo) && !prev(*f).is_some())
                    .or_else(|| s.iter().copied().find(|f| !done(f, fo)))
                    .unwrap();
                let mut f = first;
                loop {
                    fo.push(f);
                    let c = next(f);
                    if !c.is_some() {
                        break;
                    }
                    co.push(c);
                    let g = s
                        .iter()
                        .copied()
                        .find(|&g| g != f && face_cells[g.index()].contains(&c));
                    match g {
                        Some(g) if g != first && !done(&g, fo) => f = g,
                        _ => break,
                    }
                }
            }
        },
    )
}
