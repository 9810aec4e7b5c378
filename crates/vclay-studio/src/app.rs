//! The studio's window: start page, menus, tool and parameter panels, the 3D viewport, energy
//! plot, log and status bar. [`Studio::show`] draws one egui frame and is all the UI logic;
//! `eframe::App::ui` calls it in the real window and `egui_kittest` calls it in the tests.
//!
//! The UI never touches a model: it sends [`Request`]s to the simulation thread
//! ([`crate::worker`]) and draws the [`Frame`]s it gets back. The sculpting habits (shortcuts,
//! help overlay, brush circle, symmetry, handles) are in [`sculpt`].

mod sculpt;
pub use sculpt::BrushCursor;

use std::collections::{BTreeMap, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant, SystemTime};

use egui::{Color32, Key, Modifiers, PointerButton, Pos2, Rect, Sense, SurrenderFocusOn, Ui, Vec2};
use vclay_core::Vec3;
use vclay_session::{Command, Edit, Session, Target, ToolSpec};

use crate::camera::{Camera, View};
use crate::load;
use crate::pick::SurfaceHit;
use crate::render::{DrawParams, Grid, Layers, SceneBuffers, SharedScene};
use crate::symmetry::Symmetry;
use crate::worker::{AUTOSAVE_INTERVAL, Frame, Grab, Notice, Request, Worker};

/// Pick tolerance in screen points.
pub const PICK_POINTS: f64 = 8.0;
/// Log lines kept.
pub const LOG_LINES: usize = 200;
/// End of a PDE surface's time range (its time slider): a run stops there.
pub const PDE_T_MAX: f64 = 10.0;
/// Least width of a dialog, in points (an error message must be readable).
pub const DIALOG_MIN_WIDTH: f32 = 420.0;
/// The energy plot's y axis reaches at least this times the model size squared: energies of a
/// model at rest are rounding noise (positions rounded at 1e-16 of the size give energies near
/// 1e-32 of `k size^2`, and 1e-28 was seen on the unit cube), which an axis scaled to the data
/// alone draws as full-height spikes. A pull of a millionth of the size with a unit stiffness
/// (1e-12 size^2) stays eight orders above it.
pub const ENERGY_PLOT_FLOOR: f64 = 1e-20;

/// The tool a press in the viewport uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tool {
    /// Drag orbits the camera.
    Orbit,
    /// Rope (spring) drag.
    Rope,
    /// Push/pull force brush.
    Force,
    /// Fix the control point nearest the click.
    Fix,
    /// Free the control point nearest the click.
    Free,
    /// The smooth brush: fairs the rest shape under the brush; the clay settles to it.
    Smooth,
    /// Extrude the face under the click.
    Extrude,
    /// Delete the cell under the click.
    DeleteCell,
    /// Choose the face of a CAD part that is sculpted (a click on the face).
    SculptFace,
    /// Paint material on the cell under the click.
    Paint,
    /// Drag a control point.
    ControlPoint,
    /// FFD direct manipulation of a mesh point.
    FfdPoint,
    /// PDE local deformation (eqs 30-32) by drag.
    PdeLocal,
}

impl Tool {
    /// Button label.
    pub fn label(self) -> &'static str {
        match self {
            Tool::Orbit => "Orbit",
            Tool::Rope => "Rope",
            Tool::Force => "Force brush",
            Tool::Fix => "Fix",
            Tool::Free => "Free",
            Tool::Smooth => "Smooth",
            Tool::Extrude => "Extrude face",
            Tool::DeleteCell => "Delete cell",
            Tool::SculptFace => "Face to sculpt",
            Tool::Paint => "Paint material",
            Tool::ControlPoint => "Control point",
            Tool::FfdPoint => "FFD point",
            Tool::PdeLocal => "Local deformation",
        }
    }

    /// Every tool in palette order (the default of a model is the first it takes).
    pub const ALL: [Tool; 13] = [
        Tool::Rope,
        Tool::Force,
        Tool::Smooth,
        Tool::Fix,
        Tool::Free,
        Tool::Extrude,
        Tool::DeleteCell,
        Tool::Paint,
        Tool::FfdPoint,
        Tool::PdeLocal,
        Tool::SculptFace,
        Tool::ControlPoint,
        Tool::Orbit,
    ];

    /// Whether a model that takes `tools` (`vclay_session::Model::tools`) takes this tool: the
    /// tool's edit is among them (the force brush: `region-force` or `force`; painting: a
    /// `material` that acts on control cells).
    pub fn offered(self, tools: &[ToolSpec]) -> bool {
        let takes = |a: &str| tools.iter().any(|t| t.action == a);
        match self {
            Tool::Orbit => true,
            Tool::Rope => takes("rope"),
            Tool::Force => takes("region-force") || takes("force"),
            Tool::Fix => takes("fix"),
            Tool::Free => takes("free"),
            Tool::Smooth => takes("smooth"),
            Tool::Extrude => takes("extrude"),
            Tool::DeleteCell => takes("delete-cell"),
            Tool::SculptFace => takes("sculpt-face"),
            Tool::Paint => tools
                .iter()
                .any(|t| t.action == "material" && t.acts_on == Target::Cell),
            Tool::ControlPoint => takes("move-point"),
            Tool::FfdPoint => takes("ffd-move"),
            Tool::PdeLocal => takes("pde-local"),
        }
    }

    /// The palette of a model that takes `tools`, the default first.
    pub fn palette(tools: &[ToolSpec]) -> Vec<Tool> {
        Tool::ALL.into_iter().filter(|t| t.offered(tools)).collect()
    }
}

/// Whether `tools` has `action`, and it takes `key` (`None`: any key).
pub fn takes(tools: &[ToolSpec], action: &str, key: Option<&str>) -> bool {
    tools
        .iter()
        .any(|t| t.action == action && key.is_none_or(|k| t.keys.iter().any(|x| x.name == k)))
}

/// The solids' integrators by their command names (`symplectic` is the default).
pub const INTEGRATORS: [&str; 3] = ["symplectic", "explicit", "implicit"];

/// Options of the tools.
#[derive(Clone, Debug, PartialEq)]
pub struct ToolOptions {
    /// Rope stiffness (0: the kind's default).
    pub rope_stiffness: f64,
    /// Force brush strength: the total force of one dab (default 5: one dab of 0.1 s dents the
    /// unit cube of the start page by about a tenth of its size; 20, the old default, by half).
    pub force: f64,
    /// Force brush radius relative to the model size.
    pub radius: f64,
    /// Force brush duration, simulated seconds.
    pub duration: f64,
    /// Pull instead of push.
    pub pull: bool,
    /// How the force brush's share falls off from its centre on solids (one of
    /// `vclay_session::describe::FALLOFFS`; default `smooth`, as Blender's brushes).
    pub falloff: &'static str,
    /// Material painting: density, damping, edge stiffness.
    pub paint: [f64; 3],
    /// Brush half-size of fix, free and material painting, relative to the model size (0: one
    /// point or cell per click).
    pub brush: f64,
    /// Smooth brush strength: the share of each dab's step towards the neighbours' mean.
    pub smooth: f64,
    /// Weight that Ctrl+click sets on a control point (control point tool).
    pub weight: f64,
    /// PDE local deformation: half-widths of the region along u (of [0, 1]) and v.
    pub local: [f64; 2],
    /// Solids: index into [`INTEGRATORS`] (as last chosen here).
    pub integrator: usize,
    /// Gravity on, and its strength.
    pub gravity: (bool, f64),
    /// Inflation on, and its pressure.
    pub inflate: (bool, f64),
    /// Sculpt mode (the default): at the end of each pull the shape reached becomes the rest
    /// shape ([`crate::worker::Request::Sculpt`]); off: the papers' elastic clay.
    pub sculpt: bool,
    /// Sculpt mode's plastic flow: on, its rate (1/s) and its yield distance relative to the
    /// model size ([`crate::worker::Request::Flow`]); off, the shape is kept at the release.
    pub flow: (bool, f64, f64),
}

impl ToolOptions {
    /// The flow request of these options.
    pub fn flow_request(&self) -> Option<crate::worker::Flow> {
        self.flow.0.then_some(crate::worker::Flow {
            rate: self.flow.1,
            yield_fraction: self.flow.2,
        })
    }
}

impl Default for ToolOptions {
    fn default() -> Self {
        Self {
            rope_stiffness: 0.0,
            force: 5.0,
            radius: 0.15,
            duration: 0.1,
            pull: false,
            falloff: "smooth",
            paint: [1.0, 2.0, 400.0],
            brush: 0.08,
            smooth: 0.5,
            weight: 1.0,
            local: [0.15, 0.5],
            integrator: 0,
            sculpt: true,
            flow: (false, 5.0, 0.01),
            gravity: (false, 9.81),
            inflate: (false, 5.0),
        }
    }
}

enum Dialog {
    Error(String),
    Open(String),
    SaveAs(String),
    Export(String),
    Screenshot(String),
    Recover(PathBuf),
    /// Unsaved changes: save, discard or cancel before doing `Then`.
    Unsaved(Then),
    /// The shortcuts (F1 or ?).
    Help,
    /// Waiting for the desktop's file chooser ([`crate::native`]); `typed` is the path the
    /// typed dialog starts from if the person prefers it or the chooser fails.
    Native {
        purpose: PathPurpose,
        answer: std::sync::mpsc::Receiver<crate::native::Answer>,
        typed: String,
    },
}

