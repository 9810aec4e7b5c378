//! The frame-time benchmark (`vclay-studio --bench`): the studio's frame loop without the
//! window, on one thread so the figures do not depend on scheduling: per frame, `steps`
//! simulation steps, a rope cursor move every second frame (the studio coalesces moves to one
//! per [`crate::worker::DRAG_INTERVAL`], about every second frame at 60 frames/s), the display
//! data ([`crate::worker::model_views`]: `display_mesh` + `display_lines`) and the GPU buffers
//! ([`crate::render::SceneBuffers::build`], what the renderer is handed). Not a timed test.

use std::time::Instant;

use vclay_session::scenario::Scenario;
use vclay_session::{Command, Edit, Session};

use crate::render::{Layers, SceneBuffers};
use crate::worker::{Frame, model_views};

/// One benchmark model.
#[derive(Clone, Copy, Debug)]
pub struct Case {
    /// Name in the report.
    pub name: &'static str,
    /// Scenario text.
    pub scenario: &'static str,
    /// Where the rope grabs.
    pub grab: [f64; 3],
    /// Simulation steps per frame.
    pub steps: usize,
    /// Frame-rate goal of the issue: 60 for the level-3 cube and the frozen sheet (issue 16), 30
    /// for the level-4 cube (2 steps a frame) and the dynamic-weight sheets (one step a frame,
    /// "30 steps/s", issue 27).
    pub goal_fps: f64,
}

/// The cases: the 4^3 cube at levels 3 and 4 and a 32 x 32 D-NURBS surface (frozen
/// weights; dynamic weights with the direct solve and with the default for this size, the
/// block-Schur one).
pub const CASES: [Case; 5] = [
    Case {
        name: "4^3 cube, level 3 (15,625 data points), rope",
        scenario: "[model]\nkind = \"subdivision-solid\"\nprimitive = \"box\"\npoints = [4, 4, 4]\nlevel = 3\n[material]\ndamping = 2.0\nedge_stiffness = 100.0\nvirtual_stiffness = 50.0\n[simulation]\nintegrator = \"symplectic\"\ndt = 0.002\n",
        grab: [1.0, 1.0, 1.0],
        steps: 2,
        goal_fps: 60.0,
    },
    Case {
        name: "4^3 cube, level 4 (117,649 data points), rope",
        scenario: "[model]\nkind = \"subdivision-solid\"\nprimitive = \"box\"\npoints = [4, 4, 4]\nlevel = 4\n[material]\ndamping = 2.0\nedge_stiffness = 100.0\nvirtual_stiffness = 50.0\n[simulation]\nintegrator = \"symplectic\"\ndt = 0.001\n",
        grab: [1.0, 1.0, 1.0],
        steps: 2,
        goal_fps: 30.0,
    },
    Case {
        name: "32 x 32 D-NURBS surface (frozen weights), rope",
        scenario: "[model]\nkind = \"dnurbs-surface\"\nsize = [32, 32]\ndegree = [3, 3]\nengine = \"frozen\"\n[simulation]\ndt = 0.01\n",
        grab: [0.5, 0.5, 0.0],
        steps: 1,
        goal_fps: 60.0,
    },
    Case {
        name: "32 x 32 D-NURBS surface (dynamic weights, direct solver), rope",
        scenario: "[model]\nkind = \"dnurbs-surface\"\nsize = [32, 32]\ndegree = [3, 3]\n[simulation]\ndt = 0.01\nsolver = \"direct\"\n",
        grab: [0.5, 0.5, 0.0],
        steps: 1,
        goal_fps: 30.0,
    },
    Case {
        name: "32 x 32 D-NURBS surface (dynamic weights, default solver: block-schur), rope",
        scenario: "[model]\nkind = \"dnurbs-surface\"\nsize = [32, 32]\ndegree = [3, 3]\n[simulation]\ndt = 0.01\n",
        grab: [0.5, 0.5, 0.0],
        steps: 1,
        goal_fps: 30.0,
    },
];

