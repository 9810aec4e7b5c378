//! The 3D viewport's drawing: what the renderer is handed ([`SceneBuffers`], built on the CPU
//! from a [`Frame`]) and the OpenGL code that draws it inside egui ([`GlScene`], run from an
//! `egui::PaintCallback` with eframe's glow context).
//!
//! One vertex format for everything: position, normal, colour (9 `f32`). Triangles are lit by
//! three lights that move with the camera (a studio's three-point lighting: a key light above
//! and left of the eye, a fill from the right, a rim light from behind) over a sky/ground
//! ambient along world z, two-sided (the inside of a deleted cell is visible), with a key-light
//! highlight and a little Fresnel edge: faces at different angles read differently from every
//! view, where a headlight washed out the faces turned towards the viewer. Lines and markers
//! take their colour per role ([`role_color`]). A ground grid ([`Grid`]) lies under the model. Geometry stays `f64`
//! in the session; the conversion to `f32` happens here, once per revision, and the GPU buffers
//! are re-uploaded only when the revision changes.
//!
//! OpenGL calls are `unsafe` in glow; this module is the crate's only unsafe code, each call
//! made with the context eframe hands the paint callback, on the thread that owns it.

use std::sync::Arc;

use vclay_core::Vec3;
use vclay_session::{LineRole, LineSet};

use crate::worker::Frame;

/// Floats per vertex: position, normal, colour.
pub const STRIDE: usize = 9;
/// Colour of shaded surfaces (clay).
pub const CLAY: [f32; 3] = [0.80, 0.62, 0.48];
/// Marker size in pixels.
pub const MARKER_PX: f32 = 6.0;

/// Colour of a set of lines by role.
pub fn role_color(role: Option<LineRole>) -> [f32; 3] {
    match role {
        Some(LineRole::ControlNet) => [1.0, 0.6, 0.1],
        Some(LineRole::LatticeEdges) => [0.55, 0.6, 0.7],
        Some(LineRole::DataPoints) => [0.5, 0.8, 1.0],
        Some(LineRole::Ropes) => [1.0, 0.15, 0.15],
        Some(LineRole::Forces) => [0.9, 0.2, 0.9],
        Some(LineRole::Fixed) => [0.1, 0.3, 1.0],
        Some(LineRole::Constraints) => [0.1, 0.9, 0.3],
        Some(LineRole::Curve) => [0.95, 0.95, 0.95],
        None => [1.0, 1.0, 1.0],
    }
}

/// Which line roles to draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layers {
    /// Shaded triangles.
    pub shaded: bool,
    /// Triangle edges.
    pub wireframe: bool,
    /// Control net / lattice.
    pub control_net: bool,
    /// Data points.
    pub data_points: bool,
    /// The ground grid.
    pub grid: bool,
}

impl Default for Layers {
    fn default() -> Self {
        Self {
            shaded: true,
            wireframe: false,
            control_net: false,
            data_points: false,
            grid: true,
        }
    }
}

impl Layers {
    /// Whether lines of `role` are drawn.
    pub fn shows(&self, role: Option<LineRole>) -> bool {
        match role {
            Some(LineRole::ControlNet) | Some(LineRole::LatticeEdges) => self.control_net,
            Some(LineRole::DataPoints) => self.data_points,
            _ => true,
        }
    }
}

/// What the renderer is handed for one revision: interleaved `f32` vertices and `u32`
/// indices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneBuffers {
    /// Session revision, layer set, and grid and colour field (hashed together) these were
    /// built for.
    pub key: (u64, u8, u64),
    /// Triangle vertices.
    pub tri_vertices: Vec<f32>,
    /// Triangle indices.
    pub tri_indices: Vec<u32>,
    /// Triangle edges (wireframe), indices into `tri_vertices`.
    pub wire_indices: Vec<u32>,
    /// Line vertices (pairs).
    pub line_vertices: Vec<f32>,
    /// Marker vertices.
    pub point_vertices: Vec<f32>,
    /// Bounding box of everything (f64), `None` when empty.
    pub bounds: Option<(Vec3, Vec3)>,
}

