//! MacCracken-Joy (volumetric Catmull-Clark) subdivision, one level at a time.
//!
//! # What
//! One level maps a lattice with `P` points, `E` edges, `F` faces and `C` cells to a finer one and
//! gives the level's linear operator `A^(j)` (`subdivision-solids-journal.txt` section 4.2, eq 4:
//! `d^(j+1) = A^(j) d^(j)`). The rules are those of `subdivision-solids-conference.txt`
//! section 3.1, which states the edge rule completely (the journal's section 3.3 drops the words
//! "centroids of the faces that"):
//!
//! | new point | rule (interior element) |
//! | --- | --- |
//! | cell point | `c` = centroid (vertex average) of the cell |
//! | face point | `f = (c0 + 2a + c1) / 4`, `a` the face centroid, `c0`, `c1` the cell points on its two sides |
//! | edge point | `e = (c_avg + 2 a_avg + (n - 3) m) / n`, `n` = number of faces containing the edge, `c_avg` = average of the cell points of the cells containing it, `a_avg` = average of the centroids of the faces containing it, `m` = midpoint |
//! | vertex point | `v = (c_avg + 3 a_avg + 3 m_avg + p) / 8`, averages over the cells, faces and edges containing `p` |
//!
//! Weights sum to one in every rule: `(1 + 2 + 1)/4`, `(1 + 2 + (n-3))/n`, `(1 + 3 + 3 + 1)/8`, so
//! each row of `A^(j)` is an affine combination. On a regular hexahedral lattice these reduce to
//! the tricubic B-spline refinement masks (`(1,6,1)/8` at vertices, `(1,1)/2` across new points;
//! worked out for the edge rule: with `n = 4`, `c_avg` has the `y z` weights
//! `(1,2,1)/4 x (1,2,1)/4`, `2 a_avg` has `(1,2,1)/4 x delta + delta x (1,2,1)/4` and `m` has
//! `delta x delta`, giving `(9/4, 3/8, 1/16)/4 = (36, 6, 1)/64` for the centre, edge-adjacent
//! and diagonal neighbours, which is `(1,6,1)/8 x (1,6,1)/8`). `tests/bspline.rs` checks all four.
//!
//! # Where each rule applies ([`BoundaryRule`] and [`Features`])
//! An element is a *boundary* element when it lies in a boundary face (a face with one cell).
//! `nb(e)` is the number of boundary faces containing edge `e`.
//!
//! * **Crease edges**: edges tagged in [`Features`]; with [`BoundaryRule::Smooth`] or
//!   [`BoundaryRule::Sharp`] also boundary edges with `nb(e) != 2` (non-manifold boundary); with
//!   [`BoundaryRule::Sharp`] also every boundary edge contained in a number of cells other than
//!   two (the box's edges, the rims of a cylinder, the concave edge of an L). A crease edge's point
//!   is its midpoint (cubic B-spline curve rule).
//! * **Corner vertices**: vertices tagged in [`Features`]; vertices on three or more crease edges;
//!   with `Smooth`/`Sharp` also boundary vertices on at most one crease whose boundary faces do not
//!   form a single fan (the surface is pinched there). Corners stay fixed: `v = p`.
//! * **Crease vertices**: non-corner vertices on exactly two crease edges, with far end points
//!   `q1`, `q2`: `v = (q1 + 6 p + q2) / 8` (cubic B-spline curve rule).
//! * [`BoundaryRule::Interior`]: every other element uses the volumetric rules above, with the
//!   averages taken over whatever exists; a boundary face has one cell point `c0`, and
//!   `(c0 + 2a + c0)/4 = (c0 + a)/2`. (The lattice shrinks away from its boundary, as the
//!   journal says of the `4 x 4 x 4` B-spline example.)
//! * [`BoundaryRule::Smooth`] (default): the boundary surface is subdivided by itself with the
//!   Catmull-Clark surface rules: boundary face point = face centroid; boundary edge point
//!   `(a + b + f1 + f2) / 4` with `f1`, `f2` the face points (centroids) of its two boundary faces;
//!   boundary vertex point `(Q + 2R + (n - 3) p) / n` with `n` the number of boundary edges at `p`,
//!   `Q` the average of the centroids of the boundary faces at `p` and `R` the average of the
//!   midpoints of the boundary edges at `p` (a vertex on one crease edge, a "dart", uses this rule
//!   too). Interior elements use the volumetric rules (which read the boundary's old points).
//! * [`BoundaryRule::Sharp`]: as `Smooth`, plus the automatic creases and corners listed above,
//!   so a box keeps its edges and corners and a cylinder keeps its rims.
//!
//! # Connectivity of the new lattice
//! New points are numbered vertex points `0..P`, edge points `P..P+E`, face points
//! `P+E..P+E+F`, cell points `P+E+F..P+E+F+C` (`P' = P + E + F + C`).
//! * Edges: each old edge splits in two (`2E`); each old face of valence `k` gets `k` edges from
//!   its face point to its edge points; each cell gets one edge from its cell point to each of its
//!   face points. `E' = 2E + sum_f k_f + sum_c faces(c)`.
//! * Faces: each old face of valence `k` splits into `k` quads (vertex point, edge point, face
//!   point, edge point); each cell gets one quad per edge (edge point, face point, cell point,
//!   face point). `F' = sum_f k_f + sum_c edges(c)`.
//! * Cells: each old cell gets one new cell per vertex (cell point, the face and edge points of
//!   the cell's faces and edges at the vertex, vertex point). `C' = sum_c vertices(c)`. The new
//!   cell is a hexahedron when the vertex lies on three faces of the cell (every vertex of a hex,
//!   prism or tetrahedron, the base of a pyramid); at a vertex on `k > 3` faces of the cell (the
//!   apex of a pyramid) it is a `2k`-faced cell, as the connectivity rule of the papers implies.
//!
//! # Limitations
//! The crease rules are the plain curve rules (no semi-sharp creases, no special weights where a
//! crease meets the smooth boundary). Classification is topological (cell and face counts), never
//! by dihedral angle.

