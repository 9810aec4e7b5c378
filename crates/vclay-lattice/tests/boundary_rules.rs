//! Boundary treatment (`BoundaryRule`) and user-tagged creases and corners.

use crate::common;

use common::{perturb, solid};
use vclay_core::Vec3;
use vclay_lattice::{
    BoundaryRule, CellId, EdgeId, FaceId, Features, Lattice, SubdivisionRules, SubdivisionSolid,
    VertexId, cells, primitives, subdivision_operator,
};

fn cube4() -> Lattice {
    primitives::box_lattice([4, 4, 4], Vec3::zeros(), Vec3::repeat(3.0))
}

fn on_box_surface(p: Vec3, size: f64) -> bool {
    p.iter()
        .any(|&c| c.abs() < 1e-12 || (c - size).abs() < 1e-12)
}

#[test]
fn sharp_box_keeps_corners_flat_faces_and_straight_edges() {
    let l = cube4();
    let s = solid(l.clone(), BoundaryRule::Sharp, 2);
    let fine = s.finest();
    // Vertex points of old vertices keep their ids: the 8 corners are fixed.
    for v in 0..l.num_points() {
        let p = l.point(VertexId(v as u32));
        let on_faces = p.iter().filter(|&&c| c == 0.0 || c == 3.0).count();
        if on_faces == 3 {
            assert_eq!(fine.point(VertexId(v as u32)), p, "corner {p:?} moved");
        }
    }
    // Every boundary point stays on the box; points on box edges stay on the box edges.
    for f in fine.boundary_faces() {
        for &v in fine.face_vertices(f) {
            assert!(on_box_surface(fine.point(v), 3.0));
        }
    }
    // Level 1: box-edge vertex (1,0,0): (1,6,1)/8 along the edge = itself on a uniform grid;
    // the box-edge edge point between (0,0,0) and (1,0,0) is the midpoint.
    let s1 = solid(l.clone(), BoundaryRule::Sharp, 1);
    let find = |p: Vec3| {
        VertexId(
            l.points()
                .iter()
                .position(|q| (q - p).norm() < 1e-12)
                .unwrap() as u32,
        )
    };
    let (a, b) = (find(Vec3::zeros()), find(Vec3::new(1.0, 0.0, 0.0)));
    let e = l.edge_between(a, b).unwrap();
    let ep = s1.finest().points()[l.num_points() + e.index()];
    assert!((ep - Vec3::new(0.5, 0.0, 0.0)).norm() < 1e-12);
}

#[test]
fn sharp_crease_vertex_uses_the_curve_rule_on_a_perturbed_box() {
    let mut l = cube4();
    perturb(&mut l, 5, 0.2);
    let s = solid(l.clone(), BoundaryRule::Sharp, 1);
    // A vertex on a box edge but not a corner: exactly two crease edges (in one cell each).
    for v in 0..l.num_points() {
        let vid = VertexId(v as u32);
        let creases: Vec<EdgeId> = l
            .vertex_edges(vid)
            .iter()
            .copied()
            .filter(|&e| l.is_boundary_edge(e) && l.edge_cells(e).len() == 1)
            .collect();
        let want = match creases.len() {
            3 => l.point(vid),
            2 => {
                let far = |e: EdgeId| {
                    let [a, b] = l.edge_vertices(e);
                    l.point(if a == vid { b } else { a })
                };
                (far(creases[0]) + 6.0 * l.point(vid) + far(creases[1])) / 8.0
            }
            _ => continue,
        };
        assert!((s.finest().point(vid) - want).norm() < 1e-12);
    }
}

