//! Editing a control lattice: extruding a boundary face into a new cell, deleting a cell, and
//! carrying crease/corner tags ([`Features`]) across an edit.
//!
//! # What
//! * [`extrude_face`]: a boundary face `f` with vertex loop `v_0 .. v_{k-1}` (oriented outward)
//!   grows a prism: new points `v_i + h n`, where `n` is the unit Newell normal of the loop
//!   (`n ∝ Σ_i v_i × v_{i+1}`) and `h = factor · |V|^{1/3}` with `V` the signed volume of the cell
//!   behind `f` ([`ExtrudeParams`]). The face becomes interior; the new cell has `k + 2` faces
//!   (a hexahedron over a quad, a wedge over a triangle).
//! * [`delete_cell`]: removes one cell ("trimming"); faces, edges and points no other cell uses
//!   disappear with it. Refused, with a [`LatticeError`] saying why, when the result would be
//!   invalid: deleting the only cell ([`LatticeError::LastCell`]), splitting the lattice into
//!   more face-connected pieces ([`LatticeError::WouldDisconnect`]), leaving a boundary edge in
//!   other than two boundary faces ([`LatticeError::WouldCreateNonManifoldEdge`]) or pinching the
//!   boundary at a vertex ([`LatticeError::WouldCreateNonManifoldVertex`]). Defects the input
//!   already had are not blamed on the edit.
//! * Tags: [`Features::tag_crease`], [`Features::untag_crease`], [`Features::tag_corner`],
//!   [`Features::untag_corner`] edit tags in place; [`Edit::map_features`] carries the tags of
//!   the old lattice to the edited one.
//!
//! # How, and which ids stay stable
//! Each edit lists the cells of the result as face loops, builds them with
//! [`Lattice::from_cells`] (so every construction check runs again) and then renumbers the
//! result so that surviving elements keep their old order, and re-validates it with
//! [`Lattice::validate`]. The input is never modified: an edit returns a new lattice or an
//! error, never a half-edited one. Precisely:
//! * **Extrusion** keeps every id: points, edges, faces and cells `0..n` of the old lattice are
//!   the same elements in the new one (the extruded face keeps its id and vertex loop and is now
//!   interior). New points are appended in the order of the face's loop (`v_i + h n` gets id
//!   `P + i`), then the new edges, the new faces, and the new cell gets id `C`.
//! * **Deletion** removes the cell and every point, edge and face used by no other cell; every
//!   other element keeps its relative order and its id shifts down by the number of removed
//!   elements of its kind with smaller ids (so cells after the deleted one shift down by one,
//!   and all ids below the first removed one are unchanged). A face that became boundary is
//!   re-oriented outward (its loop may be reversed); all other faces keep their vertex loops.
//! * [`Edit`] holds the old-to-new id maps of all four kinds (`None` for removed elements).
//!
//! # Limitations
//! Geometry is only checked as far as [`Lattice::from_cells`] checks it: an extruded cell may
//! intersect other cells (nothing tests for self-intersection), but new points coinciding with
//! existing ones are rejected. The normal of a non-planar face is the Newell average.

use std::collections::HashMap;

use vclay_core::Vec3;

use crate::cells::prism;
use crate::csr::Csr;
use crate::error::LatticeError;
use crate::ids::{CellId, EdgeId, FaceId, VertexId};
use crate::lattice::{Lattice, Primary};
use crate::subdivide::Features;

/// Default of [`ExtrudeParams::factor`]: the extrusion height equals the cube root of the volume
/// of the cell the face belongs to (a unit cube grows a unit cube).
pub const DEFAULT_EXTRUDE_FACTOR: f64 = 1.0;

/// Parameters of [`extrude_face`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExtrudeParams {
    /// Height as a multiple of `|V|^{1/3}`, `V` the volume of the cell behind the face. Must be
    /// positive and finite. Default: [`DEFAULT_EXTRUDE_FACTOR`].
    pub factor: f64,
}

impl Default for ExtrudeParams {
    fn default() -> Self {
        Self {
            factor: DEFAULT_EXTRUDE_FACTOR,
        }
    }
}