use rayon::prelude::*;
use vclay_core::{Parallelism, Vec3};

use crate::csr::{Csr, concat};
use crate::error::LatticeError;
use crate::ids::{CellId, EdgeId, FaceId, VertexId};
use crate::lattice::{Lattice, Primary, par_for};
use crate::sparse::SparseMatrix;

/// How the subdivision treats the boundary of the lattice (see the [module docs](self)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BoundaryRule {
    /// The volumetric rules everywhere, averaging over the elements that exist.
    Interior,
    /// Catmull-Clark surface rules on the boundary surface (smooth, rounded boundary).
    #[default]
    Smooth,
    /// `Smooth` plus automatic crease edges (boundary edges in a number of cells other than two)
    /// and fixed corners (vertices on three or more creases).
    Sharp,
}

/// Parameters of one subdivision step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SubdivisionRules {
    /// Boundary treatment. Default: [`BoundaryRule::Smooth`].
    pub boundary: BoundaryRule,
    /// Thread use. Default: [`Parallelism::Auto`].
    pub parallelism: Parallelism,
}

impl SubdivisionRules {
    /// Rules with the given boundary treatment and default parallelism.
    pub fn new(boundary: BoundaryRule) -> Self {
        Self {
            boundary,
            ..Self::default()
        }
    }
}

/// User-tagged sharp features of a lattice: crease edges and corner vertices.
///
/// Tags are inherited by subdivision: both halves of a crease edge are creases, and the vertex
/// point of a corner is a corner.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Features {
    crease: Vec<bool>,
    corner: Vec<bool>,
}

impl Features {
    /// No tags, sized for `lattice`.
    pub fn none(lattice: &Lattice) -> Self {
        Self {
            crease: vec![false; lattice.num_edges()],
            corner: vec![false; lattice.num_points()],
        }
    }

    /// Tags edge `e` as a crease.
    pub fn tag_crease(&mut self, e: EdgeId) -> Result<(), LatticeError> {
        let slot = self.crease.get_mut(e.index()).ok_or(LatticeError::BadTag {
            element: e.to_string(),
        })?;
        *slot = true;
        Ok(())
    }

    /// Tags the edge between `a` and `b` as a crease.
    pub fn tag_crease_between(
        &mut self,
        lattice: &Lattice,
        a: VertexId,
        b: VertexId,
    ) -> Result<EdgeId, LatticeError> {
        let in_range = a.index() < lattice.num_points() && b.index() < lattice.num_points();
        let e = in_range
            .then(|| lattice.edge_between(a, b))
            .flatten()
            .ok_or(LatticeError::BadTag {
                element: format!("edge ({a}, {b})"),
            })?;
        self.tag_crease(e)?;
        Ok(e)
    }

    /// Tags vertex `v` as a corner (kept fixed).
    pub fn tag_corner(&mut self, v: VertexId) -> Result<(), LatticeError> {
        let slot = self.corner.get_mut(v.index()).ok_or(LatticeError::BadTag {
            element: v.to_string(),
        })?;
        *slot = true;
        Ok(())
    }