/// Figures of one case.
#[derive(Clone, Debug, PartialEq)]
pub struct Result {
    /// Case name.
    pub name: String,
    /// Frames run.
    pub frames: usize,
    /// Steps per frame.
    pub steps: usize,
    /// Mean frame time, ms.
    pub frame_ms: f64,
    /// Slowest frame, ms.
    pub max_ms: f64,
    /// Mean process CPU time per frame (all threads: the steps' element work runs on rayon's
    /// pool), ms; NaN where `/proc/self/stat` cannot be read. On a loaded machine the wall
    /// times include waits for a core, this does not.
    pub cpu_ms: f64,
    /// Mean time of the steps of one frame, ms.
    pub step_ms: f64,
    /// Mean time of the display data, ms.
    pub display_ms: f64,
    /// Mean time of the GPU buffers, ms.
    pub buffers_ms: f64,
    /// Triangles handed to the renderer.
    pub triangles: usize,
    /// Bytes handed to the renderer per frame.
    pub bytes: usize,
    /// The frame-rate goal.
    pub goal_fps: f64,
}

impl Result {
    /// Frames per second.
    pub fn fps(&self) -> f64 {
        1e3 / self.frame_ms.max(1e-9)
    }
}

/// Runs `case` for `frames` frames.
pub fn run(case: &Case, frames: usize) -> std::result::Result<Result, String> {
    let mut session: Session =
        Scenario::parse(case.scenario, case.name, "bench", std::path::Path::new("."))
            .map_err(|e| e.to_string())?
            .session;
    session
        .apply(Command::new(Edit::Rope {
            name: Some("bench".into()),
            from: case.grab,
            param: None,
            to: None,
            until: None,
            velocity: None,
            release: None,
            stiffness: None,
            length: None,
            kernel: None,
            start: None,
        }))
        .map_err(|e| e.to_string())?;
    let layers = Layers::default();
    let mut clock = crate::worker::EnergyClock::default();
    let (mut steps, mut display, mut buffers, mut max) = (0.0, 0.0, 0.0, 0.0_f64);
    let (mut tris, mut bytes) = (0, 0);
    let start = Instant::now();
    let cpu0 = vclay_core::yardstick::process_cpu_seconds();
    for f in 0..frames {
        let t0 = Instant::now();
        if f % 2 == 0 {
            let a = f as f64 * 0.05;
            let g = case.grab;
            let to = [
                g[0] + 0.3 * a.sin(),
                g[1] + 0.3 * (1.0 - a.cos()),
                g[2] + 0.2,
            ];
            session
                .apply(Command::new(Edit::MoveRope {
                    name: "bench".into(),
                    to,
                }))
                .map_err(|e| e.to_string())?;
        }
        for _ in 0..case.steps {
            session.step().map_err(|e| e.to_string())?;
        }
        let t1 = Instant::now();
        // As the worker does while the simulation runs: energies at most every
        // `ENERGY_REFRESH` and `ENERGY_COST_RATIO` times their cost.
        let known = clock.reuse(true);
        let (models, energy) = model_views(&session, None, known);
        if known.is_none() {
            clock.evaluated_in(energy, t1.elapsed());
        }
        let frame = Frame {
            revision: session.revision(),
            models,
            energy,
            ..Default::default()
        };
        let t2 = Instant::now();
        let b = SceneBuffers::build(&frame, &layers);
        let t3 = Instant::now();
        tris = b.tri_indices.len() / 3;
        bytes = b.bytes();
        steps += (t1 - t0).as_secs_f64();
        display += (t2 - t1).as_secs_f64();
        buffers += (t3 - t2).as_secs_f64();
        max = max.max((t3 - t0).as_secs_f64());
    }
    let n = frames.max(1) as f64;
    let cpu_ms = cpu0
        .zip(vclay_core::yardstick::process_cpu_seconds())
        .map_or(f64::NAN, |(a, b)| (b - a) * 1e3 / n);
    Ok(Result {
        name: case.name.into(),
        frames,
        steps: case.steps,
        frame_ms: start.elapsed().as_secs_f64() * 1e3 / n,
        max_ms: max * 1e3,
        cpu_ms,
        step_ms: steps * 1e3 / n,
        display_ms: display * 1e3 / n,
        buffers_ms: buffers * 1e3 / n,
        triangles: tris,
        bytes,
        goal_fps: case.goal_fps,
    })
}
