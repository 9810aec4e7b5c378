//! The software rasterizer: a supersampled z-buffer.
//!
//! **How.** The picture is drawn at `supersample` times the output resolution in each direction
//! into a colour buffer and a depth buffer, then box-filtered down (anti-aliasing). Triangles are
//! rasterized with edge functions at sample centres; depth is interpolated linearly in screen
//! space (it is affine there, see [`crate::camera`]); normals are interpolated perspective-correctly
//! (barycentric weights divided by view distance) and shaded per sample with Blinn-Phong and two
//! directional lights fixed to the camera (a key light from the upper left and a weaker fill
//! light from the right) plus ambient. Shading is two-sided: a normal facing away from the eye is
//! flipped, so open surfaces look right from both sides. Polylines and markers are drawn after the
//! triangles with a small depth bias ([`LINE_DEPTH_BIAS`]), so a control net lying on a surface
//! stays visible while one behind it is hidden.
//!
//! **Limitations.** Triangles, segments and markers with a vertex closer than the near plane are
//! skipped rather than clipped (framed cameras never produce them). No shadows, no transparency.

use crate::camera::{Camera, Projected, Projection, View};
use crate::error::RenderError;
use crate::image::Image;
use crate::scene::{Rgb, Scene, bounding_sphere};
use rayon::prelude::*;
use vclay_core::{Parallelism, Vec3};

/// Largest image side accepted (8192 pixels).
pub const MAX_IMAGE_SIDE: u32 = 8192;
/// Default supersampling factor per axis (3: nine samples per pixel).
pub const DEFAULT_SUPERSAMPLE: u32 = 3;
/// Default background: a light grey.
pub const BACKGROUND: Rgb = [245, 245, 242];
/// Depth bias of lines and markers, as a fraction of the near-far depth range (0.002).
pub const LINE_DEPTH_BIAS: f64 = 2e-3;

/// A directional light fixed to the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Direction towards the light in the camera frame: x right, y up, z towards the viewer.
    pub direction: Vec3,
    /// Diffuse intensity (the base colour is multiplied by it).
    pub intensity: f64,
}

/// How to draw a [`Scene`].
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Output width in pixels (default 640).
    pub width: u32,
    /// Output height in pixels (default 480).
    pub height: u32,
    /// Viewing direction used when `camera` is `None` (default [`View::Iso`]).
    pub view: View,
    /// Orthographic instead of perspective framing when `camera` is `None` (default false).
    pub orthographic: bool,
    /// A given camera; `None` frames the scene along `view` (default `None`).
    pub camera: Option<Camera>,
    /// Samples per pixel along each axis (default [`DEFAULT_SUPERSAMPLE`]; 1 disables
    /// anti-aliasing).
    pub supersample: u32,
    /// Background colour (default [`BACKGROUND`]).
    pub background: Rgb,
    /// Ambient light level (default 0.22).
    pub ambient: f64,
    /// Key and fill lights (default: key 0.75 from upper left front, fill 0.35 from the right).
    pub lights: [Light; 2],
    /// Strength of the white specular highlight (default 0.25).
    pub specular: f64,
    /// Threads for animations (frames render in parallel); a single picture uses one thread
    /// (default [`Parallelism::Auto`], measured in output pixels of all frames).
    pub parallelism: Parallelism,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            width: 640,
            height: 480,
            view: View::Iso,
            orthographic: false,
            camera: None,
            supersample: DEFAULT_SUPERSAMPLE,
            background: BACKGROUND,
            ambient: 0.22,
            lights: [
                Light {
                    direction: Vec3::new(-0.5, 0.6, 0.75),
                    intensity: 0.75,
                },
                Light {
                    direction: Vec3::new(0.8, -0.1, 0.4),
                    intensity: 0.35,
                },
            ],
            specular: 0.25,
            parallelism: Parallelism::Auto,
        }
    }
}

impl RenderOptions {
    /// Default options with a given size.
    pub fn sized(width: u32, height: u32) -> Self {
        RenderOptions {
            width,
            height,
            ..Default::default()
        }
    }