    /// Removes the crease tag of edge `e` (no effect if it was not tagged).
    pub fn untag_crease(&mut self, e: EdgeId) -> Result<(), LatticeError> {
        let slot = self.crease.get_mut(e.index()).ok_or(LatticeError::BadTag {
            element: e.to_string(),
        })?;
        *slot = false;
        Ok(())
    }

    /// Removes the corner tag of vertex `v` (no effect if it was not tagged).
    pub fn untag_corner(&mut self, v: VertexId) -> Result<(), LatticeError> {
        let slot = self.corner.get_mut(v.index()).ok_or(LatticeError::BadTag {
            element: v.to_string(),
        })?;
        *slot = false;
        Ok(())
    }

    /// The tagged crease edges, in id order.
    pub fn creases(&self) -> impl Iterator<Item = EdgeId> + '_ {
        (0..self.crease.len())
            .filter(|&e| self.crease[e])
            .map(EdgeId::new)
    }

    /// The tagged corner vertices, in id order.
    pub fn corners(&self) -> impl Iterator<Item = VertexId> + '_ {
        (0..self.corner.len())
            .filter(|&v| self.corner[v])
            .map(VertexId::new)
    }

    /// Whether edge `e` is tagged as a crease.
    pub fn is_crease(&self, e: EdgeId) -> bool {
        self.crease.get(e.index()).copied().unwrap_or(false)
    }

    /// Whether vertex `v` is tagged as a corner.
    pub fn is_corner(&self, v: VertexId) -> bool {
        self.corner.get(v.index()).copied().unwrap_or(false)
    }

    /// Number of tagged crease edges.
    pub fn num_creases(&self) -> usize {
        self.crease.iter().filter(|&&c| c).count()
    }

    /// Number of tagged corners.
    pub fn num_corners(&self) -> usize {
        self.corner.iter().filter(|&&c| c).count()
    }

    pub(crate) fn check(&self, lattice: &Lattice) -> Result<(), LatticeError> {
        if self.crease.len() != lattice.num_edges() || self.corner.len() != lattice.num_points() {
            return Err(LatticeError::BadTag {
                element: format!(
                    "feature tags sized for {} edges / {} points, lattice has {} / {}",
                    self.crease.len(),
                    self.corner.len(),
                    lattice.num_edges(),
                    lattice.num_points()
                ),
            });
        }
        Ok(())
    }

    /// Tags of the next level (see the type docs).
    fn refine(&self, coarse: &Lattice, fine: &Lattice) -> Features {
        let mut crease = vec![false; fine.num_edges()];
        for (e, &c) in self.crease.iter().enumerate() {
            if c {
                crease[2 * e] = true;
                crease[2 * e + 1] = true;
            }
        }
        let mut corner = vec![false; fine.num_points()];
        corner[..coarse.num_points()].copy_from_slice(&self.corner);
        Features { crease, corner }
    }
}

/// The result of one subdivision step.
#[derive(Clone, Debug)]
pub struct Refinement {
    /// The finer lattice (points already computed: `operator * coarse points`).
    pub lattice: Lattice,
    /// The inherited feature tags.
    pub features: Features,
    /// The level operator `A^(j)`: `fine points = operator * coarse points`.
    pub operator: SparseMatrix,
}

/// Rule applied to an edge.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum EdgeRule {
    Volume,
    Surface,
    Crease,
}

/// Rule applied to a vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum VertexRule {
    Volume,
    Surface,
    Crease(VertexId, VertexId),
    Corner,
}

/// Subdivides `lattice` once: new topology, new points and the level operator.
pub fn subdivide(
    lattice: &Lattice,
    features: &Features,
    rules: &SubdivisionRules,
) -> Result<Refinement, LatticeError> {
    features.check(lattice)?;
    lattice.build_adjacency();
    let (operator, primary) = rayon::join(
        || subdivision_operator_unchecked(lattice, features, rules),
        || refine_topology(lattice),
    );
    let mut primary = primary?;
    let mut points = vec![Vec3::zeros(); operator.nrows()];
    operator.apply_into(&lattice.points, &mut points, rules.parallelism);
    primary.points = points;
    let fine = Lattice::assemble(primary);
    let features = features.refine(lattice, &fine);
    Ok(Refinement {
        lattice: fine,
        features,
        operator,
    })
}

/// The level operator `A^(j)` alone (rows ordered vertex, edge, face, cell points).
pub fn subdivision_operator(
    lattice: &Lattice,
    features: &Features,
    rules: &SubdivisionRules,
) -> Result<SparseMatrix, LatticeError> {
    features.check(lattice)?;
    Ok(subdivision_operator_unchecked(lattice, features, rules))
}

