//! The simulation thread: it owns the [`Session`], applies what the UI sends, steps while
//! running, autosaves, and hands the UI display data ([`Frame`]) when something changed.
//!
//! # Protocol
//! The UI sends [`Request`]s over a channel and never waits for them (tests and the benchmark
//! may, through [`Worker::query`]). The worker publishes the newest [`Frame`] in a one-slot
//! mailbox and builds the next one only after the UI has taken the last, so a slow window never
//! queues frames and never slows the simulation by more than one display build per frame.
//! Notices (log lines, errors, pick results) go back over a second channel.
//!
//! # Undo groups
//! One user action may produce several commands (a rope drag: attach, cursor moves, release).
//! The worker brackets them with the session layer's `begin_group` / `end_group`, so undo and
//! redo treat the action as one, and the cursor moves of a drag keep no snapshot of their own.
//! Cursor moves are coalesced: at most one `move-rope` (or FFD move) per [`DRAG_INTERVAL`],
//! which bounds the command log's growth.
//!
//! # Undo while running
//! The session layer keeps its redo list across steps, but a drag (commands with steps between
//! them) redoes exactly only if nothing happened since its undo. So an undo while running holds
//! the simulation; redo gives the drag back exactly, and the run goes on when the redo list is
//! empty, at the next edit or press, or on Run. A new edit clears the redo list. "Nothing to
//! undo / redo" is a [`Notice::Status`], not an error.
//!
//! # Time limit
//! [`Request::TimeLimit`] stops the run (pauses) before a step would take the first model's
//! clock past the limit (the studio bounds a PDE surface's time by its slider range).
//!
//! # Sessions
//! Each [`Request::Replace`] begins a new generation: frames carry it ([`Frame::generation`])
//! and [`Notice::Replaced`] marks it in the notice stream, so the UI can drop what the old
//! session still sent.
//!
//! # Divergence
//! A step that fails pauses the simulation and sends [`Notice::Error`] with the kernel's
//! message (it names the step and a stable time step) and what to do.

use std::path::PathBuf;
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender, channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use vclay_core::{TriMesh, Vec3};
use vclay_session::{
    Command, Edit, Element, Energy, FieldSpec, Hit, LineRole, LineSet, Param, PointMove, Ray,
    Selection, Session, ToolSpec,
};

use crate::symmetry::{Axes, Symmetry};

/// Sculpt mode's plastic flow (see [`Request::Flow`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Flow {
    /// Rate `gamma` (1/s) at which the rest shape follows the clay past the yield.
    pub rate: f64,
    /// Yield distance as a fraction of the model's size (bounding-box diagonal).
    pub yield_fraction: f64,
}

/// Sculpt mode's anchor reach (see `Worker::anchor`): control points farther than this fraction
/// of the model's size (its rest bounding box diagonal) from the grab are held during a pull of
/// a model with nothing fixed.
pub const ANCHOR_FRACTION: f64 = 0.6;

/// Least time between two applied cursor moves of one drag.
pub const DRAG_INTERVAL: Duration = Duration::from_millis(40);
/// Default autosave interval.
pub const AUTOSAVE_INTERVAL: Duration = Duration::from_secs(3);
/// Name of the studio's rope tool.
pub const ROPE: &str = "studio-rope";
/// A brush acts again once the stroke has moved this fraction of its radius.
pub const STROKE_SPACING: f64 = 0.5;
/// Energy samples kept for the plot.
pub const ENERGY_SAMPLES: usize = 4000;

/// What a press on the model does (the tool of the toolbar).
#[derive(Clone, Debug, PartialEq)]
pub enum Grab {
    /// Attach a rope at the hit; drags move its cursor.
    Rope {
        /// Spring stiffness (`None`: the kind's default).
        stiffness: Option<f64>,
    },
    /// Drag the control point hit (or nearest the hit).
    ControlPoint,
    /// FFD direct manipulation: drag the embedded point hit (eq 7); the `pins` (points of the
    /// object) stay where they are, so each move is a multi-point manipulation (eq 12).
    FfdPoint {
        /// Points held in place while the dragged one moves.
        pins: Vec<Vec3>,
    },
    /// Pick a point of an FFD object to hold in place in later FFD drags (the UI keeps it;
    /// the pick comes back as [`Notice::Grabbed`]).
    FfdPin,
    /// Drag a local deformation of a PDE surface (eqs 30-32) out of the point hit: a G1 bump
    /// over `[u - half[0], u + half[0]] x [v - half[1], v + half[1]]` whose peak follows the
    /// cursor.
    PdeLocal {
        /// Half-widths along u and v.
        half: [f64; 2],
    },
    /// Set the weight of the control point hit (NURBS models and FFD lattices).
    Weight {
        /// The new weight (> 0).
        weight: f64,
    },
    /// A force at the hit, along `direction` scaled by `strength`, for `duration` seconds;
    /// solids spread it over `radius`.
    Force {
        /// Direction (unit; the view direction for a push).
        direction: Vec3,
        /// Magnitude.
        strength: f64,
        /// Brush radius (solids).
        radius: f64,
        /// Seconds of simulated time it acts.
        duration: f64,
        /// How a region force's share falls off from the centre (one of
        /// `vclay_session::describe::FALLOFFS`; solids).
        falloff: &'static str,
    },
    /// Fix the control point nearest the hit; with `brush > 0`, every control point whose rest
    /// position is within a box of half-size `brush` around the hit, and around every cursor
    /// position of the drag that follows.
    Fix {
        /// Brush half-size (0: the one point nearest the click).
        brush: f64,
    },
    /// The smooth brush (`Edit::Smooth`): the rest shape under a brush of radius `brush` is
    /// faired by `strength`, again along the stroke; the clay settles to it as it runs.
    Smooth {
        /// Brush radius (0: the control point nearest the press).
        brush: f64,
        /// Share of each dab's step, in (0, 1].
        strength: f64,
    },
    /// Free control points (as [`Grab::Fix`]).
    Free {
        /// Brush half-size (0: the one point nearest the click).
        brush: f64,
    },
    /// Extrude the control face under the hit (subdivision solids).
    Extrude,
    /// Delete the control cell under the hit (subdivision solids).
    DeleteCell,
    /// Make the CAD part's face under the hit the sculpted one (`sculpt-face`).
    SculptFace,
    /// Paint a material on the control cell under the hit (solids); with `brush > 0`, on every
    /// control cell whose centroid is within a box of half-size `brush` around the hit and
    /// around every cursor position of the drag that follows.
    PaintMaterial {
        /// Brush half-size (0: the cell under the click).
        brush: f64,
        /// Density.
        density: f64,
        /// Damping.
        damping: f64,
        /// Edge spring modulus.
        edge_stiffness: f64,
    },
}

/// One model's display data.
#[derive(Clone, Debug)]
pub struct ModelView {
    /// Name in the session.
    pub name: String,
    /// The tools it takes (`Model::tools`).
    pub tools: Vec<ToolSpec>,
    /// Summary line.
    pub summary: String,
    /// Shaded triangles with normals.
    pub mesh: Arc<TriMesh>,
    /// Lines and markers.
    pub lines: Arc<Vec<LineSet>>,
    /// Parameters (sliders).
    pub params: Vec<Param>,
    /// Model size (tolerances).
    pub size: f64,
    /// Time step.
    pub dt: f64,
    /// Simulated time.
    pub time: f64,
    /// The scalar fields the mesh can be coloured by (`Model::display_fields`).
    pub fields: Vec<FieldSpec>,
    /// The field chosen by [`Request::ColourBy`] at the mesh's vertices, if the model has it.
    pub field: Option<Arc<Vec<f64>>>,
}