/// Colour of `t` in `[0, 1]` on Moreland's cool-to-warm diverging map (blue, light grey at
/// the middle, red): low values of a painted field cool, high values warm.
pub fn colour_map(t: f32) -> [f32; 3] {
    const COOL: [f32; 3] = [0.23, 0.30, 0.75];
    const MID: [f32; 3] = [0.87, 0.87, 0.87];
    const WARM: [f32; 3] = [0.71, 0.02, 0.15];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.5
    };
    let (a, b, u) = if t < 0.5 {
        (COOL, MID, 2.0 * t)
    } else {
        (MID, WARM, 2.0 * t - 1.0)
    };
    [0, 1, 2].map(|k| a[k] + (b[k] - a[k]) * u)
}

/// How a field's values map onto [`colour_map`]: linearly between `lo` and `hi`, or by their
/// logarithm when the values are positive and span a factor of 4 or more (stiffnesses and
/// densities are painted in orders of magnitude: 50 next to 100 next to 3000 must read apart).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldScale {
    /// Smallest finite value.
    pub lo: f64,
    /// Largest finite value.
    pub hi: f64,
    /// Logarithmic.
    pub log: bool,
}

impl FieldScale {
    /// Where `x` lies on the map, in `[0, 1]`.
    pub fn t(&self, x: f64) -> f32 {
        let t = if self.log {
            (x.max(self.lo) / self.lo).ln() / (self.hi / self.lo).ln()
        } else {
            (x - self.lo) / (self.hi - self.lo)
        };
        t as f32
    }
}

/// The scale of a field's finite values, `None` when it is (nearly) uniform: a field with
/// nothing painted keeps the clay colour. Nearly: a spread below 1e-9 of its magnitude.
pub fn field_range(f: &[f64]) -> Option<FieldScale> {
    let (lo, hi) = f
        .iter()
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
            (lo.min(x), hi.max(x))
        });
    (hi - lo > 1e-9 * hi.abs().max(lo.abs())).then_some(FieldScale {
        lo,
        hi,
        log: lo > 0.0 && hi >= 4.0 * lo,
    })
}

