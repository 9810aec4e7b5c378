//! Lattices from meshes (issue 19): spheres and tori fit within the goals, bad input is refused
//! with located errors.

use vclay_core::{TriMesh, Vec3};
use vclay_lattice::from_mesh::{ClayError, ClayParams, MAX_CELLS, MAX_LEVELS, lattice_from_mesh};
use vclay_lattice::{BoundaryRule, CellId};

/// A UV sphere: `rings` latitude bands (poles closed by fans), `segments` around.
fn sphere(radius: f64, rings: usize, segments: usize) -> TriMesh {
    let profile: Vec<(f64, f64)> = (0..=rings)
        .map(|i| {
            let t = std::f64::consts::PI * i as f64 / rings as f64;
            let r = if i == 0 || i == rings {
                0.0
            } else {
                radius * t.sin()
            };
            (r, -radius * t.cos())
        })
        .collect();
    TriMesh::revolution(&profile, segments)
}

/// A torus about the z axis: `rings` points around the tube, `segments` around the axis.
fn torus(major: f64, minor: f64, rings: usize, segments: usize) -> TriMesh {
    let mut mesh = TriMesh::new();
    for s in 0..segments {
        let a = std::f64::consts::TAU * s as f64 / segments as f64;
        for r in 0..rings {
            let b = std::f64::consts::TAU * r as f64 / rings as f64;
            let rho = major + minor * b.cos();
            mesh.positions
                .push(Vec3::new(rho * a.cos(), rho * a.sin(), minor * b.sin()));
        }
    }
    let id = |s: usize, r: usize| ((s % segments) * rings + r % rings) as u32;
    for s in 0..segments {
        for r in 0..rings {
            let (a, b, c, d) = (id(s, r), id(s + 1, r), id(s + 1, r + 1), id(s, r + 1));
            mesh.triangles.push([a, b, c]);
            mesh.triangles.push([a, c, d]);
        }
    }
    mesh
}

/// The checks every fitted mesh must pass: a valid lattice at every level, every cell of every
/// level positive, the distances of issue 19's goal (0.2 % mean, 1 % maximum of the diagonal)
/// both ways, and about the asked number of cells.
fn check(mesh: &TriMesh, cells: usize) -> vclay_lattice::Clay {
    let clay = lattice_from_mesh(
        mesh,
        &ClayParams {
            cells,
            ..ClayParams::default()
        },
    )
    .unwrap();
    let r = &clay.report;
    eprintln!("{}", r.to_json());
    for j in 0..=clay.solid.levels() {
        let lattice = clay.solid.lattice(j);
        lattice.validate().unwrap();
        let folded = (0..lattice.num_cells())
            .filter(|&c| lattice.cell_signed_volume(CellId::new(c)) <= 0.0)
            .count();
        assert_eq!(folded, 0, "level {j}");
    }
    assert_eq!((r.folded_cells, r.folded_cells_finest), (0, 0));
    assert!(r.min_cell_volume > 0.0 && r.min_cell_volume_finest > 0.0);
    assert!(
        (r.cells as f64 / cells as f64 - 1.0).abs() < 0.1,
        "{} cells",
        r.cells
    );
    assert!(
        r.distance.mean < 0.002 && r.distance.max < 0.01,
        "{:?}",
        r.distance
    );
    let rev = r.reverse_distance;
    assert!(rev.mean < 0.002 && rev.max < 0.01, "{rev:?}");
    // The plain voxel lattice is far off: the fit is what meets the goal.
    assert!(r.voxel_distance.mean > 0.002, "{:?}", r.voxel_distance);
    clay
}

/// Euler characteristic of the boundary surface of the control lattice.
fn boundary_euler(clay: &vclay_lattice::Clay) -> i64 {
    let m = vclay_lattice::boundary_mesh(clay.solid.control());
    let (v, f) = (m.positions.len() as i64, m.triangles.len() as i64);
    v - 3 * f / 2 + f
}