    fn check_size(&self) -> Result<(), RenderError> {
        let ok = |s: u32| (1..=MAX_IMAGE_SIDE).contains(&s);
        if !ok(self.width) || !ok(self.height) {
            return Err(RenderError::Size {
                width: self.width,
                height: self.height,
                max: MAX_IMAGE_SIDE,
            });
        }
        Ok(())
    }

    /// The camera these options use for `scenes` (one camera for all): the given camera, or one
    /// that frames the scenes' bounding sphere along `view` and is then tightened around their
    /// projected points ([`Camera::fit_to_points`]).
    pub fn camera_for_scenes(&self, scenes: &[Scene]) -> Result<Camera, RenderError> {
        if let Some(c) = self.camera {
            c.validate()?;
            return Ok(c);
        }
        let (c, r) = bounding_sphere(scenes).ok_or(RenderError::EmptyScene)?;
        let cam = self.camera_for(c, r)?;
        let points = scenes.iter().flat_map(|s| s.all_points());
        let cam = cam.fit_to_points(points, r, self.width, self.height);
        cam.validate()?;
        Ok(cam)
    }

    /// The camera these options use for scenes whose bounding sphere is `(centre, radius)`
    /// (sphere framing only: the same for every direction, as a turntable needs).
    pub fn camera_for(&self, centre: Vec3, radius: f64) -> Result<Camera, RenderError> {
        if let Some(c) = self.camera {
            c.validate()?;
            return Ok(c);
        }
        let projection = if self.orthographic {
            Projection::Orthographic { half_height: 1.0 }
        } else {
            Projection::Perspective {
                fov_y: crate::camera::DEFAULT_FOV_Y_DEG.to_radians(),
            }
        };
        Camera::frame(
            self.view,
            projection,
            centre,
            radius,
            self.width,
            self.height,
        )
    }
}

/// Renders one scene, framed by `opts` (its camera, or its view around the scene's bounds).
pub fn render(scene: &Scene, opts: &RenderOptions) -> Result<Image, RenderError> {
    opts.check_size()?;
    scene.validate()?;
    let camera = opts.camera_for_scenes(std::slice::from_ref(scene))?;
    render_with_camera(scene, &camera, opts)
}

/// Renders several scenes (the frames of an animation) with one camera that frames them all.
pub fn render_frames(frames: &[Scene], opts: &RenderOptions) -> Result<Vec<Image>, RenderError> {
    opts.check_size()?;
    if frames.is_empty() {
        return Err(RenderError::Animation("no frames".into()));
    }
    for s in frames {
        s.validate()?;
    }
    let camera = opts.camera_for_scenes(frames)?;
    let pixels = frames.len() * opts.width as usize * opts.height as usize;
    if opts.parallelism.is_parallel(pixels) && frames.len() > 1 {
        frames
            .par_iter()
            .map(|s| render_with_camera(s, &camera, opts))
            .collect()
    } else {
        frames
            .iter()
            .map(|s| render_with_camera(s, &camera, opts))
            .collect()
    }
}

/// Renders a scenario's frames with one camera and writes them: an animated GIF for a `.gif`
/// path (`delay_ms` per frame), numbered PNGs `stem_0000.png`, ... beside a `.png` path. Returns
/// the files written.
pub fn write_animation(
    path: impl AsRef<std::path::Path>,
    frames: &[Scene],
    opts: &RenderOptions,
    delay_ms: u32,
) -> Result<Vec<std::path::PathBuf>, RenderError> {
    let path = path.as_ref();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let images = render_frames(frames, opts)?;
    match ext.as_deref() {
        Some("gif") => {
            crate::image::write_gif(path, &images, delay_ms)?;
            Ok(vec![path.to_path_buf()])
        }
        Some("png") => {
            let dir = path.parent().unwrap_or(std::path::Path::new(""));
            let stem = path
                .file_stem()
                .map_or("frame".into(), |s| s.to_string_lossy().into_owned());
            crate::image::write_png_sequence(dir, &stem, &images)
        }
        _ => Err(RenderError::Animation(format!(
            "{}: expected a .gif or .png path",
            path.display()
        ))),
    }
}

