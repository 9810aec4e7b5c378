//! Ray queries shared by the model kinds: rays against triangles (Moller-Trumbore) and
//! against points and segments within a tolerance.

use vclay_core::{TriMesh, Vec3};

use crate::model::{Element, Hit, Ray};

/// The nearest triangle of `mesh` that `ray` crosses: `(distance along the ray, triangle,
/// barycentric weights of its three corners)`. Both sides of a triangle count.
pub fn ray_mesh(ray: &Ray, mesh: &TriMesh) -> Option<(f64, usize, [f64; 3])> {
    let mut best: Option<(f64, usize, [f64; 3])> = None;
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|i| mesh.positions[i as usize]);
        if let Some((s, u, v)) = ray_triangle(ray, &a, &b, &c)
            && best.is_none_or(|b| s < b.0)
        {
            best = Some((s, t, [1.0 - u - v, u, v]));
        }
    }
    best
}

/// Moller-Trumbore: `(s, u, v)` with the hit at `origin + s direction = a + u (b - a) +
/// v (c - a)`, `s >= 0`; `None` for a miss or a ray parallel to the triangle.
pub fn ray_triangle(ray: &Ray, a: &Vec3, b: &Vec3, c: &Vec3) -> Option<(f64, f64, f64)> {
    let e1 = b - a;
    let e2 = c - a;
    let p = ray.direction.cross(&e2);
    let det = e1.dot(&p);
    let scale = e1.norm() * e2.norm() * ray.direction.norm();
    if det.abs() <= 1e-14 * scale || scale == 0.0 {
        return None;
    }
    let inv = 1.0 / det;
    let t = ray.origin - a;
    let u = t.dot(&p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = t.cross(&e1);
    let v = ray.direction.dot(&q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let s = e2.dot(&q) * inv;
    (s >= 0.0).then_some((s, u, v))
}

/// Distance from `x` to the ray and the ray parameter of the closest point (`s >= 0`).
pub fn ray_point(ray: &Ray, x: &Vec3) -> (f64, f64) {
    let d2 = ray.direction.norm_squared();
    if d2 == 0.0 {
        return ((x - ray.origin).norm(), 0.0);
    }
    let s = ((x - ray.origin).dot(&ray.direction) / d2).max(0.0);
    ((ray.origin + ray.direction * s - x).norm(), s)
}

/// The point of `points` nearest the ray within `tolerance` (nearest to the eye among those
/// within the tolerance): `(index, distance along the ray)`.
pub fn ray_points(ray: &Ray, points: &[Vec3], tolerance: f64) -> Option<(usize, f64)> {
    let mut best: Option<(usize, f64, f64)> = None;
    for (i, x) in points.iter().enumerate() {
        let (d, s) = ray_point(ray, x);
        if d <= tolerance && best.is_none_or(|b| s < b.1 || (s == b.1 && d < b.2)) {
            best = Some((i, s, d));
        }
    }
    best.map(|(i, s, _)| (i, s))
}

/// The control point of `points` that [`ray_points`] finds, as a [`Hit`] on
/// [`Element::ControlPoint`].
pub fn control_point(ray: &Ray, points: &[Vec3], tolerance: f64) -> Option<Hit> {
    ray_points(ray, points, tolerance).map(|(i, s)| Hit {
        distance: s,
        point: points[i],
        element: Element::ControlPoint { index: i },
        extra: [None, None],
    })
}

/// Checks a ray: finite, non-zero direction.
pub fn valid_ray(ray: &Ray) -> bool {
    ray.origin
        .iter()
        .chain(ray.direction.iter())
        .all(|c| c.is_finite())
        && ray.direction.norm_squared() > 0.0
}
