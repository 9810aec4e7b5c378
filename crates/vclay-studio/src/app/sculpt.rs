//! The studio's sculpting habits (Blender sculpt mode, SculptGL): keyboard shortcuts and the
//! help overlay, the brush circle under the cursor and the brush size on `[` `]`, symmetry
//! toggles, and what the viewport draws over the model (control-point handles with a hover
//! highlight, fixed points, FFD pins, mirrored brush circles, the active tool at the cursor,
//! the axes gizmo).

use egui::{Color32, Key, Modifiers, Pos2, Rect, Stroke, Ui, Vec2};
use vclay_core::Vec3;
use vclay_session::LineRole;

use super::{Dialog, PICK_POINTS, Studio, Tool};
use crate::camera::View;
use crate::keys::{BRUSH_STEP, SHORTCUTS, tool_key};
use crate::pick::tangents;
use crate::symmetry::reflect;
use crate::worker::Request;

/// Colour of the brush circle.
pub const BRUSH_COLOR: Color32 = Color32::from_rgb(255, 255, 255);
/// Colour of a mirrored brush circle.
pub const MIRROR_COLOR: Color32 = Color32::from_rgb(120, 200, 255);
/// Colour of control-point handles.
pub const HANDLE_COLOR: Color32 = Color32::from_rgb(255, 160, 40);
/// Colour of the handle under the cursor.
pub const HOVER_COLOR: Color32 = Color32::from_rgb(255, 240, 80);
/// Colour of fixed points.
pub const FIXED_COLOR: Color32 = Color32::from_rgb(70, 140, 255);
/// Colour of FFD pins.
pub const PIN_COLOR: Color32 = Color32::from_rgb(240, 60, 220);
/// Most point-triangle tests per frame for hiding the handles behind the surface; above it
/// every handle is drawn. At 4,000,000 a CAD part's 400 fixed boundary points against its
/// mesh took 2 s a frame in a debug build (about 0.1 s in release), so the budget is 250,000;
/// above it a coarse depth buffer judges them ([`DEPTH_GRID`]).
const VISIBILITY_BUDGET: usize = 250_000;
/// Cells across the coarse depth buffer that judges the handles' visibility above
/// [`VISIBILITY_BUDGET`] (one cell is about 4 points of a 800-point-wide viewport).
pub const DEPTH_GRID: usize = 200;
/// Segments of the brush circle.
const CIRCLE_SEGMENTS: usize = 48;
/// Largest brush radius relative to the model size, the force brush's and the others'.
const RADIUS_RANGE: [(f64, f64); 2] = [(0.01, 1.0), (0.0, 0.5)];

/// The brush under the cursor: where it would act, and how far.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BrushCursor {
    /// The surface point under the mouse.
    pub centre: Vec3,
    /// The surface normal there (facing the viewer).
    pub normal: Vec3,
    /// The brush radius, model units (0: the tool acts on the one element picked).
    pub radius: f64,
}

impl Studio {
    /// Whether the active tool is a brush (the circle, `[` `]`, strokes).
    pub fn is_brush(&self) -> bool {
        matches!(
            self.tool,
            Tool::Force | Tool::Fix | Tool::Free | Tool::Smooth | Tool::Paint
        )
    }

    /// The active brush's radius relative to the model size (`None`: not a brush).
    pub fn brush_radius(&self) -> Option<f64> {
        match self.tool {
            Tool::Force => Some(self.options.radius),
            Tool::Fix | Tool::Free | Tool::Smooth | Tool::Paint => Some(self.options.brush),
            _ => None,
        }
    }

    /// Scales the active brush by `factor` within its slider's range (growing a click tool,
    /// radius 0, gives it the smallest brush).
    pub fn scale_brush(&mut self, factor: f64) {
        let (r, (lo, hi)) = match self.tool {
            Tool::Force => (&mut self.options.radius, RADIUS_RANGE[0]),
            Tool::Fix | Tool::Free | Tool::Smooth | Tool::Paint => {
                (&mut self.options.brush, RADIUS_RANGE[1])
            }
            _ => return,
        };
        let next = if *r <= 0.0 && factor > 1.0 {
            0.02
        } else if factor < 1.0 && *r * factor < 0.01 {
            lo
        } else {
            *r * factor
        };
        *r = next.clamp(lo, hi);
    }

