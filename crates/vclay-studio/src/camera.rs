//! The viewport's camera: an orbit camera around a target point, in `f64`.
//!
//! The eye sits at `target + distance * d(yaw, pitch)` with
//! `d = (cos pitch cos yaw, cos pitch sin yaw, sin pitch)` (z up, the convention of the
//! kernel's primitives). Orbit changes yaw and pitch, pan moves the target in the view plane,
//! zoom scales the distance. The projection is a perspective one with a vertical field of view
//! [`FOV_Y`]; [`Camera::ray`] inverts it for picking, so a pixel and its ray always agree.
//! Only the GPU upload converts the matrices to `f32`.

use nalgebra::{Matrix4, Point3, Vector3};
use vclay_core::Vec3;
use vclay_session::Ray;

/// Vertical field of view in radians (default 40 degrees).
pub const FOV_Y: f64 = 40.0 * std::f64::consts::PI / 180.0;
/// Pitch limit: just short of the poles, so the up vector stays defined.
pub const MAX_PITCH: f64 = 1.55;
/// Radians of orbit per point of mouse drag.
pub const ORBIT_PER_POINT: f64 = 0.008;

/// Standard views of the toolbar.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// Looking along -y (x right, z up).
    Front,
    /// Looking down -z.
    Top,
    /// Looking along -x.
    Side,
    /// The isometric-like default.
    Iso,
}

/// An orbit camera (see the [module docs](self)).
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Point looked at.
    pub target: Vec3,
    /// Eye distance from the target.
    pub distance: f64,
    /// Angle about z, radians.
    pub yaw: f64,
    /// Elevation, radians, within `[-MAX_PITCH, MAX_PITCH]`.
    pub pitch: f64,
}

impl Default for Camera {
    fn default() -> Self {
        let mut c = Self {
            target: Vec3::zeros(),
            distance: 4.0,
            yaw: 0.0,
            pitch: 0.0,
        };
        c.set_view(View::Iso);
        c
    }
}

impl Camera {
    /// Unit vector from the target to the eye.
    pub fn back(&self) -> Vec3 {
        Vec3::new(
            self.pitch.cos() * self.yaw.cos(),
            self.pitch.cos() * self.yaw.sin(),
            self.pitch.sin(),
        )
    }

    /// The eye position.
    pub fn eye(&self) -> Vec3 {
        self.target + self.back() * self.distance
    }

    /// Unit right and up vectors of the view plane.
    pub fn right_up(&self) -> (Vec3, Vec3) {
        let back = self.back();
        let right = Vec3::z().cross(&back);
        let right = if right.norm() < 1e-12 {
            Vec3::x()
        } else {
            right.normalize()
        };
        let up = back.cross(&right).normalize();
        (right, up)
    }

    /// Sets one of the standard views (keeps target and distance).
    pub fn set_view(&mut self, view: View) {
        use std::f64::consts::FRAC_PI_2;
        let (yaw, pitch) = match view {
            View::Front => (-FRAC_PI_2, 0.0),
            View::Top => (-FRAC_PI_2, MAX_PITCH),
            View::Side => (0.0, 0.0),
            View::Iso => (-1.0, 0.5),
        };
        self.yaw = yaw;
        self.pitch = pitch;
    }