/// What a path dialog is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum PathPurpose {
    Open,
    SaveAs,
    Export,
    Screenshot,
}

impl PathPurpose {
    fn title(self) -> &'static str {
        match self {
            PathPurpose::Open => "Open",
            PathPurpose::SaveAs => "Save session as",
            PathPurpose::Export => "Export the model",
            PathPurpose::Screenshot => "Screenshot (PNG)",
        }
    }
    /// The typed-path dialog for this purpose.
    fn typed(self, path: String) -> Dialog {
        match self {
            PathPurpose::Open => Dialog::Open(path),
            PathPurpose::SaveAs => Dialog::SaveAs(path),
            PathPurpose::Export => Dialog::Export(path),
            PathPurpose::Screenshot => Dialog::Screenshot(path),
        }
    }
}

/// What waits for the unsaved-changes prompt (and for the save it may start).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Then {
    /// Show the open dialog.
    Open,
    /// Open the recently opened file of this index (File > Open recent).
    OpenRecent(usize),
    /// Close the session and show the start page.
    StartPage,
    /// Quit.
    Quit,
}

/// What a button, Enter or Esc did in a dialog.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Answer {
    /// The dialog's main action (Enter).
    Submit,
    /// The dialog's other action (the prompt's Discard).
    Other,
    /// Close (Esc, Cancel).
    Cancel,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Press {
    /// Waiting for the worker's pick.
    Waiting,
    /// Dragging the grabbed point; the cursor is at the point.
    Grabbed(Vec3),
    /// Nothing hit: the drag orbits.
    Orbit,
}

/// Start-up options.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// File to open.
    pub file: Option<PathBuf>,
    /// Autosave file (`None`: the default place).
    pub autosave: Option<PathBuf>,
    /// Start with the simulation paused.
    pub paused: bool,
    /// Do not offer recovery (tests, scripts).
    pub no_recovery: bool,
    /// The list of recently opened files (JSON; `None`: none kept). The binary keeps it in
    /// `$XDG_CONFIG_HOME/vclay/recent.json` (else `~/.config/vclay/recent.json`).
    pub recent: Option<PathBuf>,
    /// The desktop's file chooser for Open, Save as, Export and Screenshot (`None`: the typed
    /// path dialogs). The binary uses [`crate::native::Chooser::find`].
    pub chooser: Option<crate::native::Chooser>,
    /// A file that receives one line a second of the window's frame rate and the simulation's
    /// speed (`vclay-studio --frame-log PATH`; `bench/window_fps.sh` reads it): wall seconds
    /// since the start, frames/s, simulated time, steps, steps/s, step ms, display ms,
    /// triangles, separated by spaces after a `#` header line.
    pub frame_log: Option<PathBuf>,
}

/// The studio (see the [module docs](self)).
pub struct Studio {
    worker: Option<Worker>,
    frame: Frame,
    scene: Arc<SceneBuffers>,
    gl: SharedScene,
    /// The camera.
    pub camera: Camera,
    /// Layers drawn.
    pub layers: Layers,
    /// The scalar field the meshes are coloured by (`Model::display_fields`: painted
    /// material), `None` for the clay colour; with `colour_chosen` once picked in View.
    pub colour_by: Option<&'static str>,
    colour_chosen: bool,
    /// The active tool.
    pub tool: Tool,
    /// Tool options.
    pub options: ToolOptions,
    file: Option<PathBuf>,
    autosave: Option<PathBuf>,
    opts: Options,
    dialog: Option<Dialog>,
    log: VecDeque<String>,
    energy: Vec<[f64; 3]>,
    /// The energy plot's y range as last drawn (tests read it).
    energy_y_range: Option<[f64; 2]>,
    /// The open `--frame-log` file, when the last line was written, and the studio's start.
    frame_log: Option<(std::fs::File, Instant, Instant)>,
    press: Option<Press>,
    fitted: bool,
    edits: BTreeMap<String, f64>,
    frame_times: VecDeque<Instant>,
    allow_close: bool,
    shots: Arc<Mutex<Vec<Result<PathBuf, String>>>>,
    /// What the first model takes (`Model::tools`): the palette and panels follow from it.
    tools: Vec<ToolSpec>,
    /// Recently opened files, newest first, and where they are kept.
    recent: Vec<PathBuf>,
    recent_file: Option<PathBuf>,
    pde_t: f64,
    viewport: Rect,
    /// FFD points held in place while another is dragged (multi-point moves, eq 12).
    ffd_pins: Vec<Vec3>,
    /// A pin pick is on its way to the worker.
    pin_pending: bool,
    /// What to do once the session is saved (the unsaved-changes prompt's Save).
    after_save: Option<Then>,
    /// The worker's session generation whose frames and notices are shown (see
    /// [`Frame::generation`]).
    generation: u64,
    /// The generation of the notices arriving (the last [`Notice::Replaced`] seen).
    notice_generation: u64,
    /// The status bar's message (undo, redo, the end of a time range).
    note: Option<String>,
    /// How many lines at the end of the log are a drag's progress lines
    /// ([`Notice::Progress`]), each the latest of its tool.
    progress_lines: usize,
    /// The tool symmetry (sent to the worker with each press).
    pub symmetry: Symmetry,
    /// The surface under the mouse (brush tools).
    hover: Option<SurfaceHit>,
    /// The control point under the mouse (handles shown).
    hovered_handle: Option<Vec3>,
    /// The mouse in the viewport.
    pointer: Option<Pos2>,
    /// The ground grid (placed when the camera frames the model).
    grid: Option<Grid>,
}

impl std::fmt::Debug for Studio {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Studio")
            .field("file", &self.file)
            .field("tool", &self.tool)
            .finish()
    }
}

/// The default autosave file: beside `file`, else in the user's data folder.
pub fn default_autosave(file: Option<&Path>) -> PathBuf {
    if let Some(f) = file {
        let name = f
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_else(|| "vclay".into());
        return f.with_file_name(format!(".{name}.autosave.session"));
    }
    let base = std::env::var_os("XDG_DATA_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".local/share")))
        .unwrap_or_else(std::env::temp_dir);
    base.join("vclay").join("studio-autosave.session")
}

/// `p` made absolute (against the working folder); `p` itself if that fails.
fn absolute(p: &Path) -> PathBuf {
    std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf())
}

fn modified(p: &Path) -> Option<SystemTime> {
    std::fs::metadata(p).and_then(|m| m.modified()).ok()
}

impl Studio {
    /// A studio: opens `options.file` (an error shows in a dialog and the start page opens).
    pub fn new(options: Options) -> Self {
        let mut s = Self {
            worker: None,
            frame: Frame::default(),
            scene: Arc::new(SceneBuffers::default()),
            gl: Arc::new(Mutex::new(None)),
            camera: Camera::default(),
            layers: Layers::default(),
            colour_by: None,
            colour_chosen: false,
            tool: Tool::Orbit,
            options: ToolOptions::default(),
            file: None,
            autosave: None,
            opts: options.clone(),
            dialog: None,
            log: VecDeque::new(),
            energy: Vec::new(),
            energy_y_range: None,
            frame_log: None,
            press: None,
            ffd_pins: Vec::new(),
            pin_pending: false,
            fitted: false,
            edits: BTreeMap::new(),
            frame_times: VecDeque::new(),
            allow_close: false,
            shots: Arc::new(Mutex::new(Vec::new())),
            tools: Vec::new(),
            pde_t: 0.0,
            recent: crate::recent::load(options.recent.as_deref()),
            recent_file: options.recent.clone(),
            viewport: Rect::NOTHING,
            after_save: None,
            generation: 0,
            notice_generation: 0,
            note: None,
            progress_lines: 0,
            symmetry: Symmetry::default(),
            hover: None,
            hovered_handle: None,
            pointer: None,
            grid: None,
        };
        if let Some(f) = &options.file
            && let Err(e) = s.open_file(f)
        {
            s.dialog = Some(Dialog::Error(e));
        }
        if !options.no_recovery && s.dialog.is_none() {
            let auto = options
                .autosave
                .clone()
                .unwrap_or_else(|| default_autosave(options.file.as_deref()));
            let newer = match (modified(&auto), options.file.as_deref().and_then(modified)) {
                (Some(a), Some(f)) => a > f,
                (Some(_), None) => true,
                _ => false,
            };
            if newer {
                s.dialog = Some(Dialog::Recover(auto));
            }
        }
        s
    }

    /// Opens `path` (any file vclay reads, [`load::open`]) as the session, and puts it first in
    /// the recent files.
    pub fn open_file(&mut self, path: &Path) -> Result<(), String> {
        let o = load::open(path)?;
        self.set_opened(o, Some(path.to_path_buf()));
        self.recent = crate::recent::remember(self.recent_file.as_deref(), path);
        Ok(())
    }

    /// The recently opened files, newest first.
    pub fn recent(&self) -> &[PathBuf] {
        &self.recent
    }