/// Dense accumulator for one sparse row.
struct RowAcc {
    w: Vec<f64>,
    stamp: Vec<u32>,
    touched: Vec<u32>,
    row: u32,
}

impl RowAcc {
    fn new(n: usize) -> Self {
        Self {
            w: vec![0.0; n],
            stamp: vec![u32::MAX; n],
            touched: Vec::with_capacity(64),
            row: 0,
        }
    }

    #[inline]
    fn add(&mut self, j: VertexId, x: f64) {
        let j = j.index();
        if self.stamp[j] != self.row {
            self.stamp[j] = self.row;
            self.w[j] = 0.0;
            self.touched.push(j as u32);
        }
        self.w[j] += x;
    }

    fn flush(&mut self, cols: &mut Vec<u32>, vals: &mut Vec<f64>) -> u32 {
        self.touched.sort_unstable();
        let before = cols.len();
        for &j in &self.touched {
            let w = self.w[j as usize];
            if w != 0.0 {
                cols.push(j);
                vals.push(w);
            }
        }
        self.touched.clear();
        self.row = self.row.wrapping_add(1);
        if self.row == u32::MAX {
            self.stamp.fill(u32::MAX - 1);
            self.row = 0;
        }
        (cols.len() - before) as u32
    }
}

/// Weighted-centroid helpers on the accumulator.
struct Stencil<'a> {
    l: &'a Lattice,
}

impl Stencil<'_> {
    #[inline]
    fn cell(&self, acc: &mut RowAcc, c: CellId, w: f64) {
        let vs = self.l.cell_vertices(c);
        let x = w / vs.len() as f64;
        for &v in vs {
            acc.add(v, x);
        }
    }
    #[inline]
    fn face(&self, acc: &mut RowAcc, f: FaceId, w: f64) {
        let vs = self.l.face_vertices(f);
        let x = w / vs.len() as f64;
        for &v in vs {
            acc.add(v, x);
        }
    }
    #[inline]
    fn mid(&self, acc: &mut RowAcc, e: EdgeId, w: f64) {
        let [a, b] = self.l.edges[e.index()];
        acc.add(a, 0.5 * w);
        acc.add(b, 0.5 * w);
    }
}

fn classify(
    l: &Lattice,
    features: &Features,
    rule: BoundaryRule,
    par: bool,
) -> (Vec<EdgeRule>, Vec<VertexRule>) {
    let bface = |f: FaceId| !l.face_cells[f.index()][1].is_some();
    let edge_nb = |e: usize| {
        l.d()
            .edge_faces
            .get(e)
            .iter()
            .filter(|&&f| bface(f))
            .count()
    };
    let surface = rule != BoundaryRule::Interior;
    let edge_rule = |e: usize| -> EdgeRule {
        let nb = edge_nb(e);
        let crease = features.crease[e]
            || (surface && nb > 0 && nb != 2)
            || (rule == BoundaryRule::Sharp && nb > 0 && l.d().edge_cells.get(e).len() != 2);
        if crease {
            EdgeRule::Crease
        } else if surface && nb == 2 {
            EdgeRule::Surface
        } else {
            EdgeRule::Volume
        }
    };
    let ne = l.num_edges();
    let erules: Vec<EdgeRule> = if par {
        (0..ne).into_par_iter().map(edge_rule).collect()
    } else {
        (0..ne).map(edge_rule).collect()
    };
    let vertex_rule = |v: usize| -> VertexRule {
        let vid = VertexId(v as u32);
        if features.corner[v] {
            return VertexRule::Corner;
        }
        let mut ncrease = 0;
        let mut far = [vid; 2];
        for &e in l.d().vertex_edges.get(v) {
            if erules[e.index()] == EdgeRule::Crease {
                if ncrease < 2 {
                    let [a, b] = l.edges[e.index()];
                    far[ncrease] = if a == vid { b } else { a };
                }
                ncrease += 1;
            }
        }
        match ncrease {
            n if n >= 3 => VertexRule::Corner,
            2 => VertexRule::Crease(far[0], far[1]),
            _ => {
                if surface && l.d().vertex_faces.get(v).iter().any(|&f| bface(f)) {
                    if single_boundary_fan(l, vid) {
                        VertexRule::Surface
                    } else {
                        VertexRule::Corner
                    }
                } else {
                    VertexRule::Volume
                }
            }
        }
    };
    let np = l.num_points();
    let vrules: Vec<VertexRule> = if par {
        (0..np).into_par_iter().map(vertex_rule).collect()
    } else {
        (0..np).map(vertex_rule).collect()
    };
    (erules, vrules)
}