#[test]
fn smooth_boundary_depends_only_on_the_boundary() {
    let mut l = cube4();
    perturb(&mut l, 9, 0.2);
    let a = subdivision_operator(
        &l,
        &Features::none(&l),
        &SubdivisionRules::new(BoundaryRule::Smooth),
    )
    .unwrap();
    let s = solid(l.clone(), BoundaryRule::Smooth, 1);
    let fine = s.finest();
    let mut rows = 0;
    for f in fine.boundary_faces() {
        for &v in fine.face_vertices(f) {
            let (cols, _) = a.row(v.index());
            assert!(
                cols.iter().all(|&c| l.is_boundary_vertex(VertexId(c))),
                "boundary point {v} reads an interior control point"
            );
            rows += 1;
        }
    }
    assert!(rows > 0);
    // With the interior rule the boundary does read interior points.
    let ai = subdivision_operator(
        &l,
        &Features::none(&l),
        &SubdivisionRules::new(BoundaryRule::Interior),
    )
    .unwrap();
    let reads_interior = (0..l.num_points()).any(|v| {
        l.is_boundary_vertex(VertexId(v as u32))
            && ai
                .row(v)
                .0
                .iter()
                .any(|&c| !l.is_boundary_vertex(VertexId(c)))
    });
    assert!(reads_interior);
}

#[test]
fn interior_rule_boundary_face_point_is_half_cell_half_face() {
    let mut l = cube4();
    perturb(&mut l, 2, 0.2);
    let s = solid(l.clone(), BoundaryRule::Interior, 1);
    let base = l.num_points() + l.num_edges();
    let f = l.boundary_faces().next().unwrap();
    let c0 = l.face_cells(f)[0].unwrap();
    let want = (l.cell_centroid(c0) + l.face_centroid(f)) / 2.0;
    assert!((s.finest().points()[base + f.index()] - want).norm() < 1e-12);
    // An interior face: (c0 + 2a + c1) / 4.
    let g = (0..l.num_faces())
        .map(|i| FaceId(i as u32))
        .find(|&g| !l.is_boundary_face(g))
        .unwrap();
    let [c0, c1] = l.face_cells(g);
    let want =
        (l.cell_centroid(c0.unwrap()) + 2.0 * l.face_centroid(g) + l.cell_centroid(c1.unwrap()))
            / 4.0;
    assert!((s.finest().points()[base + g.index()] - want).norm() < 1e-12);
    // Cell point: the centroid.
    let c = CellId(5);
    let want = l.cell_centroid(c);
    assert!((s.finest().points()[base + l.num_faces() + 5] - want).norm() < 1e-12);
}

#[test]
fn volumetric_edge_and_vertex_rules_at_an_irregular_edge() {
    // Five triangular prisms around the z axis: the axis edges have n = 5 faces... check the rule
    // as stated on every edge and vertex away from the boundary of a cylinder with the interior
    // rule.
    let mut l = primitives::cylinder(1.0, 2.0, 5, 2, 1);
    perturb(&mut l, 4, 0.05);
    let s = solid(l.clone(), BoundaryRule::Interior, 1);
    let np = l.num_points();
    let avg = |v: Vec<Vec3>| v.iter().sum::<Vec3>() / v.len() as f64;
    for e in 0..l.num_edges() {
        let eid = EdgeId(e as u32);
        let fs = l.edge_faces(eid);
        let n = fs.len() as f64;
        let c = avg(l
            .edge_cells(eid)
            .iter()
            .map(|&c| l.cell_centroid(c))
            .collect());
        let a = avg(fs.iter().map(|&f| l.face_centroid(f)).collect());
        let want = (c + 2.0 * a + (n - 3.0) * l.edge_midpoint(eid)) / n;
        assert!(
            (s.finest().points()[np + e] - want).norm() < 1e-12,
            "edge {e}"
        );
    }
    for v in 0..np {
        let vid = VertexId(v as u32);
        let c = avg(l
            .vertex_cells(vid)
            .iter()
            .map(|&c| l.cell_centroid(c))
            .collect());
        let a = avg(l
            .vertex_faces(vid)
            .iter()
            .map(|&f| l.face_centroid(f))
            .collect());
        let m = avg(l
            .vertex_edges(vid)
            .iter()
            .map(|&e| l.edge_midpoint(e))
            .collect());
        let want = (c + 3.0 * a + 3.0 * m + l.point(vid)) / 8.0;
        assert!((s.finest().point(vid) - want).norm() < 1e-12, "vertex {v}");
    }
}

