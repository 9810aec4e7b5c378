//! Cameras: named views that frame a bounding sphere, or a camera given by eye, target and up.
//!
//! **What.** A [`Camera`] maps world points to pixel coordinates and a depth in `[0, 1]` (0 at the
//! near plane). Projection is perspective (vertical field of view `fov_y`) or orthographic
//! (`half_height` world units from the centre to the top edge of the picture).
//!
//! **How.** The view frame is right-handed: `forward = (target - eye) / |target - eye|`,
//! `right = forward x up` (normalised), `true_up = right x forward`. A point `p` has view
//! coordinates `x = (p - eye) . right`, `y = (p - eye) . true_up`, `z = (p - eye) . forward`
//! (distance in front of the eye). Perspective pixel coordinates are
//! `px = W/2 + f x / z`, `py = H/2 - f y / z` with `f = (H/2) / tan(fov_y / 2)`; orthographic
//! ones drop the division by `z` and use `f = (H/2) / half_height`. The stored depth is
//! `(1/near - 1/z) / (1/near - 1/far)` for perspective and `(z - near) / (far - near)` for
//! orthographic projection: both are affine in screen space, so the rasterizer can interpolate
//! them linearly.
//!
//! **Framing.** [`Camera::frame`] places the eye along a [`View`] direction so that the bounding
//! sphere `(centre, radius)` fills the picture with a margin ([`FRAME_MARGIN`]), whatever the
//! aspect ratio. vclay models are z-up: `front` looks along +y, `side` along -x, `top` down -z,
//! `iso` from the (+x, -y, +z) octant.

use crate::error::RenderError;
use vclay_core::Vec3;

/// Ratio of the picture's half-size to the bounding sphere's radius used by [`Camera::frame`]
/// (1.1: ten percent of empty border).
pub const FRAME_MARGIN: f64 = 1.1;

/// Default vertical field of view of a perspective camera, in degrees (30).
pub const DEFAULT_FOV_Y_DEG: f64 = 30.0;

/// A named viewing direction (z-up world).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum View {
    /// From the (+x, -y, +z) octant, looking at the centre: the usual isometric-like view.
    Iso,
    /// From -y looking along +y (x to the right, z up).
    Front,
    /// From +z looking down (x to the right, y up).
    Top,
    /// From +x looking along -x (y to the right, z up).
    Side,
    /// From a given direction (the eye lies at `centre + t * from`), with a given up vector.
    Direction {
        /// Direction from the centre towards the eye.
        from: Vec3,
        /// Approximate up direction of the picture.
        up: Vec3,
    },
}

impl View {
    /// Parses `iso`, `front`, `top` or `side` (the names the command line accepts).
    pub fn parse(name: &str) -> Option<View> {
        match name {
            "iso" => Some(View::Iso),
            "front" => Some(View::Front),
            "top" => Some(View::Top),
            "side" => Some(View::Side),
            _ => None,
        }
    }

    /// `(direction from the centre to the eye, up)`.
    pub fn direction(self) -> (Vec3, Vec3) {
        match self {
            View::Iso => (Vec3::new(1.0, -1.4, 0.9), Vec3::z()),
            View::Front => (-Vec3::y(), Vec3::z()),
            View::Top => (Vec3::z(), Vec3::y()),
            View::Side => (Vec3::x(), Vec3::z()),
            View::Direction { from, up } => (from, up),
        }
    }
}

/// The projection of a [`Camera`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Perspective with a vertical field of view in radians.
    Perspective {
        /// Vertical field of view (radians, in (0, pi)).
        fov_y: f64,
    },
    /// Orthographic: world distance from the picture centre to its top edge.
    Orthographic {
        /// Half of the visible height, in world units (> 0).
        half_height: f64,
    },
}

/// A camera: eye, target, up, projection and near/far distances.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: Vec3,
    /// Point looked at (the picture centre).
    pub target: Vec3,
    /// Approximate up direction (must not be parallel to the view direction).
    pub up: Vec3,
    /// Perspective or orthographic.
    pub projection: Projection,
    /// Distance of the near plane in front of the eye (> 0).
    pub near: f64,
    /// Distance of the far plane (> near).
    pub far: f64,
}