#[test]
fn sphere_at_2000_cells_meets_the_goal() {
    let clay = check(&sphere(1.0, 64, 128), 2000);
    assert_eq!(boundary_euler(&clay), 2);
}

#[test]
fn torus_at_2000_cells_meets_the_goal_and_keeps_genus_1() {
    let clay = check(&torus(1.0, 0.4, 64, 128), 2000);
    assert_eq!(boundary_euler(&clay), 0);
}

#[test]
fn inside_out_input_is_flipped() {
    let mut m = sphere(1.0, 16, 32);
    for t in &mut m.triangles {
        t.swap(1, 2);
    }
    let clay = lattice_from_mesh(
        &m,
        &ClayParams {
            cells: 200,
            levels: 1,
            ..ClayParams::default()
        },
    )
    .unwrap();
    assert!(clay.report.flipped);
    assert_eq!(clay.report.folded_cells, 0);
}

#[test]
fn open_mesh_names_its_boundary_edges() {
    let mut m = sphere(1.0, 8, 12);
    m.triangles.remove(40);
    let e = lattice_from_mesh(&m, &ClayParams::default()).unwrap_err();
    let ClayError::Open { count, first } = &e else {
        panic!("{e}")
    };
    assert_eq!(*count, 3);
    assert!(first.0.iter().all(|f| f.triangles.len() == 1));
    let msg = e.to_string();
    assert!(
        msg.contains("open") && msg.contains("in triangles"),
        "{msg}"
    );
}

#[test]
fn non_manifold_mesh_names_the_shared_edge() {
    // Two tetrahedra sharing the edge (0, 1): four triangles use it.
    let p = |x: f64, y: f64, z: f64| Vec3::new(x, y, z);
    let mut m = TriMesh::new();
    m.positions = vec![
        p(0.0, 0.0, 0.0),
        p(1.0, 0.0, 0.0),
        p(0.5, 1.0, 0.0),
        p(0.5, 0.3, 1.0),
        p(0.5, -1.0, 0.0),
        p(0.5, -0.3, -1.0),
    ];
    let tet = |a: u32, b: u32, c: u32, d: u32| [[a, c, b], [a, b, d], [b, c, d], [c, a, d]];
    m.triangles.extend(tet(0, 1, 2, 3));
    m.triangles.extend(tet(1, 0, 4, 5));
    let e = lattice_from_mesh(&m, &ClayParams::default()).unwrap_err();
    let ClayError::NonManifold { count, first } = &e else {
        panic!("{e}")
    };
    assert_eq!(*count, 1);
    assert_eq!((first.0[0].a, first.0[0].b), (0, 1));
    assert_eq!(first.0[0].triangles.len(), 4);
}

#[test]
fn flipped_triangle_is_an_orientation_error() {
    let mut m = sphere(1.0, 8, 12);
    m.triangles[30].swap(1, 2);
    let e = lattice_from_mesh(&m, &ClayParams::default()).unwrap_err();
    let ClayError::Orientation { count, first } = &e else {
        panic!("{e}")
    };
    assert_eq!(*count, 3);
    assert!(first.0.iter().all(|f| f.triangles.contains(&30)));
}

#[test]
fn sizes_are_bounded_before_any_work() {
    let m = sphere(1.0, 8, 12);
    for params in [
        ClayParams {
            cells: 0,
            ..ClayParams::default()
        },
        ClayParams {
            cells: MAX_CELLS + 1,
            ..ClayParams::default()
        },
        ClayParams {
            levels: MAX_LEVELS + 1,
            ..ClayParams::default()
        },
        ClayParams {
            cells: MAX_CELLS,
            levels: 4,
            ..ClayParams::default()
        },
        ClayParams {
            boundary: BoundaryRule::Interior,
            ..ClayParams::default()
        },
    ] {
        let e = lattice_from_mesh(&m, &params).unwrap_err();
        assert!(matches!(e, ClayError::Parameter { .. }), "{e}");
    }
}