/// What the UI draws: the session's models at one revision.
#[derive(Clone, Debug, Default)]
pub struct Frame {
    /// The session revision shown.
    pub revision: u64,
    /// Models.
    pub models: Vec<ModelView>,
    /// Session time.
    pub time: f64,
    /// Steps taken by the first model.
    pub steps: u64,
    /// Energies of the models, summed.
    pub energy: Energy,
    /// Energy samples `(time, kinetic, elastic)` since the last frame.
    pub samples: Vec<[f64; 3]>,
    /// Mean wall time of the recent steps, seconds.
    pub step_seconds: f64,
    /// Steps per wall second recently.
    pub steps_per_second: f64,
    /// Whether the simulation runs.
    pub running: bool,
    /// Undo / redo available.
    pub can_undo: bool,
    /// See `can_undo`.
    pub can_redo: bool,
    /// Changes since the last explicit save (or the load).
    pub dirty: bool,
    /// Commands scheduled and not yet applied (a scenario's timeline).
    pub scheduled: usize,
    /// Wall time to build this frame's display data, seconds.
    pub build_seconds: f64,
    /// The session's generation: the number of [`Request::Replace`]s handled before it.
    pub generation: u64,
}

/// Messages from the UI to the worker.
pub enum Request {
    /// Apply a command (one undo group).
    Apply(Command),
    /// Undo the last action (a whole drag counts as one).
    Undo,
    /// Redo.
    Redo,
    /// Run or pause.
    Run(bool),
    /// Take `n` steps (while paused).
    Step(u64),
    /// Simulated seconds per wall second while running (0: as fast as possible).
    Speed(f64),
    /// Press on the model: pick with `ray` within `tolerance` (model units) and start
    /// `grab`.
    Grab {
        /// The mouse ray.
        ray: Ray,
        /// Pick tolerance (model units).
        tolerance: f64,
        /// What to do.
        grab: Grab,
    },
    /// Move the grabbed point's cursor to `to`.
    Drag {
        /// The cursor.
        to: Vec3,
    },
    /// A brush stroke goes on under the mouse `ray`: the brush acts where it meets the model
    /// (picked within `tolerance`), spaced by [`STROKE_SPACING`] of its radius.
    Stroke {
        /// The mouse ray.
        ray: Ray,
        /// Pick tolerance (model units).
        tolerance: f64,
    },
    /// Release the grab.
    Drop,
    /// The axes the tools mirror across (see [`crate::symmetry`]); taken at the next press.
    Symmetry(Symmetry),
    /// Sculpt mode: at the end of each rope pull or force stroke the shape reached becomes the
    /// rest shape and the motion stops (the papers' plastic reset, journal section 5.4, applied
    /// per stroke), so what the designer pulls stays. Off: the papers' elastic clay, which
    /// springs back. Taken at the next press; only for models that take `plastic-reset`.
    Sculpt(bool),
    /// Sculpt mode's plastic flow (`vclay_core::plasticity`, docs/sculpting.md): `Some`, the
    /// rest shape follows the clay during a pull, after every step, where it is displaced past
    /// the yield distance (a fraction of the model's size), at the rate; the clay then springs
    /// back only by its elastic part at the release, and nothing is reset there. `None`: the
    /// whole shape reached is kept at the release (the flow's limit of infinite rate and zero
    /// yield). Applies while sculpt mode is on, to every model that has a rest shape.
    Flow(Option<Flow>),
    /// Colour the meshes by this scalar field (`Model::display_fields`: painted material);
    /// `None`: clay colour.
    ColourBy(Option<String>),
    /// Pause once the first model's step count reaches this (a scenario's run length), and
    /// say so; Run then goes on past it. `None`: no such stop.
    StopAt(Option<u64>),
    /// The run the opened file describes (a scenario's name, end step and outputs): kept in
    /// saved and autosaved sessions, so that `vclay run` and Recover go on to the same end.
    RunInfo(Option<Box<vclay_session::file::RunInfo>>),
    /// Replace the session (open, new); `path` is where explicit saves go.
    Replace(Box<Session>),
    /// Save the session to `path` (clears the dirty flag).
    Save(PathBuf),
    /// Set the autosave file (`None`: off).
    Autosave(Option<PathBuf>, Duration),
    /// Turn autosave off and delete the autosave file (a clean exit: nothing to recover).
    DiscardAutosave,
    /// The session differs from its file (a recovered autosave): it counts as modified and is
    /// autosaved again.
    MarkModified,
    /// Pause before a step would take the first model's clock past this time (`None`: no
    /// limit).
    TimeLimit(Option<f64>),
    /// Export model `model` to `path` through `Model::export`.
    Export {
        /// Model name.
        model: String,
        /// File.
        path: PathBuf,
    },
    /// Run a closure on the session (tests, benchmark).
    Query(Box<dyn FnOnce(&mut Session) + Send>),
    /// Stop the thread.
    Quit,
}

impl std::fmt::Debug for Request {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Request::Apply(_) => "Apply",
            Request::Undo => "Undo",
            Request::Redo => "Redo",
            Request::Run(_) => "Run",
            Request::Step(_) => "Step",
            Request::Speed(_) => "Speed",
            Request::Grab { .. } => "Grab",
            Request::Drag { .. } => "Drag",
            Request::Stroke { .. } => "Stroke",
            Request::Drop => "Drop",
            Request::Symmetry(_) => "Symmetry",
            Request::Sculpt(_) => "Sculpt",
            Request::Flow(_) => "Flow",
            Request::ColourBy(_) => "ColourBy",
            Request::StopAt(_) => "StopAt",
            Request::RunInfo(_) => "RunInfo",
            Request::Replace(_) => "Replace",
            Request::Save(_) => "Save",
            Request::Autosave(..) => "Autosave",
            Request::DiscardAutosave => "DiscardAutosave",
            Request::MarkModified => "MarkModified",
            Request::TimeLimit(_) => "TimeLimit",
            Request::Export { .. } => "Export",
            Request::Query(_) => "Query",
            Request::Quit => "Quit",
        })
    }
}

/// Messages from the worker to the UI.
#[derive(Clone, Debug, PartialEq)]
pub enum Notice {
    /// A log line (a command applied, a file saved).
    Log(String),
    /// A line for the status bar (and the log): undo and redo results, "nothing to undo", a
    /// run stopped at the time limit.
    Status(String),
    /// A log line that a drag's next move supersedes (a rope's or a control point's cursor
    /// moved): the log keeps one line per tool for a run of such lines, the latest (see
    /// `Studio`'s log), so a stroke reads as "attached", "cursor at (last)", "released" instead
    /// of one line per mouse move.
    Progress(String),
    /// The session was replaced: what follows belongs to generation `.0` (see
    /// [`Frame::generation`]).
    Replaced(u64),
    /// Something failed; `paused` says the simulation was paused (divergence).
    Error {
        /// The message.
        message: String,
        /// Whether the simulation was paused because of it.
        paused: bool,
    },
    /// A grab started at `point` on model `model`.
    Grabbed {
        /// Model name.
        model: String,
        /// The hit point (the drag's anchor).
        point: Vec3,
        /// What was hit.
        element: Element,
    },
    /// A press hit nothing.
    Missed,
    /// The session was saved to the path.
    Saved(PathBuf),
    /// The session was autosaved to the path.
    Autosaved(PathBuf),
}