    /// Replaces the session with an opened file's: a scenario's run stops at its end step
    /// (the status line says so; Run continues past it).
    pub fn set_opened(&mut self, opened: vclay_session::Opened, file: Option<PathBuf>) {
        let end = opened.run.as_ref().map(|r| r.end_step);
        let now = opened.session.model(None).map_or(0, |m| m.steps());
        self.set_session(opened.session, file);
        if let Some(end) = end.filter(|&e| e > now) {
            self.send(Request::StopAt(Some(end)));
        }
        self.send(Request::RunInfo(opened.run.map(Box::new)));
    }

    /// Replaces the session (a new simulation thread if none runs).
    pub fn set_session(&mut self, session: Session, file: Option<PathBuf>) {
        self.tools = session.model(None).map(|m| m.tools()).unwrap_or_default();
        self.tool = Tool::palette(&self.tools)[0];
        // A PDE surface's time waits for Run (its shape at t = 0 is the model).
        let pde = takes(&self.tools, "pde-set", None);
        let running = !self.opts.paused && !pde;
        match &self.worker {
            Some(w) => {
                // The session replaced was saved, discarded or unchanged: nothing to recover.
                w.send(Request::DiscardAutosave);
                w.send(Request::Replace(Box::new(session)));
                w.send(Request::Run(running));
                self.generation += 1;
            }
            None => {
                self.worker = Some(Worker::start(session, running));
                self.generation = 0;
                self.notice_generation = 0;
            }
        }
        self.send(Request::TimeLimit(pde.then_some(PDE_T_MAX)));
        self.send(Request::StopAt(None));
        self.reset_view_state();
        self.file = file;
        let auto = self
            .opts
            .autosave
            .clone()
            .unwrap_or_else(|| default_autosave(self.file.as_deref()));
        if let Some(dir) = auto.parent() {
            let _ = std::fs::create_dir_all(dir);
        }
        self.send(Request::Autosave(Some(auto.clone()), AUTOSAVE_INTERVAL));
        self.autosave = Some(auto);
        self.fitted = false;
        self.energy.clear();
        self.edits.clear();
        self.press = None;
        self.frame = Frame::default();
    }

    /// Forgets what belonged to the previous session: log, energy plot, grab, pins, pending
    /// slider values; the next frame fits the camera.
    fn reset_view_state(&mut self) {
        self.frame = Frame::default();
        self.log.clear();
        self.progress_lines = 0;
        self.energy.clear();
        self.press = None;
        self.ffd_pins.clear();
        self.pin_pending = false;
        self.edits.clear();
        self.fitted = false;
        self.pde_t = 0.0;
        self.note = None;
        self.hover = None;
        self.hovered_handle = None;
        self.grid = None;
        self.scene = Arc::new(SceneBuffers::default());
    }

    /// The simulation thread's handle (tests and the benchmark query the session through it).
    pub fn worker(&self) -> Option<&Worker> {
        self.worker.as_ref()
    }

    /// The last frame received.
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// The viewport's rectangle in the last frame (screen points).
    pub fn viewport(&self) -> Rect {
        self.viewport
    }

    /// The error shown in a dialog, if any.
    pub fn error(&self) -> Option<&str> {
        match &self.dialog {
            Some(Dialog::Error(e)) => Some(e),
            _ => None,
        }
    }

    /// Log lines, oldest first.
    pub fn log(&self) -> impl Iterator<Item = &String> {
        self.log.iter()
    }

    /// The energy plot's samples `(time, kinetic, elastic)`, oldest first.
    pub fn energy_samples(&self) -> &[[f64; 3]] {
        &self.energy
    }

    /// The energy plot's y range `[min, max]` as last drawn (`None` before the first draw).
    pub fn energy_y_range(&self) -> Option<[f64; 2]> {
        self.energy_y_range
    }

    /// The status bar's message (undo and redo results, a run stopped at the end of the time
    /// range).
    pub fn note(&self) -> Option<&str> {
        self.note.as_deref()
    }

