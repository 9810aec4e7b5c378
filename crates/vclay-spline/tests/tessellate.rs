//! Tessellation: outward orientation of volume boundaries, normals at degenerate points.
use vclay_core::{TriMesh, Vec3};
use vclay_spline::{NurbsSurface, NurbsVolume, tessellate_surface, tessellate_volume_boundary};

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
    assert_eq!(m.positions.len(), 33 * 41);
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