    /// The brush circle shown under the mouse, if the active tool is a brush and the mouse is
    /// over the model.
    pub fn brush_cursor(&self) -> Option<BrushCursor> {
        let hit = self.hover?;
        Some(BrushCursor {
            centre: hit.point,
            normal: hit.normal,
            radius: self.brush_radius()? * self.model_size(),
        })
    }

    /// The control point (handle) under the mouse, if handles are shown.
    pub fn hovered_handle(&self) -> Option<Vec3> {
        self.hovered_handle
    }

    /// Sets the tool symmetry (the worker takes it at the next press).
    pub fn set_symmetry(&mut self, axes: crate::symmetry::Axes) {
        self.symmetry = crate::symmetry::Symmetry(axes);
    }

    /// The symmetry toggles (X, Y, Z) of the tools that mirror.
    pub(super) fn symmetry_ui(&mut self, ui: &mut Ui) {
        if !(self.is_brush() || self.tool == Tool::Rope) {
            return;
        }
        ui.horizontal(|ui| {
            ui.label("Symmetry:");
            for (k, name) in ["X", "Y", "Z"].iter().enumerate() {
                ui.toggle_value(&mut self.symmetry.0[k], *name)
                    .on_hover_text(format!(
                        "mirror across {} (key {name})",
                        name.to_lowercase()
                    ));
            }
        });
    }

    /// Sculpt mode's plastic flow (docs/sculpting.md): off, the shape reached is kept whole at
    /// the release; on, the rest shape follows the clay during the pull past a yield distance
    /// at a rate, and the elastic part springs back. Sent to the worker at once.
    pub(super) fn flow_ui(&mut self, ui: &mut Ui) {
        let (mut on, mut rate, mut yield_fraction) = self.options.flow;
        let mut changed = false;
        ui.horizontal(|ui| {
            changed |= ui
                .checkbox(&mut on, "Plastic flow")
                .on_hover_text(
                    "off: the whole shape reached is kept at the release; on: the clay yields \
                     while you pull (past the yield distance, at the rate) and springs back by \
                     its elastic part",
                )
                .changed();
        });
        if on {
            let r = ui.add(
                egui::Slider::new(&mut rate, 0.1..=100.0)
                    .logarithmic(true)
                    .text("rate 1/s"),
            );
            let y = ui.add(
                egui::Slider::new(&mut yield_fraction, 0.0..=0.2)
                    .text("yield")
                    .custom_formatter(|v, _| format!("{:.1} %", 100.0 * v)),
            );
            changed |= r.drag_stopped() || (r.changed() && !r.dragged());
            changed |= y.drag_stopped() || (y.changed() && !y.dragged());
        }
        self.options.flow = (on, rate, yield_fraction);
        if changed {
            self.send(Request::Sculpt(self.options.sculpt));
            self.send(Request::Flow(self.options.flow_request()));
        }
    }