    /// The title of the dialog shown, if any.
    pub fn dialog_title(&self) -> Option<&'static str> {
        self.dialog.as_ref().map(|d| match d {
            Dialog::Error(_) => "Error",
            Dialog::Open(_) => "Open",
            Dialog::SaveAs(_) => "Save session as",
            Dialog::Export(_) => "Export the model",
            Dialog::Screenshot(_) => "Screenshot (PNG)",
            Dialog::Recover(_) => "Recover?",
            Dialog::Unsaved(_) => "Unsaved changes",
            Dialog::Help => "Help",
            Dialog::Native { purpose, .. } => purpose.title(),
        })
    }

    /// Whether the session has changes not saved explicitly.
    pub fn dirty(&self) -> bool {
        self.frame.dirty
    }

    fn send(&self, r: Request) {
        if let Some(w) = &self.worker {
            w.send(r);
        }
    }

    fn push_log(&mut self, l: String) {
        self.progress_lines = 0;
        self.push_line(l);
    }

    fn push_line(&mut self, l: String) {
        self.log.push_back(crate::text::round_numbers(&l));
        while self.log.len() > LOG_LINES {
            self.log.pop_front();
        }
        self.progress_lines = self.progress_lines.min(self.log.len());
    }

    /// A [`Notice::Progress`] line: it replaces the line of the same tool among the run of
    /// progress lines at the end of the log (the text before its last `[` names the tool and
    /// the point: "rope `studio-rope` cursor at", "moved control point 12 to"), else it is
    /// added to the run.
    fn push_progress(&mut self, l: String) {
        let key = |s: &str| s[..s.rfind('[').unwrap_or(s.len())].to_string();
        let k = key(&l);
        let n = self.log.len();
        let same = (n - self.progress_lines..n)
            .rev()
            .find(|&i| key(&self.log[i]) == k);
        match same {
            Some(i) => self.log[i] = crate::text::round_numbers(&l),
            None => {
                self.push_line(l);
                self.progress_lines += 1;
            }
        }
    }

    fn model_name(&self) -> Option<String> {
        self.frame.models.first().map(|m| m.name.clone())
    }

    fn apply(&self, edit: Edit) {
        if let Some(m) = self.model_name() {
            self.send(Request::Apply(Command::to(&m, edit)));
        }
    }

    /// Polls the worker: frames and notices (those of a replaced session are dropped).
    fn poll(&mut self, ctx: &egui::Context) {
        let Some(w) = &self.worker else { return };
        let notices = w.notices();
        let frame = w.take_frame().filter(|f| f.generation == self.generation);
        for n in notices {
            if let Notice::Replaced(g) = n {
                self.notice_generation = g;
            } else if self.notice_generation == self.generation {
                self.notice(ctx, n);
            }
            // Else it belongs to a session already replaced.
        }
        if let Some(f) = frame {
            self.take_frame(f);
            ctx.request_repaint();
        }
    }

    /// Handles one notice of the worker.
    fn notice(&mut self, ctx: &egui::Context, n: Notice) {
        match n {
            Notice::Log(l) => self.push_log(l),
            Notice::Progress(l) => self.push_progress(l),
            Notice::Status(l) => {
                // The status line reads like the log: numbers rounded.
                self.note = Some(crate::text::round_numbers(&l));
                self.push_log(l);
            }
            Notice::Replaced(_) => {}
            Notice::Error { message, .. } => {
                self.push_log(format!("error: {message}"));
                self.dialog = Some(Dialog::Error(message));
                self.press = None;
                // A failed save does not go on to what waited for it.
                self.after_save = None;
            }
            Notice::Grabbed { point, .. } if self.pin_pending => {
                self.pin_pending = false;
                self.ffd_pins.push(point);
                self.press = None;
            }
            Notice::Grabbed { point, .. } => {
                if self.press == Some(Press::Waiting) {
                    self.press = Some(Press::Grabbed(point));
                }
            }
            Notice::Missed => {
                if self.press == Some(Press::Waiting) {
                    self.press = Some(Press::Orbit);
                }
            }
            Notice::Saved(p) => {
                self.push_log(format!("saved {}", p.display()));
                self.file = Some(p);
                if let Some(then) = self.after_save.take() {
                    self.proceed(ctx, then);
                }
            }
            Notice::Autosaved(_) => {}
        }
    }

    /// Shows a frame of the current session.
    fn take_frame(&mut self, f: Frame) {
        self.energy.extend_from_slice(&f.samples);
        if self.energy.len() > crate::worker::ENERGY_SAMPLES {
            let cut = self.energy.len() - crate::worker::ENERGY_SAMPLES;
            self.energy.drain(..cut);
        }
        self.frame = f;
        if let Some(m) = self.frame.models.first()
            && takes(&m.tools, "pde-set", None)
        {
            self.pde_t = m.time;
        }
        self.rebuild_scene();
        if !self.fitted && !self.frame.models.is_empty() {
            self.fit();
            self.fitted = true;
        }
    }

    fn rebuild_scene(&mut self) {
        let grid = self.grid.filter(|_| self.layers.grid);
        self.scene = Arc::new(SceneBuffers::build(&self.frame, &self.layers).with_grid(grid));
    }

    /// Fits the camera to the scene (the ground grid moves under it).
    pub fn fit(&mut self) {
        if let Some((lo, hi)) = self.scene.bounds {
            self.camera.fit(lo, hi);
            self.grid = Grid::under(lo, hi);
            self.rebuild_scene();
        }
    }

    fn model_size(&self) -> f64 {
        self.frame
            .models
            .iter()
            .map(|m| m.size)
            .fold(0.0, f64::max)
            .max(1e-9)
    }

    /// Appends a line to the `--frame-log` file once a second (see [`Options::frame_log`]).
    /// A file that cannot be written is reported once in the log and then left alone.
    fn write_frame_log(&mut self, now: Instant) {
        use std::io::Write;
        if self.frame_log.is_none()
            && let Some(p) = self.opts.frame_log.take()
        {
            let opened = std::fs::File::create(&p).and_then(|mut f| {
                writeln!(
                    f,
                    "# wall_s frames_per_s sim_t steps steps_per_s step_ms display_ms triangles"
                )?;
                Ok(f)
            });
            match opened {
                Ok(f) => self.frame_log = Some((f, now, now)),
                Err(e) => self.push_log(format!("frame log {}: {e}", p.display())),
            }
        }
        let Some((f, last, start)) = &mut self.frame_log else {
            return;
        };
        if now.duration_since(*last) < Duration::from_secs(1) {
            return;
        }
        *last = now;
        let line = format!(
            "{:.2} {} {:.4} {} {:.1} {:.3} {:.3} {}",
            now.duration_since(*start).as_secs_f64(),
            self.frame_times.len(),
            self.frame.time,
            self.frame.steps,
            self.frame.steps_per_second,
            self.frame.step_seconds * 1e3,
            self.frame.build_seconds * 1e3,
            self.scene.tri_indices.len() / 3
        );
        if let Err(e) = writeln!(f, "{line}") {
            self.frame_log = None;
            self.push_log(format!("frame log: {e}"));
        }
    }

    /// Draws one frame of the whole window.
    pub fn show(&mut self, ui: &mut Ui) {
        let ctx = ui.ctx().clone();
        if let Some(w) = &self.worker {
            let c = ctx.clone();
            w.set_wake(move || c.request_repaint());
        }
        self.poll(&ctx);
        let now = Instant::now();
        self.frame_times.push_back(now);
        while self
            .frame_times
            .front()
            .is_some_and(|t| now.duration_since(*t) > Duration::from_secs(1))
        {
            self.frame_times.pop_front();
        }
        self.write_frame_log(now);
        self.shortcuts(&ctx);
        self.handle_close(&ctx);
        self.handle_screenshot();

        egui::Panel::top("menu").show(ui, |ui| self.menu(ui));
        egui::Panel::bottom("status").show(ui, |ui| self.status(ui));
        if self.worker.is_some() {
            egui::Panel::left("tools")
                .default_size(230.0)
                .show(ui, |ui| {
                    egui::ScrollArea::vertical().show(ui, |ui| self.tools_panel(ui));
                });
            egui::Panel::right("plot")
                .default_size(260.0)
                .show(ui, |ui| self.plot_panel(ui));
            egui::CentralPanel::default().show(ui, |ui| self.viewport_ui(ui));
        } else {
            egui::CentralPanel::default().show(ui, |ui| self.start_page(ui));
        }
        self.dialogs(&ctx);
        if self.frame.running || self.press.is_some() {
            // The worker wakes us with each new frame; this keeps the frame-rate figure alive.
            ctx.request_repaint_after(Duration::from_millis(250));
        }
    }

    fn handle_close(&mut self, ctx: &egui::Context) {
        if !ctx.input(|i| i.viewport().close_requested()) {
            return;
        }
        if self.dirty() && !self.allow_close {
            ctx.send_viewport_cmd(egui::ViewportCommand::CancelClose);
            self.dialog = Some(Dialog::Unsaved(Then::Quit));
        } else {
            self.clean_exit();
        }
    }

    /// A deliberate exit: the autosave file goes (nothing to recover next time). The worker
    /// deletes it before it stops (requests are handled in order).
    fn clean_exit(&mut self) {
        self.send(Request::DiscardAutosave);
    }

    /// Quits now (the user has saved or discarded the changes).
    fn quit(&mut self, ctx: &egui::Context) {
        self.allow_close = true;
        self.clean_exit();
        ctx.send_viewport_cmd(egui::ViewportCommand::Close);
    }

    /// Asks about unsaved changes before `then`, or does it at once when there are none.
    fn confirm(&mut self, ctx: &egui::Context, then: Then) {
        if self.worker.is_some() && self.dirty() {
            self.dialog = Some(Dialog::Unsaved(then));
        } else {
            self.proceed(ctx, then);
        }
    }

    /// Does what waited for the unsaved-changes prompt (the prompt answered, or the save done).
    fn proceed(&mut self, ctx: &egui::Context, then: Then) {
        self.after_save = None;
        match then {
            Then::Open => self.ask_path(PathPurpose::Open, String::new()),
            Then::OpenRecent(k) => {
                if let Some(p) = self.recent.get(k).cloned()
                    && let Err(e) = self.open_file(&p)
                {
                    self.dialog = Some(Dialog::Error(e));
                }
            }
            Then::StartPage => self.close_session(),
            Then::Quit => self.quit(ctx),
        }
    }

    /// Closes the session (its autosave goes: the user chose to leave it) and shows the start
    /// page.
    fn close_session(&mut self) {
        self.clean_exit();
        self.worker = None;
        self.file = None;
        self.tools.clear();
        self.reset_view_state();
    }

    fn handle_screenshot(&mut self) {
        let done: Vec<Result<PathBuf, String>> = match self.shots.lock() {
            Ok(mut v) => v.drain(..).collect(),
            Err(_) => Vec::new(),
        };
        for r in done {
            match r {
                Ok(p) => self.push_log(format!("screenshot {}", p.display())),
                Err(e) => self.dialog = Some(Dialog::Error(e)),
            }
        }
    }

    /// Requests a screenshot of the window into `path` (a PNG written when the image arrives).
    pub fn screenshot(&mut self, ctx: &egui::Context, path: PathBuf) {
        let shots = self.shots.clone();
        let c = ctx.clone();
        let cb = egui::ScreenshotCallback::new(move |img| {
            let r = write_png(&path, &img).map(|()| path);
            if let Ok(mut v) = shots.lock() {
                v.push(r);
            }
            c.request_repaint();
        });
        ctx.send_viewport_cmd(egui::ViewportCommand::Screenshot(cb));
    }

    /// Asks for a path: the desktop's file chooser when there is one ([`crate::native`]),
    /// else the typed-path dialog starting at `start`.
    fn ask_path(&mut self, purpose: PathPurpose, start: String) {
        self.dialog = Some(match &self.opts.chooser {
            Some(c) => {
                let native = if purpose == PathPurpose::Open {
                    crate::native::Purpose::Open
                } else {
                    crate::native::Purpose::Save
                };
                let from = match (&self.file, purpose) {
                    (Some(f), PathPurpose::Open) => {
                        f.parent().map(|d| d.join("")).unwrap_or_default()
                    }
                    _ => PathBuf::from(&start),
                };
                Dialog::Native {
                    purpose,
                    answer: c.ask(native, purpose.title(), &from),
                    typed: start,
                }
            }
            None => purpose.typed(start),
        });
    }

    /// Does what a path dialog was for once it is answered: opens, saves, exports or takes
    /// the screenshot on Submit; on Cancel a save that something waited for is dropped.
    /// Returns the next dialog (an error).
    fn path_answered(
        &mut self,
        ctx: &egui::Context,
        purpose: PathPurpose,
        answer: Option<Answer>,
        path: &str,
    ) -> Option<Dialog> {
        match answer {
            Some(Answer::Submit) => match purpose {
                PathPurpose::Open => {
                    // A relative path is read from the folder the dialog names (the opened
                    // file's), not from wherever the studio was started.
                    let path = self.open_folder().join(path.trim());
                    if let Err(e) = self.open_file(&path) {
                        return Some(Dialog::Error(e));
                    }
                }
                PathPurpose::SaveAs => self.send(Request::Save(PathBuf::from(path))),
                PathPurpose::Export => {
                    if let Some(m) = self.model_name() {
                        self.send(Request::Export {
                            model: m,
                            path: PathBuf::from(path),
                        });
                    }
                }
                PathPurpose::Screenshot => self.screenshot(ctx, PathBuf::from(path)),
            },
            Some(_) if purpose == PathPurpose::SaveAs => {
                // Cancelled: what waited for the save does not happen.
                self.after_save = None;
            }
            _ => {}
        }
        None
    }

    fn save_as(&mut self) {
        self.ask_path(PathPurpose::SaveAs, self.suggestion("session"));
    }

    fn save(&mut self) {
        match &self.file {
            Some(f) if load::is_session_file(f) => self.send(Request::Save(f.clone())),
            _ => self.ask_path(PathPurpose::SaveAs, self.suggestion("session")),
        }
    }

    /// The folder the Open dialog reads a relative path from: the opened file's, else the
    /// working folder (absolute either way, so that the dialog can say which).
    pub fn open_folder(&self) -> PathBuf {
        let dir = self
            .file
            .as_deref()
            .and_then(Path::parent)
            .filter(|d| !d.as_os_str().is_empty())
            .map(Path::to_path_buf)
            .unwrap_or_else(|| std::env::current_dir().unwrap_or_default());
        absolute(&dir)
    }

    /// An absolute path with extension `ext` for a save dialog: beside the opened file, else
    /// in the working folder named after the model.
    fn suggestion(&self, ext: &str) -> String {
        let p = match &self.file {
            Some(f) => f.with_extension(ext),
            None => PathBuf::from(format!(
                "{}.{ext}",
                self.model_name().unwrap_or_else(|| "model".into())
            )),
        };
        absolute(&p).display().to_string()
    }

    fn menu(&mut self, ui: &mut Ui) {
        let ctx = ui.ctx().clone();
        ui.horizontal(|ui| {
            ui.menu_button("File", |ui| {
                if ui.button("Open...").clicked() {
                    self.confirm(&ctx, Then::Open);
                }
                let recent: Vec<String> = self
                    .recent
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect();
                ui.add_enabled_ui(!recent.is_empty(), |ui| {
                    ui.menu_button("Open recent", |ui| {
                        for (k, label) in recent.iter().enumerate() {
                            if ui.button(label).clicked() {
                                self.confirm(&ctx, Then::OpenRecent(k));
                            }
                        }
                    });
                });
                if ui.button("Start page").clicked() {
                    self.confirm(&ctx, Then::StartPage);
                }
                ui.separator();
                let has = self.worker.is_some();
                if ui.add_enabled(has, egui::Button::new("Save")).clicked() {
                    self.save();
                }
                if ui
                    .add_enabled(has, egui::Button::new("Save as..."))
                    .clicked()
                {
                    self.save_as();
                }
                if ui
                    .add_enabled(has, egui::Button::new("Export..."))
                    .clicked()
                {
                    self.ask_path(PathPurpose::Export, self.suggestion("obj"));
                }
                if ui.button("Screenshot...").clicked() {
                    self.ask_path(PathPurpose::Screenshot, self.suggestion("png"));
                }
                ui.separator();
                if ui.button("Quit").clicked() {
                    ui.ctx().send_viewport_cmd(egui::ViewportCommand::Close);
                }
            });
            ui.menu_button("Edit", |ui| {
                if ui
                    .add_enabled(self.frame.can_undo, egui::Button::new("Undo (Ctrl+Z)"))
                    .clicked()
                {
                    self.send(Request::Undo);
                }
                if ui
                    .add_enabled(
                        self.frame.can_redo,
                        egui::Button::new("Redo (Ctrl+Shift+Z)"),
                    )
                    .clicked()
                {
                    self.send(Request::Redo);
                }
            });
            ui.menu_button("View", |ui| self.view_buttons(ui));
            ui.separator();
            if self.worker.is_some() {
                self.view_buttons(ui);
            }
        });
    }

    fn view_buttons(&mut self, ui: &mut Ui) {
        if ui.button("Fit").clicked() {
            self.fit();
        }
        for (label, v) in [
            ("Front", View::Front),
            ("Top", View::Top),
            ("Side", View::Side),
            ("Iso", View::Iso),
        ] {
            if ui.button(label).clicked() {
                self.camera.set_view(v);
            }
        }
        let before = self.layers;
        ui.checkbox(&mut self.layers.shaded, "Shaded");
        ui.checkbox(&mut self.layers.wireframe, "Wireframe");
        ui.checkbox(&mut self.layers.control_net, "Control net");
        ui.checkbox(&mut self.layers.data_points, "Data points");
        ui.checkbox(&mut self.layers.grid, "Grid");
        self.colour_ui(ui);
        if ui.button("Help (F1)").clicked() {
            self.dialog = Some(Dialog::Help);
        }
        if before != self.layers {
            self.rebuild_scene();
        }
    }

    fn start_page(&mut self, ui: &mut Ui) {
        ui.heading("vclay studio");
        ui.label("Physics-based free-form modeling. Open a built-in model:");
        ui.add_space(8.0);
        let mut chosen = None;
        for b in &load::BUILTINS {
            if ui.button(b.title).clicked() {
                chosen = Some(*b);
            }
        }
        ui.add_space(8.0);
        // What the session layer opens, in its own words (one way in for every file).
        ui.add(
            egui::Label::new(format!(
                "Or File > Open: {}.",
                vclay_session::open::openable()
            ))
            .wrap(),
        );
        if let Some(b) = chosen {
            self.open_builtin(&b);
        }
    }

    /// Opens a built-in model by value.
    pub fn open_builtin(&mut self, b: &load::Builtin) {
        match load::builtin(b) {
            Ok(s) => self.set_session(s, None),
            Err(e) => self.dialog = Some(Dialog::Error(e)),
        }
    }

    fn tools_panel(&mut self, ui: &mut Ui) {
        ui.heading("Tools");
        let tools = Tool::palette(&self.tools);
        ui.horizontal_wrapped(|ui| {
            for t in tools {
                let key = crate::keys::tool_key(t).name();
                ui.selectable_value(&mut self.tool, t, format!("{} ({key})", t.label()))
                    .on_hover_text(format!("key {key}"));
            }
        });
        self.symmetry_ui(ui);
        let o = &mut self.options;
        match self.tool {
            Tool::Rope => {
                ui.add(
                    egui::Slider::new(&mut o.rope_stiffness, 0.0..=500.0)
                        .text("stiffness (0: default)"),
                );
                ui.small("Drag on the model; Alt+drag moves along the view direction.");
            }
            Tool::Force => {
                ui.add(egui::Slider::new(&mut o.force, 0.0..=500.0).text("strength"));
                ui.add(egui::Slider::new(&mut o.radius, 0.01..=1.0).text("radius (x size)"));
                ui.add(egui::Slider::new(&mut o.duration, 0.01..=2.0).text("duration (s)"));
                ui.checkbox(&mut o.pull, "pull (towards the viewer)");
                // The falloff choices come from the model's tool description.
                if let Some(k) = self
                    .tools
                    .iter()
                    .filter(|t| t.action == "region-force")
                    .flat_map(|t| t.keys.iter())
                    .find(|k| k.name == "falloff" && !k.choices.is_empty())
                {
                    egui::ComboBox::from_label("falloff")
                        .selected_text(o.falloff)
                        .show_ui(ui, |ui| {
                            for c in k.choices {
                                ui.selectable_value(&mut o.falloff, c, *c);
                            }
                        });
                }
            }
            Tool::FfdPoint => {
                ui.small("Drag a point of the object: it goes exactly where the mouse is (eq 7). Ctrl+click pins points that stay in place while you drag another (eq 12).");
                ui.horizontal(|ui| {
                    ui.label(format!("{} pinned", self.ffd_pins.len()));
                    if ui.button("Clear pins").clicked() {
                        self.ffd_pins.clear();
                    }
                });
            }
            Tool::PdeLocal => {
                ui.add(egui::Slider::new(&mut o.local[0], 0.02..=0.5).text("half-width along u"));
                ui.add(egui::Slider::new(&mut o.local[1], 0.02..=3.0).text("half-width along v"));
                ui.small("Drag a point of the surface: a G1 local deformation (eq 32) around it follows the mouse; each drag adds one (undo removes it).");
            }
            Tool::ControlPoint => {
                ui.add(
                    egui::Slider::new(&mut o.weight, 0.05..=20.0)
                        .logarithmic(true)
                        .text("weight"),
                );
                ui.small("Drag a control point to move it; Ctrl+click one to give it this weight.");
            }
            Tool::Smooth => {
                ui.add(egui::Slider::new(&mut o.brush, 0.0..=0.5).text("brush (x size; 0: click)"));
                ui.add(egui::Slider::new(&mut o.smooth, 0.05..=1.0).text("strength"));
                ui.small("Drag over bumps: the rest shape under the brush is faired and the clay settles to it while it runs.");
            }
            Tool::Fix | Tool::Free => {
                ui.add(egui::Slider::new(&mut o.brush, 0.0..=0.5).text("brush (x size; 0: click)"));
                ui.small("With a brush, drag to fix or free every control point it passes.");
            }
            Tool::Paint => {
                ui.add(egui::Slider::new(&mut o.brush, 0.0..=0.5).text("brush (x size; 0: click)"));
                ui.add(egui::Slider::new(&mut o.paint[0], 0.01..=100.0).text("density"));
                ui.add(egui::Slider::new(&mut o.paint[1], 0.0..=100.0).text("damping"));
                ui.add(
                    egui::Slider::new(&mut o.paint[2], 0.0..=10_000.0)
                        .logarithmic(true)
                        .text("edge stiffness"),
                );
                // Painting shows what it paints (unless a colouring was chosen in View).
                if !self.colour_chosen && self.colour_by.is_none() {
                    self.set_colour_by(Some("edge-stiffness"));
                }
            }
            _ => {}
        }
        self.simulation_ui(ui);
        ui.separator();
        ui.heading("Parameters");
        self.params_ui(ui);
    }

    /// The simulation section: run, step, integrator, gravity, inflation, speed, PDE time.
    fn simulation_ui(&mut self, ui: &mut Ui) {
        ui.separator();
        ui.heading("Simulation");
        ui.horizontal(|ui| {
            let running = self.frame.running;
            if ui.button(if running { "Pause" } else { "Run" }).clicked() {
                self.run_clicked(running);
            }
            if ui.button("Step").clicked() {
                self.send(Request::Step(1));
            }
            if ui.button("Stop motion").clicked() {
                self.apply(Edit::Stop);
            }
        });
        let physical = takes(&self.tools, "plastic-reset", None);
        if takes(&self.tools, "integrator", Some("integrator")) {
            // The integrator of journal section 4.4 (explicit), symplectic Euler, or the
            // implicit Euler with conjugate gradient; the time step is a parameter below.
            let mut chosen = self.options.integrator;
            egui::ComboBox::from_label("integrator")
                .selected_text(INTEGRATORS[chosen])
                .show_ui(ui, |ui| {
                    for (k, name) in INTEGRATORS.iter().enumerate() {
                        ui.selectable_value(&mut chosen, k, *name);
                    }
                });
            if chosen != self.options.integrator {
                self.options.integrator = chosen;
                self.apply(Edit::Integrator {
                    integrator: Some(INTEGRATORS[chosen].to_string()),
                    dt: None,
                });
            }
        }
        if physical {
            ui.horizontal(|ui| {
                if ui
                    .checkbox(&mut self.options.sculpt, "Sculpt (K)")
                    .on_hover_text(
                        "on: what you pull stays (the shape at the end of each pull becomes the \
                     rest shape and the motion stops, or the clay yields as you pull with plastic \
                     flow); off: elastic clay that springs back",
                    )
                    .changed()
                {
                    self.send(Request::Sculpt(self.options.sculpt));
                }
                if ui.button("Plastic reset").clicked() {
                    self.apply(Edit::PlasticReset);
                }
            });
            if self.options.sculpt {
                self.flow_ui(ui);
            }
            let (mut on, mut g) = self.options.gravity;
            let c1 = ui.checkbox(&mut on, "Gravity").changed();
            let r = ui.add(egui::Slider::new(&mut g, 0.0..=50.0).text("g"));
            let c2 = on && (r.drag_stopped() || (r.changed() && !r.dragged()));
            self.options.gravity = (on, g);
            if c1 || c2 {
                self.apply(if on {
                    Edit::Gravity {
                        name: Some("studio-gravity".into()),
                        g: [0.0, 0.0, -g],
                        until: None,
                    }
                } else {
                    Edit::Release {
                        name: "studio-gravity".into(),
                    }
                });
            }
            if takes(&self.tools, "inflate", None) {
                let (mut on, mut p) = self.options.inflate;
                let c1 = ui.checkbox(&mut on, "Inflation").changed();
                let r = ui.add(egui::Slider::new(&mut p, -50.0..=50.0).text("pressure"));
                let c2 = on && (r.drag_stopped() || (r.changed() && !r.dragged()));
                self.options.inflate = (on, p);
                if c1 || c2 {
                    self.apply(if on {
                        Edit::Inflate {
                            name: Some("studio-inflate".into()),
                            pressure: p,
                            until: None,
                        }
                    } else {
                        Edit::Release {
                            name: "studio-inflate".into(),
                        }
                    });
                }
            }
        }
        let mut speed = 1.0_f64;
        ui.horizontal(|ui| {
            ui.label("Speed:");
            for (l, s) in [("real time", 1.0), ("0.25x", 0.25), ("max", 0.0)] {
                if ui.button(l).clicked() {
                    speed = s;
                    self.send(Request::Speed(s));
                }
            }
        });
        let _ = speed;
        if takes(&self.tools, "pde-set", None) {
            self.pde_time_ui(ui);
        }
    }

    /// Run or pause; Run at the end of a PDE surface's time range starts it over from 0.
    fn run_clicked(&mut self, running: bool) {
        if !running
            && let Some(m) = self.frame.models.first()
            && takes(&m.tools, "pde-set", None)
            && m.time + m.dt > PDE_T_MAX
        {
            self.apply(Edit::PdeSet {
                name: "t".into(),
                value: 0.0,
            });
        }
        self.send(Request::Run(!running));
    }

    /// A PDE surface's time: a slider over `[0, PDE_T_MAX]`; a run stops at its end.
    fn pde_time_ui(&mut self, ui: &mut Ui) {
        let mut t = self.pde_t;
        let r = ui.add(egui::Slider::new(&mut t, 0.0..=PDE_T_MAX).text("time t"));
        self.pde_t = t;
        if r.drag_stopped() || (r.changed() && !r.dragged()) {
            self.apply(Edit::PdeSet {
                name: "t".into(),
                value: t,
            });
        }
        ui.small(format!(
            "Run plays t up to {PDE_T_MAX} and stops there; Run again starts over from 0."
        ));
    }

    fn params_ui(&mut self, ui: &mut Ui) {
        let Some(m) = self.frame.models.first().cloned() else {
            return;
        };
        ui.label(egui::RichText::new(&m.summary).small());
        for p in &m.params {
            let mut v = *self.edits.get(&p.name).unwrap_or(&p.value);
            let (lo, hi) = (p.min.min(v), p.max.max(v));
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                continue;
            }
            let log = lo > 0.0 && hi / lo > 100.0;
            let r = ui
                .add(
                    egui::Slider::new(&mut v, lo..=hi)
                        .logarithmic(log)
                        .text(&p.name),
                )
                .on_hover_text(&p.doc);
            if r.changed() {
                self.edits.insert(p.name.clone(), v);
            }
            if r.drag_stopped() || (r.changed() && !r.dragged()) {
                self.edits.remove(&p.name);
                // Every listed parameter (PDE boundary constants included) takes `set`.
                let edit = Edit::Set {
                    name: p.name.clone(),
                    value: v,
                };
                self.send(Request::Apply(Command::to(&m.name, edit)));
            }
        }
    }

    fn plot_panel(&mut self, ui: &mut Ui) {
        ui.heading("Energy");
        let kin: egui_plot::PlotPoints<'_> = self.energy.iter().map(|s| [s[0], s[1]]).collect();
        let ela: egui_plot::PlotPoints<'_> = self.energy.iter().map(|s| [s[0], s[2]]).collect();
        let (size, dt) = self
            .frame
            .models
            .first()
            .map_or((1.0, 1.0), |m| (m.size, m.dt));
        // The time axis spans at least one step: with the y floor below, a single sample would
        // otherwise give egui_plot bounds of zero width (which it rejects).
        let t0 = self.energy.first().map_or(self.frame.time, |s| s[0]);
        let t1 = self.energy.last().map_or(t0, |s| s[0]);
        let step = if dt.is_finite() && dt > 0.0 { dt } else { 1.0 };
        let shown = egui_plot::Plot::new("energy")
            .include_x(t0)
            .include_x(t1.max(t0 + step))
            .height(200.0)
            .legend(egui_plot::Legend::default())
            // A model at rest has energies of rounding size (1e-28); autoscaled alone they
            // would fill the plot as spikes. The axis always reaches the noise floor.
            .include_y(0.0)
            .include_y(ENERGY_PLOT_FLOOR * size * size)
            .show(ui, |p| {
                p.line(egui_plot::Line::new("kinetic", kin));
                p.line(egui_plot::Line::new("elastic", ela));
            });
        let b = shown.transform.bounds();
        self.energy_y_range = Some([b.min()[1], b.max()[1]]);
        ui.label(format!(
            "kinetic {:.4e}  elastic {:.4e}",
            self.frame.energy.kinetic, self.frame.energy.elastic
        ));
        ui.separator();
        ui.heading("Log");
        egui::ScrollArea::vertical()
            .stick_to_bottom(true)
            .show(ui, |ui| {
                for l in &self.log {
                    ui.label(egui::RichText::new(l).small());
                }
            });
    }

    fn status(&mut self, ui: &mut Ui) {
        ui.horizontal(|ui| {
            let fps = self.frame_times.len();
            ui.label(format!("{fps} frames/s"));
            ui.separator();
            ui.label(format!(
                "t = {:.4}  steps {}  {:.0} steps/s  step {:.2} ms  display {:.1} ms",
                self.frame.time,
                self.frame.steps,
                self.frame.steps_per_second,
                self.frame.step_seconds * 1e3,
                self.frame.build_seconds * 1e3
            ));
            ui.separator();
            ui.label(format!("{} triangles", self.scene.tri_indices.len() / 3));
            if self.symmetry.any() {
                ui.separator();
                ui.label(format!("symmetry {}", self.symmetry.label()));
            }
            if self.frame.scheduled > 0 {
                ui.separator();
                ui.label(format!("{} scheduled", self.frame.scheduled));
            }
            if self.frame.dirty {
                ui.separator();
                ui.label("modified");
            }
            if let Some(n) = &self.note {
                ui.separator();
                ui.label(n);
            }
            if let Some(f) = &self.file {
                ui.separator();
                ui.label(f.display().to_string());
            }
        });
    }

    fn viewport_ui(&mut self, ui: &mut Ui) {
        let (rect, resp) = ui.allocate_exact_size(ui.available_size(), Sense::click_and_drag());
        self.viewport = rect;
        self.hover(ui, rect);
        ui.painter()
            .rect_filled(rect, 0.0, Color32::from_rgb(38, 42, 50));
        let (w, h) = (rect.width() as f64, rect.height() as f64);
        let input = ui.input(|i| {
            (
                i.pointer.primary_pressed(),
                i.pointer.primary_released(),
                i.pointer.interact_pos(),
                i.pointer.delta(),
                i.modifiers,
                i.smooth_scroll_delta.y,
                i.pointer.button_down(PointerButton::Middle),
                i.pointer.button_down(PointerButton::Primary),
            )
        });
        let (pressed, released, pos, delta, mods, scroll, middle, primary) = input;
        let local = |p: Pos2| ((p.x - rect.min.x) as f64, (p.y - rect.min.y) as f64);
        // Press: start a grab with the tool, or orbit/pan. Only a press on the viewport itself
        // counts: egui gives one on a dialog, menu or window above it to that layer (the
        // viewport is then not pressed), and none counts while a dialog or popup is open. A
        // press and its release in one frame (a quick click on a slow frame) is a click on the
        // viewport: the grab starts and is dropped below.
        let blocked = self.dialog.is_some() || egui::Popup::is_any_open(ui.ctx());
        if pressed
            && !blocked
            && (resp.is_pointer_button_down_on() || resp.clicked())
            && let Some(p) = pos
            && rect.contains(p)
        {
            if self.tool == Tool::Orbit || mods.shift {
                self.press = Some(Press::Orbit);
            } else if let Some(grab) = if mods.command || mods.ctrl {
                self.ctrl_grab_for_tool()
            } else {
                self.grab_for_tool()
            } {
                self.pin_pending = grab == Grab::FfdPin;
                let (x, y) = local(p);
                let ray = self.camera.ray(x, y, w, h);
                let per_point =
                    2.0 * self.camera.distance * (crate::camera::FOV_Y / 2.0).tan() / h.max(1.0);
                self.send(Request::Symmetry(self.symmetry));
                self.send(Request::Sculpt(self.options.sculpt));
                self.send(Request::Flow(self.options.flow_request()));
                self.send(Request::Grab {
                    ray,
                    tolerance: PICK_POINTS * per_point,
                    grab,
                });
                self.press = Some(Press::Waiting);
            }
        }
        // Drag.
        if primary && delta != Vec2::ZERO {
            match self.press {
                Some(Press::Grabbed(_)) if self.is_brush() => {
                    // A stroke: the brush acts where the mouse meets the model.
                    if let Some(p) = pos {
                        let (x, y) = local(p);
                        let per_point =
                            2.0 * self.camera.distance * (crate::camera::FOV_Y / 2.0).tan()
                                / h.max(1.0);
                        self.send(Request::Stroke {
                            ray: self.camera.ray(x, y, w, h),
                            tolerance: PICK_POINTS * per_point,
                        });
                    }
                }
                Some(Press::Grabbed(cursor)) => {
                    let next = if mods.alt {
                        let per_point =
                            2.0 * self.camera.distance * (crate::camera::FOV_Y / 2.0).tan()
                                / h.max(1.0);
                        cursor - self.camera.back() * (delta.y as f64 * per_point)
                    } else if let Some(p) = pos {
                        let (x, y) = local(p);
                        let ray = self.camera.ray(x, y, w, h);
                        self.camera.on_view_plane(&ray, cursor)
                    } else {
                        cursor
                    };
                    self.press = Some(Press::Grabbed(next));
                    self.send(Request::Drag { to: next });
                }
                Some(Press::Orbit) if mods.shift => {
                    self.camera.pan(delta.x as f64, delta.y as f64, h)
                }
                Some(Press::Orbit) => self.camera.orbit(delta.x as f64, delta.y as f64),
                _ => {}
            }
        }
        if middle && delta != Vec2::ZERO && resp.hovered() {
            self.camera.pan(delta.x as f64, delta.y as f64, h);
        }
        if released || (!primary && self.press.is_some()) {
            if matches!(self.press, Some(Press::Grabbed(_)) | Some(Press::Waiting)) {
                self.send(Request::Drop);
            }
            self.press = None;
        }
        if resp.hovered() && scroll != 0.0 {
            self.camera.zoom(scroll as f64 / 50.0);
        }
        if resp.double_clicked() {
            self.fit();
        }
        self.paint_3d(ui, rect);
        // Grab cursor marker (not for a brush: its circle follows the mouse).
        if let Some(Press::Grabbed(c)) = self.press
            && !self.is_brush()
            && let Some((x, y)) = self.camera.project(c, w, h)
        {
            ui.painter().circle_stroke(
                rect.min + Vec2::new(x as f32, y as f32),
                6.0,
                egui::Stroke::new(1.5, Color32::YELLOW),
            );
        }
        self.overlays(ui, rect);
    }

    fn grab_for_tool(&self) -> Option<Grab> {
        let o = &self.options;
        Some(match self.tool {
            Tool::Orbit => return None,
            Tool::Rope => Grab::Rope {
                stiffness: (o.rope_stiffness > 0.0).then_some(o.rope_stiffness),
            },
            Tool::Force => {
                let back = self.camera.back();
                Grab::Force {
                    direction: if o.pull { back } else { -back },
                    strength: o.force,
                    radius: o.radius * self.model_size(),
                    duration: o.duration,
                    falloff: o.falloff,
                }
            }
            Tool::Fix => Grab::Fix {
                brush: o.brush * self.model_size(),
            },
            Tool::Free => Grab::Free {
                brush: o.brush * self.model_size(),
            },
            Tool::Smooth => Grab::Smooth {
                brush: o.brush * self.model_size(),
                strength: o.smooth,
            },
            Tool::Extrude => Grab::Extrude,
            Tool::DeleteCell => Grab::DeleteCell,
            Tool::SculptFace => Grab::SculptFace,
            Tool::Paint => Grab::PaintMaterial {
                brush: o.brush * self.model_size(),
                density: o.paint[0],
                damping: o.paint[1],
                edge_stiffness: o.paint[2],
            },
            Tool::ControlPoint => Grab::ControlPoint,
            Tool::FfdPoint => Grab::FfdPoint {
                pins: self.ffd_pins.clone(),
            },
            Tool::PdeLocal => Grab::PdeLocal { half: o.local },
        })
    }

    /// What Ctrl+click does with the active tool: pin an FFD point, set a control point's
    /// weight; else the same as a plain click.
    fn ctrl_grab_for_tool(&self) -> Option<Grab> {
        match self.tool {
            Tool::FfdPoint => Some(Grab::FfdPin),
            Tool::ControlPoint => Some(Grab::Weight {
                weight: self.options.weight,
            }),
            _ => self.grab_for_tool(),
        }
    }

    fn paint_3d(&self, ui: &mut Ui, rect: Rect) {
        let aspect = rect.width() as f64 / rect.height().max(1.0) as f64;
        let size = self
            .scene
            .bounds
            .map(|(lo, hi)| (hi - lo).norm())
            .unwrap_or(1.0);
        let m = self.camera.projection_matrix(aspect, size) * self.camera.view_matrix();
        let mut mvp = [0.0_f32; 16];
        for (k, v) in m.as_slice().iter().enumerate() {
            mvp[k] = *v as f32;
        }
        let b = self.camera.back();
        let (r, u) = self.camera.right_up();
        let f = |v: Vec3| [v.x as f32, v.y as f32, v.z as f32];
        let params = DrawParams {
            mvp,
            view: f(b),
            lights: crate::render::lights(b, r, u).map(f),
            shaded: self.layers.shaded,
            wireframe: self.layers.wireframe,
        };
        let scene = self.scene.clone();
        let gl_scene = self.gl.clone();
        let cb = eframe::egui_glow::CallbackFn::new(move |info, painter| {
            let gl = painter.gl();
            let Ok(mut slot) = gl_scene.lock() else {
                return;
            };
            let s = slot.get_or_insert_with(|| crate::render::GlScene::new(gl));
            if let Ok(s) = s {
                s.upload(gl, &scene);
                let v = info.viewport_in_pixels();
                s.draw(
                    gl,
                    &params,
                    [v.left_px, v.from_bottom_px, v.width_px, v.height_px],
                );
            }
        });
        ui.painter().add(egui::PaintCallback {
            rect,
            callback: Arc::new(cb),
        });
        if let Ok(slot) = self.gl.lock()
            && let Some(Err(e)) = slot.as_ref()
        {
            ui.painter().text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                format!("OpenGL: {e}"),
                egui::FontId::proportional(14.0),
                Color32::RED,
            );
        }
    }

    /// Shows the open dialog, if any, and acts on its answer: the dialog stays while it is
    /// unanswered, or the one that follows takes its place.
    fn dialogs(&mut self, ctx: &egui::Context) {
        let Some(d) = self.dialog.take() else { return };
        let modal = egui::Modal::new(egui::Id::unique("vclay-studio-dialog"));
        let (d, keep, next) = match d {
            Dialog::Error(msg) => {
                let a = prompt(ctx, modal, "Error", &msg, "OK", None);
                (Dialog::Error(msg), a.is_none(), None)
            }
            Dialog::Open(path) => self.path_step(ctx, modal, PathPurpose::Open, path),
            Dialog::SaveAs(path) => self.path_step(ctx, modal, PathPurpose::SaveAs, path),
            Dialog::Export(path) => self.path_step(ctx, modal, PathPurpose::Export, path),
            Dialog::Screenshot(path) => self.path_step(ctx, modal, PathPurpose::Screenshot, path),
            Dialog::Native {
                purpose,
                answer,
                typed,
            } => self.native_step(ctx, modal, purpose, answer, typed),
            Dialog::Recover(path) => self.recover_step(ctx, modal, path),
            Dialog::Help => (Dialog::Help, self.help_dialog(ctx, modal), None),
            Dialog::Unsaved(then) => self.unsaved_step(ctx, modal, then),
        };
        if next.is_some() {
            self.dialog = next;
        } else if keep && self.dialog.is_none() {
            self.dialog = Some(d);
        }
    }

    /// One frame of the typed-path dialog for `purpose`: the dialog, whether it stays, and
    /// the dialog that follows it.
    fn path_step(
        &mut self,
        ctx: &egui::Context,
        modal: egui::Modal,
        purpose: PathPurpose,
        mut path: String,
    ) -> (Dialog, bool, Option<Dialog>) {
        let (note, ok) = match purpose {
            PathPurpose::Open => (
                Some(format!(
                    "A relative path is read from {}",
                    self.open_folder().display()
                )),
                "Open",
            ),
            PathPurpose::SaveAs => (None, "Save"),
            PathPurpose::Export => (
                Some(format!(
                    "By extension: {}",
                    vclay_session::model::EXPORT_EXTENSIONS.join(", ")
                )),
                "Export",
            ),
            PathPurpose::Screenshot => (None, "Take"),
        };
        let a = path_dialog(ctx, modal, purpose.title(), note.as_deref(), &mut path, ok);
        let next = self.path_answered(ctx, purpose, a, &path);
        (purpose.typed(path), a.is_none(), next)
    }

    /// One frame of waiting for the desktop's file chooser (see [`Studio::path_step`]).
    fn native_step(
        &mut self,
        ctx: &egui::Context,
        modal: egui::Modal,
        purpose: PathPurpose,
        answer: std::sync::mpsc::Receiver<crate::native::Answer>,
        typed: String,
    ) -> (Dialog, bool, Option<Dialog>) {
        let got = answer.try_recv();
        let a = prompt(
            ctx,
            modal,
            purpose.title(),
            "Choose the file in the system's file dialog.",
            "Type the path instead",
            None,
        );
        let mut keep = false;
        let mut next = None;
        match (got, a) {
            (Ok(Ok(Some(path))), _) => {
                let path = path.display().to_string();
                next = self.path_answered(ctx, purpose, Some(Answer::Submit), &path);
            }
            (Ok(Ok(None)), _) | (_, Some(Answer::Cancel)) => {
                next = self.path_answered(ctx, purpose, Some(Answer::Cancel), "");
            }
            (Ok(Err(why)), _) => {
                // The chooser is broken here: type paths from now on.
                self.push_log(format!("file dialog: {why}; type the path instead"));
                self.opts.chooser = None;
                next = Some(purpose.typed(typed.clone()));
            }
            (Err(std::sync::mpsc::TryRecvError::Disconnected), _) => {
                next = Some(purpose.typed(typed.clone()));
            }
            (_, Some(_)) => next = Some(purpose.typed(typed.clone())),
            (Err(_), None) => {
                keep = true;
                ctx.request_repaint_after(std::time::Duration::from_millis(100));
            }
        }
        let d = Dialog::Native {
            purpose,
            answer,
            typed,
        };
        (d, keep, next)
    }

    /// One frame of the offer to recover an autosaved session newer than its file (see
    /// [`Studio::path_step`]).
    fn recover_step(
        &mut self,
        ctx: &egui::Context,
        modal: egui::Modal,
        path: PathBuf,
    ) -> (Dialog, bool, Option<Dialog>) {
        let text = format!(
            "An autosaved session newer than the file exists:\n{}",
            path.display()
        );
        let a = prompt(ctx, modal, "Recover?", &text, "Recover", Some("Discard"));
        let mut next = None;
        if a == Some(Answer::Submit) {
            match load::open(&path) {
                Ok(o) => {
                    let f = self.file.clone();
                    self.set_opened(o, f);
                    // Not in the file yet: modified, and autosaved again.
                    self.send(Request::MarkModified);
                }
                Err(e) => next = Some(Dialog::Error(e)),
            }
        }
        (Dialog::Recover(path), a.is_none(), next)
    }

    /// One frame of the unsaved-changes prompt before `then` (see [`Studio::path_step`]).
    fn unsaved_step(
        &mut self,
        ctx: &egui::Context,
        modal: egui::Modal,
        then: Then,
    ) -> (Dialog, bool, Option<Dialog>) {
        let other = match then {
            Then::Quit => "Discard and quit",
            _ => "Discard",
        };
        let text = "The session has changes that are not saved.";
        let a = prompt(ctx, modal, "Unsaved changes", text, "Save", Some(other));
        match a {
            Some(Answer::Submit) => {
                // Saved (perhaps after a save-as dialog), the worker's notice goes on.
                self.after_save = Some(then);
                self.save();
            }
            Some(Answer::Other) => self.proceed(ctx, then),
            _ => {}
        }
        (Dialog::Unsaved(then), a.is_none(), None)
    }
}