/// A turntable: `frames` pictures of the scene seen from directions turning once around the
/// vertical (z) axis, starting at `opts.view`, with the same distance and framing.
pub fn turntable(
    scene: &Scene,
    frames: usize,
    opts: &RenderOptions,
) -> Result<Vec<Image>, RenderError> {
    opts.check_size()?;
    scene.validate()?;
    if frames == 0 {
        return Err(RenderError::Animation(
            "a turntable needs at least one frame".into(),
        ));
    }
    let (centre, radius) = scene.bounding_sphere().ok_or(RenderError::EmptyScene)?;
    let (from, up) = opts.view.direction();
    let one = |k: usize| {
        let a = std::f64::consts::TAU * k as f64 / frames as f64;
        let (s, c) = a.sin_cos();
        let from = Vec3::new(c * from.x - s * from.y, s * from.x + c * from.y, from.z);
        let o = RenderOptions {
            view: View::Direction { from, up },
            camera: None,
            ..opts.clone()
        };
        let cam = o.camera_for(centre, radius)?;
        render_with_camera(scene, &cam, &o)
    };
    let pixels = frames * opts.width as usize * opts.height as usize;
    if opts.parallelism.is_parallel(pixels) && frames > 1 {
        (0..frames).into_par_iter().map(one).collect()
    } else {
        (0..frames).map(one).collect()
    }
}

/// The supersampled frame being drawn.
struct Canvas {
    w: usize,
    h: usize,
    color: Vec<[f32; 3]>,
    depth: Vec<f32>,
}

impl Canvas {
    /// Writes `color` at sample `(x, y)` if `depth` passes the z-test.
    #[inline]
    fn plot(&mut self, x: usize, y: usize, depth: f64, color: [f32; 3]) {
        let i = y * self.w + x;
        let d = depth as f32;
        if d < self.depth[i] {
            self.depth[i] = d;
            self.color[i] = color;
        }
    }
}

fn to_f32(c: Rgb) -> [f32; 3] {
    c.map(|v| v as f32 / 255.0)
}