    /// The keys (see [`crate::keys`]); none while a dialog is open or a text field has focus.
    pub(super) fn shortcuts(&mut self, ctx: &egui::Context) {
        // A dialog or a text field takes the keys (Ctrl+Z in a path field is not the model's).
        if self.dialog.is_some() || ctx.text_edit_focused() {
            return;
        }
        let (undo, redo, save, save_as, open) = ctx.input_mut(|i| {
            let redo = i.consume_key(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z)
                || i.consume_key(Modifiers::COMMAND, Key::Y);
            let undo = i.consume_key(Modifiers::COMMAND, Key::Z);
            let save_as = i.consume_key(Modifiers::COMMAND | Modifiers::SHIFT, Key::S);
            let save = i.consume_key(Modifiers::COMMAND, Key::S);
            let open = i.consume_key(Modifiers::COMMAND, Key::O);
            (undo, redo, save, save_as, open)
        });
        if save_as && self.worker.is_some() {
            self.save_as();
        }
        if open {
            self.confirm(ctx, super::Then::Open);
        }
        if redo {
            self.send(Request::Redo);
        } else if undo {
            self.send(Request::Undo);
        }
        if save {
            self.save();
        }
        // Plain keys (the Ctrl combinations above are consumed already).
        let pressed = |k: Key| ctx.input_mut(|i| i.consume_key(Modifiers::NONE, k));
        if pressed(Key::F1) || pressed(Key::Questionmark) {
            self.dialog = Some(Dialog::Help);
            return;
        }
        if self.worker.is_none() {
            return;
        }
        for t in Tool::palette(&self.tools) {
            if pressed(tool_key(t)) {
                self.tool = t;
            }
        }
        if pressed(Key::F) {
            self.fit();
        }
        if pressed(Key::OpenBracket) {
            self.scale_brush(1.0 / BRUSH_STEP);
        }
        if pressed(Key::CloseBracket) {
            self.scale_brush(BRUSH_STEP);
        }
        if pressed(Key::Space) {
            let running = self.frame.running;
            self.run_clicked(running);
        }
        if pressed(Key::K) {
            self.options.sculpt = !self.options.sculpt;
            self.send(Request::Sculpt(self.options.sculpt));
        }
        for (k, axis) in [(Key::X, 0), (Key::Y, 1), (Key::Z, 2)] {
            if pressed(k) {
                self.symmetry.0[axis] = !self.symmetry.0[axis];
            }
        }
        for (k, v) in [
            (Key::Num1, View::Front),
            (Key::Num3, View::Side),
            (Key::Num7, View::Top),
            (Key::Num0, View::Iso),
        ] {
            if pressed(k) {
                self.camera.set_view(v);
            }
        }
        let before = self.layers;
        if pressed(Key::W) {
            self.layers.wireframe = !self.layers.wireframe;
        }
        if pressed(Key::N) {
            self.layers.control_net = !self.layers.control_net;
        }
        if before != self.layers {
            self.rebuild_scene();
        }
    }

    /// The help overlay's content: every shortcut.
    pub(super) fn help_ui(&self, ui: &mut Ui) {
        ui.heading("Shortcuts");
        egui::Grid::new("help-keys")
            .num_columns(2)
            .striped(true)
            .show(ui, |ui| {
                for t in Tool::ALL {
                    let offered = self.worker.is_none() || Tool::palette(&self.tools).contains(&t);
                    let text = egui::RichText::new(format!("{} tool", t.label()));
                    ui.monospace(tool_key(t).name());
                    ui.label(if offered { text } else { text.weak() });
                    ui.end_row();
                }
                for (k, what) in SHORTCUTS {
                    ui.monospace(k);
                    ui.label(what);
                    ui.end_row();
                }
            });
        ui.small("Keys act while no dialog is open and no text field has the focus.");
    }

    /// The help overlay; `false` once it is closed (its button, Esc, Enter, F1 or ?).
    pub(super) fn help_dialog(&self, ctx: &egui::Context, modal: egui::Modal) -> bool {
        let closed = modal
            .show(ctx, |ui| {
                ui.set_min_width(super::DIALOG_MIN_WIDTH);
                self.help_ui(ui);
                ui.button("Close").clicked()
            })
            .inner;
        let keys = ctx.input_mut(|i| {
            [Key::Escape, Key::Enter, Key::F1, Key::Questionmark]
                .iter()
                .any(|&k| i.consume_key(Modifiers::NONE, k))
        });
        !(closed || keys)
    }

    /// The mouse over the model: the surface under it (for the brush circle) and the handle
    /// under it.
    pub(super) fn hover(&mut self, ui: &Ui, rect: Rect) {
        let pos = ui
            .input(|i| i.pointer.hover_pos())
            .filter(|p| rect.contains(*p));
        self.pointer = pos;
        self.hover = None;
        self.hovered_handle = None;
        let Some(p) = pos else { return };
        let (w, h) = (rect.width() as f64, rect.height() as f64);
        let (x, y) = ((p.x - rect.min.x) as f64, (p.y - rect.min.y) as f64);
        if self.is_brush() {
            let ray = self.camera.ray(x, y, w, h);
            self.hover = crate::pick::ray_frame(&ray, &self.frame);
        }
        if self.shows_handles() {
            let mut best = PICK_POINTS;
            for c in self.points_of(&[LineRole::ControlNet, LineRole::LatticeEdges]) {
                if let Some((px, py)) = self.camera.project(c, w, h) {
                    let d = ((px - x).powi(2) + (py - y).powi(2)).sqrt();
                    if d < best {
                        best = d;
                        self.hovered_handle = Some(c);
                    }
                }
            }
        }
    }