/// The result of an edit: the new, validated lattice and the old-to-new id maps (indexed by old
/// id; `None` where the element was removed).
#[derive(Clone, Debug)]
pub struct Edit {
    /// The edited lattice.
    pub lattice: Lattice,
    /// New id of each old point.
    pub point_map: Vec<Option<VertexId>>,
    /// New id of each old edge.
    pub edge_map: Vec<Option<EdgeId>>,
    /// New id of each old face.
    pub face_map: Vec<Option<FaceId>>,
    /// New id of each old cell.
    pub cell_map: Vec<Option<CellId>>,
}

impl Edit {
    /// The tags of `old` (features of the lattice before the edit) carried to the edited
    /// lattice: surviving crease edges and corner vertices stay tagged, new elements are untagged.
    pub fn map_features(&self, old: &Features) -> Features {
        let mut f = Features::none(&self.lattice);
        for e in old.creases() {
            if let Some(Some(n)) = self.edge_map.get(e.index()) {
                f.tag_crease(*n).expect("mapped edge exists");
            }
        }
        for v in old.corners() {
            if let Some(Some(n)) = self.point_map.get(v.index()) {
                f.tag_corner(*n).expect("mapped point exists");
            }
        }
        f
    }
}

/// The face loops of cell `c`, each oriented outward for `c`, with point ids mapped by `map`.
fn cell_loops(lattice: &Lattice, c: CellId, map: impl Fn(VertexId) -> u32) -> Vec<Vec<u32>> {
    lattice
        .cell_faces(c)
        .iter()
        .map(|&f| {
            let mut l: Vec<u32> = lattice.face_vertices(f).iter().map(|&v| map(v)).collect();
            if lattice.cell_uses_face_reversed(c, f) {
                l.reverse();
            }
            l
        })
        .collect()
}

/// Unit Newell normal of a vertex loop (`None` for a loop of zero area).
pub(crate) fn newell_normal(points: &[Vec3], lp: &[VertexId]) -> Option<Vec3> {
    let mut n = Vec3::zeros();
    for i in 0..lp.len() {
        let a = points[lp[i].index()];
        let b = points[lp[(i + 1) % lp.len()].index()];
        n += a.cross(&b);
    }
    let len = n.norm();
    (len > 0.0 && len.is_finite()).then(|| n / len)
}

/// Extrudes boundary face `face` outward into a new prism cell (see the [module docs](self) for
/// the height rule and the ids).
///
/// Errors: [`LatticeError::NoSuchFace`], [`LatticeError::CannotExtrude`] (interior face, zero
/// area, zero-volume cell, bad factor), or a construction error of the result (e.g. a new point
/// coinciding with an existing one).
pub fn extrude_face(
    lattice: &Lattice,
    face: FaceId,
    params: &ExtrudeParams,
) -> Result<Edit, LatticeError> {
    if face.index() >= lattice.num_faces() {
        return Err(LatticeError::NoSuchFace { face });
    }
    let fail = |reason: String| LatticeError::CannotExtrude { face, reason };
    if !(params.factor.is_finite() && params.factor > 0.0) {
        return Err(fail(format!(
            "the height factor must be positive and finite, got {}",
            params.factor
        )));
    }
    let [front, back] = lattice.face_cells(face);
    if back.is_some() {
        return Err(fail(
            "it is an interior face (it has a cell on both sides)".into(),
        ));
    }
    let cell = front.expect("every face has a front cell");
    let lp = lattice.face_vertices(face).to_vec();
    let n = newell_normal(lattice.points(), &lp).ok_or_else(|| fail("it has zero area".into()))?;
    let volume = lattice.cell_signed_volume(cell).abs();
    let h = params.factor * volume.cbrt();
    if !(h > 0.0 && h.is_finite()) {
        return Err(fail(format!("{cell} has zero volume")));
    }
    let np = lattice.num_points() as u32;
    let mut points = lattice.points().to_vec();
    points.extend(lp.iter().map(|&v| lattice.point(v) + n * h));
    let mut cells: Vec<Vec<Vec<u32>>> = (0..lattice.num_cells())
        .map(|c| cell_loops(lattice, CellId::new(c), |v| v.0))
        .collect();
    let bottom: Vec<u32> = lp.iter().map(|v| v.0).collect();
    let top: Vec<u32> = (0..lp.len() as u32).map(|i| np + i).collect();
    cells.push(prism(&bottom, &top));
    let point_map: Vec<Option<u32>> = (0..np).map(Some).collect();
    let (new, maps) = rebuild(lattice, points, &point_map, &cells)?;
    Ok(Edit {
        lattice: new,
        point_map: maps.points,
        edge_map: maps.edges,
        face_map: maps.faces,
        cell_map: (0..lattice.num_cells())
            .map(|c| Some(CellId::new(c)))
            .collect(),
    })
}