struct Shared {
    frame: Mutex<Option<Frame>>,
    wake: Mutex<Option<Box<dyn Fn() + Send>>>,
}

/// The handle the UI keeps: request sender, notice receiver, frame mailbox.
pub struct Worker {
    tx: Sender<Request>,
    notices: Receiver<Notice>,
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl std::fmt::Debug for Worker {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Worker(..)")
    }
}

impl Worker {
    /// Starts the thread with `session`; `running` starts the simulation at once.
    pub fn start(session: Session, running: bool) -> Self {
        let (tx, rx) = channel();
        let (ntx, notices) = channel();
        let shared = Arc::new(Shared {
            frame: Mutex::new(None),
            wake: Mutex::new(None),
        });
        let sh = shared.clone();
        let thread = std::thread::Builder::new()
            .name("vclay-sim".into())
            .spawn(move || State::new(session, running, sh, ntx).run(rx))
            .ok();
        Self {
            tx,
            notices,
            shared,
            thread,
        }
    }

    /// Sets what the worker calls when a new frame or notice is ready (the UI's repaint).
    pub fn set_wake(&self, wake: impl Fn() + Send + 'static) {
        if let Ok(mut w) = self.shared.wake.lock() {
            *w = Some(Box::new(wake));
        }
    }

    /// Sends a request (ignored if the thread has stopped).
    pub fn send(&self, r: Request) {
        let _ = self.tx.send(r);
    }

    /// The newest frame, if one is ready since the last call.
    pub fn take_frame(&self) -> Option<Frame> {
        self.shared.frame.lock().ok()?.take()
    }

    /// Notices since the last call.
    pub fn notices(&self) -> Vec<Notice> {
        self.notices.try_iter().collect()
    }