    /// Whether control-point handles are drawn: the control net is shown or the control point
    /// tool is active.
    fn shows_handles(&self) -> bool {
        self.layers.control_net || self.tool == Tool::ControlPoint
    }

    /// The points of the frame's line sets with one of `roles`.
    fn points_of(&self, roles: &[LineRole]) -> Vec<Vec3> {
        self.frame
            .models
            .iter()
            .flat_map(|m| m.lines.iter())
            .filter(|l| l.role.is_some_and(|r| roles.contains(&r)))
            .flat_map(|l| l.points.iter().copied())
            .collect()
    }

    /// Draws over the model: handles, fixed points, pins, the brush circles, the tool at the
    /// cursor, the axes gizmo.
    pub(super) fn overlays(&self, ui: &Ui, rect: Rect) {
        let painter = ui.painter_at(rect);
        self.colour_legend(&painter, rect);
        let (w, h) = (rect.width() as f64, rect.height() as f64);
        let at = |p: Vec3| {
            self.camera
                .project(p, w, h)
                .map(|(x, y)| rect.min + Vec2::new(x as f32, y as f32))
        };
        if self.shows_handles() {
            let handles = self.points_of(&[LineRole::ControlNet, LineRole::LatticeEdges]);
            let seen = self.visibility(&handles);
            for (c, v) in handles.into_iter().zip(seen) {
                if let Some(s) = at(c) {
                    if v {
                        painter.circle(s, 3.0, HANDLE_COLOR, Stroke::new(1.0, Color32::BLACK));
                    } else {
                        // Behind the surface: faint, as in an x-ray view.
                        painter.circle_filled(s, 2.0, HANDLE_COLOR.gamma_multiply(0.35));
                    }
                }
            }
            if let Some(s) = self.hovered_handle.and_then(at) {
                painter.circle_stroke(s, 7.0, Stroke::new(2.0, HOVER_COLOR));
            }
        }
        let fixed = self.points_of(&[LineRole::Fixed]);
        let seen = self.visibility(&fixed);
        for (c, _) in fixed.into_iter().zip(seen).filter(|(_, v)| *v) {
            if let Some(s) = at(c) {
                let r = Rect::from_center_size(s, Vec2::splat(7.0));
                painter.rect_filled(r, 1.0, FIXED_COLOR);
                painter.rect_stroke(
                    r,
                    1.0,
                    Stroke::new(1.0, Color32::WHITE),
                    egui::StrokeKind::Outside,
                );
            }
        }
        for &c in &self.ffd_pins {
            if let Some(s) = at(c) {
                painter.circle_stroke(s, 6.0, Stroke::new(2.0, PIN_COLOR));
                painter.circle_filled(s, 2.0, PIN_COLOR);
            }
        }
        if let Some(b) = self.brush_cursor() {
            self.brush_circles(&painter, rect, &b);
        }
        self.tool_at_cursor(&painter);
        axes_gizmo(&painter, rect, &self.camera);
    }

    /// Whether each of `points` is in sight (no display surface between it and the eye): a ray
    /// per point against the meshes, or, when that would cost over [`VISIBILITY_BUDGET`]
    /// point-triangle tests (many points on a fine mesh, a CAD part's boundary), a coarse depth
    /// buffer of the meshes ([`Studio::visibility_by_depth`]).
    pub fn visibility(&self, points: &[Vec3]) -> Vec<bool> {
        let tris: usize = self
            .frame
            .models
            .iter()
            .map(|m| m.mesh.triangles.len())
            .sum();
        if points.len().saturating_mul(tris) > VISIBILITY_BUDGET {
            return self.visibility_by_depth(points);
        }
        let eye = self.camera.eye();
        points
            .iter()
            .map(|&p| {
                let d = p - eye;
                let ray = vclay_session::Ray {
                    origin: eye,
                    direction: d,
                };
                // Distances are in units of |d|: the point itself is at 1.
                crate::pick::ray_frame(&ray, &self.frame).is_none_or(|h| h.distance > 0.995)
            })
            .collect()
    }