/// A hash of a field's values (the GPU upload's key changes with the colours).
fn field_hash(f: &[f64]) -> u64 {
    f.iter().fold(0xcbf2_9ce4_8422_2325_u64, |h, x| {
        (h ^ x.to_bits()).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

fn push(v: &mut Vec<f32>, p: &Vec3, n: &Vec3, c: [f32; 3]) {
    v.extend_from_slice(&[
        p.x as f32, p.y as f32, p.z as f32, n.x as f32, n.y as f32, n.z as f32, c[0], c[1], c[2],
    ]);
}

impl SceneBuffers {
    /// Converts a frame's meshes and lines (the layers `layers` shows).
    pub fn build(frame: &Frame, layers: &Layers) -> Self {
        let bits = layers.control_net as u8 | (layers.data_points as u8) << 1;
        let mut b = SceneBuffers {
            key: (frame.revision, bits, 0),
            ..Default::default()
        };
        let mut lo = Vec3::repeat(f64::INFINITY);
        let mut hi = Vec3::repeat(f64::NEG_INFINITY);
        let mut grow = |p: &Vec3| {
            if p.iter().all(|c| c.is_finite()) {
                lo = lo.inf(p);
                hi = hi.sup(p);
            }
        };
        for m in &frame.models {
            let mesh = &m.mesh;
            let base = (b.tri_vertices.len() / STRIDE) as u32;
            b.tri_vertices.reserve(mesh.positions.len() * STRIDE);
            let zero = Vec3::zeros();
            let colours = m
                .field
                .as_deref()
                .filter(|f| f.len() == mesh.positions.len())
                .and_then(|f| field_range(f).map(|r| (f, r)));
            if let Some((f, _)) = colours {
                b.key.2 ^= field_hash(f);
            }
            for (i, p) in mesh.positions.iter().enumerate() {
                grow(p);
                let c = match colours {
                    Some((f, scale)) => colour_map(scale.t(f[i])),
                    None => CLAY,
                };
                push(
                    &mut b.tri_vertices,
                    p,
                    mesh.normals.get(i).unwrap_or(&zero),
                    c,
                );
            }
            let nv = mesh.positions.len() as u32;
            b.tri_indices.reserve(mesh.triangles.len() * 3);
            b.wire_indices.reserve(mesh.triangles.len() * 6);
            for t in &mesh.triangles {
                if t.iter().any(|&i| i >= nv) {
                    continue;
                }
                b.tri_indices
                    .extend_from_slice(&[base + t[0], base + t[1], base + t[2]]);
                b.wire_indices.extend_from_slice(&[
                    base + t[0],
                    base + t[1],
                    base + t[1],
                    base + t[2],
                    base + t[2],
                    base + t[0],
                ]);
            }
            for set in m.lines.iter() {
                Self::add_lines(&mut b, set, layers, &mut grow);
            }
        }
        if lo.x.is_finite() {
            b.bounds = Some((lo, hi));
        }
        b
    }

    fn add_lines(b: &mut Self, set: &LineSet, layers: &Layers, grow: &mut impl FnMut(&Vec3)) {
        if !layers.shows(set.role) {
            return;
        }
        let c = role_color(set.role);
        let z = Vec3::zeros();
        if set.segments.is_empty() {
            for p in &set.points {
                grow(p);
                push(&mut b.point_vertices, p, &z, c);
            }
        } else {
            for s in &set.segments {
                let (Some(p), Some(q)) =
                    (set.points.get(s[0] as usize), set.points.get(s[1] as usize))
                else {
                    continue;
                };
                grow(p);
                grow(q);
                push(&mut b.line_vertices, p, &z, c);
                push(&mut b.line_vertices, q, &z, c);
            }
        }
    }

    /// Bytes handed to the GPU.
    pub fn bytes(&self) -> usize {
        4 * (self.tri_vertices.len()
            + self.tri_indices.len()
            + self.wire_indices.len()
            + self.line_vertices.len()
            + self.point_vertices.len())
    }
}

/// Colour of the ground grid's lines.
pub const GRID_COLOR: [f32; 3] = [0.30, 0.32, 0.37];
/// Colour of the grid's two centre lines.
pub const GRID_CENTRE_COLOR: [f32; 3] = [0.42, 0.44, 0.50];

/// A ground grid: a square of lines `2 * half * spacing` wide around `centre`, in the plane
/// `z = z`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    /// Centre (x, y), a multiple of `spacing`.
    pub centre: [f64; 2],
    /// Height.
    pub z: f64,
    /// Line spacing: 1, 2 or 5 times a power of ten.
    pub spacing: f64,
    /// Lines on each side of the centre.
    pub half: u32,
}

impl Grid {
    /// The grid under the box `[lo, hi]`: just below it, about as wide as three of the box's
    /// diagonals, with 10 to 25 lines each way.
    pub fn under(lo: Vec3, hi: Vec3) -> Option<Self> {
        let diag = (hi - lo).norm();
        if !(diag.is_finite() && diag > 0.0) {
            return None;
        }
        let raw = diag / 6.0;
        let p = 10f64.powf(raw.log10().floor());
        let spacing = if raw / p > 5.0 {
            5.0 * p
        } else if raw / p > 2.0 {
            2.0 * p
        } else {
            p
        };
        let c = (lo + hi) * 0.5;
        Some(Self {
            centre: [
                (c.x / spacing).round() * spacing,
                (c.y / spacing).round() * spacing,
            ],
            z: lo.z - 0.01 * diag,
            spacing,
            half: (1.5 * diag / spacing).ceil().clamp(1.0, 200.0) as u32,
        })
    }

    /// A number that changes when the grid does (the GPU upload's key).
    pub fn key(&self) -> u64 {
        self.centre[0].to_bits()
            ^ self.centre[1].to_bits().rotate_left(21)
            ^ self.z.to_bits().rotate_left(42)
            ^ self.spacing.to_bits().rotate_left(7)
            ^ u64::from(self.half)
    }
}

impl SceneBuffers {
    /// Adds the grid's lines (they do not count in [`SceneBuffers::bounds`]).
    pub fn with_grid(mut self, grid: Option<Grid>) -> Self {
        let Some(g) = grid else { return self };
        self.key.2 ^= g.key();
        let z = Vec3::zeros();
        let n = g.half as i64;
        let ext = g.half as f64 * g.spacing;
        for k in -n..=n {
            let o = k as f64 * g.spacing;
            let c = if k == 0 {
                GRID_CENTRE_COLOR
            } else {
                GRID_COLOR
            };
            let (x, y) = (g.centre[0], g.centre[1]);
            for (p, q) in [
                (
                    Vec3::new(x + o, y - ext, g.z),
                    Vec3::new(x + o, y + ext, g.z),
                ),
                (
                    Vec3::new(x - ext, y + o, g.z),
                    Vec3::new(x + ext, y + o, g.z),
                ),
            ] {
                push(&mut self.line_vertices, &p, &z, c);
                push(&mut self.line_vertices, &q, &z, c);
            }
        }
        self
    }
}

/// The three lights of a view, towards the lights, in world coordinates: key (above and left
/// of the eye), fill (right), rim (behind the model, above). `back` points from the model to
/// the eye; `right` and `up` span the view plane.
pub fn lights(back: Vec3, right: Vec3, up: Vec3) -> [Vec3; 3] {
    [
        (back + up * 0.8 - right * 0.6).normalize(),
        (back * 0.6 + right - up * 0.2).normalize(),
        (-back + up * 0.6).normalize(),
    ]
}

/// Camera and style for one draw.
#[derive(Clone, Copy, Debug)]
pub struct DrawParams {
    /// Projection times view, column-major `f32`.
    pub mvp: [f32; 16],
    /// Unit vector from the scene towards the eye.
    pub view: [f32; 3],
    /// Unit vectors towards the key, fill and rim lights ([`lights`]).
    pub lights: [[f32; 3]; 3],
    /// Draw shaded triangles.
    pub shaded: bool,
    /// Draw triangle edges.
    pub wireframe: bool,
}

#[allow(unsafe_code)]
mod gl {
    use super::*;
    use eframe::glow::{self, HasContext};

    const VERTEX: &str = r#"
        in vec3 a_pos;
        in vec3 a_normal;
        in vec3 a_color;
        uniform mat4 u_mvp;
        uniform float u_point;
        out vec3 v_normal;
        out vec3 v_color;
        void main() {
            gl_Position = u_mvp * vec4(a_pos, 1.0);
            gl_PointSize = u_point;
            v_normal = a_normal;
            v_color = a_color;
        }
    "#;
    const FRAGMENT: &str = r#"
        precision mediump float;
        in vec3 v_normal;
        in vec3 v_color;
        uniform vec3 u_view;
        uniform vec3 u_key;
        uniform vec3 u_fill;
        uniform vec3 u_rim;
        uniform float u_lit;
        out vec4 out_color;
        void main() {
            vec3 c = v_color;
            if (u_lit > 0.5) {
                float len = length(v_normal);
                vec3 n = len > 0.0 ? v_normal / len : u_view;
                // Two-sided: the side facing the viewer is lit.
                if (dot(n, u_view) < 0.0) n = -n;
                float key = max(dot(n, u_key), 0.0);
                float fill = max(dot(n, u_fill), 0.0);
                float rim = max(dot(n, u_rim), 0.0);
                vec3 ambient = mix(vec3(0.13, 0.12, 0.13), vec3(0.30, 0.31, 0.34), 0.5 + 0.5 * n.z);
                float spec = pow(max(dot(n, normalize(u_key + u_view)), 0.0), 40.0) * 0.22;
                float edge = pow(1.0 - max(dot(n, u_view), 0.0), 3.0) * 0.12;
                c = v_color * (ambient + 0.72 * key + 0.28 * fill + 0.22 * rim) + vec3(spec + edge);
            }
            out_color = vec4(c, 1.0);
        }
    "#;

    struct Buffers {
        vao: glow::VertexArray,
        vbo: glow::Buffer,
        ebo: Option<glow::Buffer>,
    }

    /// The GPU side of the viewport: program and buffers, created on the first paint.
    pub struct GlScene {
        program: glow::Program,
        tris: Buffers,
        wire: glow::Buffer,
        lines: Buffers,
        points: Buffers,
        counts: [i32; 5],
        key: Option<(u64, u8, u64)>,
    }

    impl std::fmt::Debug for GlScene {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.debug_struct("GlScene")
                .field("counts", &self.counts)
                .finish()
        }
    }

    fn attribs(gl: &glow::Context, program: glow::Program) {
        let stride = (STRIDE * 4) as i32;
        for (name, offset) in [("a_pos", 0), ("a_normal", 12), ("a_color", 24)] {
            // SAFETY: the program is linked on this context; the bound VAO/VBO belong to it.
            unsafe {
                if let Some(loc) = gl.get_attrib_location(program, name) {
                    gl.enable_vertex_attrib_array(loc);
                    gl.vertex_attrib_pointer_f32(loc, 3, glow::FLOAT, false, stride, offset);
                }
            }
        }
    }

    fn buffers(
        gl: &glow::Context,
        program: glow::Program,
        indexed: bool,
    ) -> Result<Buffers, String> {
        // SAFETY: plain object creation and binding on the current context.
        unsafe {
            let vao = gl.create_vertex_array()?;
            let vbo = gl.create_buffer()?;
            gl.bind_vertex_array(Some(vao));
            gl.bind_buffer(glow::ARRAY_BUFFER, Some(vbo));
            attribs(gl, program);
            let ebo = if indexed {
                let e = gl.create_buffer()?;
                gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, Some(e));
                Some(e)
            } else {
                None
            };
            gl.bind_vertex_array(None);
            Ok(Buffers { vao, vbo, ebo })
        }
    }

    impl GlScene {
        /// Compiles the shaders and creates the buffers.
        pub fn new(gl: &glow::Context) -> Result<Self, String> {
            let version = egui_glow_version(gl);
            // SAFETY: shader and program objects are created, used and checked on this context.
            unsafe {
                let program = gl.create_program()?;
                let mut shaders = Vec::new();
                for (kind, src) in [
                    (glow::VERTEX_SHADER, VERTEX),
                    (glow::FRAGMENT_SHADER, FRAGMENT),
                ] {
                    let s = gl.create_shader(kind)?;
                    gl.shader_source(s, &format!("{version}\n{src}"));
                    gl.compile_shader(s);
                    if !gl.get_shader_compile_status(s) {
                        return Err(format!("shader: {}", gl.get_shader_info_log(s)));
                    }
                    gl.attach_shader(program, s);
                    shaders.push(s);
                }
                gl.link_program(program);
                if !gl.get_program_link_status(program) {
                    return Err(format!("program: {}", gl.get_program_info_log(program)));
                }
                for s in shaders {
                    gl.detach_shader(program, s);
                    gl.delete_shader(s);
                }
                let tris = buffers(gl, program, true)?;
                let wire = gl.create_buffer()?;
                let lines = buffers(gl, program, false)?;
                let points = buffers(gl, program, false)?;
                Ok(Self {
                    program,
                    tris,
                    wire,
                    lines,
                    points,
                    counts: [0; 5],
                    key: None,
                })
            }
        }

        /// Uploads `b` if its key differs from the last upload.
        pub fn upload(&mut self, gl: &glow::Context, b: &SceneBuffers) {
            if self.key == Some(b.key) {
                return;
            }
            self.key = Some(b.key);
            let f = |v: &[f32]| -> Vec<u8> { bytemuck::cast_slice(v).to_vec() };
            // SAFETY: buffers belong to this context; data slices outlive the calls.
            unsafe {
                gl.bind_vertex_array(None);
                gl.bind_buffer(glow::ARRAY_BUFFER, Some(self.tris.vbo));
                gl.buffer_data_u8_slice(
                    glow::ARRAY_BUFFER,
                    bytemuck::cast_slice(&b.tri_vertices),
                    glow::DYNAMIC_DRAW,
                );
                gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, self.tris.ebo);
                gl.buffer_data_u8_slice(
                    glow::ELEMENT_ARRAY_BUFFER,
                    bytemuck::cast_slice(&b.tri_indices),
                    glow::DYNAMIC_DRAW,
                );
                gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, Some(self.wire));
                gl.buffer_data_u8_slice(
                    glow::ELEMENT_ARRAY_BUFFER,
                    bytemuck::cast_slice(&b.wire_indices),
                    glow::DYNAMIC_DRAW,
                );
                gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, None);
                gl.bind_buffer(glow::ARRAY_BUFFER, Some(self.lines.vbo));
                gl.buffer_data_u8_slice(
                    glow::ARRAY_BUFFER,
                    &f(&b.line_vertices),
                    glow::DYNAMIC_DRAW,
                );
                gl.bind_buffer(glow::ARRAY_BUFFER, Some(self.points.vbo));
                gl.buffer_data_u8_slice(
                    glow::ARRAY_BUFFER,
                    &f(&b.point_vertices),
                    glow::DYNAMIC_DRAW,
                );
                gl.bind_buffer(glow::ARRAY_BUFFER, None);
            }
            self.counts = [
                b.tri_indices.len() as i32,
                b.wire_indices.len() as i32,
                (b.line_vertices.len() / STRIDE) as i32,
                (b.point_vertices.len() / STRIDE) as i32,
                0,
            ];
        }

        /// Draws into the current viewport (set by egui to the widget's rectangle).
        pub fn draw(&self, gl: &glow::Context, p: &DrawParams, viewport_px: [i32; 4]) {
            // SAFETY: the program and buffers belong to this context; state is restored for
            // egui (which resets its own state after a callback).
            unsafe {
                gl.enable(glow::SCISSOR_TEST);
                gl.scissor(
                    viewport_px[0],
                    viewport_px[1],
                    viewport_px[2],
                    viewport_px[3],
                );
                gl.clear_depth_f32(1.0);
                gl.clear(glow::DEPTH_BUFFER_BIT);
                gl.enable(glow::DEPTH_TEST);
                gl.depth_func(glow::LEQUAL);
                gl.depth_mask(true);
                gl.disable(glow::BLEND);
                gl.disable(glow::CULL_FACE);
                gl.enable(glow::PROGRAM_POINT_SIZE);
                gl.use_program(Some(self.program));
                let u = |n: &str| gl.get_uniform_location(self.program, n);
                gl.uniform_matrix_4_f32_slice(u("u_mvp").as_ref(), false, &p.mvp);
                let v3 =
                    |name: &str, v: [f32; 3]| gl.uniform_3_f32(u(name).as_ref(), v[0], v[1], v[2]);
                v3("u_view", p.view);
                v3("u_key", p.lights[0]);
                v3("u_fill", p.lights[1]);
                v3("u_rim", p.lights[2]);
                gl.uniform_1_f32(u("u_point").as_ref(), MARKER_PX);
                let lit = u("u_lit");
                if p.shaded && self.counts[0] > 0 {
                    gl.uniform_1_f32(lit.as_ref(), 1.0);
                    gl.enable(glow::POLYGON_OFFSET_FILL);
                    gl.polygon_offset(1.0, 1.0);
                    gl.bind_vertex_array(Some(self.tris.vao));
                    gl.draw_elements(glow::TRIANGLES, self.counts[0], glow::UNSIGNED_INT, 0);
                    gl.disable(glow::POLYGON_OFFSET_FILL);
                }
                gl.uniform_1_f32(lit.as_ref(), 0.0);
                if (p.wireframe || !p.shaded) && self.counts[1] > 0 {
                    gl.bind_vertex_array(Some(self.tris.vao));
                    gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, Some(self.wire));
                    gl.draw_elements(glow::LINES, self.counts[1], glow::UNSIGNED_INT, 0);
                    // Put the VAO's own index buffer back.
                    gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, self.tris.ebo);
                }
                if self.counts[2] > 0 {
                    gl.bind_vertex_array(Some(self.lines.vao));
                    gl.draw_arrays(glow::LINES, 0, self.counts[2]);
                }
                if self.counts[3] > 0 {
                    gl.bind_vertex_array(Some(self.points.vao));
                    gl.draw_arrays(glow::POINTS, 0, self.counts[3]);
                }
                gl.bind_vertex_array(None);
                gl.disable(glow::DEPTH_TEST);
                gl.disable(glow::PROGRAM_POINT_SIZE);
            }
        }
    }

    fn egui_glow_version(gl: &glow::Context) -> &'static str {
        let v = eframe::egui_glow::ShaderVersion::get(gl);
        if v.is_new_shader_interface() {
            v.version_declaration()
        } else {
            // The shaders use `in`/`out`; GLSL 1.40 is the oldest desktop version with them.
            "#version 140"
        }
    }
}

pub use gl::GlScene;

/// A shared handle for the paint callback.
pub type SharedScene = Arc<std::sync::Mutex<Option<Result<GlScene, String>>>>;