/// Whether the boundary faces at `v` form one fan (a disk, as on a manifold boundary surface).
fn single_boundary_fan(l: &Lattice, v: VertexId) -> bool {
    let bface = |f: FaceId| !l.face_cells[f.index()][1].is_some();
    let bfaces: Vec<FaceId> = l
        .vertex_faces(v)
        .iter()
        .copied()
        .filter(|&f| bface(f))
        .collect();
    let bedges: Vec<EdgeId> = l
        .vertex_edges(v)
        .iter()
        .copied()
        .filter(|&e| l.edge_faces(e).iter().any(|&f| bface(f)))
        .collect();
    if bfaces.len() != bedges.len() {
        return false;
    }
    for &e in &bedges {
        if l.edge_faces(e).iter().filter(|&&f| bface(f)).count() != 2 {
            return false;
        }
    }
    // Walk the fan: from a face, leave through its edge at v that we did not come from.
    let start = bfaces[0];
    let mut f = start;
    let mut came: Option<EdgeId> = None;
    let mut seen = 1;
    loop {
        let es = l.face_edges(f);
        let vs = l.face_vertices(f);
        let p = vs.iter().position(|&x| x == v).unwrap();
        let k = vs.len();
        let (e1, e2) = (es[p], es[(p + k - 1) % k]);
        let out = if Some(e1) == came { e2 } else { e1 };
        let g = l
            .edge_faces(out)
            .iter()
            .copied()
            .find(|&g| g != f && bface(g))
            .unwrap();
        if g == start {
            break;
        }
        seen += 1;
        if seen > bfaces.len() {
            return false;
        }
        came = Some(out);
        f = g;
    }
    seen == bfaces.len()
}