    /// Orbits by a mouse drag of `(dx, dy)` points.
    pub fn orbit(&mut self, dx: f64, dy: f64) {
        self.yaw -= dx * ORBIT_PER_POINT;
        self.pitch = (self.pitch + dy * ORBIT_PER_POINT).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Pans by a mouse drag of `(dx, dy)` points in a viewport `height` points tall: the
    /// target moves so that the point under the mouse follows it (at the target's depth).
    pub fn pan(&mut self, dx: f64, dy: f64, height: f64) {
        let per_point = 2.0 * self.distance * (FOV_Y / 2.0).tan() / height.max(1.0);
        let (r, u) = self.right_up();
        self.target += (-r * dx + u * dy) * per_point;
    }

    /// Zooms by `steps` wheel steps (positive: closer).
    pub fn zoom(&mut self, steps: f64) {
        self.distance = (self.distance * (-0.1 * steps).exp()).clamp(1e-6, 1e9);
    }

    /// Frames the box `[min, max]` so all of it is in view.
    pub fn fit(&mut self, min: Vec3, max: Vec3) {
        if !(min.iter().chain(max.iter()).all(|c| c.is_finite())
            && (0..3).all(|i| max[i] >= min[i]))
        {
            return;
        }
        self.target = (min + max) * 0.5;
        let radius = ((max - min).norm() * 0.5).max(1e-6);
        self.distance = radius / (FOV_Y / 2.0).sin() * 1.05;
    }

    /// Near and far clip distances that enclose a model of size `size` around the target.
    fn clip(&self, size: f64) -> (f64, f64) {
        let far = self.distance + size.max(self.distance) * 4.0;
        let near = (far * 1e-4).max(self.distance - size * 4.0).max(1e-6);
        (near, far)
    }

    /// View matrix (world to eye).
    pub fn view_matrix(&self) -> Matrix4<f64> {
        let (_, up) = self.right_up();
        let e = self.eye();
        let t = self.target;
        Matrix4::look_at_rh(
            &Point3::new(e.x, e.y, e.z),
            &Point3::new(t.x, t.y, t.z),
            &Vector3::new(up.x, up.y, up.z),
        )
    }

    /// Projection matrix for a viewport of `aspect` = width / height, for a model of `size`.
    pub fn projection_matrix(&self, aspect: f64, size: f64) -> Matrix4<f64> {
        let (near, far) = self.clip(size);
        Matrix4::new_perspective(aspect.max(1e-6), FOV_Y, near, far)
    }

    /// The ray through the viewport point `(x, y)` (points from the top left) of a viewport
    /// `width` x `height` points.
    pub fn ray(&self, x: f64, y: f64, width: f64, height: f64) -> Ray {
        let (w, h) = (width.max(1.0), height.max(1.0));
        let ndc_x = 2.0 * x / w - 1.0;
        let ndc_y = 1.0 - 2.0 * y / h;
        let t = (FOV_Y / 2.0).tan();
        let (r, u) = self.right_up();
        let dir = -self.back() + r * (ndc_x * t * w / h) + u * (ndc_y * t);
        Ray {
            origin: self.eye(),
            direction: dir.normalize(),
        }
    }

    /// Projects a world point to viewport points `(x, y)` (the inverse of [`Camera::ray`]);
    /// `None` behind the eye.
    pub fn project(&self, p: Vec3, width: f64, height: f64) -> Option<(f64, f64)> {
        let (w, h) = (width.max(1.0), height.max(1.0));
        let d = p - self.eye();
        let depth = d.dot(&-self.back());
        if depth <= 1e-12 {
            return None;
        }
        let t = (FOV_Y / 2.0).tan();
        let (r, u) = self.right_up();
        let ndc_x = d.dot(&r) / depth / (t * w / h);
        let ndc_y = d.dot(&u) / depth / t;
        Some(((ndc_x + 1.0) * w / 2.0, (1.0 - ndc_y) * h / 2.0))
    }

    /// The point where `ray` meets the plane through `anchor` facing the viewer (the paper's
    /// 3D cursor driven by a 2D mouse); `anchor` itself if the ray is parallel to the plane.
    pub fn on_view_plane(&self, ray: &Ray, anchor: Vec3) -> Vec3 {
        let n = self.back();
        let denom = ray.direction.dot(&n);
        if denom.abs() < 1e-12 {
            return anchor;
        }
        let s = (anchor - ray.origin).dot(&n) / denom;
        ray.origin + ray.direction * s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ray_and_project_agree() {
        let mut c = Camera::default();
        c.fit(Vec3::zeros(), Vec3::new(1.0, 1.0, 1.0));
        let p = Vec3::new(0.8, 0.3, 0.6);
        let (x, y) = c.project(p, 800.0, 600.0).unwrap();
        let ray = c.ray(x, y, 800.0, 600.0);
        let to_p = (p - ray.origin).normalize();
        assert!((to_p - ray.direction).norm() < 1e-9);
        // The view plane through p returns p for its own ray.
        assert!((c.on_view_plane(&ray, p) - p).norm() < 1e-9);
    }

    #[test]
    fn matrices_match_projection() {
        let mut c = Camera::default();
        c.fit(Vec3::zeros(), Vec3::new(2.0, 1.0, 1.0));
        let p = Vec3::new(1.5, 0.2, 0.9);
        let m = c.projection_matrix(800.0 / 600.0, 2.5) * c.view_matrix();
        let q = m * nalgebra::Vector4::new(p.x, p.y, p.z, 1.0);
        let (x, y) = c.project(p, 800.0, 600.0).unwrap();
        assert!(((q.x / q.w + 1.0) * 400.0 - x).abs() < 1e-6);
        assert!(((1.0 - q.y / q.w) * 300.0 - y).abs() < 1e-6);
    }

    #[test]
    fn fit_ignores_bad_boxes() {
        let mut c = Camera::default();
        let before = c.clone();
        c.fit(Vec3::new(f64::NAN, 0.0, 0.0), Vec3::zeros());
        assert_eq!(c, before);
    }
}