/// Renders with a validated camera (the scene is validated by the callers).
fn render_with_camera(
    scene: &Scene,
    camera: &Camera,
    opts: &RenderOptions,
) -> Result<Image, RenderError> {
    camera.validate()?;
    let ss = opts.supersample.clamp(1, 8) as usize;
    let (w, h) = (opts.width as usize * ss, opts.height as usize * ss);
    let proj = camera.projector(w as f64, h as f64);
    let mut cv = Canvas {
        w,
        h,
        color: vec![to_f32(opts.background); w * h],
        depth: vec![f32::INFINITY; w * h],
    };
    let (right, up, forward) = proj.frame();
    let lights: Vec<(Vec3, f64)> = opts
        .lights
        .iter()
        .filter(|l| l.direction.norm() > 0.0)
        .map(|l| {
            let d = l.direction.normalize();
            (
                (right * d.x + up * d.y - forward * d.z).normalize(),
                l.intensity,
            )
        })
        .collect();
    for m in &scene.meshes {
        let mesh = &m.mesh;
        let base = to_f32(m.color);
        let projected: Vec<Option<Projected>> =
            mesh.positions.iter().map(|p| proj.project(p)).collect();
        for tri in &mesh.triangles {
            let [a, b, c] = tri.map(|i| i as usize);
            let (Some(pa), Some(pb), Some(pc)) = (projected[a], projected[b], projected[c]) else {
                continue;
            };
            let face = (mesh.positions[b] - mesh.positions[a])
                .cross(&(mesh.positions[c] - mesh.positions[a]));
            let face = if face.norm() > 0.0 {
                face.normalize()
            } else {
                continue;
            };
            let normals = if mesh.normals.len() == mesh.positions.len() {
                [a, b, c].map(|i| {
                    let n = mesh.normals[i];
                    if n.norm() > 0.0 { n } else { face }
                })
            } else {
                [face; 3]
            };
            let centroid = (mesh.positions[a] + mesh.positions[b] + mesh.positions[c]) / 3.0;
            let to_eye = proj.eye_direction(&centroid);
            let shade = |n: Vec3| -> [f32; 3] {
                let n = if n.dot(&to_eye) < 0.0 { -n } else { n };
                let mut diffuse = opts.ambient;
                let mut spec = 0.0;
                for &(l, i) in &lights {
                    let ndl = n.dot(&l);
                    if ndl > 0.0 {
                        diffuse += i * ndl;
                        let hv = (l + to_eye).normalize();
                        spec += i * n.dot(&hv).max(0.0).powi(40);
                    }
                }
                let s = (opts.specular * spec) as f32;
                let d = diffuse as f32;
                base.map(|c| (c * d + s).min(1.0))
            };
            raster_triangle(&mut cv, [pa, pb, pc], normals, &shade);
            if let Some(ec) = m.edges {
                let ec = to_f32(ec);
                for (p, q) in [(pa, pb), (pb, pc), (pc, pa)] {
                    raster_segment(&mut cv, p, q, 0.8 * ss as f64, ec);
                }
            }
        }
    }
    for l in &scene.lines {
        let col = to_f32(l.color);
        let n = l.points.len();
        let segs = if l.closed && n > 2 {
            n
        } else {
            n.saturating_sub(1)
        };
        let width = (l.width * ss as f64).max(1.0);
        for k in 0..segs {
            let (p, q) = (l.points[k], l.points[(k + 1) % n]);
            if let (Some(pp), Some(pq)) = (proj.project(&p), proj.project(&q)) {
                raster_segment(&mut cv, pp, pq, width, col);
            }
        }
    }
    for m in &scene.markers {
        if let Some(p) = proj.project(&m.position) {
            raster_disc(&mut cv, p, (m.radius * ss as f64).max(1.0), to_f32(m.color));
        }
    }
    Ok(downsample(&cv, ss, opts.width, opts.height))
}

/// Fills a triangle: linear depth, perspective-correct normals shaded per sample.
fn raster_triangle(
    cv: &mut Canvas,
    p: [Projected; 3],
    n: [Vec3; 3],
    shade: &dyn Fn(Vec3) -> [f32; 3],
) {
    let area = (p[1].x - p[0].x) * (p[2].y - p[0].y) - (p[1].y - p[0].y) * (p[2].x - p[0].x);
    if area.abs() < 1e-12 {
        return;
    }
    let min_x = p.iter().map(|q| q.x).fold(f64::INFINITY, f64::min);
    let max_x = p.iter().map(|q| q.x).fold(f64::NEG_INFINITY, f64::max);
    let min_y = p.iter().map(|q| q.y).fold(f64::INFINITY, f64::min);
    let max_y = p.iter().map(|q| q.y).fold(f64::NEG_INFINITY, f64::max);
    let x0 = (min_x - 0.5).ceil().max(0.0) as usize;
    let y0 = (min_y - 0.5).ceil().max(0.0) as usize;
    let x1 = ((max_x - 0.5).floor()).min(cv.w as f64 - 1.0);
    let y1 = ((max_y - 0.5).floor()).min(cv.h as f64 - 1.0);
    if x1 < x0 as f64 || y1 < y0 as f64 {
        return;
    }
    let (x1, y1) = (x1 as usize, y1 as usize);
    let inv = 1.0 / area;
    let edge = |a: &Projected, b: &Projected, x: f64, y: f64| {
        (b.x - a.x) * (y - a.y) - (b.y - a.y) * (x - a.x)
    };
    let iz = [1.0 / p[0].z, 1.0 / p[1].z, 1.0 / p[2].z];
    for y in y0..=y1 {
        let sy = y as f64 + 0.5;
        for x in x0..=x1 {
            let sx = x as f64 + 0.5;
            let b0 = edge(&p[1], &p[2], sx, sy) * inv;
            let b1 = edge(&p[2], &p[0], sx, sy) * inv;
            let b2 = 1.0 - b0 - b1;
            // Inclusive edges with a tiny tolerance: shared edges leave no cracks.
            if b0 < -1e-9 || b1 < -1e-9 || b2 < -1e-9 {
                continue;
            }
            let depth = b0 * p[0].depth + b1 * p[1].depth + b2 * p[2].depth;
            let i = y * cv.w + x;
            if depth as f32 >= cv.depth[i] {
                continue;
            }
            let (w0, w1, w2) = (b0 * iz[0], b1 * iz[1], b2 * iz[2]);
            let nn = (n[0] * w0 + n[1] * w1 + n[2] * w2) / (w0 + w1 + w2);
            let nn = if nn.norm() > 0.0 {
                nn.normalize()
            } else {
                n[0]
            };
            cv.plot(x, y, depth, shade(nn));
        }
    }
}