/// A prompt in `modal`: `heading`, the wrapped `text`, then [`buttons`] (`ok`, `other`,
/// Cancel); `None` while none was pressed.
fn prompt(
    ctx: &egui::Context,
    modal: egui::Modal,
    heading: &str,
    text: &str,
    ok: &str,
    other: Option<&str>,
) -> Option<Answer> {
    modal
        .show(ctx, |ui| {
            ui.heading(heading);
            ui.add(egui::Label::new(text).wrap());
            buttons(ui, ok, other)
        })
        .inner
}

/// The dialog's buttons: `ok` (also Enter), `other` if any, and Cancel (also Esc); `None`
/// while none was pressed. Buttons in a row, after the content.
fn buttons(ui: &mut Ui, ok: &str, other: Option<&str>) -> Option<Answer> {
    ui.set_min_width(DIALOG_MIN_WIDTH);
    let mut a = None;
    ui.horizontal(|ui| {
        if ui.button(ok).clicked() {
            a = Some(Answer::Submit);
        }
        if let Some(o) = other
            && ui.button(o).clicked()
        {
            a = Some(Answer::Other);
        }
        if ui.button("Cancel").clicked() {
            a = Some(Answer::Cancel);
        }
    });
    a.or_else(|| keys_answer(ui.ctx()))
}