/// Deletes cell `cell` (see the [module docs](self) for the checks and the ids).
///
/// Errors: [`LatticeError::NoSuchCell`], [`LatticeError::LastCell`],
/// [`LatticeError::WouldDisconnect`], [`LatticeError::WouldCreateNonManifoldEdge`],
/// [`LatticeError::WouldCreateNonManifoldVertex`], or a construction error of the result.
pub fn delete_cell(lattice: &Lattice, cell: CellId) -> Result<Edit, LatticeError> {
    let nc = lattice.num_cells();
    if cell.index() >= nc {
        return Err(LatticeError::NoSuchCell { cell });
    }
    if nc == 1 {
        return Err(LatticeError::LastCell { cell });
    }
    // Points still used by another cell keep their relative order.
    let mut used = vec![false; lattice.num_points()];
    for c in (0..nc).filter(|&c| c != cell.index()) {
        for &v in lattice.cell_vertices(CellId::new(c)) {
            used[v.index()] = true;
        }
    }
    let mut point_map = vec![None; lattice.num_points()];
    let mut points = Vec::with_capacity(lattice.num_points());
    for (v, &u) in used.iter().enumerate() {
        if u {
            point_map[v] = Some(points.len() as u32);
            points.push(lattice.points()[v]);
        }
    }
    let cells: Vec<Vec<Vec<u32>>> = (0..nc)
        .filter(|&c| c != cell.index())
        .map(|c| cell_loops(lattice, CellId::new(c), |v| point_map[v.index()].unwrap()))
        .collect();
    let (new, maps) = rebuild(lattice, points, &point_map, &cells)?;

    // Refuse edits that break the complex.
    let before = components(lattice);
    let after = components(&new);
    if after > before {
        return Err(LatticeError::WouldDisconnect {
            cell,
            before,
            after,
        });
    }
    let boundary_count = |l: &Lattice, e: EdgeId| {
        l.edge_faces(e)
            .iter()
            .filter(|&&f| l.is_boundary_face(f))
            .count()
    };
    for &e in lattice.cell_edges(cell) {
        if let Some(ne) = maps.edges[e.index()] {
            let (old, now) = (boundary_count(lattice, e), boundary_count(&new, ne));
            if (old == 0 || old == 2) && now != 0 && now != 2 {
                let [a, b] = lattice.edge_vertices(e);
                return Err(LatticeError::WouldCreateNonManifoldEdge {
                    cell,
                    edge: e,
                    a,
                    b,
                    boundary_faces: now,
                });
            }
        }
    }
    for &v in lattice.cell_vertices(cell) {
        if let Some(nv) = maps.points[v.index()] {
            let now = boundary_fans(&new, nv);
            if now > 1 && boundary_fans(lattice, v) <= 1 {
                return Err(LatticeError::WouldCreateNonManifoldVertex {
                    cell,
                    vertex: v,
                    fans: now,
                });
            }
        }
    }
    let cell_map = (0..nc)
        .map(|c| match c.cmp(&cell.index()) {
            std::cmp::Ordering::Less => Some(CellId::new(c)),
            std::cmp::Ordering::Equal => None,
            std::cmp::Ordering::Greater => Some(CellId::new(c - 1)),
        })
        .collect();
    Ok(Edit {
        lattice: new,
        point_map: maps.points,
        edge_map: maps.edges,
        face_map: maps.faces,
        cell_map,
    })
}