/// A camera prepared for one image size: the view frame and the pixel scale.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Projector {
    eye: Vec3,
    right: Vec3,
    up: Vec3,
    forward: Vec3,
    focal: f64,
    cx: f64,
    cy: f64,
    perspective: bool,
    near: f64,
    far: f64,
}

/// A projected point: pixel coordinates, depth in [0, 1], and the view distance.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Projected {
    pub x: f64,
    pub y: f64,
    pub depth: f64,
    /// Distance in front of the eye (for perspective-correct interpolation).
    pub z: f64,
}

impl Camera {
    /// A camera looking at the sphere `(centre, radius)` along `view`, framing it in a
    /// `width x height` picture with [`FRAME_MARGIN`].
    pub fn frame(
        view: View,
        projection: Projection,
        centre: Vec3,
        radius: f64,
        width: u32,
        height: u32,
    ) -> Result<Camera, RenderError> {
        let (from, up) = view.direction();
        if !(radius.is_finite() && centre.iter().all(|c| c.is_finite())) {
            return Err(RenderError::NonFinite {
                what: "bounding sphere".into(),
            });
        }
        let len = from.norm();
        if !(len.is_finite() && len > 0.0) {
            return Err(RenderError::Camera("view direction is zero".into()));
        }
        let dir = from / len;
        // A point object still gets a visible neighbourhood.
        let radius = if radius > 0.0 {
            radius
        } else {
            centre.norm().max(1.0) * 1e-3
        };
        // Fit the sphere in the smaller picture side.
        let aspect = width as f64 / height.max(1) as f64;
        let fit = FRAME_MARGIN * radius * if aspect < 1.0 { 1.0 / aspect } else { 1.0 };
        let (projection, dist) = match projection {
            Projection::Perspective { fov_y } => {
                let d = fit / (0.5 * fov_y).tan() + radius;
                (projection, d.max(2.0 * radius))
            }
            Projection::Orthographic { .. } => {
                (Projection::Orthographic { half_height: fit }, 4.0 * radius)
            }
        };
        let cam = Camera {
            eye: centre + dir * dist,
            target: centre,
            up,
            projection,
            near: (dist - 1.5 * radius).max(dist * 1e-3),
            far: dist + 1.5 * radius,
        };
        cam.validate()?;
        Ok(cam)
    }

    /// Checks that the camera can produce a picture.
    pub fn validate(&self) -> Result<(), RenderError> {
        let finite = |v: &Vec3| v.iter().all(|c| c.is_finite());
        if !(finite(&self.eye) && finite(&self.target) && finite(&self.up)) {
            return Err(RenderError::NonFinite {
                what: "camera eye, target or up".into(),
            });
        }
        let f = self.target - self.eye;
        if f.norm() == 0.0 {
            return Err(RenderError::Camera("eye and target coincide".into()));
        }
        if f.normalize().cross(&self.up).norm() < 1e-9 * self.up.norm().max(f64::MIN_POSITIVE) {
            return Err(RenderError::Camera(
                "up vector is zero or parallel to the view direction".into(),
            ));
        }
        if !(self.near > 0.0 && self.far > self.near && self.far.is_finite()) {
            return Err(RenderError::Camera(format!(
                "need 0 < near < far, got near {} and far {}",
                self.near, self.far
            )));
        }
        match self.projection {
            Projection::Perspective { fov_y } if !(fov_y > 0.0 && fov_y < std::f64::consts::PI) => {
                Err(RenderError::Camera(format!(
                    "field of view {fov_y} rad is outside (0, pi)"
                )))
            }
            Projection::Orthographic { half_height }
                if half_height.is_nan() || half_height <= 0.0 =>
            {
                Err(RenderError::Camera(format!(
                    "orthographic half height {half_height} is not > 0"
                )))
            }
            _ => Ok(()),
        }
    }