/// Enter submits, Esc cancels (both consumed).
fn keys_answer(ctx: &egui::Context) -> Option<Answer> {
    ctx.input_mut(|i| {
        if i.consume_key(Modifiers::NONE, Key::Escape) {
            Some(Answer::Cancel)
        } else if i.consume_key(Modifiers::NONE, Key::Enter) {
            Some(Answer::Submit)
        } else {
            None
        }
    })
}

/// A dialog with a path field: its heading, an optional note, the field and the buttons.
/// The field keeps the keyboard focus while the dialog is open, so text typed in the same
/// frame as a click on a button is in `path` before the click counts.
fn path_dialog(
    ctx: &egui::Context,
    modal: egui::Modal,
    title: &str,
    note: Option<&str>,
    path: &mut String,
    ok: &str,
) -> Option<Answer> {
    modal
        .show(ctx, |ui| {
            ui.heading(title);
            if let Some(n) = note {
                ui.add(egui::Label::new(n).wrap());
            }
            // By default a click elsewhere takes the focus from the field before the field
            // reads this frame's keys: the last character typed would be lost.
            let surrender = ctx.options(|o| o.input_options.surrender_focus_on);
            ctx.options_mut(|o| o.input_options.surrender_focus_on = SurrenderFocusOn::Never);
            let r = ui.add(egui::TextEdit::singleline(path).desired_width(f32::INFINITY));
            ctx.options_mut(|o| o.input_options.surrender_focus_on = surrender);
            if !r.has_focus() && ctx.memory(|m| m.focused().is_none()) {
                r.request_focus();
            }
            buttons(ui, ok, None)
        })
        .inner
}

/// Writes an egui image as PNG.
pub fn write_png(path: &Path, img: &egui::ColorImage) -> Result<(), String> {
    let err = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    let f = std::fs::File::create(path).map_err(|e| err(&e))?;
    let mut enc = png::Encoder::new(
        std::io::BufWriter::new(f),
        img.size[0] as u32,
        img.size[1] as u32,
    );
    enc.set_color(png::ColorType::Rgba);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().map_err(|e| err(&e))?;
    let bytes: Vec<u8> = img.pixels.iter().flat_map(|c| c.to_array()).collect();
    w.write_image_data(&bytes).map_err(|e| err(&e))
}

impl eframe::App for Studio {
    fn ui(&mut self, ui: &mut Ui, _frame: &mut eframe::Frame) {
        self.show(ui);
    }
}