#[test]
fn smooth_vertex_rule_on_an_extraordinary_boundary_vertex() {
    // The centre of a cylinder's cap has 5 boundary edges: (Q + 2R + (n-3) p) / n.
    let mut l = primitives::cylinder(1.0, 1.0, 5, 1, 0);
    perturb(&mut l, 8, 0.05);
    let s = solid(l.clone(), BoundaryRule::Smooth, 1);
    let v = VertexId(0); // profile point 0 at z = 0: the axis.
    let bf: Vec<FaceId> = l
        .vertex_faces(v)
        .iter()
        .copied()
        .filter(|&f| l.is_boundary_face(f))
        .collect();
    let be: Vec<EdgeId> = l
        .vertex_edges(v)
        .iter()
        .copied()
        .filter(|&e| l.is_boundary_edge(e))
        .collect();
    assert_eq!((bf.len(), be.len()), (5, 5));
    let q = bf.iter().map(|&f| l.face_centroid(f)).sum::<Vec3>() / 5.0;
    let r = be.iter().map(|&e| l.edge_midpoint(e)).sum::<Vec3>() / 5.0;
    let want = (q + 2.0 * r + 2.0 * l.point(v)) / 5.0;
    assert!((s.finest().point(v) - want).norm() < 1e-12);
}

#[test]
fn tagged_creases_and_corners_are_inherited() {
    let mut l = cube4();
    perturb(&mut l, 1, 0.1);
    let mut feats = Features::none(&l);
    // Crease along an interior edge line of the top face and a corner at one of its ends.
    let e = (0..l.num_edges())
        .map(|e| EdgeId(e as u32))
        .find(|&e| {
            l.is_boundary_edge(e)
                && !l
                    .edge_vertices(e)
                    .iter()
                    .any(|&v| l.vertex_cells(v).len() < 2)
        })
        .unwrap();
    feats.tag_crease(e).unwrap();
    let corner = l.edge_vertices(e)[0];
    feats.tag_corner(corner).unwrap();
    assert!(feats.tag_corner(VertexId(1000)).is_err());
    assert!(feats.tag_crease(EdgeId(1000)).is_err());
    let s = SubdivisionSolid::new(
        l.clone(),
        feats,
        SubdivisionRules::new(BoundaryRule::Smooth),
        2,
    )
    .unwrap();
    // The crease edge point is the midpoint; the corner never moves.
    assert!(
        (s.lattice(1).points()[l.num_points() + e.index()] - l.edge_midpoint(e)).norm() < 1e-12
    );
    assert_eq!(s.finest().point(corner), l.point(corner));
    assert_eq!(s.features(1).num_creases(), 2);
    assert_eq!(s.features(2).num_creases(), 4);
    assert_eq!(s.features(2).num_corners(), 1);
}

#[test]
fn non_manifold_boundary_edge_becomes_a_crease() {
    // Two cubes sharing only an edge.
    let mut pts = Vec::new();
    for z in [0.0, 1.0] {
        for (x, y) in [
            (0.0, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (0.0, 1.0),
            (2.0, 1.0),
            (2.0, 2.0),
            (1.0, 2.0),
        ] {
            pts.push(Vec3::new(x, y, z));
        }
    }
    let c1 = cells::hexahedron([0, 1, 2, 3, 7, 8, 9, 10]);
    let c2 = cells::hexahedron([2, 4, 5, 6, 9, 11, 12, 13]);
    let l = Lattice::from_cells(pts, &[c1, c2]).unwrap();
    let shared = l.edge_between(VertexId(2), VertexId(9)).unwrap();
    assert_eq!(l.edge_faces(shared).len(), 4);
    assert_eq!(l.edge_cells(shared).len(), 2);
    for rule in [BoundaryRule::Smooth, BoundaryRule::Sharp] {
        let s = solid(l.clone(), rule, 2);
        let ep = s.lattice(1).points()[l.num_points() + shared.index()];
        assert!((ep - l.edge_midpoint(shared)).norm() < 1e-12);
        s.finest().validate().unwrap();
    }
}