    /// [`Studio::visibility`] by a depth buffer of [`DEPTH_GRID`] cells across (the
    /// viewport's aspect): each triangle's view depth is written into the cells whose centres
    /// it covers (1/depth interpolated, which is linear on the screen), and a point is in
    /// sight when it is no deeper than its cell plus a slack of two cells' width at its depth
    /// and 1 % of the model size (points lie on the surface; a cell keeps the nearest depth it
    /// covers). Cost: the triangles' covered cells plus one lookup a point. Triangles with a
    /// corner behind the eye occlude nothing.
    fn visibility_by_depth(&self, points: &[Vec3]) -> Vec<bool> {
        let v = self.viewport;
        let aspect = (v.height() / v.width().max(1.0)) as f64;
        let gw = DEPTH_GRID;
        let gh = ((gw as f64 * aspect).ceil() as usize).clamp(1, 4 * DEPTH_GRID);
        let (fw, fh) = (gw as f64, gh as f64);
        let eye = self.camera.eye();
        let ahead = -self.camera.back();
        let depth = |p: Vec3| (p - eye).dot(&ahead);
        let mut zbuf = vec![f64::INFINITY; gw * gh];
        for m in &self.frame.models {
            let mesh = &m.mesh;
            for t in &mesh.triangles {
                let mut c = [(0.0, 0.0, 0.0); 3];
                let mut ok = true;
                for k in 0..3 {
                    let Some(&p) = mesh.positions.get(t[k] as usize) else {
                        ok = false;
                        break;
                    };
                    match self.camera.project(p, fw, fh) {
                        Some((x, y)) => c[k] = (x, y, 1.0 / depth(p)),
                        None => ok = false,
                    }
                }
                if !ok {
                    continue;
                }
                let [(x0, y0, w0), (x1, y1, w1), (x2, y2, w2)] = c;
                let area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
                if area.abs() < 1e-12 {
                    continue;
                }
                let lo = |a: f64, b: f64, c: f64| (a.min(b).min(c) - 0.5).ceil().max(0.0);
                let hi =
                    |a: f64, b: f64, c: f64, n: f64| (a.max(b).max(c) - 0.5).floor().min(n - 1.0);
                let (ix0, ix1) = (lo(x0, x1, x2), hi(x0, x1, x2, fw));
                let (iy0, iy1) = (lo(y0, y1, y2), hi(y0, y1, y2, fh));
                if ix0 > ix1 || iy0 > iy1 {
                    continue;
                }
                for iy in iy0 as usize..=iy1 as usize {
                    for ix in ix0 as usize..=ix1 as usize {
                        let (px, py) = (ix as f64 + 0.5, iy as f64 + 0.5);
                        let b1 = ((px - x0) * (y2 - y0) - (x2 - x0) * (py - y0)) / area;
                        let b2 = ((x1 - x0) * (py - y0) - (px - x0) * (y1 - y0)) / area;
                        let b0 = 1.0 - b1 - b2;
                        if b0 < 0.0 || b1 < 0.0 || b2 < 0.0 {
                            continue;
                        }
                        let z = 1.0 / (b0 * w0 + b1 * w1 + b2 * w2);
                        let cell = &mut zbuf[iy * gw + ix];
                        if z < *cell {
                            *cell = z;
                        }
                    }
                }
            }
        }
        let size = self.model_size();
        let cell_angle = 2.0 * (crate::camera::FOV_Y / 2.0).tan() / fh;
        points
            .iter()
            .map(|&p| {
                let Some((x, y)) = self.camera.project(p, fw, fh) else {
                    return true;
                };
                let (ix, iy) = (x.floor(), y.floor());
                if ix < 0.0 || iy < 0.0 || ix >= fw || iy >= fh {
                    return true;
                }
                let d = depth(p);
                let slack = 2.0 * cell_angle * d + 0.01 * size;
                d <= zbuf[iy as usize * gw + ix as usize] + slack
            })
            .collect()
    }

