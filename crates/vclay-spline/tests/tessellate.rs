//! Tessellation: outward orientation of volume boundaries, normals at degenerate points,
//! sample lines on C0 knots with split normals (issue 28).
use vclay_core::{TriMesh, Vec3};
use vclay_spline::{
    NurbsSurface, NurbsVolume, SurfaceSampling, tessellate_surface, tessellate_volume_boundary,
};

#[test]
fn box_volume_boundary_is_closed_and_outward() {
    let lo = Vec3::new(0.0, 0.0, 0.0);
    let hi = Vec3::new(2.0, 1.0, 3.0);
    let vol = NurbsVolume::box_lattice([2, 2, 2], [3, 4, 3], lo, hi).unwrap();
    let mut m = TriMesh::new();
    tessellate_volume_boundary(&vol, [5, 6, 7], &mut m).unwrap();
    m.validate().unwrap();
    // 6 faces, (n1-1)(n2-1)*2 triangles each.
    assert_eq!(m.triangles.len(), 2 * 2 * (4 * 5 + 5 * 6 + 6 * 4));
    let c = (lo + hi) / 2.0;
    for tri in &m.triangles {
        let [a, b, d] = tri.map(|i| m.positions[i as usize]);
        let n = (b - a).cross(&(d - a));
        let centroid = (a + b + d) / 3.0;
        assert!(
            n.dot(&(centroid - c)) > 0.0,
            "inward triangle at {centroid:?}"
        );
    }
    for (p, n) in m.positions.iter().zip(&m.normals) {
        assert!((n.norm() - 1.0).abs() < 1e-12);
        assert!(n.dot(&(p - c)) > 0.0);
    }
    // Divergence theorem: enclosed volume of an outward closed mesh is 2*1*3.
    assert!((enclosed_volume(&m) - 6.0).abs() < 1e-12);
}

#[test]
fn mirrored_volume_is_still_outward() {
    // A left-handed parametrization (x mirrored) must flip the faces.
    let mut vol =
        NurbsVolume::box_lattice([1, 1, 1], [2, 2, 2], Vec3::zeros(), Vec3::repeat(1.0)).unwrap();
    vol.transform(
        &nalgebra::Matrix3::new(-1., 0., 0., 0., 1., 0., 0., 0., 1.),
        &Vec3::zeros(),
    );
    let mut m = TriMesh::new();
    tessellate_volume_boundary(&vol, [3, 3, 3], &mut m).unwrap();
    let v = enclosed_volume(&m);
    assert!((v - 1.0).abs() < 1e-12, "signed volume {v}");
}

#[test]
fn sphere_normals_are_radial_even_at_the_poles() {
    let s = NurbsSurface::sphere(1.5).unwrap();
    let mut m = TriMesh::new();
    tessellate_surface(&s, [33, 41], &mut m).unwrap();
    m.validate().unwrap();
    // The rational circles' double knots are C0 knots (G1 in space): lines are cut there, and
    // there are still 33 x 41 of them.
    let sampling = SurfaceSampling::new(&s, [33, 41]);
    assert_eq!(m.positions.len(), 33 * 41);
    assert_eq!(sampling.vertex_count(), 33 * 41);
    assert!(
        sampling.pieces[1].len() > 1,
        "the circle's double knots cut the v lines"
    );
    let sign = m.normals[500].dot(&m.positions[500]).signum();
    for (p, n) in m.positions.iter().zip(&m.normals) {
        assert!(
            (n.norm() - 1.0).abs() < 1e-9,
            "normal at {p:?} has length {}",
            n.norm()
        );
        // Away from the poles the analytic normal is radial; at the poles the fallback mesh
        // normal is the limit of the analytic one (evaluated just inside the domain).
        let cos = sign * n.dot(&(p / 1.5));
        assert!(cos > 1.0 - 1e-9, "normal {n:?} at {p:?}: cos {cos}");
    }
}