    /// Runs `f` on the session and waits for its result (`None` if the thread has stopped).
    pub fn query<R: Send + 'static>(
        &self,
        f: impl FnOnce(&mut Session) -> R + Send + 'static,
    ) -> Option<R> {
        let (tx, rx) = channel();
        self.send(Request::Query(Box::new(move |s| {
            let _ = tx.send(f(s));
        })));
        rx.recv_timeout(Duration::from_secs(120)).ok()
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        let _ = self.tx.send(Request::Quit);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

enum Active {
    /// A rope named `name` whose cursor follows the drag.
    Rope {
        name: String,
    },
    /// A brush: `edit` made again at each stroke position (see `State::stroke_edit`), over
    /// `radius`, acting `duration` seconds where it acts for a time (the force brush).
    Brush {
        edit: Box<Edit>,
        radius: f64,
        duration: Option<f64>,
    },
    ControlPoint {
        model: String,
        index: usize,
    },
    Ffd {
        model: String,
        last: Vec3,
        pins: Vec<Vec3>,
    },
    PdeLocal {
        name: String,
        patch: usize,
        uv: [f64; 2],
        start: Vec3,
        half: [f64; 2],
    },
}

/// One acting copy of a press: the press itself (`flip` all false) or a mirror image.
struct Part {
    flip: Axes,
    active: Active,
}

struct Drag {
    model: String,
    /// Centre of the symmetry planes (the model's bounding box at the press).
    centre: Vec3,
    parts: Vec<Part>,
    /// The cursor's next position.
    pending: Option<Vec3>,
    /// A brush stroke's next mouse ray and pick tolerance.
    pending_ray: Option<(Ray, f64)>,
    /// Where the stroke acted last (the press itself, not a mirror image).
    last_at: Option<Vec3>,
    /// Least distance between two positions at which a brush acts.
    spacing: f64,
    last_applied: Instant,
    /// Control points fixed for the pull only (sculpt mode on a model with nothing fixed),
    /// freed at the release.
    anchors: Vec<usize>,
}

/// The material point of a surface or curve hit (D-NURBS ropes and forces take one).
fn surface_param(hit: &Hit) -> Option<[f64; 2]> {
    match hit.element {
        Element::SurfacePoint { param } => Some(param),
        Element::CurvePoint { u } => Some([u, 0.0]),
        _ => None,
    }
}

/// The control cell under a hit (subdivision solids).
fn cell(h: &Hit) -> Option<usize> {
    h.extra.iter().find_map(|e| match e {
        Some(Element::Cell { index }) => Some(*index),
        _ => None,
    })
}

struct State {
    session: Session,
    /// Local deformations made so far (for their names).
    locals: usize,
    running: bool,
    shared: Arc<Shared>,
    notices: Sender<Notice>,
    drag: Option<Drag>,
    speed: f64,
    clock: (Instant, f64),
    samples: Vec<[f64; 3]>,
    step_times: std::collections::VecDeque<(Instant, f64)>,
    shown_revision: Option<u64>,
    /// When the published frames last evaluated the energies.
    energy_clock: EnergyClock,
    saved_revision: u64,
    autosave: Option<(PathBuf, Duration)>,
    autosaved: (Instant, u64),
    /// Pause before passing this time.
    time_limit: Option<f64>,
    /// Pause when the first model's step count reaches this (a scenario's end).
    stop_at: Option<u64>,
    /// Sculpt mode (see [`Request::Sculpt`]).
    sculpt: bool,
    /// Sculpt mode's plastic flow (see [`Request::Flow`]).
    flow: Option<Flow>,
    /// The field the meshes are coloured by (see [`Request::ColourBy`]).
    colour_by: Option<String>,
    /// The run was paused by the scenario's end (a press runs it again).
    ended: bool,
    /// The run was held by an undo (see `Worker::undo`).
    held: bool,
    /// What saves write as the run information (see [`Request::RunInfo`]).
    run_info: Option<vclay_session::file::RunInfo>,
    /// Mirror symmetry of the tools.
    symmetry: Symmetry,
    /// Replacements handled.
    generation: u64,
}

impl State {
    fn new(session: Session, running: bool, shared: Arc<Shared>, notices: Sender<Notice>) -> Self {
        let rev = session.revision();
        let t = session.time();
        Self {
            session,
            locals: 0,
            running,
            shared,
            notices,
            drag: None,
            speed: 1.0,
            clock: (Instant::now(), t),
            samples: Vec::new(),
            step_times: Default::default(),
            shown_revision: None,
            energy_clock: EnergyClock::default(),
            saved_revision: rev,
            autosave: None,
            autosaved: (Instant::now(), rev),
            time_limit: None,
            stop_at: None,
            run_info: None,
            sculpt: false,
            flow: None,
            colour_by: None,
            ended: false,
            held: false,
            symmetry: Symmetry::default(),
            generation: 0,
        }
    }

    fn notify(&self, n: Notice) {
        let _ = self.notices.send(n);
        self.wake();
    }

    fn wake(&self) {
        if let Ok(w) = self.shared.wake.lock()
            && let Some(w) = w.as_ref()
        {
            w();
        }
    }

    fn run(mut self, rx: Receiver<Request>) {
        loop {
            // Wait for requests while there is nothing to do.
            let idle = !self.running
                && self
                    .drag
                    .as_ref()
                    .is_none_or(|d| d.pending.is_none() && d.pending_ray.is_none());
            let first = if idle {
                match rx.recv_timeout(Duration::from_millis(100)) {
                    Ok(r) => Some(r),
                    Err(RecvTimeoutError::Timeout) => None,
                    Err(RecvTimeoutError::Disconnected) => return,
                }
            } else {
                None
            };
            for r in first.into_iter().chain(rx.try_iter().collect::<Vec<_>>()) {
                if matches!(r, Request::Quit) {
                    return;
                }
                self.handle(r);
                // Flags in the frame (running, dirty, undo) may have changed.
                self.shown_revision = None;
            }
            self.apply_drag(false);
            if self.running && self.at_time_limit() {
                self.running = false;
                self.shown_revision = None;
                let t = self.session.time();
                self.notify(Notice::Status(format!(
                    "t = {t:.3} is the end of the time range: paused (Run starts over)"
                )));
            }
            if self.running && self.at_scenario_end() {
                self.running = false;
                self.ended = true;
                self.shown_revision = None;
                let (n, t) = (self.stop_at.take().unwrap_or(0), self.session.time());
                self.notify(Notice::Status(format!(
                    "scenario finished at step {n} (t = {t:.3}); Run continues past it"
                )));
            }
            if self.running {
                if self.ahead_of_wall_clock() {
                    std::thread::sleep(Duration::from_millis(1));
                } else {
                    self.step_once();
                }
            }
            self.publish();
            self.autosave_if_due();
        }
    }

    /// Whether the next step would take the first model's clock past the time limit.
    fn at_time_limit(&self) -> bool {
        let Some(limit) = self.time_limit else {
            return false;
        };
        self.session
            .model(None)
            .is_ok_and(|m| m.time() + m.dt() > limit + 1e-9 * limit.abs().max(1.0))
    }

    /// Whether the first model has taken the scenario's steps.
    fn at_scenario_end(&self) -> bool {
        self.stop_at
            .is_some_and(|n| self.session.model(None).is_ok_and(|m| m.steps() >= n))
    }

    fn ahead_of_wall_clock(&self) -> bool {
        self.speed > 0.0
            && self.session.time() - self.clock.1
                > self.speed * self.clock.0.elapsed().as_secs_f64()
    }

    fn step_once(&mut self) {
        let t0 = Instant::now();
        match self.session.step() {
            Ok((reports, lines)) => {
                let dt = t0.elapsed().as_secs_f64();
                let now = Instant::now();
                self.step_times.push_back((now, dt));
                while self
                    .step_times
                    .front()
                    .is_some_and(|(t, _)| now.duration_since(*t) > Duration::from_secs(1))
                {
                    self.step_times.pop_front();
                }
                let (mut k, mut e) = (0.0, 0.0);
                for r in &reports {
                    k += r.energy.kinetic;
                    e += r.energy.elastic;
                }
                self.samples.push([self.session.time(), k, e]);
                if self.samples.len() > ENERGY_SAMPLES {
                    self.samples.drain(..self.samples.len() - ENERGY_SAMPLES);
                }
                for l in lines {
                    self.notify(Notice::Log(l));
                }
            }
            Err(err) => {
                self.running = false;
                self.notify(Notice::Error {
                    message: format!(
                        "{err}\nThe simulation is paused. Lower the time step (Simulation \
                         panel: dt; the message above suggests a stable one), or undo the last \
                         edit, then run again."
                    ),
                    paused: true,
                });
            }
        }
    }

    fn apply(&mut self, c: Command) -> bool {
        self.apply_noting(c, Notice::Log)
    }

    /// [`Self::apply`], its message sent as `note` says (a log line, or a drag's progress).
    fn apply_noting(&mut self, c: Command, note: fn(String) -> Notice) -> bool {
        match self.session.apply(c) {
            Ok(m) => {
                self.notify(note(m));
                true
            }
            Err(e) => {
                self.notify(Notice::Error {
                    message: e.to_string(),
                    paused: false,
                });
                false
            }
        }
    }

    fn handle(&mut self, r: Request) {
        match r {
            Request::Apply(c) => {
                self.resume_held();
                self.apply(c);
            }
            Request::Undo => self.undo(),
            Request::Redo => self.redo(),
            Request::Run(on) => {
                self.ended = false;
                self.held = false;
                self.running = on;
                self.clock = (Instant::now(), self.session.time());
            }
            Request::Step(n) => {
                for _ in 0..n {
                    self.step_once();
                }
            }
            Request::Speed(s) => {
                self.speed = if s.is_finite() { s.max(0.0) } else { 0.0 };
                self.clock = (Instant::now(), self.session.time());
            }
            Request::Grab {
                ray,
                tolerance,
                grab,
            } => {
                // A scenario that reached its end paused the run, not the designer: a pull
                // afterwards runs the clay again (a pull on paused clay would do nothing).
                if self.ended {
                    self.ended = false;
                    self.running = true;
                    self.clock = (Instant::now(), self.session.time());
                }
                self.resume_held();
                self.grab(ray, tolerance, grab)
            }
            Request::Drag { to } => {
                if let Some(d) = self.drag.as_mut() {
                    d.pending = Some(to);
                }
            }
            Request::Stroke { ray, tolerance } => {
                if let Some(d) = self.drag.as_mut() {
                    d.pending_ray = Some((ray, tolerance));
                }
            }
            Request::Drop => self.drop_grab(),
            Request::Symmetry(s) => self.symmetry = s,
            Request::Sculpt(on) => {
                self.sculpt = on;
                self.set_flow();
            }
            Request::Flow(f) => {
                self.flow = f;
                self.set_flow();
            }
            Request::ColourBy(f) => {
                self.colour_by = f;
                self.shown_revision = None;
            }
            Request::StopAt(n) => self.stop_at = n,
            Request::RunInfo(r) => self.run_info = r.map(|r| *r),
            Request::Replace(s) => {
                self.drop_grab();
                self.session = *s;
                self.set_flow();
                self.stop_at = None;
                self.ended = false;
                self.held = false;
                self.run_info = None;
                self.generation += 1;
                self.notify(Notice::Replaced(self.generation));
                self.samples.clear();
                self.step_times.clear();
                self.shown_revision = None;
                self.saved_revision = self.session.revision();
                self.autosaved = (Instant::now(), self.saved_revision);
                self.clock = (Instant::now(), self.session.time());
            }
            Request::Save(path) => {
                match vclay_session::file::save(&path, &self.session, self.run_info.as_ref()) {
                    Ok(()) => {
                        self.saved_revision = self.session.revision();
                        // The file holds this revision: no autosave of it is needed.
                        self.autosaved = (Instant::now(), self.saved_revision);
                        self.shown_revision = None;
                        self.notify(Notice::Saved(path));
                    }
                    Err(e) => self.notify(Notice::Error {
                        message: e.to_string(),
                        paused: false,
                    }),
                }
            }
            Request::Autosave(p, every) => {
                self.autosave = p.map(|p| (p, every));
            }
            Request::DiscardAutosave => {
                if let Some((p, _)) = self.autosave.take() {
                    let _ = std::fs::remove_file(p);
                }
            }
            Request::MarkModified => {
                // No revision equals these: dirty until saved, autosaved at the next chance.
                self.saved_revision = u64::MAX;
                self.autosaved.1 = u64::MAX;
            }
            Request::TimeLimit(limit) => self.time_limit = limit.filter(|l| l.is_finite()),
            Request::Export { model, path } => {
                let r = self
                    .session
                    .model(Some(&model))
                    .and_then(|m| m.export(&path));
                match r {
                    Ok(()) => self.notify(Notice::Log(format!(
                        "exported `{model}` to {}",
                        path.display()
                    ))),
                    Err(e) => self.notify(Notice::Error {
                        message: e.to_string(),
                        paused: false,
                    }),
                }
            }
            Request::Query(f) => {
                f(&mut self.session);
                self.shown_revision = None;
            }
            Request::Quit => {}
        }
    }

    fn undo(&mut self) {
        self.drop_grab();
        match self.session.undo() {
            Ok(first) => {
                let mut line = format!("undone: {}", first.message);
                if self.running {
                    // Steps after an undo would make a drag's redo apply its commands again at
                    // once (no deformation); held, the session gives the drag back exactly.
                    self.running = false;
                    self.held = true;
                    line.push_str(" (simulation held so that redo gives it back; Run continues)");
                }
                self.notify(Notice::Status(line));
            }
            Err(e) => self.history_error(e),
        }
    }

    /// Runs again a simulation an undo held (see [`Self::undo`]).
    fn resume_held(&mut self) {
        if self.held {
            self.held = false;
            self.running = true;
            self.clock = (Instant::now(), self.session.time());
        }
    }

    fn redo(&mut self) {
        match self.session.redo() {
            Ok(m) => {
                let n = m.lines().count();
                self.notify(Notice::Status(format!("redone ({n} command(s))")));
                if !self.session.can_redo() {
                    self.resume_held();
                }
            }
            Err(e) => self.history_error(e),
        }
    }

    /// "Nothing to undo / redo" is a status line; other failures are errors.
    fn history_error(&self, e: vclay_session::SessionError) {
        match e {
            vclay_session::SessionError::History(_) => self.notify(Notice::Status(e.to_string())),
            e => self.notify(Notice::Error {
                message: e.to_string(),
                paused: false,
            }),
        }
    }

    /// The edit of a brush stroke at `at`: `template` acting on the points within `radius` of
    /// `at` (fix/free: at their current positions; material: the cells in the box around it).
    fn brush_edit(template: &Edit, at: Vec3, radius: f64) -> Edit {
        let min = Some([at.x - radius, at.y - radius, at.z - radius]);
        let max = Some([at.x + radius, at.y + radius, at.z + radius]);
        let mut e = template.clone();
        match &mut e {
            // The points under the brush where they are now (not where they rested).
            Edit::Fix(sel) | Edit::Free(sel) => *sel = Selection::brush([at.x, at.y, at.z], radius),
            Edit::Smooth {
                near, radius: r, ..
            } => (*near, *r) = ([at.x, at.y, at.z], radius),
            Edit::Material {
                cells,
                min: a,
                max: b,
                ..
            } => {
                (*cells, *a, *b) = (None, min, max);
            }
            _ => {}
        }
        e
    }

    /// Whether `grab` acts at the mirror images too when symmetry is on.
    fn mirrored(grab: &Grab) -> bool {
        matches!(
            grab,
            Grab::Rope { .. }
                | Grab::Force { .. }
                | Grab::Fix { .. }
                | Grab::Free { .. }
                | Grab::Smooth { .. }
                | Grab::PaintMaterial { .. }
        )
    }

    /// Least distance between two positions of a stroke at which a brush acts again.
    fn spacing(grab: &Grab) -> f64 {
        match grab {
            Grab::Force { radius, .. } => radius * STROKE_SPACING,
            Grab::Fix { brush }
            | Grab::Free { brush }
            | Grab::Smooth { brush, .. }
            | Grab::PaintMaterial { brush, .. } => brush * STROKE_SPACING,
            _ => 0.0,
        }
    }

    fn grab(&mut self, ray: Ray, tolerance: f64, grab: Grab) {
        self.drop_grab();
        let Some((model, hit)) = self.session.pick(&ray, tolerance) else {
            self.notify(Notice::Missed);
            return;
        };
        let Ok(m) = self.session.model(Some(&model)) else {
            return;
        };
        let tools = m.tools();
        let centre = m
            .display_mesh()
            .ok()
            .and_then(|mesh| crate::symmetry::centre(&mesh.positions))
            .unwrap_or(hit.point);
        // The press and its mirror images (a mirror image off the model acts nowhere).
        let mut hits = vec![([false; 3], hit)];
        if Self::mirrored(&grab) {
            for flip in self.symmetry.mirrors() {
                let r = crate::symmetry::reflect_ray(flip, centre, &ray);
                if let Some((m2, h)) = self.session.pick(&r, tolerance)
                    && m2 == model
                {
                    hits.push((flip, h));
                }
            }
        }
        self.session.begin_group();
        let anchors = self.anchor(&model, &grab, &hits);
        let mut parts = Vec::new();
        for (flip, h) in hits {
            if let Some(active) = self.start(&model, &tools, flip, &h, &grab) {
                parts.push(Part { flip, active });
            }
        }
        self.notify(Notice::Grabbed {
            model: model.clone(),
            point: hit.point,
            element: hit.element,
        });
        if parts.is_empty() {
            self.free_anchors(&model, anchors);
            self.session.end_group();
            return;
        }
        self.drag = Some(Drag {
            model,
            centre,
            parts,
            pending: None,
            pending_ray: None,
            last_at: Some(hit.point),
            spacing: Self::spacing(&grab),
            last_applied: Instant::now() - DRAG_INTERVAL,
            anchors,
        });
    }

    /// Sculpt mode's anchor: a rope pull on a model with no fixed control point would move it
    /// as a whole, so for the pull the control points farther than [`ANCHOR_FRACTION`] of the
    /// model's size from every grabbed point are fixed (and freed at the release), and the
    /// pull deforms the clay where it is pulled. Returns the anchored points.
    fn anchor(&mut self, model: &str, grab: &Grab, hits: &[([bool; 3], Hit)]) -> Vec<usize> {
        let Ok(m) = self.session.model(Some(model)) else {
            return Vec::new();
        };
        let fixable = m.accepts(&Edit::Fix(Selection::default()));
        let none_fixed = m
            .display_lines()
            .iter()
            .all(|l| l.role != Some(LineRole::Fixed) || l.points.is_empty());
        if !(self.sculpt && matches!(grab, Grab::Rope { .. }) && fixable && none_fixed) {
            return Vec::new();
        }
        let reach = ANCHOR_FRACTION * m.size();
        let pts = m.control_points();
        let far: Vec<usize> = (0..pts.len())
            .filter(|&i| hits.iter().all(|(_, h)| (pts[i] - h.point).norm() > reach))
            .collect();
        if far.is_empty() || far.len() == pts.len() {
            return Vec::new();
        }
        let fix = Command::to(model, Edit::Fix(Selection::ids(far.clone())));
        if self.apply(fix) { far } else { Vec::new() }
    }

    /// Frees the points [`Self::anchor`] fixed.
    fn free_anchors(&mut self, model: &str, anchors: Vec<usize>) {
        if !anchors.is_empty() {
            self.apply(Command::to(model, Edit::Free(Selection::ids(anchors))));
        }
    }

    /// Starts `grab` at `hit` on `model` (a mirror image when `flip` has an axis): applies its
    /// first command and returns what the drag that follows does.
    fn start(
        &mut self,
        model: &str,
        tools: &[ToolSpec],
        flip: Axes,
        hit: &Hit,
        grab: &Grab,
    ) -> Option<Active> {
        let p = [hit.point.x, hit.point.y, hit.point.z];
        let one = |edit: Edit| Command::to(model, edit);
        match grab {
            Grab::Rope { stiffness } => {
                // A material point where the model's rope takes one (D-NURBS).
                let param = if crate::app::takes(tools, "rope", Some("param")) {
                    surface_param(hit)
                } else {
                    None
                };
                let name = format!("{ROPE}{}", crate::symmetry::suffix(flip));
                let edit = Edit::Rope {
                    name: Some(name.clone()),
                    from: p,
                    param,
                    to: None,
                    until: None,
                    velocity: None,
                    release: None,
                    stiffness: *stiffness,
                    length: None,
                    kernel: None,
                    start: None,
                };
                self.apply(one(edit)).then_some(Active::Rope { name })
            }
            Grab::ControlPoint => {
                if let Element::ControlPoint { index } = hit.element {
                    return Some(Active::ControlPoint {
                        model: model.to_string(),
                        index,
                    });
                }
                self.notify(Notice::Error {
                    message: "no control point under the mouse (show the control net and \
                              press on one of its points)"
                        .into(),
                    paused: false,
                });
                None
            }
            Grab::FfdPoint { pins } => Some(Active::Ffd {
                model: model.to_string(),
                last: hit.point,
                pins: pins.clone(),
            }),
            Grab::FfdPin => None,
            Grab::PdeLocal { half } => self.start_pde_local(hit, *half),
            Grab::Weight { weight } => {
                match hit.element {
                    Element::ControlPoint { index } => {
                        self.apply(one(Edit::SetWeight {
                            index,
                            weight: *weight,
                        }));
                    }
                    _ => self.notify(Notice::Error {
                        message: "click a control point to set its weight".into(),
                        paused: false,
                    }),
                }
                None
            }
            Grab::Force {
                direction,
                strength,
                radius,
                duration,
                falloff,
            } => self.start_force(
                model,
                tools,
                flip,
                hit,
                *direction * *strength,
                (*radius, falloff),
                *duration,
            ),
            Grab::Fix { brush } | Grab::Free { brush } => {
                self.start_fix(model, hit, matches!(grab, Grab::Fix { .. }), *brush)
            }
            Grab::Smooth { brush, strength } => {
                let template = Edit::Smooth {
                    near: [0.0; 3],
                    radius: *brush,
                    strength: Some(*strength),
                };
                let edit = self.stroke_edit(model, &template, hit.point, None, *brush, None);
                self.apply(Command::to(model, edit));
                (*brush > 0.0).then(|| Active::Brush {
                    edit: Box::new(template),
                    radius: *brush,
                    duration: None,
                })
            }
            Grab::Extrude => {
                let face = hit.extra.iter().find_map(|e| match e {
                    Some(Element::Face { index }) => Some(*index),
                    _ => None,
                });
                self.apply(one(Edit::Extrude {
                    face,
                    near: if face.is_none() { Some(p) } else { None },
                    factor: None,
                }));
                None
            }
            Grab::SculptFace => {
                // The face the pick names (another face's hit, or the sculpted face's
                // `extra`), else the face nearest the point.
                let face = std::iter::once(&Some(hit.element))
                    .chain(hit.extra.iter())
                    .find_map(|e| match e {
                        Some(Element::Face { index }) => Some(*index),
                        _ => None,
                    });
                self.apply(one(Edit::SculptFace {
                    face,
                    near: if face.is_none() { Some(p) } else { None },
                }));
                None
            }
            Grab::DeleteCell => {
                let c = cell(hit);
                self.apply(one(Edit::DeleteCell {
                    cell: c,
                    near: if c.is_none() { Some(p) } else { None },
                }));
                None
            }
            Grab::PaintMaterial { brush, .. } => self.start_paint(model, hit, grab, *brush),
        }
    }

    fn start_pde_local(&mut self, hit: &Hit, half: [f64; 2]) -> Option<Active> {
        match (hit.element, hit.extra[0]) {
            (Element::SurfacePoint { param }, patch) => {
                self.locals += 1;
                Some(Active::PdeLocal {
                    name: format!("studio-local-{}", self.locals),
                    patch: match patch {
                        Some(Element::Patch { index }) => index,
                        _ => 0,
                    },
                    uv: param,
                    start: hit.point,
                    half,
                })
            }
            _ => {
                self.notify(Notice::Error {
                    message: "a local deformation starts on a PDE surface's point".into(),
                    paused: false,
                });
                None
            }
        }
    }

    /// The force brush: a force at the hit (a region force where the model takes one), made
    /// again along the stroke.
    #[allow(clippy::too_many_arguments)]
    fn start_force(
        &mut self,
        model: &str,
        tools: &[ToolSpec],
        flip: Axes,
        hit: &Hit,
        force: Vec3,
        (radius, falloff): (f64, &str),
        duration: f64,
    ) -> Option<Active> {
        let f = crate::symmetry::reflect_dir(flip, force);
        let force = [f.x, f.y, f.z];
        let template = if crate::app::takes(tools, "region-force", None) {
            Edit::RegionForce {
                name: None,
                center: [0.0; 3],
                radius: radius.max(1e-9),
                force,
                until: None,
                falloff: (falloff != "constant"
                    && crate::app::takes(tools, "region-force", Some("falloff")))
                .then(|| falloff.to_string()),
            }
        } else {
            Edit::Force {
                name: None,
                near: None,
                // A material point where the model's force takes one (D-NURBS).
                param: crate::app::takes(tools, "force", Some("param")).then_some([0.0; 2]),
                force,
                until: None,
            }
        };
        let duration = Some(duration.max(0.0));
        let edit = self.stroke_edit(
            model,
            &template,
            hit.point,
            surface_param(hit),
            radius,
            duration,
        );
        self.apply(Command::to(model, edit));
        Some(Active::Brush {
            edit: Box::new(template),
            radius,
            duration,
        })
    }

    fn start_fix(&mut self, model: &str, hit: &Hit, fix: bool, brush: f64) -> Option<Active> {
        let make = |sel: Selection| if fix { Edit::Fix(sel) } else { Edit::Free(sel) };
        if brush > 0.0 {
            let template = make(Selection::default());
            let edit = self.stroke_edit(model, &template, hit.point, None, brush, None);
            self.apply(Command::to(model, edit));
            return Some(Active::Brush {
                edit: Box::new(template),
                radius: brush,
                duration: None,
            });
        }
        let edit = match hit.element {
            Element::ControlPoint { index } => make(Selection::ids(vec![index])),
            _ => make(Selection::nearest([hit.point.x, hit.point.y, hit.point.z])),
        };
        self.apply(Command::to(model, edit));
        None
    }

    fn start_paint(&mut self, model: &str, hit: &Hit, grab: &Grab, brush: f64) -> Option<Active> {
        let Grab::PaintMaterial {
            density,
            damping,
            edge_stiffness,
            ..
        } = *grab
        else {
            return None;
        };
        let template = Edit::Material {
            cells: None,
            min: None,
            max: None,
            density: Some(density),
            damping: Some(damping),
            edge_stiffness: Some(edge_stiffness),
            virtual_stiffness: None,
            anisotropy: None,
            mu: None,
            gamma: None,
            alpha: None,
            beta: None,
        };
        if brush > 0.0 {
            let edit = self.stroke_edit(model, &template, hit.point, None, brush, None);
            self.apply(Command::to(model, edit));
            return Some(Active::Brush {
                edit: Box::new(template),
                radius: brush,
                duration: None,
            });
        }
        if let Some(c) = cell(hit) {
            let mut edit = template;
            if let Edit::Material { cells, .. } = &mut edit {
                *cells = Some(vec![c]);
            }
            self.apply(Command::to(model, edit));
        } else {
            self.notify(Notice::Error {
                message: "material painting needs a solid's control cell under the mouse".into(),
                paused: false,
            });
        }
        None
    }

    /// The edit of a brush at `at` (`param`: the material point there, where the edit takes
    /// one): `template` with its box, centre or point there, acting for `duration` seconds of
    /// the model's time from now.
    fn stroke_edit(
        &self,
        model: &str,
        template: &Edit,
        at: Vec3,
        param: Option<[f64; 2]>,
        radius: f64,
        duration: Option<f64>,
    ) -> Edit {
        let until = duration.map(|d| self.session.model(Some(model)).map_or(0.0, |m| m.time()) + d);
        let p = [at.x, at.y, at.z];
        match template {
            Edit::RegionForce {
                force,
                radius,
                falloff,
                ..
            } => Edit::RegionForce {
                name: None,
                center: p,
                radius: *radius,
                force: *force,
                until,
                falloff: falloff.clone(),
            },
            Edit::Force {
                force, param: tp, ..
            } => {
                let param = if tp.is_some() { param } else { None };
                Edit::Force {
                    name: None,
                    near: if param.is_some() { None } else { Some(p) },
                    param,
                    force: *force,
                    until,
                }
            }
            t => Self::brush_edit(t, at, radius),
        }
    }

    /// The command of `part` for the cursor at `to` (the primary part's; a mirror image's
    /// cursor is its reflection).
    fn part_command(&self, d_model: &str, centre: Vec3, part: &mut Part, to: Vec3) -> Command {
        let to = crate::symmetry::reflect(part.flip, centre, to);
        let t = [to.x, to.y, to.z];
        match &mut part.active {
            Active::Brush {
                edit,
                radius,
                duration,
            } => Command::to(
                d_model,
                self.stroke_edit(d_model, edit, to, None, *radius, *duration),
            ),
            Active::Rope { name } => Command::to(
                d_model,
                Edit::MoveRope {
                    name: name.clone(),
                    to: t,
                },
            ),
            Active::ControlPoint { model, index } => Command::to(
                model,
                Edit::MovePoint {
                    index: *index,
                    to: t,
                },
            ),
            Active::PdeLocal {
                name,
                patch,
                uv,
                start,
                half,
            } => {
                // The G1 bump's peak is p / 256 (eq 32 at the region's centre).
                let p = (to - *start) * 256.0;
                Command::to(
                    d_model,
                    Edit::PdeLocal {
                        name: name.clone(),
                        patch: *patch,
                        u: [(uv[0] - half[0]).max(0.0), (uv[0] + half[0]).min(1.0)],
                        v: [uv[1] - half[1], uv[1] + half[1]],
                        continuity: Some("G1".into()),
                        p: [p.x, p.y, p.z],
                    },
                )
            }
            Active::Ffd { model, last, pins } => {
                let from = [last.x, last.y, last.z];
                *last = to;
                let mut moves = vec![PointMove { from, to: t }];
                moves.extend(pins.iter().map(|p| PointMove {
                    from: [p.x, p.y, p.z],
                    to: [p.x, p.y, p.z],
                }));
                Command::to(model, Edit::FfdMove { moves })
            }
        }
    }

    /// Applies the pending cursor move (or brush stroke position) of the drag, at most once
    /// per [`DRAG_INTERVAL`] (`force`: now, and a brush acts even nearer than its spacing).
    fn apply_drag(&mut self, force: bool) {
        let Some(d) = self.drag.as_ref() else { return };
        if d.pending.is_none() && d.pending_ray.is_none() {
            return;
        }
        if !force && d.last_applied.elapsed() < DRAG_INTERVAL {
            if !self.running {
                // Nothing else to do: wait out the interval without spinning.
                std::thread::sleep(Duration::from_millis(2));
            }
            return;
        }
        let Some(mut d) = self.drag.take() else {
            return;
        };
        d.last_applied = Instant::now();
        if let Some((ray, tol)) = d.pending_ray.take() {
            self.stroke_at(&mut d, &ray, tol, force);
        } else if let Some(to) = d.pending.take() {
            let brush = d
                .parts
                .iter()
                .any(|p| matches!(p.active, Active::Brush { .. }));
            let near = d.last_at.is_some_and(|l| (to - l).norm() < d.spacing);
            if brush && near && !force {
                // Too near the last position: wait for the cursor to move on.
                d.pending = Some(to);
            } else {
                d.last_at = Some(to);
                let model = d.model.clone();
                let centre = d.centre;
                // A brush's dabs each say what they did; a rope's or a handle's moves only
                // where the cursor is now.
                let note = if brush { Notice::Log } else { Notice::Progress };
                for part in &mut d.parts {
                    let c = self.part_command(&model, centre, part, to);
                    self.apply_noting(c, note);
                }
            }
        }
        self.drag = Some(d);
    }

    /// A brush stroke's position from the mouse ray: the brush acts where the ray meets the
    /// model (its mirror images where the mirrored rays do), once the stroke has moved by the
    /// brush's spacing.
    fn stroke_at(&mut self, d: &mut Drag, ray: &Ray, tolerance: f64, force: bool) {
        let Some((m, hit)) = self.session.pick(ray, tolerance) else {
            return;
        };
        if m != d.model
            || (!force
                && d.last_at
                    .is_some_and(|l| (hit.point - l).norm() < d.spacing))
        {
            return;
        }
        d.last_at = Some(hit.point);
        for part in &d.parts {
            let Active::Brush {
                edit,
                radius,
                duration,
            } = &part.active
            else {
                continue;
            };
            let (at, param) = if part.flip == [false; 3] {
                (hit.point, surface_param(&hit))
            } else {
                let r = crate::symmetry::reflect_ray(part.flip, d.centre, ray);
                match self.session.pick(&r, tolerance) {
                    Some((m2, h)) if m2 == d.model => (h.point, surface_param(&h)),
                    _ => continue,
                }
            };
            let e = self.stroke_edit(&d.model, edit, at, param, *radius, *duration);
            self.apply(Command::to(&d.model, e));
        }
    }

    fn drop_grab(&mut self) {
        if self.drag.is_none() {
            return;
        }
        self.apply_drag(true);
        let Some(d) = self.drag.take() else { return };
        let mut pulled = false;
        for part in &d.parts {
            match &part.active {
                Active::Rope { name } => {
                    pulled = true;
                    self.apply(Command::to(&d.model, Edit::Release { name: name.clone() }));
                }
                Active::Brush {
                    duration: Some(_), ..
                } => pulled = true,
                _ => {}
            }
        }
        self.free_anchors(&d.model, d.anchors.clone());
        // Sculpt mode: the shape reached stays (one undo step with the pull).
        let keeps = self
            .session
            .model(Some(&d.model))
            .is_ok_and(|m| m.accepts(&Edit::PlasticReset));
        if self.sculpt && self.flow.is_none() && pulled && keeps {
            self.apply(Command::to(&d.model, Edit::Stop));
            self.apply(Command::to(&d.model, Edit::PlasticReset));
        }
        self.session.end_group();
    }

    /// Puts the sculpt mode's plastic flow on every model that has a rest shape (off where
    /// sculpt mode or the flow is off). The yield distance scales with each model's size.
    fn set_flow(&mut self) {
        let names: Vec<String> = self
            .session
            .model_names()
            .into_iter()
            .map(str::to_string)
            .collect();
        for name in names {
            let p = match (self.sculpt, self.flow) {
                (true, Some(f)) => self.session.model(Some(&name)).ok().and_then(|m| {
                    vclay_session::Plasticity::new(f.rate, f.yield_fraction * m.size()).ok()
                }),
                _ => None,
            };
            // Kinds without a rest shape (FFD, PDE, frozen weights) refuse the flow: they
            // have nothing to keep.
            let _ = self.session.set_plasticity(Some(&name), p);
        }
    }

    fn publish(&mut self) {
        let rev = self.session.revision();
        if self.shown_revision == Some(rev) {
            return;
        }
        let Ok(mut slot) = self.shared.frame.lock() else {
            return;
        };
        if slot.is_some() {
            // The UI has not taken the last frame: do not build another.
            return;
        }
        let t0 = Instant::now();
        let known = self.energy_clock.reuse(self.running);
        let (models, energy) = model_views(&self.session, self.colour_by.as_deref(), known);
        if known.is_none() {
            self.energy_clock.evaluated_in(energy, t0.elapsed());
        }
        // Mean over the last second's steps; 0 without steps (a float sum of nothing is -0,
        // which the status bar would print as "-0.00 ms").
        let step_seconds = if self.step_times.is_empty() {
            0.0
        } else {
            self.step_times.iter().map(|s| s.1).sum::<f64>() / self.step_times.len() as f64
        };
        let steps = self
            .session
            .model(None)
            .map(|m| m.steps())
            .unwrap_or_default();
        *slot = Some(Frame {
            revision: rev,
            models,
            time: self.session.time(),
            steps,
            energy,
            samples: std::mem::take(&mut self.samples),
            step_seconds,
            steps_per_second: self.step_times.len() as f64,
            running: self.running,
            can_undo: self.session.can_undo(),
            can_redo: self.session.can_redo(),
            dirty: rev != self.saved_revision,
            scheduled: self.session.schedule().len(),
            build_seconds: t0.elapsed().as_secs_f64(),
            generation: self.generation,
        });
        drop(slot);
        self.shown_revision = Some(rev);
        self.wake();
    }

    fn autosave_if_due(&mut self) {
        let Some((path, every)) = &self.autosave else {
            return;
        };
        let rev = self.session.revision();
        if rev == self.autosaved.1 || self.autosaved.0.elapsed() < *every {
            return;
        }
        let path = path.clone();
        match vclay_session::file::save(&path, &self.session, self.run_info.as_ref()) {
            Ok(()) => {
                self.autosaved = (Instant::now(), rev);
                let _ = self.notices.send(Notice::Autosaved(path));
            }
            Err(e) => {
                self.autosave = None;
                self.notify(Notice::Error {
                    message: format!("autosave failed and is off: {e}"),
                    paused: false,
                });
            }
        }
    }
}

/// The display data of every model of `session` and their summed energies (what a frame
/// carries; the benchmark times exactly this); `colour_by` names the field to colour meshes by
/// (see [`Request::ColourBy`]).
///
/// `known`: the energies to report instead of asking every model (the worker's
/// [`EnergyClock`] while a simulation runs); `None` evaluates them (for a D-NURBS with dynamic
/// weights, a pass over every quadrature point: about a third of a step).
pub fn model_views(
    session: &Session,
    colour_by: Option<&str>,
    known: Option<Energy>,
) -> (Vec<ModelView>, Energy) {
    let mut models = Vec::new();
    let mut energy = Energy::default();
    for name in session.model_names() {
        let Ok(m) = session.model(Some(name)) else {
            continue;
        };
        if known.is_none() {
            let e = m.energy();
            energy.kinetic += e.kinetic;
            energy.elastic += e.elastic;
            energy.tools += e.tools;
        }
        models.push(ModelView {
            name: name.to_string(),
            tools: m.tools(),
            summary: m.summary(),
            mesh: Arc::new(m.display_mesh().unwrap_or_default()),
            lines: Arc::new(m.display_lines()),
            params: m.params(),
            size: m.size(),
            dt: m.dt(),
            time: m.time(),
            fields: m.display_fields(),
            field: colour_by.and_then(|f| m.display_field(f)).map(Arc::new),
        });
    }
    (models, known.unwrap_or(energy))
}

/// How often the frames of a running simulation evaluate the models' energies for the
/// readout under the energy plot, at most. The plot's samples come from the steps' own
/// reports, so only the readout waits; a paused model's frames always evaluate them.
pub const ENERGY_REFRESH: Duration = Duration::from_millis(100);

/// The interval between two evaluations of a running simulation's energies is also at least
/// this many times what the last evaluating frame's display data took
/// ([`EnergyClock::evaluated_in`]), so the readout costs at most 1/20 of the worker's time: a
/// 32 x 32 D-NURBS with dynamic weights pays about a third of a step for it, and with steps of
/// 50-100 ms a fixed 100 ms interval evaluated it every frame or every second frame.
pub const ENERGY_COST_RATIO: u32 = 20;

/// When the frames last evaluated the energies, and what they were ([`ENERGY_REFRESH`],
/// [`ENERGY_COST_RATIO`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct EnergyClock {
    last: Option<(Instant, Energy)>,
    /// Wait at least this long before the next evaluation.
    interval: Duration,
}

impl EnergyClock {
    /// The energies to reuse for this frame (`None`: evaluate them). `running`: whether the
    /// simulation runs.
    pub fn reuse(&self, running: bool) -> Option<Energy> {
        match self.last {
            Some((t, e)) if running && t.elapsed() < ENERGY_REFRESH.max(self.interval) => Some(e),
            _ => None,
        }
    }

    /// Records energies just evaluated.
    pub fn evaluated(&mut self, e: Energy) {
        self.evaluated_in(e, Duration::ZERO);
    }

    /// Records energies just evaluated by a frame whose display data took `took`: the next
    /// evaluation waits [`ENERGY_COST_RATIO`] times that, at least [`ENERGY_REFRESH`].
    pub fn evaluated_in(&mut self, e: Energy, took: Duration) {
        self.last = Some((Instant::now(), e));
        self.interval = took.saturating_mul(ENERGY_COST_RATIO);
    }
}