/// Number of face-connected components of the cells.
pub(crate) fn components(l: &Lattice) -> usize {
    let mut parent: Vec<usize> = (0..l.num_cells()).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for f in 0..l.num_faces() {
        if let [Some(a), Some(b)] = l.face_cells(FaceId::new(f)) {
            let (ra, rb) = (find(&mut parent, a.index()), find(&mut parent, b.index()));
            parent[ra] = rb;
        }
    }
    (0..parent.len())
        .filter(|&c| find(&mut parent, c) == c)
        .count()
}

/// Number of fans the boundary faces at `v` form (linked through boundary edges at `v`);
/// 0 for an interior vertex.
fn boundary_fans(l: &Lattice, v: VertexId) -> usize {
    let faces: Vec<FaceId> = l
        .vertex_faces(v)
        .iter()
        .copied()
        .filter(|&f| l.is_boundary_face(f))
        .collect();
    let mut parent: Vec<usize> = (0..faces.len()).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            x = p[x];
        }
        x
    }
    for &e in l.vertex_edges(v) {
        let at: Vec<usize> = (0..faces.len())
            .filter(|&i| l.face_edges(faces[i]).contains(&e))
            .collect();
        for w in at.windows(2) {
            let (a, b) = (find(&mut parent, w[0]), find(&mut parent, w[1]));
            parent[a] = b;
        }
    }
    (0..faces.len())
        .filter(|&i| find(&mut parent, i) == i)
        .count()
}

/// Old-to-new id maps of a rebuild.
struct Maps {
    points: Vec<Option<VertexId>>,
    edges: Vec<Option<EdgeId>>,
    faces: Vec<Option<FaceId>>,
}

/// Builds `cells` over `points` with [`Lattice::from_cells`] and renumbers the result like `old`
/// (through `point_map`, old point -> new point); see [`renumber_like`].
fn rebuild(
    old: &Lattice,
    points: Vec<Vec3>,
    point_map: &[Option<u32>],
    cells: &[Vec<Vec<u32>>],
) -> Result<(Lattice, Maps), LatticeError> {
    let built = Lattice::from_cells(points, cells)?;
    let pm = |v: VertexId| point_map[v.index()];
    let ref_edges: Vec<Option<[u32; 2]>> = old
        .edges()
        .iter()
        .map(|&[a, b]| Some([pm(a)?, pm(b)?]))
        .collect();
    let ref_faces: Vec<Option<Vec<u32>>> = (0..old.num_faces())
        .map(|f| {
            old.face_vertices(FaceId::new(f))
                .iter()
                .map(|&v| pm(v))
                .collect::<Option<Vec<u32>>>()
        })
        .collect();
    let (lattice, edges, faces) = renumber_like(built, &ref_edges, &ref_faces)?;
    let points = point_map.iter().map(|p| p.map(VertexId)).collect();
    Ok((
        lattice,
        Maps {
            points,
            edges,
            faces,
        },
    ))
}