/// Builds `A^(j)` (see the module docs for the rules and the row order).
fn subdivision_operator_unchecked(
    l: &Lattice,
    features: &Features,
    rules: &SubdivisionRules,
) -> SparseMatrix {
    let (np, ne, nf, nc) = (l.num_points(), l.num_edges(), l.num_faces(), l.num_cells());
    let nrows = np + ne + nf + nc;
    let par = rules.parallelism.is_parallel(nrows);
    let (erules, vrules) = classify(l, features, rules.boundary, par);
    let rule = rules.boundary;
    let st = Stencil { l };
    let bface = |f: FaceId| !l.face_cells[f.index()][1].is_some();

    let fill_row = |acc: &mut RowAcc, r: usize| {
        if r < np {
            let vid = VertexId(r as u32);
            match vrules[r] {
                VertexRule::Corner => acc.add(vid, 1.0),
                VertexRule::Crease(q1, q2) => {
                    acc.add(q1, 0.125);
                    acc.add(vid, 0.75);
                    acc.add(q2, 0.125);
                }
                VertexRule::Surface => {
                    // (Q + 2R + (n - 3) p) / n on the boundary surface.
                    let bf = l.vertex_faces(vid).iter().filter(|&&f| bface(f)).count();
                    let be: Vec<EdgeId> = l
                        .vertex_edges(vid)
                        .iter()
                        .copied()
                        .filter(|&e| l.edge_faces(e).iter().any(|&f| bface(f)))
                        .collect();
                    let n = be.len() as f64;
                    for &f in l.vertex_faces(vid) {
                        if bface(f) {
                            st.face(acc, f, 1.0 / (n * bf as f64));
                        }
                    }
                    for &e in &be {
                        st.mid(acc, e, 2.0 / (n * n));
                    }
                    acc.add(vid, (n - 3.0) / n);
                }
                VertexRule::Volume => {
                    // (c_avg + 3 a_avg + 3 m_avg + p) / 8.
                    let cs = l.vertex_cells(vid);
                    let fs = l.vertex_faces(vid);
                    let es = l.vertex_edges(vid);
                    let wc = 1.0 / (8.0 * cs.len() as f64);
                    let wf = 3.0 / (8.0 * fs.len() as f64);
                    let we = 3.0 / (8.0 * es.len() as f64);
                    for &c in cs {
                        st.cell(acc, c, wc);
                    }
                    for &f in fs {
                        st.face(acc, f, wf);
                    }
                    for &e in es {
                        st.mid(acc, e, we);
                    }
                    acc.add(vid, 0.125);
                }
            }
        } else if r < np + ne {
            let e = r - np;
            let eid = EdgeId(e as u32);
            match erules[e] {
                EdgeRule::Crease => st.mid(acc, eid, 1.0),
                EdgeRule::Surface => {
                    // (a + b + f1 + f2) / 4 with f1, f2 the boundary face centroids.
                    st.mid(acc, eid, 0.5);
                    for &f in l.edge_faces(eid) {
                        if bface(f) {
                            st.face(acc, f, 0.25);
                        }
                    }
                }
                EdgeRule::Volume => {
                    // (c_avg + 2 a_avg + (n - 3) m) / n.
                    let fs = l.edge_faces(eid);
                    let cs = l.edge_cells(eid);
                    let n = fs.len() as f64;
                    let wc = 1.0 / (n * cs.len() as f64);
                    for &c in cs {
                        st.cell(acc, c, wc);
                    }
                    for &f in fs {
                        st.face(acc, f, 2.0 / (n * n));
                    }
                    if fs.len() != 3 {
                        st.mid(acc, eid, (n - 3.0) / n);
                    }
                }
            }
        } else if r < np + ne + nf {
            let f = FaceId((r - np - ne) as u32);
            let [c0, c1] = l.face_cells[f.index()];
            if c1.is_some() {
                // (c0 + 2a + c1) / 4.
                st.cell(acc, c0, 0.25);
                st.face(acc, f, 0.5);
                st.cell(acc, c1, 0.25);
            } else if rule == BoundaryRule::Interior {
                // (c0 + 2a + c0) / 4.
                st.cell(acc, c0, 0.5);
                st.face(acc, f, 0.5);
            } else {
                st.face(acc, f, 1.0);
            }
        } else {
            st.cell(acc, CellId((r - np - ne - nf) as u32), 1.0);
        }
    };

    const ROWS_PER_BLOCK: usize = 4096;
    let blocks = nrows.div_ceil(ROWS_PER_BLOCK);
    let run = |acc: &mut RowAcc, b: usize| {
        let lo = b * ROWS_PER_BLOCK;
        let hi = (lo + ROWS_PER_BLOCK).min(nrows);
        let mut lens = Vec::with_capacity(hi - lo);
        let mut cols = Vec::with_capacity((hi - lo) * 20);
        let mut vals = Vec::with_capacity((hi - lo) * 20);
        for r in lo..hi {
            fill_row(acc, r);
            lens.push(acc.flush(&mut cols, &mut vals));
        }
        (lens, cols, vals)
    };
    let parts: Vec<(Vec<u32>, Vec<u32>, Vec<f64>)> = if par && blocks > 1 {
        (0..blocks)
            .into_par_iter()
            .map_init(|| RowAcc::new(np), run)
            .collect()
    } else {
        let mut acc = RowAcc::new(np);
        (0..blocks).map(|b| run(&mut acc, b)).collect()
    };
    let nnz: usize = parts.iter().map(|p| p.1.len()).sum();
    let mut row_ptr = Vec::with_capacity(nrows + 1);
    row_ptr.push(0usize);
    let mut cols = Vec::with_capacity(nnz);
    let mut vals = Vec::with_capacity(nnz);
    let mut acc = 0usize;
    for (lens, c, v) in parts {
        for len in lens {
            acc += len as usize;
            row_ptr.push(acc);
        }
        cols.extend_from_slice(&c);
        vals.extend_from_slice(&v);
    }
    SparseMatrix::from_csr_unchecked(nrows, np, row_ptr, cols, vals)
}