#[test]
fn closed_primitives_are_oriented_outward() {
    // The torus and the sphere are closed: their tessellations must enclose positive volume
    // (triangles counter-clockwise seen from outside) and their normals must point out, as
    // renderers with back-face culling and mesh tools expect.
    for (name, s, volume) in [
        (
            "torus",
            NurbsSurface::torus(2.0, 0.5).unwrap(),
            2.0 * std::f64::consts::PI.powi(2) * 2.0 * 0.25,
        ),
        (
            "sphere",
            NurbsSurface::sphere(1.5).unwrap(),
            4.0 / 3.0 * std::f64::consts::PI * 1.5f64.powi(3),
        ),
    ] {
        let mut m = TriMesh::new();
        tessellate_surface(&s, [65, 65], &mut m).unwrap();
        let v = enclosed_volume(&m);
        assert!(
            v > 0.0 && (v - volume).abs() < 0.01 * volume,
            "{name}: encloses {v}, the solid's volume is {volume}"
        );
        // Normals point out: away from the centre (sphere) or from the tube's core circle.
        for (p, n) in m.positions.iter().zip(&m.normals) {
            let out = if name == "sphere" {
                *p
            } else {
                let rho = (p.x * p.x + p.y * p.y).sqrt();
                *p - Vec3::new(p.x / rho * 2.0, p.y / rho * 2.0, 0.0)
            };
            assert!(n.dot(&out) > 0.0, "{name}: normal {n:?} at {p:?} points in");
        }
    }
}

/// A sheet folded by 90 degrees along a double knot of a quadratic: flat in `z = 0` for
/// `x in [0, 1]` (u in [0, 0.5]), then straight up the plane `x = 1` to `z = 1` (u in
/// [0.5, 1]); linear in `y` over `[0, 2]`.
fn folded_sheet() -> NurbsSurface {
    let xz = [(0.0, 0.0), (0.5, 0.0), (1.0, 0.0), (1.0, 0.5), (1.0, 1.0)];
    let rows = xz
        .iter()
        .map(|&(x, z)| vec![Vec3::new(x, 0.0, z), Vec3::new(x, 2.0, z)])
        .collect();
    NurbsSurface::new(
        [2, 1],
        [
            vec![0.0, 0.0, 0.0, 0.5, 0.5, 1.0, 1.0, 1.0],
            vec![0.0, 0.0, 1.0, 1.0],
        ],
        rows,
        None,
    )
    .unwrap()
}

#[test]
fn c0_knots_get_sample_lines_and_split_normals() {
    // Issue 28 (Fig 2's swung cube looked chamfered): a uniform grid of 32 lines misses the
    // double knot at u = 0.5, so a chord cut the fold and the normals were averaged across
    // it. 32 lines do not hit 0.5 (i / 31); the tessellation must still put a line there.
    let s = folded_sheet();
    let sampling = SurfaceSampling::new(&s, [32, 5]);
    assert_eq!(sampling.pieces[0].len(), 2, "{:?}", sampling.pieces[0]);
    assert_eq!(*sampling.pieces[0][0].last().unwrap(), 0.5);
    assert_eq!(sampling.pieces[0][1][0], 0.5);
    // Still 32 lines: 30 intervals, 15 on each half, each half uniform.
    assert_eq!(
        sampling.pieces[0][0],
        vclay_core::Interval::new(0.0, 0.5).linspace(16)
    );
    assert_eq!(
        sampling.pieces[0][1],
        vclay_core::Interval::new(0.5, 1.0).linspace(16)
    );
    assert_eq!(sampling.pieces[1], vec![vec![0.0, 0.25, 0.5, 0.75, 1.0]]);
    let mut m = TriMesh::new();
    tessellate_surface(&s, [32, 5], &mut m).unwrap();
    m.validate().unwrap();
    assert_eq!(m.positions.len(), 32 * 5);
    assert_eq!(sampling.vertex_count(), 32 * 5);
    assert_eq!(sampling.vertex_params().len(), m.positions.len());
    // Every vertex on the L, and at its parameters.
    for (p, uv) in m.positions.iter().zip(sampling.vertex_params()) {
        let on_floor = p.z.abs() < 1e-12 && (-1e-12..=1.0 + 1e-12).contains(&p.x);
        let on_wall = (p.x - 1.0).abs() < 1e-12 && (-1e-12..=1.0 + 1e-12).contains(&p.z);
        assert!(on_floor || on_wall, "vertex {p:?} off the fold");
        let q = vclay_spline::ParametricSurface::point(&s, uv[0], uv[1]).unwrap();
        assert!((p - q).norm() < 1e-12, "vertex {p:?} is not s({uv:?})");
    }
    // Every triangle lies in the floor or in the wall: no chord across the fold (dihedral
    // angle 90 degrees between the two sides' triangles).
    let (mut floor, mut wall) = (0, 0);
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        let n = (b - a).cross(&(c - a)).normalize();
        if (n.z.abs() - 1.0).abs() < 1e-12 {
            floor += 1;
        } else if (n.x.abs() - 1.0).abs() < 1e-12 {
            wall += 1;
        } else {
            panic!("triangle {a:?} {b:?} {c:?} cuts the fold (normal {n:?})");
        }
    }
    assert_eq!(floor, wall);
    // On the crease x = 1, z = 0 each point is written twice, with the floor's normal and
    // the wall's normal (one-sided derivatives), 90 degrees apart; elsewhere the normal is
    // the flat side's.
    let crease: Vec<usize> = (0..m.positions.len())
        .filter(|&k| (m.positions[k].x - 1.0).abs() < 1e-12 && m.positions[k].z.abs() < 1e-12)
        .collect();
    assert_eq!(crease.len(), 2 * 5);
    let floor_normal = m.normals[0];
    assert!(
        (floor_normal.z.abs() - 1.0).abs() < 1e-12,
        "{floor_normal:?}"
    );
    let (mut on_floor, mut on_wall) = (0, 0);
    for &k in &crease {
        let n = m.normals[k];
        if (n - floor_normal).norm() < 1e-12 {
            on_floor += 1;
        } else {
            assert!((n.x.abs() - 1.0).abs() < 1e-12, "crease normal {n:?}");
            assert!(n.dot(&floor_normal).abs() < 1e-12);
            on_wall += 1;
        }
    }
    assert_eq!((on_floor, on_wall), (5, 5));
}

