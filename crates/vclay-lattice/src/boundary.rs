//! Boundary surface extraction.
//!
//! The boundary of a lattice is the set of faces with one cell. Each is written, oriented outward
//! (its stored loop, see [`crate::lattice`] conventions), into a [`MeshSink`], polygons
//! fan-triangulated from their first vertex. Only points used by boundary faces are emitted, in
//! increasing id order, without normals. Applied to the finest level of a
//! [`crate::SubdivisionSolid`] this is the surface to render or export.
//!
//! Limitations: fan triangulation assumes convex (or mildly non-convex) polygons; subdivided
//! lattices have only quads, for which it is exact.

use vclay_core::{MeshSink, TriMesh};

use crate::ids::VertexId;
use crate::lattice::Lattice;

/// Writes the outward-oriented boundary faces of `lattice` into `sink`; returns the number of
/// triangles written.
pub fn write_boundary<S: MeshSink + ?Sized>(lattice: &Lattice, sink: &mut S) -> usize {
    let mut remap = vec![u32::MAX; lattice.num_points()];
    let mut nverts = 0usize;
    let mut ntris = 0usize;
    for f in lattice.boundary_faces() {
        for &v in lattice.face_vertices(f) {
            if remap[v.index()] == u32::MAX {
                remap[v.index()] = 0;
                nverts += 1;
            }
        }
        ntris += lattice.face_vertices(f).len() - 2;
    }
    sink.reserve(nverts, ntris);
    for (v, slot) in remap.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = sink.add_vertex(lattice.point(VertexId(v as u32)), None);
        }
    }
    for f in lattice.boundary_faces() {
        let vs = lattice.face_vertices(f);
        // A boundary face's only cell is its front cell, so its stored loop faces outward.
        let reversed = lattice.face_cells(f)[0].is_none();
        let idx = |i: usize| {
            let i = if reversed {
                (vs.len() - i) % vs.len()
            } else {
                i
            };
            remap[vs[i].index()]
        };
        for i in 1..vs.len() - 1 {
            sink.add_triangle([idx(0), idx(i), idx(i + 1)]);
        }
    }
    ntris
}

/// The boundary surface as a [`TriMesh`] (see [`write_boundary`]).
pub fn boundary_mesh(lattice: &Lattice) -> TriMesh {
    let mut m = TriMesh::new();
    write_boundary(lattice, &mut m);
    m
}