    /// The brush circle on the surface's tangent plane under the mouse, and its mirror images.
    fn brush_circles(&self, painter: &egui::Painter, rect: Rect, b: &BrushCursor) {
        let (w, h) = (rect.width() as f64, rect.height() as f64);
        let circle = |centre: Vec3, normal: Vec3, color: Color32| {
            let (t1, t2) = tangents(normal);
            // A click tool (radius 0) shows the pick's reach instead.
            let r = if b.radius > 0.0 {
                b.radius
            } else {
                PICK_POINTS * 2.0 * self.camera.distance * (crate::camera::FOV_Y / 2.0).tan() / h
            };
            let pts: Vec<Pos2> = (0..CIRCLE_SEGMENTS)
                .filter_map(|k| {
                    let a = k as f64 / CIRCLE_SEGMENTS as f64 * std::f64::consts::TAU;
                    let p = centre + (t1 * a.cos() + t2 * a.sin()) * r;
                    self.camera
                        .project(p, w, h)
                        .map(|(x, y)| rect.min + Vec2::new(x as f32, y as f32))
                })
                .collect();
            if pts.len() == CIRCLE_SEGMENTS {
                painter.add(egui::Shape::closed_line(pts, Stroke::new(1.5, color)));
            }
        };
        circle(b.centre, b.normal, BRUSH_COLOR);
        if let Some(c) = self.symmetry_centre() {
            for f in self.symmetry.mirrors() {
                let n = crate::symmetry::reflect_dir(f, b.normal);
                circle(reflect(f, c, b.centre), n, MIRROR_COLOR);
            }
        }
    }

    /// The centre of the symmetry planes: the first model's bounding box (as the worker
    /// takes it at a press).
    pub fn symmetry_centre(&self) -> Option<Vec3> {
        self.frame
            .models
            .first()
            .and_then(|m| crate::symmetry::centre(&m.mesh.positions))
    }

    /// The active tool's name (and brush size) beside the cursor.
    fn tool_at_cursor(&self, painter: &egui::Painter) {
        let Some(p) = self.pointer else { return };
        let mut text = self.tool.label().to_string();
        if let Some(r) = self.brush_radius() {
            text += &format!("  r {r:.2}");
        }
        if self.tool == Tool::Force {
            text += &format!("  s {:.0}", self.options.force);
        }
        if self.symmetry.any() && (self.is_brush() || self.tool == Tool::Rope) {
            text += &format!("  sym {}", self.symmetry.label());
        }
        // Right of the cursor, or left of it near the viewport's right edge (the text stays
        // whole).
        let font = egui::FontId::proportional(12.0);
        let width = painter
            .layout_no_wrap(text.clone(), font.clone(), Color32::WHITE)
            .size()
            .x;
        let (offset, align) = if p.x + 14.0 + width > painter.clip_rect().max.x {
            (Vec2::new(-14.0, 14.0), egui::Align2::RIGHT_TOP)
        } else {
            (Vec2::new(14.0, 14.0), egui::Align2::LEFT_TOP)
        };
        painter.text(p + offset, align, text, font, Color32::from_gray(230));
    }
}