/// Renumbers the edges and faces of `built` so that those matching a reference come first, in
/// reference order, and the others follow in their built order; faces matching a reference loop
/// running the same way keep that loop (its start vertex). References are point pairs (any order)
/// and vertex loops in `built`'s point ids; `None` entries match nothing. Returns the renumbered,
/// validated lattice and, per reference, the id it got (`None` if `built` lacks it).
#[allow(clippy::type_complexity)]
pub(crate) fn renumber_like(
    built: Lattice,
    ref_edges: &[Option<[u32; 2]>],
    ref_faces: &[Option<Vec<u32>>],
) -> Result<(Lattice, Vec<Option<EdgeId>>, Vec<Option<FaceId>>), LatticeError> {
    // Edges: referenced ones first (reference order), others after (build order).
    let mut ref_edge: HashMap<[u32; 2], u32> = HashMap::with_capacity(ref_edges.len());
    for (e, r) in ref_edges.iter().enumerate() {
        if let Some([x, y]) = *r {
            ref_edge.entry([x.min(y), x.max(y)]).or_insert(e as u32);
        }
    }
    let ne = built.num_edges();
    let edge_rank = |e: usize| {
        let [a, b] = built.edges[e];
        ref_edge
            .get(&[a.0, b.0])
            .map_or(u64::from(u32::MAX) + e as u64, |&o| u64::from(o))
    };
    let mut edge_order: Vec<usize> = (0..ne).collect();
    edge_order.sort_by_key(|&e| edge_rank(e));
    let edges: Vec<[VertexId; 2]> = edge_order.iter().map(|&e| built.edges[e]).collect();
    let mut edge_id: HashMap<[u32; 2], EdgeId> = HashMap::with_capacity(ne);
    for (i, &[a, b]) in edges.iter().enumerate() {
        edge_id.insert([a.0, b.0], EdgeId::new(i));
    }
    let edge_map: Vec<Option<EdgeId>> = ref_edges
        .iter()
        .map(|r| r.and_then(|[x, y]| edge_id.get(&[x.min(y), x.max(y)]).copied()))
        .collect();

    // Faces likewise, keyed by their sorted vertex sets.
    let mut ref_face: HashMap<Vec<u32>, u32> = HashMap::with_capacity(ref_faces.len());
    for (f, r) in ref_faces.iter().enumerate() {
        if let Some(lp) = r {
            let mut key = lp.clone();
            key.sort_unstable();
            ref_face.entry(key).or_insert(f as u32);
        }
    }
    let nf = built.num_faces();
    let ref_of: Vec<Option<u32>> = (0..nf)
        .map(|f| {
            let mut key: Vec<u32> = built
                .face_vertices(FaceId::new(f))
                .iter()
                .map(|v| v.0)
                .collect();
            key.sort_unstable();
            ref_face.get(&key).copied()
        })
        .collect();
    let mut face_order: Vec<usize> = (0..nf).collect();
    face_order.sort_by_key(|&f| ref_of[f].map_or(u64::from(u32::MAX) + f as u64, u64::from));
    let mut new_of_built = vec![0u32; nf];
    for (i, &f) in face_order.iter().enumerate() {
        new_of_built[f] = i as u32;
    }
    let mut face_map = vec![None; ref_faces.len()];
    let mut face_offsets = Vec::with_capacity(nf + 1);
    face_offsets.push(0u32);
    let mut face_vertices = Vec::with_capacity(built.face_vertices.len());
    let mut face_edges = Vec::with_capacity(built.face_edges.len());
    let mut face_cells = Vec::with_capacity(nf);
    for (i, &f) in face_order.iter().enumerate() {
        let mut lp: Vec<u32> = built
            .face_vertices(FaceId::new(f))
            .iter()
            .map(|v| v.0)
            .collect();
        let mut sides = built.face_cells[f];
        if let Some(o) = ref_of[f] {
            face_map[o as usize] = Some(FaceId::new(i));
            // Keep the reference loop when it runs the same way; when it runs the other way and
            // the face is interior, keep it too and swap the face's front and back cells.
            let ref_lp = ref_faces[o as usize].as_ref().expect("matched a reference");
            let k = lp.len();
            if let Some(s) = ref_lp.iter().position(|&x| x == lp[0]) {
                if (0..k).all(|j| ref_lp[(s + j) % k] == lp[j]) {
                    lp.clone_from(ref_lp);
                } else if sides[1].is_some() && (0..k).all(|j| ref_lp[(s + k - j) % k] == lp[j]) {
                    lp.clone_from(ref_lp);
                    sides.swap(0, 1);
                }
            }
        }
        let k = lp.len();
        for j in 0..k {
            let (a, b) = (lp[j], lp[(j + 1) % k]);
            face_edges.push(edge_id[&[a.min(b), a.max(b)]]);
        }
        face_vertices.extend(lp.iter().map(|&v| VertexId(v)));
        face_offsets.push(face_vertices.len() as u32);
        face_cells.push(sides);
    }
    let cell_faces = Csr::par_build(built.num_cells(), false, |c, out| {
        out.extend(
            built
                .cell_faces(CellId::new(c))
                .iter()
                .map(|f| FaceId(new_of_built[f.index()])),
        );
    });
    let lattice = Lattice::assemble(Primary {
        points: built.points,
        edges,
        face_offsets,
        face_vertices,
        face_edges,
        face_cells,
        cell_faces,
    });
    lattice.validate()?;
    Ok((lattice, edge_map, face_map))
}