/// The connectivity of the next level (points left empty).
fn refine_topology(l: &Lattice) -> Result<Primary, LatticeError> {
    let (np, ne, nf, nc) = (l.num_points(), l.num_edges(), l.num_faces(), l.num_cells());
    let k_total = l.face_vertices.len();
    let scf = l.cell_faces.data.len();
    let sce = l.d().cell_edges.data.len();
    let scv = l.d().cell_vertices.data.len();
    let p2 = np + ne + nf + nc;
    let e2 = 2 * ne + k_total + scf;
    let f2 = k_total + sce;
    let c2 = scv;
    for (what, count) in [
        ("points", p2),
        ("edges", e2),
        ("faces", f2),
        ("cells", c2),
        ("face corners", 4 * f2),
    ] {
        if count >= u32::MAX as usize {
            return Err(LatticeError::TooLarge { what, count });
        }
    }
    let par = par_for(nc.max(ne));
    let (pe, pf, pc) = (np as u32, (np + ne) as u32, (np + ne + nf) as u32);
    let (ek, ekc) = ((2 * ne) as u32, (2 * ne + k_total) as u32);
    let fo = &l.face_offsets;
    let cfo = &l.cell_faces.offsets;
    let ceo = &l.d().cell_edges.offsets;
    let cvo = &l.d().cell_vertices.offsets;
    let child = |e: EdgeId, v: VertexId| -> EdgeId {
        EdgeId(2 * e.0 + u32::from(l.edges[e.index()][0] != v))
    };
    // Fine cell (c, v): cell-vertex incidence index.
    let fine_cell = |c: CellId, v: VertexId| -> CellId {
        let vs = l.cell_vertices(c);
        let p = vs
            .binary_search(&v)
            .expect("vertex of face not in its cell");
        CellId(cvo[c.index()] + p as u32)
    };

    // Edges.
    let edge_of = |i: usize| -> [VertexId; 2] {
        if i < 2 * ne {
            let e = i / 2;
            [l.edges[e][i % 2], VertexId(pe + e as u32)]
        } else if i < 2 * ne + k_total {
            let q = i - 2 * ne;
            [VertexId(pe + l.face_edges[q].0), VertexId::default()]
        } else {
            [VertexId::default(), VertexId::default()]
        }
    };
    let mut edges: Vec<[VertexId; 2]> = if par {
        (0..e2)
            .into_par_iter()
            .with_min_len(4096)
            .map(edge_of)
            .collect()
    } else {
        (0..e2).map(edge_of).collect()
    };
    // Face edges need their face: fill per face; cell edges per cell.
    for f in 0..nf {
        for q in fo[f] as usize..fo[f + 1] as usize {
            edges[2 * ne + q][1] = VertexId(pf + f as u32);
        }
    }
    for c in 0..nc {
        for (j, &f) in l.cell_faces.get(c).iter().enumerate() {
            edges[ekc as usize + cfo[c] as usize + j] =
                [VertexId(pf + f.0), VertexId(pc + c as u32)];
        }
    }

    // Face quads of old faces: quad q = fo[f] + i at corner i of face f.
    let mut quad_face = vec![0u32; k_total];
    for f in 0..nf {
        quad_face[fo[f] as usize..fo[f + 1] as usize].fill(f as u32);
    }
    let mut face_vertices = vec![VertexId::default(); 4 * f2];
    let mut face_edges = vec![EdgeId::default(); 4 * f2];
    let mut face_cells = vec![[CellId::NONE; 2]; f2];
    {
        let (fv_head, _) = face_vertices.split_at_mut(4 * k_total);
        let (fe_head, _) = face_edges.split_at_mut(4 * k_total);
        let (fc_head, _) = face_cells.split_at_mut(k_total);
        type QuadSlot<'a> = (
            usize,
            ((&'a mut [VertexId], &'a mut [EdgeId]), &'a mut [CellId; 2]),
        );
        let quad = |(q, ((fv, fe), fc)): QuadSlot<'_>| {
            let f = quad_face[q] as usize;
            let lo = fo[f] as usize;
            let k = fo[f + 1] as usize - lo;
            let i = q - lo;
            let im = (i + k - 1) % k;
            let v = l.face_vertices[lo + i];
            let (e, e_prev) = (l.face_edges[lo + i], l.face_edges[lo + im]);
            fv.copy_from_slice(&[
                v,
                VertexId(pe + e.0),
                VertexId(pf + f as u32),
                VertexId(pe + e_prev.0),
            ]);
            fe.copy_from_slice(&[
                child(e, v),
                EdgeId(ek + (lo + i) as u32),
                EdgeId(ek + (lo + im) as u32),
                child(e_prev, v),
            ]);
            let [c0, c1] = l.face_cells[f];
            *fc = [
                fine_cell(c0, v),
                if c1.is_some() {
                    fine_cell(c1, v)
                } else {
                    CellId::NONE
                },
            ];
        };
        let it = fv_head
            .par_chunks_mut(4)
            .zip(fe_head.par_chunks_mut(4))
            .zip(fc_head.par_iter_mut());
        if par {
            it.enumerate().with_min_len(2048).for_each(quad);
        } else {
            it.enumerate().with_min_len(usize::MAX).for_each(quad);
        }
    }

    // Per old cell: its interior quads and the face lists of its new cells.
    type CellPart = (
        Vec<VertexId>,
        Vec<EdgeId>,
        Vec<[CellId; 2]>,
        Vec<u32>,
        Vec<FaceId>,
    );
    const CELLS_PER_BLOCK: usize = 1024;
    let blocks = nc.div_ceil(CELLS_PER_BLOCK);
    let run = |b: usize| -> CellPart {
        let lo = b * CELLS_PER_BLOCK;
        let hi = (lo + CELLS_PER_BLOCK).min(nc);
        let mut qv = Vec::new();
        let mut qe = Vec::new();
        let mut qc = Vec::new();
        let mut lens = Vec::new();
        let mut cf = Vec::new();
        // Scratch: per local edge (face-local index, position) for the a->b and b->a uses.
        let mut ab: Vec<(u32, u32)> = Vec::new();
        let mut ba: Vec<(u32, u32)> = Vec::new();
        let mut pairs: Vec<(u32, FaceId)> = Vec::new();
        for c in lo..hi {
            let cid = CellId(c as u32);
            let cedges = l.d().cell_edges.get(c);
            let cverts = l.d().cell_vertices.get(c);
            ab.clear();
            ab.resize(cedges.len(), (0, 0));
            ba.clear();
            ba.resize(cedges.len(), (0, 0));
            pairs.clear();
            for (t, &f) in l.cell_faces.get(c).iter().enumerate() {
                let reversed = l.face_cells[f.index()][1] == cid;
                let flo = fo[f.index()] as usize;
                let fhi = fo[f.index() + 1] as usize;
                for i in 0..fhi - flo {
                    let v = l.face_vertices[flo + i];
                    let e = l.face_edges[flo + i];
                    let le = cedges.binary_search(&e).unwrap();
                    let forward = (l.edges[e.index()][0] == v) != reversed;
                    if forward {
                        ab[le] = (t as u32, i as u32);
                    } else {
                        ba[le] = (t as u32, i as u32);
                    }
                    let lv = cverts.binary_search(&v).unwrap() as u32;
                    pairs.push((lv, FaceId((flo + i) as u32)));
                }
            }
            let cfaces = l.cell_faces.get(c);
            for (j, &e) in cedges.iter().enumerate() {
                let (tab, iab) = ab[j];
                let (tba, iba) = ba[j];
                let (fab, fba) = (cfaces[tab as usize], cfaces[tba as usize]);
                qv.extend_from_slice(&[
                    VertexId(pe + e.0),
                    VertexId(pf + fba.0),
                    VertexId(pc + c as u32),
                    VertexId(pf + fab.0),
                ]);
                qe.extend_from_slice(&[
                    EdgeId(ek + fo[fba.index()] + iba),
                    EdgeId(ekc + cfo[c] + tba),
                    EdgeId(ekc + cfo[c] + tab),
                    EdgeId(ek + fo[fab.index()] + iab),
                ]);
                let [a, b] = l.edges[e.index()];
                let la = cverts.binary_search(&a).unwrap() as u32;
                let lb = cverts.binary_search(&b).unwrap() as u32;
                qc.push([CellId(cvo[c] + la), CellId(cvo[c] + lb)]);
                let qid = FaceId((k_total + ceo[c] as usize + j) as u32);
                pairs.push((la, qid));
                pairs.push((lb, qid));
            }
            pairs.sort_unstable_by_key(|p| p.0);
            let mut s = 0;
            for lv in 0..cverts.len() as u32 {
                let start = s;
                while s < pairs.len() && pairs[s].0 == lv {
                    cf.push(pairs[s].1);
                    s += 1;
                }
                lens.push((s - start) as u32);
            }
        }
        (qv, qe, qc, lens, cf)
    };
    let parts: Vec<CellPart> = if par && blocks > 1 {
        (0..blocks).into_par_iter().map(run).collect()
    } else {
        (0..blocks).map(run).collect()
    };
    let mut fv_pos = 4 * k_total;
    let mut fc_pos = k_total;
    let mut cell_parts = Vec::with_capacity(parts.len());
    for (qv, qe, qc, lens, cf) in parts {
        face_vertices[fv_pos..fv_pos + qv.len()].copy_from_slice(&qv);
        face_edges[fv_pos..fv_pos + qe.len()].copy_from_slice(&qe);
        fv_pos += qv.len();
        face_cells[fc_pos..fc_pos + qc.len()].copy_from_slice(&qc);
        fc_pos += qc.len();
        cell_parts.push((lens, cf));
    }
    debug_assert_eq!(fv_pos, 4 * f2);
    let cell_faces: Csr<FaceId> = concat(c2, cell_parts);
    debug_assert_eq!(cell_faces.len(), c2);
    let face_offsets: Vec<u32> = (0..=f2 as u32).map(|i| 4 * i).collect();
    Ok(Primary {
        points: Vec::new(),
        edges,
        face_offsets,
        face_vertices,
        face_edges,
        face_cells,
        cell_faces,
    })
}