/// A segment of pixel width `width` (in samples), depth interpolated, with a depth bias.
fn raster_segment(cv: &mut Canvas, a: Projected, b: Projected, width: f64, col: [f32; 3]) {
    let r = 0.5 * width;
    let x0 = (a.x.min(b.x) - r - 0.5).ceil().max(0.0) as usize;
    let y0 = (a.y.min(b.y) - r - 0.5).ceil().max(0.0) as usize;
    let x1 = (a.x.max(b.x) + r - 0.5).floor().min(cv.w as f64 - 1.0);
    let y1 = (a.y.max(b.y) + r - 0.5).floor().min(cv.h as f64 - 1.0);
    if x1 < x0 as f64 || y1 < y0 as f64 {
        return;
    }
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let len2 = dx * dx + dy * dy;
    for y in y0..=y1 as usize {
        let sy = y as f64 + 0.5;
        for x in x0..=x1 as usize {
            let sx = x as f64 + 0.5;
            let t = if len2 > 0.0 {
                (((sx - a.x) * dx + (sy - a.y) * dy) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (qx, qy) = (a.x + t * dx - sx, a.y + t * dy - sy);
            if qx * qx + qy * qy <= r * r {
                let depth = a.depth + t * (b.depth - a.depth) - LINE_DEPTH_BIAS;
                cv.plot(x, y, depth, col);
            }
        }
    }
}

/// A disc of radius `r` samples at a projected point, with the line depth bias.
fn raster_disc(cv: &mut Canvas, p: Projected, r: f64, col: [f32; 3]) {
    let x0 = (p.x - r - 0.5).ceil().max(0.0) as usize;
    let y0 = (p.y - r - 0.5).ceil().max(0.0) as usize;
    let x1 = (p.x + r - 0.5).floor().min(cv.w as f64 - 1.0);
    let y1 = (p.y + r - 0.5).floor().min(cv.h as f64 - 1.0);
    if x1 < x0 as f64 || y1 < y0 as f64 {
        return;
    }
    for y in y0..=y1 as usize {
        for x in x0..=x1 as usize {
            let (qx, qy) = (x as f64 + 0.5 - p.x, y as f64 + 0.5 - p.y);
            if qx * qx + qy * qy <= r * r {
                cv.plot(x, y, p.depth - 2.0 * LINE_DEPTH_BIAS, col);
            }
        }
    }
}

/// Box filter from the supersampled canvas to the output image.
fn downsample(cv: &Canvas, ss: usize, width: u32, height: u32) -> Image {
    let (w, h) = (width as usize, height as usize);
    let mut data = Vec::with_capacity(3 * w * h);
    let norm = 1.0 / (ss * ss) as f32;
    for y in 0..h {
        for x in 0..w {
            let mut acc = [0.0f32; 3];
            for sy in 0..ss {
                let row = (y * ss + sy) * cv.w;
                for sx in 0..ss {
                    let c = cv.color[row + x * ss + sx];
                    for k in 0..3 {
                        acc[k] += c[k];
                    }
                }
            }
            for a in acc {
                data.push((a * norm * 255.0).round().clamp(0.0, 255.0) as u8);
            }
        }
    }
    debug_assert_eq!(cv.h, h * ss);
    Image {
        width,
        height,
        data,
    }
}
