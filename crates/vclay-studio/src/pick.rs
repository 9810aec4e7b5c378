//! The surface under the mouse, on the UI thread: a ray against the display meshes of the
//! last [`Frame`] (no round trip to the simulation thread), for the brush circle drawn while
//! the mouse hovers and for the control-point handle under it.
//!
//! Ray-triangle intersection by Möller & Trumbore, "Fast, minimum storage ray/triangle
//! intersection", J. Graphics Tools 2(1), 1997 (doi:10.1080/10867651.1997.10487468); the
//! normal is the hit triangle's vertex normals interpolated (the shading normal), facing the
//! ray. A linear scan: about a millisecond for the studio's largest display meshes (100k
//! triangles), once per mouse move.
//!
//! Limitations: it sees the frame shown, which may lag the simulation by a frame; the
//! simulation thread's own pick ([`vclay_session::Session::pick`]) decides what a press acts on.

use vclay_core::{TriMesh, Vec3};
use vclay_session::Ray;

use crate::worker::Frame;

/// Where a ray meets a display surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    /// The point.
    pub point: Vec3,
    /// Unit normal there, facing the ray's origin.
    pub normal: Vec3,
    /// Distance along the ray (in units of `|direction|`).
    pub distance: f64,
}

/// The nearest hit of `ray` on `mesh`.
pub fn ray_mesh(ray: &Ray, mesh: &TriMesh) -> Option<SurfaceHit> {
    let (o, d) = (ray.origin, ray.direction);
    let mut best: Option<(f64, usize, f64, f64)> = None;
    for (k, t) in mesh.triangles.iter().enumerate() {
        let (Some(a), Some(b), Some(c)) = (
            mesh.positions.get(t[0] as usize),
            mesh.positions.get(t[1] as usize),
            mesh.positions.get(t[2] as usize),
        ) else {
            continue;
        };
        let (e1, e2) = (b - a, c - a);
        let p = d.cross(&e2);
        let det = e1.dot(&p);
        if det.abs() < 1e-300 {
            continue;
        }
        let inv = 1.0 / det;
        let s = o - a;
        let u = s.dot(&p) * inv;
        if !(0.0..=1.0).contains(&u) {
            continue;
        }
        let q = s.cross(&e1);
        let v = d.dot(&q) * inv;
        if v < 0.0 || u + v > 1.0 {
            continue;
        }
        let dist = e2.dot(&q) * inv;
        if dist > 0.0 && best.is_none_or(|b| dist < b.0) {
            best = Some((dist, k, u, v));
        }
    }
    let (distance, k, u, v) = best?;
    let t = mesh.triangles[k];
    let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
    let face = (b - a).cross(&(c - a));
    let n = match (
        mesh.normals.get(t[0] as usize),
        mesh.normals.get(t[1] as usize),
        mesh.normals.get(t[2] as usize),
    ) {
        (Some(na), Some(nb), Some(nc)) => na * (1.0 - u - v) + nb * u + nc * v,
        _ => face,
    };
    let n = if n.norm() > 1e-300 { n } else { face };
    let n = n.normalize();
    Some(SurfaceHit {
        point: o + d * distance,
        normal: if n.dot(&d) > 0.0 { -n } else { n },
        distance,
    })
}

/// The nearest hit of `ray` on the display meshes of `frame`'s models.
pub fn ray_frame(ray: &Ray, frame: &Frame) -> Option<SurfaceHit> {
    frame
        .models
        .iter()
        .filter_map(|m| ray_mesh(ray, &m.mesh))
        .min_by(|a, b| a.distance.total_cmp(&b.distance))
}

/// Two unit vectors spanning the plane normal to `n` (the brush circle's tangent plane).
pub fn tangents(n: Vec3) -> (Vec3, Vec3) {
    let a = if n.x.abs() < 0.9 {
        Vec3::x()
    } else {
        Vec3::y()
    };
    let t1 = n.cross(&a).normalize();
    (t1, n.cross(&t1))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> TriMesh {
        TriMesh {
            positions: vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            ],
            normals: vec![Vec3::z(); 4],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    #[test]
    fn a_ray_down_hits_the_square_and_faces_up() {
        let ray = Ray {
            origin: Vec3::new(0.25, 0.6, 2.0),
            direction: Vec3::new(0.0, 0.0, -1.0),
        };
        let h = ray_mesh(&ray, &square()).unwrap();
        assert!((h.point - Vec3::new(0.25, 0.6, 0.0)).norm() < 1e-12);
        assert!((h.normal - Vec3::z()).norm() < 1e-12);
        assert!((h.distance - 2.0).abs() < 1e-12);
        // From below the normal faces down; beside the square nothing is hit.
        let up = Ray {
            origin: Vec3::new(0.25, 0.6, -1.0),
            direction: Vec3::z(),
        };
        assert!((ray_mesh(&up, &square()).unwrap().normal + Vec3::z()).norm() < 1e-12);
        let off = Ray {
            origin: Vec3::new(1.5, 0.6, 2.0),
            ..ray
        };
        assert!(ray_mesh(&off, &square()).is_none());
    }

    #[test]
    fn tangents_are_orthonormal() {
        for n in [Vec3::x(), Vec3::z(), Vec3::new(1.0, 2.0, 3.0).normalize()] {
            let (a, b) = tangents(n);
            assert!(a.dot(&n).abs() < 1e-12 && b.dot(&n).abs() < 1e-12 && a.dot(&b).abs() < 1e-12);
            assert!((a.norm() - 1.0).abs() < 1e-12 && (b.norm() - 1.0).abs() < 1e-12);
        }
    }
}