    /// Prepares the projection onto a `width x height` picture (camera already validated).
    pub(crate) fn projector(&self, width: f64, height: f64) -> Projector {
        let forward = (self.target - self.eye).normalize();
        let right = forward.cross(&self.up).normalize();
        let up = right.cross(&forward);
        let (focal, perspective) = match self.projection {
            Projection::Perspective { fov_y } => (0.5 * height / (0.5 * fov_y).tan(), true),
            Projection::Orthographic { half_height } => (0.5 * height / half_height, false),
        };
        Projector {
            eye: self.eye,
            right,
            up,
            forward,
            focal,
            cx: 0.5 * width,
            cy: 0.5 * height,
            perspective,
            near: self.near,
            far: self.far,
        }
    }
}

impl Camera {
    /// Tightens a framing camera around `points`: moves the view sideways so that their projected
    /// bounding box is centred, and moves the eye along the view direction (perspective) or
    /// scales the visible height (orthographic) so that the box fills the picture with
    /// [`FRAME_MARGIN`]. `radius` (of a bounding sphere of the points) keeps the eye outside the
    /// object and sets near and far. Two passes (perspective sizes depend on the distance).
    pub fn fit_to_points<'a>(
        mut self,
        points: impl Iterator<Item = &'a Vec3> + Clone,
        radius: f64,
        width: u32,
        height: u32,
    ) -> Camera {
        let (w, h) = (width as f64, height as f64);
        for _ in 0..2 {
            let proj = self.projector(w, h);
            let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for p in points.clone() {
                if let Some(q) = proj.project(p) {
                    lo = [lo[0].min(q.x), lo[1].min(q.y)];
                    hi = [hi[0].max(q.x), hi[1].max(q.y)];
                }
            }
            let ext = [hi[0] - lo[0], hi[1] - lo[1]];
            let fill = (ext[0] / w).max(ext[1] / h) * FRAME_MARGIN;
            if !(fill.is_finite() && fill > 1e-9) {
                return self;
            }
            let dist = (self.target - self.eye).norm();
            // World size of one pixel at the target's depth.
            let pixel = dist / proj.focal_length().max(f64::MIN_POSITIVE);
            let pixel = if matches!(self.projection, Projection::Orthographic { .. }) {
                1.0 / proj.focal_length()
            } else {
                pixel
            };
            let (right, up, forward) = proj.frame();
            let shift = right * ((0.5 * (lo[0] + hi[0]) - 0.5 * w) * pixel)
                - up * ((0.5 * (lo[1] + hi[1]) - 0.5 * h) * pixel);
            self.target += shift;
            self.eye += shift;
            match &mut self.projection {
                Projection::Orthographic { half_height } => *half_height *= fill,
                Projection::Perspective { .. } => {
                    let d = (dist * fill).max(1.5 * radius);
                    self.eye = self.target - forward * d;
                }
            }
            let d = (self.target - self.eye).norm();
            self.near = (d - 1.5 * radius).max(d * 1e-3);
            self.far = d + 1.5 * radius;
        }
        self
    }
}

impl Projector {
    /// Pixels per unit of `x / z` (perspective) or per world unit (orthographic).
    pub(crate) fn focal_length(&self) -> f64 {
        self.focal
    }

    /// Pixel coordinates and depth of `p`; `None` when `p` is in front of the near plane.
    pub(crate) fn project(&self, p: &Vec3) -> Option<Projected> {
        let d = p - self.eye;
        let (x, y, z) = (d.dot(&self.right), d.dot(&self.up), d.dot(&self.forward));
        if z < self.near * 0.999 {
            return None;
        }
        let (s, depth) = if self.perspective {
            (
                self.focal / z,
                (1.0 / self.near - 1.0 / z) / (1.0 / self.near - 1.0 / self.far),
            )
        } else {
            (self.focal, (z - self.near) / (self.far - self.near))
        };
        Some(Projected {
            x: self.cx + s * x,
            y: self.cy - s * y,
            depth,
            z: if self.perspective { z } else { 1.0 },
        })
    }

    /// World direction from a surface point towards the eye (for two-sided shading).
    pub(crate) fn eye_direction(&self, p: &Vec3) -> Vec3 {
        if self.perspective {
            (self.eye - p).normalize()
        } else {
            -self.forward
        }
    }

    /// The view frame `(right, up, forward)`.
    pub(crate) fn frame(&self) -> (Vec3, Vec3, Vec3) {
        (self.right, self.up, self.forward)
    }
}