#[test]
fn a_net_finer_than_the_samples_is_sampled_uniformly() {
    // A bilinear sheet has a C0 knot at each of its 9 interior knots: 10 pieces, more than
    // half of 8 samples, so the axis is not cut (the mesh keeps at most 8 x 8 vertices); with
    // 20 samples it is cut at every knot.
    let rows = (0..11)
        .map(|i| {
            (0..2)
                .map(|j| Vec3::new(i as f64, j as f64, (i % 2) as f64))
                .collect()
        })
        .collect();
    let mut u = vec![0.0];
    u.extend((0..=10).map(|i| i as f64 / 10.0));
    u.push(1.0);
    let s = NurbsSurface::new([1, 1], [u, vec![0.0, 0.0, 1.0, 1.0]], rows, None).unwrap();
    let coarse = SurfaceSampling::new(&s, [8, 8]);
    assert_eq!(coarse.pieces[0].len(), 1);
    assert_eq!(coarse.vertex_count(), 64);
    let fine = SurfaceSampling::new(&s, [20, 8]);
    assert_eq!(fine.pieces[0].len(), 10);
    assert_eq!(fine.vertex_count(), 20 * 8);
    for (i, piece) in fine.pieces[0].iter().enumerate() {
        assert_eq!(
            (piece[0], piece[piece.len() - 1]),
            (i as f64 / 10.0, (i + 1) as f64 / 10.0)
        );
    }
}

#[test]
fn surfaces_without_c0_knots_keep_the_uniform_grid() {
    // A cubic sheet with simple interior knots: one piece per axis, the plain linspace.
    let rows = (0..5)
        .map(|i| {
            (0..4)
                .map(|j| Vec3::new(i as f64, j as f64, ((i * j) as f64).sin()))
                .collect()
        })
        .collect();
    let s = NurbsSurface::new(
        [3, 2],
        [
            vec![0.0, 0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0, 1.0],
            vec![0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0],
        ],
        rows,
        None,
    )
    .unwrap();
    let sampling = SurfaceSampling::new(&s, [7, 9]);
    assert_eq!(
        sampling.pieces[0],
        vec![vclay_core::Interval::new(0.0, 1.0).linspace(7)]
    );
    assert_eq!(
        sampling.pieces[1],
        vec![vclay_core::Interval::new(0.0, 1.0).linspace(9)]
    );
    let mut m = TriMesh::new();
    tessellate_surface(&s, [7, 9], &mut m).unwrap();
    assert_eq!(m.positions.len(), 7 * 9);
    assert_eq!(m.triangles.len(), 2 * 6 * 8);
}

/// Signed volume enclosed by a closed triangle mesh (divergence theorem): positive when its
/// triangles run counter-clockwise seen from outside.
fn enclosed_volume(m: &TriMesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, d] = t.map(|i| m.positions[i as usize]);
            a.dot(&b.cross(&d))
        })
        .sum::<f64>()
        / 6.0
}