/// The world axes as seen from the camera, in the viewport's bottom-left corner (x red, y
/// green, z blue, as Blender's).
fn axes_gizmo(painter: &egui::Painter, rect: Rect, camera: &crate::camera::Camera) {
    let o = Pos2::new(rect.min.x + 40.0, rect.max.y - 40.0);
    let (r, u) = camera.right_up();
    let back = camera.back();
    let mut axes = [
        (Vec3::x(), "x", Color32::from_rgb(230, 70, 70)),
        (Vec3::y(), "y", Color32::from_rgb(110, 200, 80)),
        (Vec3::z(), "z", Color32::from_rgb(80, 140, 255)),
    ];
    // The axis nearest the viewer last (on top).
    axes.sort_by(|a, b| a.0.dot(&back).total_cmp(&b.0.dot(&back)));
    painter.circle_filled(o, 32.0, Color32::from_black_alpha(60));
    for (a, name, c) in axes {
        let d = Vec2::new(a.dot(&r) as f32, -(a.dot(&u) as f32)) * 24.0;
        painter.line_segment([o, o + d], Stroke::new(2.0, c));
        painter.circle_filled(o + d, 7.0, c);
        painter.text(
            o + d,
            egui::Align2::CENTER_CENTER,
            name,
            egui::FontId::proportional(10.0),
            Color32::BLACK,
        );
    }
}

impl Studio {
    /// The designer's choice of colouring (View > Colour): [`Self::set_colour_by`], and the
    /// paint tool no longer switches to the stiffness map by itself.
    pub fn choose_colour(&mut self, field: Option<&'static str>) {
        self.colour_chosen = true;
        self.set_colour_by(field);
    }

    /// Colours the meshes by `field` (one of the first model's `display_fields`; `None`: clay).
    pub fn set_colour_by(&mut self, field: Option<&'static str>) {
        let known = field.is_none_or(|f| {
            self.frame
                .models
                .first()
                .is_some_and(|m| m.fields.iter().any(|s| s.name == f))
        });
        if known && field != self.colour_by {
            self.colour_by = field;
            self.send(Request::ColourBy(field.map(str::to_string)));
        }
    }

    /// View > Colour: clay, or a field the model offers (painted material).
    pub(super) fn colour_ui(&mut self, ui: &mut Ui) {
        let Some(fields) = self.frame.models.first().map(|m| m.fields.clone()) else {
            return;
        };
        if fields.is_empty() {
            return;
        }
        let mut chosen = self.colour_by;
        egui::ComboBox::from_label("Colour")
            .selected_text(chosen.unwrap_or("clay"))
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut chosen, None, "clay");
                for f in &fields {
                    ui.selectable_value(&mut chosen, Some(f.name), f.name)
                        .on_hover_text(format!("{} ({})", f.help, f.unit));
                }
            });
        if chosen != self.colour_by {
            self.choose_colour(chosen);
        }
    }

    /// The colour map's legend (bottom right of the viewport): the field, its range, the ramp.
    pub(super) fn colour_legend(&self, painter: &egui::Painter, rect: Rect) {
        let (Some(name), Some(m)) = (self.colour_by, self.frame.models.first()) else {
            return;
        };
        let Some(field) = m.field.as_deref() else {
            return;
        };
        let w = 160.0;
        let bar = Rect::from_min_size(
            Pos2::new(rect.max.x - w - 16.0, rect.max.y - 40.0),
            Vec2::new(w, 10.0),
        );
        let text = match crate::render::field_range(field) {
            Some(scale) => {
                let n = 32;
                for k in 0..n {
                    let t = (k as f32 + 0.5) / n as f32;
                    let c = crate::render::colour_map(t).map(|x| (x * 255.0) as u8);
                    let x0 = bar.min.x + bar.width() * k as f32 / n as f32;
                    painter.rect_filled(
                        Rect::from_min_max(
                            Pos2::new(x0, bar.min.y),
                            Pos2::new(x0 + bar.width() / n as f32 + 0.5, bar.max.y),
                        ),
                        0.0,
                        Color32::from_rgb(c[0], c[1], c[2]),
                    );
                }
                format!(
                    "{name}: {} .. {}{}",
                    crate::text::round_numbers(&format!("{}", scale.lo)),
                    crate::text::round_numbers(&format!("{}", scale.hi)),
                    if scale.log { " (log)" } else { "" }
                )
            }
            None => format!("{name}: uniform (clay colour)"),
        };
        painter.text(
            Pos2::new(bar.max.x, bar.min.y - 4.0),
            egui::Align2::RIGHT_BOTTOM,
            text,
            egui::FontId::proportional(12.0),
            Color32::WHITE,
        );
    }
}
