//! TOML scenario files for dynamic solids, and their runner (`vclay run SCENARIO.toml`).
//!
//! A scenario names a model, its material, the integrator, a timeline of tool actions and the
//! outputs; `docs/formats.md` ("Scenario files") documents every key. The `[model]` table's
//! `kind` chooses the module that reads the rest: this one handles `"subdivision-solid"` and
//! `"bspline-solid"` ([`SOLID_KINDS`]); [`model_kind`] reads only the kind so a caller can
//! dispatch other kinds elsewhere.
//!
//! Errors name the file, the line and the key: syntax and type errors come from the `toml`
//! parser with its location; range checks done after parsing look up the line of the key in the
//! table or timeline entry they belong to.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use toml::Spanned;
use vclay_core::Vec3;
use vclay_lattice::formats::vtu::PointData;
use vclay_lattice::{BoundaryRule, Lattice, formats, primitives};
use vclay_spline::{KnotVector, NurbsVolume};

use crate::error::SolidsError;
use crate::material::{Material, MaterialField};
use crate::model::SolidSource;
use crate::solid::{DynamicSolid, Integrator, SolidParams, ToolId};
use crate::tools::Tool;

/// The model kinds this module runs.
pub const SOLID_KINDS: [&str; 2] = ["subdivision-solid", "bspline-solid"];

/// Default `[simulation] duration` in seconds when neither `steps` nor `duration` is given.
pub const DEFAULT_DURATION: f64 = 1.0;
/// Default `[material] metric_stiffness` (weight `c` of the metric-tensor energy).
pub const DEFAULT_METRIC_STIFFNESS: f64 = 100.0;
/// Default `[output] every`.
pub const DEFAULT_FRAME_EVERY: usize = 50;

// ------------------------------------------------------------------------------------------
// File structure
// ------------------------------------------------------------------------------------------

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    model: Spanned<ModelSpec>,
    #[serde(default)]
    material: Option<Spanned<MaterialSpec>>,
    #[serde(default)]
    simulation: Option<Spanned<SimulationSpec>>,
    #[serde(default)]
    timeline: Vec<Spanned<Action>>,
    #[serde(default)]
    output: Option<Spanned<OutputSpec>>,
}

/// Only the kind, for dispatch.
#[derive(Debug, Deserialize)]
struct KindOnly {
    model: KindTable,
}

#[derive(Debug, Deserialize)]
struct KindTable {
    kind: Spanned<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelSpec {
    kind: String,
    // subdivision-solid
    primitive: Option<String>,
    file: Option<PathBuf>,
    points: Option<[usize; 3]>,
    min: Option<[f64; 3]>,
    max: Option<[f64; 3]>,
    level: Option<usize>,
    boundary: Option<String>,
    radius: Option<f64>,
    height: Option<f64>,
    // bspline-solid
    entity: Option<usize>,
    control: Option<[usize; 3]>,
    degree: Option<[usize; 3]>,
    samples: Option<[usize; 3]>,
}

#[derive(Debug, Default)]
struct MaterialValues {
    density: Option<f64>,
    damping: Option<f64>,
    edge_stiffness: Option<f64>,
    virtual_stiffness: Option<f64>,
    anisotropy: Option<[f64; 3]>,
}

impl MaterialValues {
    fn apply(&self, m: &mut Material) {
        if let Some(v) = self.density {
            m.density = v;
        }
        if let Some(v) = self.damping {
            m.damping = v;
        }
        if let Some(v) = self.edge_stiffness {
            m.edge_stiffness = v;
        }
        if let Some(v) = self.virtual_stiffness {
            m.virtual_stiffness = v;
        }
        if let Some(v) = self.anisotropy {
            m.anisotropy = v;
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialSpec {
    density: Option<f64>,
    damping: Option<f64>,
    edge_stiffness: Option<f64>,
    virtual_stiffness: Option<f64>,
    anisotropy: Option<[f64; 3]>,
    energy: Option<String>,
    metric_stiffness: Option<f64>,
    #[serde(default)]
    cells: Vec<Spanned<CellMaterial>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CellMaterial {
    cells: Vec<usize>,
    density: Option<f64>,
    damping: Option<f64>,
    edge_stiffness: Option<f64>,
    virtual_stiffness: Option<f64>,
    anisotropy: Option<[f64; 3]>,
}

/// `MaterialValues` from a struct with the same five optional fields.
macro_rules! values_of {
    ($x:expr) => {
        MaterialValues {
            density: $x.density,
            damping: $x.damping,
            edge_stiffness: $x.edge_stiffness,
            virtual_stiffness: $x.virtual_stiffness,
            anisotropy: $x.anisotropy,
        }
    };
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct SimulationSpec {
    integrator: Option<String>,
    dt: Option<f64>,
    steps: Option<usize>,
    duration: Option<f64>,
    divergence_factor: Option<f64>,
    cg_tolerance: Option<f64>,
    cg_max_iterations: Option<usize>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct OutputSpec {
    dir: Option<PathBuf>,
    #[serde(default)]
    frames: Vec<String>,
    every: Option<usize>,
    #[serde(rename = "final")]
    final_model: Option<PathBuf>,
    csv: Option<PathBuf>,
}

/// Control points chosen by index or by a box around their rest positions.
#[derive(Debug, Default)]
struct Selection {
    points: Option<Vec<usize>>,
    min: Option<[f64; 3]>,
    max: Option<[f64; 3]>,
}

#[derive(Debug, Deserialize)]
#[serde(tag = "action", rename_all = "kebab-case", deny_unknown_fields)]
enum Action {
    Rope {
        at: f64,
        from: [f64; 3],
        to: Option<[f64; 3]>,
        until: Option<f64>,
        release: Option<f64>,
        stiffness: Option<f64>,
        length: Option<f64>,
        name: Option<String>,
    },
    Force {
        at: f64,
        near: [f64; 3],
        force: [f64; 3],
        until: Option<f64>,
        name: Option<String>,
    },
    RegionForce {
        at: f64,
        center: [f64; 3],
        radius: f64,
        force: [f64; 3],
        until: Option<f64>,
        name: Option<String>,
    },
    Gravity {
        at: f64,
        g: [f64; 3],
        until: Option<f64>,
        name: Option<String>,
    },
    Inflate {
        at: f64,
        pressure: f64,
        until: Option<f64>,
        name: Option<String>,
    },
    Release {
        at: f64,
        name: String,
    },
    Fix {
        at: f64,
        points: Option<Vec<usize>>,
        min: Option<[f64; 3]>,
        max: Option<[f64; 3]>,
    },
    Free {
        at: f64,
        points: Option<Vec<usize>>,
        min: Option<[f64; 3]>,
        max: Option<[f64; 3]>,
    },
    Extrude {
        at: f64,
        face: Option<usize>,
        near: Option<[f64; 3]>,
        factor: Option<f64>,
    },
    #[serde(alias = "trim")]
    DeleteCell {
        at: f64,
        cell: Option<usize>,
        near: Option<[f64; 3]>,
    },
    PlasticReset {
        at: f64,
    },
    Stop {
        at: f64,
    },
    Material {
        at: f64,
        cells: Option<Vec<usize>>,
        density: Option<f64>,
        damping: Option<f64>,
        edge_stiffness: Option<f64>,
        virtual_stiffness: Option<f64>,
        anisotropy: Option<[f64; 3]>,
    },
    Integrator {
        at: f64,
        integrator: Option<String>,
        dt: Option<f64>,
    },
}

impl Action {
    fn at(&self) -> f64 {
        match self {
            Action::Rope { at, .. }
            | Action::Force { at, .. }
            | Action::RegionForce { at, .. }
            | Action::Gravity { at, .. }
            | Action::Inflate { at, .. }
            | Action::Release { at, .. }
            | Action::Fix { at, .. }
            | Action::Free { at, .. }
            | Action::Extrude { at, .. }
            | Action::DeleteCell { at, .. }
            | Action::PlasticReset { at }
            | Action::Stop { at }
            | Action::Material { at, .. }
            | Action::Integrator { at, .. } => *at,
        }
    }
}

// ------------------------------------------------------------------------------------------
// Locations
// ------------------------------------------------------------------------------------------

/// The source text and name, for errors with lines.
struct Source<'a> {
    name: &'a str,
    text: &'a str,
}

impl Source<'_> {
    fn err(&self, span: &Range<usize>, key: &str, message: impl std::fmt::Display) -> SolidsError {
        SolidsError::Scenario {
            file: self.name.to_string(),
            line: vclay_core::text::key_line(self.text, span, key),
            message: format!("`{key}`: {message}"),
        }
    }
}

fn parse_error(name: &str, text: &str, e: toml::de::Error) -> SolidsError {
    let line = e.span().map_or(0, |s| {
        text[..s.start.min(text.len())].matches('\n').count() + 1
    });
    SolidsError::Scenario {
        file: name.to_string(),
        line,
        message: e.message().to_string(),
    }
}

/// The `[model] kind` of a scenario text (`name` is used in errors).
pub fn model_kind(text: &str, name: &str) -> Result<String, SolidsError> {
    let k: KindOnly = toml::from_str(text).map_err(|e| parse_error(name, text, e))?;
    Ok(k.model.kind.into_inner())
}

// ------------------------------------------------------------------------------------------
// The parsed scenario
// ------------------------------------------------------------------------------------------

/// A scenario ready to run: the solid, the timeline and the outputs.
#[derive(Debug)]
pub struct Scenario {
    /// The solid in its initial state.
    pub solid: DynamicSolid,
    /// Number of steps to run.
    pub steps: usize,
    events: Vec<(f64, Action)>,
    /// Output settings.
    pub output: Output,
}

/// Where and what to write.
#[derive(Clone, Debug, PartialEq)]
pub struct Output {
    /// Output folder (relative paths below are inside it).
    pub dir: PathBuf,
    /// Frame files written every [`Output::every`] steps, one per format, in the order given
    /// (no duplicates).
    pub frames: Vec<FrameFormat>,
    /// Frame interval in steps.
    pub every: usize,
    /// Final model file (`.ovm` control lattice for subdivision solids, `.json` NURBS volume
    /// model for B-spline solids).
    pub final_model: Option<PathBuf>,
    /// Per-step CSV (step, time, energies, step time, CG iterations).
    pub csv: Option<PathBuf>,
}

/// The file format of a frame of a running scenario (`[output] frames`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameFormat {
    /// The boundary surface of the data lattice, Wavefront OBJ (`frame_NNNNNN.obj`).
    Obj,
    /// The boundary surface of the data lattice, ASCII PLY (`frame_NNNNNN.ply`).
    Ply,
    /// The boundary surface of the data lattice, ASCII STL (`frame_NNNNNN.stl`).
    Stl,
    /// The data lattice (hexahedra), VTK XML unstructured grid (`frame_NNNNNN.vtu`), with the
    /// point data `displacement` (from the rest shape), `velocity`, `spring_force` (not under
    /// the metric-tensor energy) and `mass`.
    Vtu,
}

impl FrameFormat {
    /// Every format.
    pub const ALL: [FrameFormat; 4] = [Self::Obj, Self::Ply, Self::Stl, Self::Vtu];

    /// The format named `name` (its extension: `"obj"`, `"ply"`, `"stl"` or `"vtu"`).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|f| f.extension() == name)
    }

    /// The file extension (without the dot), which is also its name in scenario files.
    pub fn extension(self) -> &'static str {
        match self {
            Self::Obj => "obj",
            Self::Ply => "ply",
            Self::Stl => "stl",
            Self::Vtu => "vtu",
        }
    }
}

fn vec3(a: [f64; 3]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

fn check_finite(
    src: &Source<'_>,
    span: &Range<usize>,
    key: &str,
    v: &[f64],
) -> Result<(), SolidsError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(src.err(span, key, "must be finite"))
    }
}

impl Scenario {
    /// Reads and builds a scenario file; relative model files are resolved against the
    /// scenario's folder, the output folder against the current directory.
    pub fn from_file(path: &Path) -> Result<Self, SolidsError> {
        let text = std::fs::read_to_string(path).map_err(|source| SolidsError::Io {
            path: path.display().to_string(),
            source,
        })?;
        let base = path.parent().unwrap_or(Path::new("."));
        Self::parse(&text, &path.display().to_string(), base)
    }

    /// Parses and builds a scenario from text (`name` for errors, `base` for relative model
    /// files).
    pub fn parse(text: &str, name: &str, base: &Path) -> Result<Self, SolidsError> {
        let src = Source { name, text };
        let file: File = toml::from_str(text).map_err(|e| parse_error(name, text, e))?;
        let mspan = file.model.span();
        let model = file.model.into_inner();
        let (source, p) = build_model(&src, &mspan, &model, base)?;
        // Material.
        let mut field = MaterialField::uniform(Material::default(), source.control_cells());
        let mut metric: Option<(Range<usize>, Option<f64>)> = None;
        if let Some(m) = file.material {
            let span = m.span();
            let m = m.into_inner();
            let check = |sp: &Range<usize>,
                         vals: &MaterialValues,
                         cells: Option<&[usize]>,
                         field: &mut MaterialField| {
                field.update(cells, |x| vals.apply(x)).map_err(|e| match e {
                    SolidsError::InvalidParameter {
                        name,
                        value,
                        expected,
                    } => src.err(
                        sp,
                        name.split('[').next().unwrap_or(&name),
                        format!("{value} is invalid: {expected}"),
                    ),
                    SolidsError::NoSuchElement { index, count, .. } => src.err(
                        sp,
                        "cells",
                        format!("control cell {index} does not exist (there are {count})"),
                    ),
                    e => e,
                })
            };
            check(&span, &values_of!(m), None, &mut field)?;
            match m.energy.as_deref() {
                None | Some("springs") => {
                    if m.metric_stiffness.is_some() {
                        return Err(src.err(
                            &span,
                            "metric_stiffness",
                            "needs `energy = \"metric-tensor\"`",
                        ));
                    }
                }
                Some("metric-tensor") => metric = Some((span.clone(), m.metric_stiffness)),
                Some(other) => {
                    return Err(src.err(
                        &span,
                        "energy",
                        format!(
                            "unknown energy \"{other}\"; expected \"springs\" or \"metric-tensor\""
                        ),
                    ));
                }
            }
            for c in &m.cells {
                let cm = c.get_ref();
                check(&c.span(), &values_of!(cm), Some(&cm.cells), &mut field)?;
            }
        }
        // Simulation.
        let (sim_span, sim) = match file.simulation {
            Some(s) => (s.span(), s.into_inner()),
            None => (0..0, SimulationSpec::default()),
        };
        let mut params = SolidParams::default();
        if let Some(i) = &sim.integrator {
            params.integrator = parse_integrator(i).ok_or_else(|| {
                src.err(&sim_span, "integrator", format!("unknown integrator \"{i}\"; expected \"explicit\", \"symplectic\" or \"implicit\""))
            })?;
        }
        if let Some(dt) = sim.dt {
            params.dt = dt;
        }
        if let Some(f) = sim.divergence_factor {
            params.divergence_factor = f;
        }
        if let Some(t) = sim.cg_tolerance {
            params.cg_tolerance = t;
        }
        if let Some(n) = sim.cg_max_iterations {
            params.cg_max_iterations = n;
        }
        params.validate().map_err(|e| match e {
            SolidsError::InvalidParameter {
                name,
                value,
                expected,
            } => src.err(&sim_span, &name, format!("{value} is invalid: {expected}")),
            e => e,
        })?;
        let steps = match (sim.steps, sim.duration) {
            (Some(_), Some(_)) => {
                return Err(src.err(
                    &sim_span,
                    "duration",
                    "give either `steps` or `duration`, not both",
                ));
            }
            (Some(n), None) => n,
            (None, d) => {
                let d = d.unwrap_or(DEFAULT_DURATION);
                if !(d.is_finite() && d >= 0.0) {
                    return Err(src.err(
                        &sim_span,
                        "duration",
                        format!("{d} must be non-negative"),
                    ));
                }
                (d / params.dt).round() as usize
            }
        };
        let mut solid = DynamicSolid::with_material(source, p, field, params).map_err(|e| {
            let key = match &e {
                SolidsError::InvalidParameter { name, .. } if name.starts_with("samples") => {
                    "samples"
                }
                _ => "kind",
            };
            src.err(&mspan, key, e)
        })?;
        if let Some((span, c)) = metric {
            solid
                .use_metric_energy(Some(c.unwrap_or(DEFAULT_METRIC_STIFFNESS)))
                .map_err(|e| match e {
                    SolidsError::InvalidParameter {
                        name,
                        value,
                        expected,
                    } => src.err(&span, &name, format!("{value} is invalid: {expected}")),
                    e => e,
                })?;
        }
        // Timeline.
        let mut events = Vec::with_capacity(file.timeline.len());
        for a in file.timeline {
            let span = a.span();
            let a = a.into_inner();
            validate_action(&src, &span, &a, &solid)?;
            events.push((a.at(), a));
        }
        events.sort_by(|a, b| a.0.total_cmp(&b.0));
        // Output.
        let (out_span, out) = match file.output {
            Some(o) => (o.span(), o.into_inner()),
            None => (0..0, OutputSpec::default()),
        };
        let mut output = Output {
            dir: out.dir.unwrap_or_else(|| PathBuf::from("vclay-run")),
            frames: Vec::new(),
            every: out.every.unwrap_or(DEFAULT_FRAME_EVERY),
            final_model: out.final_model,
            csv: out.csv,
        };
        if output.every == 0 {
            return Err(src.err(&out_span, "every", "must be at least 1"));
        }
        for f in &out.frames {
            let Some(format) = FrameFormat::from_name(f) else {
                return Err(src.err(
                    &out_span,
                    "frames",
                    format!(
                        "unknown frame format \"{f}\"; expected one of {}",
                        FrameFormat::ALL
                            .map(|f| format!("\"{}\"", f.extension()))
                            .join(", ")
                    ),
                ));
            };
            if output.frames.contains(&format) {
                return Err(src.err(
                    &out_span,
                    "frames",
                    format!("frame format \"{f}\" is listed twice"),
                ));
            }
            output.frames.push(format);
        }
        if let Some(f) = &output.final_model {
            let ext = f.extension().and_then(|e| e.to_str()).unwrap_or("");
            let want = match solid.source() {
                SolidSource::Subdivision { .. } => "ovm",
                SolidSource::BSpline { .. } => "json",
            };
            if ext != want {
                return Err(src.err(
                    &out_span,
                    "final",
                    format!(
                        "\"{}\" should end in .{want} for this model kind",
                        f.display()
                    ),
                ));
            }
        }
        Ok(Self {
            solid,
            steps,
            events,
            output,
        })
    }
}

fn parse_integrator(s: &str) -> Option<Integrator> {
    match s {
        "explicit" => Some(Integrator::Explicit),
        "symplectic" | "symplectic-euler" => Some(Integrator::SymplecticEuler),
        "implicit" | "implicit-euler" => Some(Integrator::ImplicitEuler),
        _ => None,
    }
}

fn build_model(
    src: &Source<'_>,
    span: &Range<usize>,
    m: &ModelSpec,
    base: &Path,
) -> Result<(SolidSource, Vec<Vec3>), SolidsError> {
    let min = vec3(m.min.unwrap_or([0.0; 3]));
    let max = vec3(m.max.unwrap_or([1.0; 3]));
    check_finite(src, span, "min", min.as_slice())?;
    check_finite(src, span, "max", max.as_slice())?;
    if (0..3).any(|a| max[a] <= min[a]) {
        return Err(src.err(span, "max", "must exceed `min` along every axis"));
    }
    let forbid = |key: &str, present: bool, kind: &str| {
        if present {
            Err(src.err(span, key, format!("is not a key of kind \"{kind}\"")))
        } else {
            Ok(())
        }
    };
    match m.kind.as_str() {
        "subdivision-solid" => {
            forbid("control", m.control.is_some(), &m.kind)?;
            forbid("degree", m.degree.is_some(), &m.kind)?;
            forbid("samples", m.samples.is_some(), &m.kind)?;
            forbid("entity", m.entity.is_some(), &m.kind)?;
            if m.file.is_some() {
                from_file_only(
                    src,
                    span,
                    [
                        ("points", m.points.is_some()),
                        ("min", m.min.is_some()),
                        ("max", m.max.is_some()),
                        ("radius", m.radius.is_some()),
                        ("height", m.height.is_some()),
                    ],
                )?;
            }
            let lattice: Lattice = match (&m.primitive, &m.file) {
                (Some(_), Some(_)) => {
                    return Err(src.err(
                        span,
                        "file",
                        "give either `primitive` or `file`, not both",
                    ));
                }
                (None, Some(f)) => {
                    formats::ovm::read(&resolve(base, f)).map_err(|e| src.err(span, "file", e))?
                }
                (prim, None) => {
                    build_primitive(src, span, prim.as_deref().unwrap_or("box"), m, min, max)?
                }
            };
            let level = m.level.unwrap_or(2);
            if level > crate::model::MAX_LEVEL {
                return Err(src.err(
                    span,
                    "level",
                    format!("{level} is above the maximum {}", crate::model::MAX_LEVEL),
                ));
            }
            let boundary = match m.boundary.as_deref().unwrap_or("sharp") {
                "sharp" => BoundaryRule::Sharp,
                "smooth" => BoundaryRule::Smooth,
                "interior" => BoundaryRule::Interior,
                other => {
                    return Err(src.err(span, "boundary", format!("unknown rule \"{other}\"; expected \"sharp\", \"smooth\" or \"interior\"")));
                }
            };
            Ok(SolidSource::subdivision(lattice, boundary, level))
        }
        "bspline-solid" => {
            for (k, present) in [
                ("primitive", m.primitive.is_some()),
                ("level", m.level.is_some()),
                ("boundary", m.boundary.is_some()),
                ("points", m.points.is_some()),
                ("radius", m.radius.is_some()),
                ("height", m.height.is_some()),
            ] {
                forbid(k, present, &m.kind)?;
            }
            let samples = m.samples.unwrap_or([10; 3]);
            for (a, &n) in samples.iter().enumerate() {
                if n < 2 {
                    return Err(src.err(
                        span,
                        "samples",
                        format!("{n} samples along axis {a}; at least 2 needed"),
                    ));
                }
            }
            if let Some(f) = &m.file {
                from_file_only(
                    src,
                    span,
                    [
                        ("control", m.control.is_some()),
                        ("degree", m.degree.is_some()),
                        ("min", m.min.is_some()),
                        ("max", m.max.is_some()),
                    ],
                )?;
                let vol = read_volume(src, span, &resolve(base, f), m.entity.unwrap_or(0))?;
                return Ok((
                    SolidSource::BSpline {
                        knots: vol.knots().clone(),
                        weights: vol.weights().to_vec(),
                        samples,
                    },
                    vol.control_points().to_vec(),
                ));
            }
            if m.entity.is_some() {
                return Err(src.err(span, "entity", "selects an entity of `file`; give `file`"));
            }
            let control = m.control.unwrap_or([4; 3]);
            let degree = m.degree.unwrap_or([3; 3]);
            let mut knots = Vec::with_capacity(3);
            for a in 0..3 {
                knots.push(
                    KnotVector::clamped_uniform(degree[a], control[a])
                        .map_err(|e| src.err(span, "control", format!("axis {a}: {e}")))?,
                );
            }
            let knots: [KnotVector; 3] = knots.try_into().expect("three axes");
            let vol = NurbsVolume::box_lattice(degree, control, min, max)
                .map_err(|e| src.err(span, "control", e))?;
            Ok((
                SolidSource::BSpline {
                    knots,
                    weights: vec![1.0; vol.control_points().len()],
                    samples,
                },
                vol.control_points().to_vec(),
            ))
        }
        other => Err(src.err(
            span,
            "kind",
            format!("unknown model kind \"{other}\"; this runner reads {SOLID_KINDS:?}"),
        )),
    }
}

/// `f` relative to the scenario's folder `base` (unless absolute).
fn resolve(base: &Path, f: &Path) -> PathBuf {
    if f.is_absolute() {
        f.to_path_buf()
    } else {
        base.join(f)
    }
}

/// Rejects the keys that describe a primitive when the model is read from `file`.
fn from_file_only<const N: usize>(
    src: &Source<'_>,
    span: &Range<usize>,
    keys: [(&str, bool); N],
) -> Result<(), SolidsError> {
    match keys.iter().find(|k| k.1) {
        Some((key, _)) => Err(src.err(
            span,
            key,
            "describes a primitive; it does not apply to a model read from `file`",
        )),
        None => Ok(()),
    }
}

/// Entity `idx` of the model file at `path` (`docs/formats.md` section 1), which must be a
/// `nurbs-volume`.
fn read_volume(
    src: &Source<'_>,
    span: &Range<usize>,
    path: &Path,
    idx: usize,
) -> Result<NurbsVolume, SolidsError> {
    let entities =
        vclay_io::model::read_model(path).map_err(|e| src.err(span, "file", e.to_string()))?;
    let count = entities.len();
    match entities.into_iter().nth(idx) {
        Some(vclay_io::Entity::Volume(v)) => Ok(v),
        Some(other) => Err(src.err(
            span,
            "entity",
            format!(
                "entity {idx} of {} is a {}, not a nurbs-volume",
                path.display(),
                other.type_name()
            ),
        )),
        None => Err(src.err(
            span,
            "entity",
            format!(
                "{} has {count} entities; there is no entity {idx}",
                path.display()
            ),
        )),
    }
}

fn build_primitive(
    src: &Source<'_>,
    span: &Range<usize>,
    name: &str,
    m: &ModelSpec,
    min: Vec3,
    max: Vec3,
) -> Result<Lattice, SolidsError> {
    let size = (max - min).min();
    let r = m.radius.unwrap_or(0.5 * size);
    let h = m.height.unwrap_or(size);
    if !(r.is_finite() && r > 0.0) {
        return Err(src.err(span, "radius", format!("{r} must be positive")));
    }
    if !(h.is_finite() && h > 0.0) {
        return Err(src.err(span, "height", format!("{h} must be positive")));
    }
    let l = match name {
        "box" => {
            let n = m.points.unwrap_or([4; 3]);
            if let Some(a) = (0..3).find(|&a| n[a] < 2 || n[a] > 64) {
                return Err(src.err(
                    span,
                    "points",
                    format!("{} points along axis {a}; expected 2 to 64", n[a]),
                ));
            }
            primitives::box_lattice(n, min, max)
        }
        "cylinder" => primitives::cylinder(r, h, 4, 2, 0),
        "torus" => primitives::torus(r, 0.4 * r, 8, 4),
        "paper-torus" => primitives::paper_torus(0.5 * r, r, h),
        "gear" => primitives::gear(0.5 * r, r, 1.3 * r, h),
        "cube-with-holes" => primitives::cube_with_holes(size / 3.0),
        "l-solid" => primitives::l_solid(2, 1, size / 3.0),
        "t-solid" => primitives::t_solid(2, 1, size / 3.0),
        other => {
            return Err(src.err(span, "primitive", format!("unknown primitive \"{other}\"; expected box, cylinder, torus, paper-torus, gear, cube-with-holes, l-solid or t-solid")));
        }
    };
    Ok(l)
}

fn validate_action(
    src: &Source<'_>,
    span: &Range<usize>,
    a: &Action,
    solid: &DynamicSolid,
) -> Result<(), SolidsError> {
    let at = a.at();
    if !(at.is_finite() && at >= 0.0) {
        return Err(src.err(span, "at", format!("{at} must be a non-negative time")));
    }
    let after = |key: &str, t: Option<f64>| match t {
        Some(t) if !(t.is_finite() && t >= at) => Err(src.err(
            span,
            key,
            format!("{t} must be a time not before `at` = {at}"),
        )),
        _ => Ok(()),
    };
    let pos = |key: &str, v: Option<f64>| match v {
        Some(v) if !(v.is_finite() && v >= 0.0) => {
            Err(src.err(span, key, format!("{v} must be non-negative")))
        }
        _ => Ok(()),
    };
    let subdivision = matches!(solid.source(), SolidSource::Subdivision { .. });
    match a {
        Action::Rope {
            from,
            to,
            until,
            release,
            stiffness,
            length,
            ..
        } => {
            check_finite(src, span, "from", from)?;
            check_finite(src, span, "to", &to.unwrap_or(*from))?;
            after("until", *until)?;
            after("release", *release)?;
            pos("stiffness", *stiffness)?;
            pos("length", *length)?;
        }
        Action::Force {
            near, force, until, ..
        } => {
            check_finite(src, span, "near", near)?;
            check_finite(src, span, "force", force)?;
            after("until", *until)?;
        }
        Action::RegionForce {
            center,
            radius,
            force,
            until,
            ..
        } => {
            check_finite(src, span, "center", center)?;
            check_finite(src, span, "force", force)?;
            pos("radius", Some(*radius))?;
            after("until", *until)?;
        }
        Action::Gravity { g, until, .. } => {
            check_finite(src, span, "g", g)?;
            after("until", *until)?;
        }
        Action::Inflate {
            pressure, until, ..
        } => {
            check_finite(src, span, "pressure", &[*pressure])?;
            after("until", *until)?;
        }
        Action::Release { .. } | Action::PlasticReset { .. } | Action::Stop { .. } => {}
        Action::Fix {
            points, min, max, ..
        }
        | Action::Free {
            points, min, max, ..
        } => {
            let n = solid.control_points().len();
            match (points, min.zip(*max)) {
                (Some(pts), None) => {
                    if let Some(&i) = pts.iter().find(|&&i| i >= n) {
                        return Err(src.err(
                            span,
                            "points",
                            format!("control point {i} does not exist (there are {n})"),
                        ));
                    }
                }
                (None, Some((lo, hi))) => {
                    check_finite(src, span, "min", &lo)?;
                    check_finite(src, span, "max", &hi)?;
                }
                _ => {
                    return Err(src.err(
                        span,
                        "points",
                        "give `points = [...]` or both `min` and `max`",
                    ));
                }
            }
        }
        Action::Extrude {
            face, near, factor, ..
        } => {
            if !subdivision {
                return Err(src.err(span, "action", "extrude needs a subdivision-solid model"));
            }
            if face.is_some() == near.is_some() {
                return Err(src.err(span, "face", "give exactly one of `face` and `near`"));
            }
            pos("factor", *factor)?;
        }
        Action::DeleteCell { cell, near, .. } => {
            if !subdivision {
                return Err(src.err(
                    span,
                    "action",
                    "delete-cell needs a subdivision-solid model",
                ));
            }
            if cell.is_some() == near.is_some() {
                return Err(src.err(span, "cell", "give exactly one of `cell` and `near`"));
            }
        }
        Action::Material { .. } => {
            let Action::Material {
                density,
                damping,
                edge_stiffness,
                virtual_stiffness,
                anisotropy,
                ..
            } = a
            else {
                unreachable!()
            };
            let values = MaterialValues {
                density: *density,
                damping: *damping,
                edge_stiffness: *edge_stiffness,
                virtual_stiffness: *virtual_stiffness,
                anisotropy: *anisotropy,
            };
            let mut m = Material::default();
            values.apply(&mut m);
            m.validate().map_err(|e| match e {
                SolidsError::InvalidParameter {
                    name,
                    value,
                    expected,
                } => src.err(
                    span,
                    name.split('[').next().unwrap_or(&name),
                    format!("{value} is invalid: {expected}"),
                ),
                e => e,
            })?;
        }
        Action::Integrator { integrator, dt, .. } => {
            if let Some(i) = integrator
                && parse_integrator(i).is_none()
            {
                return Err(src.err(span, "integrator", format!("unknown integrator \"{i}\"")));
            }
            if let Some(dt) = dt
                && !(dt.is_finite() && *dt > 0.0)
            {
                return Err(src.err(span, "dt", format!("{dt} must be positive")));
            }
        }
    }
    Ok(())
}

// ------------------------------------------------------------------------------------------
// Running
// ------------------------------------------------------------------------------------------

/// Progress of a run, reported after each step.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    /// Steps done.
    pub step: usize,
    /// Steps in all.
    pub steps: usize,
    /// Simulated time.
    pub time: f64,
    /// Total energy (kinetic + internal) at the start of the last step.
    pub energy: f64,
}

/// The summary of a run.
#[derive(Clone, Debug)]
pub struct RunSummary {
    /// Steps taken.
    pub steps: usize,
    /// Mean step time in milliseconds.
    pub mean_step_ms: f64,
    /// Largest step time in milliseconds.
    pub max_step_ms: f64,
    /// Total energy (kinetic + internal) at the end.
    pub final_energy: f64,
    /// Model sizes at the end.
    pub stats: crate::solid::SolidStats,
    /// Files written (paths as created).
    pub files: Vec<PathBuf>,
    /// Messages about timeline actions (one line each).
    pub log: Vec<String>,
}

/// A moving rope cursor.
struct Cursor {
    id: ToolId,
    from: Vec3,
    to: Vec3,
    start: f64,
    end: f64,
}

impl Scenario {
    /// Runs the scenario, writing outputs under `self.output.dir`; `progress` is called after
    /// every step. On divergence the CSV of the steps so far is still written and the error
    /// returned.
    pub fn run(mut self, progress: &mut dyn FnMut(Progress)) -> Result<RunSummary, SolidsError> {
        let dir = self.output.dir.clone();
        std::fs::create_dir_all(&dir).map_err(|source| SolidsError::Io {
            path: dir.display().to_string(),
            source,
        })?;
        let mut files = Vec::new();
        let mut log = Vec::new();
        let mut csv =
            String::from("step,time,kinetic,internal,tools,total,step_ms,cg_iterations\n");
        let mut names: HashMap<String, ToolId> = HashMap::new();
        let mut expiry: Vec<(f64, ToolId)> = Vec::new();
        let mut cursors: Vec<Cursor> = Vec::new();
        let mut next_event = 0;
        let (mut sum_ms, mut max_ms) = (0.0, 0.0f64);
        let mut result = Ok(());
        self.write_frame(0, &mut files)?;
        for step in 0..self.steps {
            // Actions due at this step.
            let half = 0.5 * self.solid.params().dt;
            while next_event < self.events.len()
                && self.events[next_event].0 <= self.solid.time() + half
            {
                let action =
                    std::mem::replace(&mut self.events[next_event].1, Action::Stop { at: 0.0 });
                next_event += 1;
                let line = self.apply(action, &mut names, &mut expiry, &mut cursors)?;
                log.push(format!("t = {:.4}: {line}", self.solid.time()));
            }
            let t = self.solid.time();
            // Expired tools.
            let mut k = 0;
            while k < expiry.len() {
                if expiry[k].0 <= t + 0.5 * self.solid.params().dt {
                    let id = expiry.swap_remove(k).1;
                    let _ = self.solid.remove_tool(id);
                    cursors.retain(|c| c.id != id);
                } else {
                    k += 1;
                }
            }
            for c in &cursors {
                let s = if c.end > c.start {
                    ((t - c.start) / (c.end - c.start)).clamp(0.0, 1.0)
                } else {
                    1.0
                };
                self.solid.move_cursor(c.id, c.from + (c.to - c.from) * s)?;
            }
            match self.solid.step() {
                Ok(r) => {
                    let ms = r.seconds * 1e3;
                    sum_ms += ms;
                    max_ms = max_ms.max(ms);
                    let _ = writeln!(
                        csv,
                        "{step},{},{},{},{},{},{ms},{}",
                        t,
                        r.energy.kinetic,
                        r.energy.internal,
                        r.energy.tools,
                        r.energy.total(),
                        r.cg_iterations
                    );
                    progress(Progress {
                        step: step + 1,
                        steps: self.steps,
                        time: self.solid.time(),
                        energy: r.energy.total(),
                    });
                }
                Err(e) => {
                    result = Err(e);
                    break;
                }
            }
            if (step + 1) % self.output.every == 0 || step + 1 == self.steps {
                self.write_frame(step + 1, &mut files)?;
            }
        }
        if let Some(c) = &self.output.csv {
            let path = dir.join(c);
            formats::write_atomic(&path, |w| w.write_all(csv.as_bytes()))?;
            files.push(path);
        }
        result?;
        if let Some(f) = &self.output.final_model {
            let path = dir.join(f);
            match self.solid.source() {
                SolidSource::Subdivision { .. } => {
                    let l = self.solid.control_lattice().expect("subdivision solid");
                    formats::ovm::write(&l, &path)?;
                }
                SolidSource::BSpline { knots, weights, .. } => {
                    let vol = NurbsVolume::from_flat(
                        knots.clone(),
                        self.solid.control_points().to_vec(),
                        weights.clone(),
                    )?;
                    vclay_io::write_model(&path, &[vclay_io::Entity::Volume(vol)]).map_err(
                        |e| SolidsError::Io {
                            path: path.display().to_string(),
                            source: std::io::Error::other(e.to_string()),
                        },
                    )?;
                }
            }
            files.push(path);
        }
        let steps = self.solid.steps() as usize;
        Ok(RunSummary {
            steps,
            mean_step_ms: if steps > 0 {
                sum_ms / steps as f64
            } else {
                0.0
            },
            max_step_ms: max_ms,
            final_energy: self.solid.energy().total(),
            stats: self.solid.stats(),
            files,
            log,
        })
    }

    fn write_frame(&mut self, step: usize, files: &mut Vec<PathBuf>) -> Result<(), SolidsError> {
        if self.output.frames.is_empty() {
            return Ok(());
        }
        // Per data point, for the VTU frames: displacement from the rest shape, velocity
        // `A p'`, the springs' force (none under the metric-tensor energy, which acts on the
        // control points), lumped mass.
        let fields = if self.output.frames.contains(&FrameFormat::Vtu) {
            let s = &self.solid;
            let rest = s.map_to_data(s.rest_control_points())?;
            let disp: Vec<Vec3> = s
                .data_points()
                .iter()
                .zip(&rest)
                .map(|(d, r)| d - r)
                .collect();
            (
                disp,
                s.map_to_data(s.velocities())?,
                (!s.uses_metric_energy()).then(|| s.internal_forces()),
                s.masses().to_vec(),
            )
        } else {
            Default::default()
        };
        let lattice = self.solid.data_lattice();
        // The boundary surface, built once for the surface formats.
        let mut surface = None;
        let mesh_of = || vclay_lattice::boundary_mesh(lattice);
        for &format in &self.output.frames {
            let path = self
                .output
                .dir
                .join(format!("frame_{step:06}.{}", format.extension()));
            match format {
                FrameFormat::Vtu => {
                    let (disp, vel, force, mass) = &fields;
                    let mut data = vec![
                        PointData::Vectors("displacement", disp),
                        PointData::Vectors("velocity", vel),
                    ];
                    if let Some(force) = force {
                        data.push(PointData::Vectors("spring_force", force));
                    }
                    data.push(PointData::Scalars("mass", mass));
                    formats::vtu::write_with_point_data(lattice, &data, &path)?
                }
                FrameFormat::Obj => {
                    formats::surface::write_obj(surface.get_or_insert_with(mesh_of), &path)?
                }
                FrameFormat::Ply => {
                    formats::surface::write_ply(surface.get_or_insert_with(mesh_of), &path)?
                }
                FrameFormat::Stl => {
                    formats::surface::write_stl(surface.get_or_insert_with(mesh_of), &path)?
                }
            }
            files.push(path);
        }
        Ok(())
    }

    /// Applies one timeline action; returns a log line.
    fn apply(
        &mut self,
        a: Action,
        names: &mut HashMap<String, ToolId>,
        expiry: &mut Vec<(f64, ToolId)>,
        cursors: &mut Vec<Cursor>,
    ) -> Result<String, SolidsError> {
        let s = &mut self.solid;
        let mut track = |id: ToolId, name: Option<String>, until: Option<f64>, what: &str| {
            if let Some(u) = until {
                expiry.push((u, id));
            }
            let label = name.unwrap_or_else(|| format!("{what}{}", id.0));
            names.insert(label.clone(), id);
            label
        };
        Ok(match a {
            Action::Rope {
                at,
                from,
                to,
                until,
                release,
                stiffness,
                length,
                name,
            } => {
                let from = vec3(from);
                let id = s.attach_rope(from, stiffness.unwrap_or(50.0), length.unwrap_or(0.0))?;
                let Some(Tool::Rope { point, .. }) = s.tool(id) else {
                    unreachable!("just added a rope")
                };
                let point = *point;
                cursors.push(Cursor {
                    id,
                    from,
                    to: vec3(to.unwrap_or([from.x, from.y, from.z])),
                    start: at,
                    end: until.unwrap_or(at),
                });
                let label = track(id, name, release, "rope");
                format!("rope `{label}` attached to data point {point}")
            }
            Action::Force {
                near,
                force,
                until,
                name,
                ..
            } => {
                let point = crate::tools::nearest(s.data_points(), &vec3(near)).unwrap_or(0);
                let id = s.add_tool(Tool::PointForce {
                    point,
                    force: vec3(force),
                })?;
                let label = track(id, name, until, "force");
                format!("force `{label}` on data point {point}")
            }
            Action::RegionForce {
                center,
                radius,
                force,
                until,
                name,
                ..
            } => {
                let id = s.add_region_force(vec3(center), radius, vec3(force))?;
                let label = track(id, name, until, "region");
                let n = match s.tool(id) {
                    Some(Tool::RegionForce { points, .. }) => points.len(),
                    _ => 0,
                };
                format!("region force `{label}` on {n} data points")
            }
            Action::Gravity { g, until, name, .. } => {
                let id = s.add_tool(Tool::Gravity { g: vec3(g) })?;
                format!("gravity `{}` on", track(id, name, until, "gravity"))
            }
            Action::Inflate {
                pressure,
                until,
                name,
                ..
            } => {
                let id = s.add_tool(Tool::Inflation { pressure })?;
                format!("inflation `{}` on", track(id, name, until, "inflate"))
            }
            Action::Release { name, .. } => match names.remove(&name) {
                Some(id) => {
                    let _ = s.remove_tool(id);
                    cursors.retain(|c| c.id != id);
                    format!("released `{name}`")
                }
                None => format!("release: no active tool named `{name}` (ignored)"),
            },
            Action::Fix {
                points, min, max, ..
            } => {
                let pts = select_points(s, &Selection { points, min, max });
                let t0 = std::time::Instant::now();
                s.set_fixed(&pts, true)?;
                let st = s.stats();
                format!(
                    "fixed {} control points ({} of {} data points and {} springs remain active; rebuilt in {:.1} ms)",
                    pts.len(),
                    st.active_data_points,
                    st.data_points,
                    st.active_springs,
                    t0.elapsed().as_secs_f64() * 1e3
                )
            }
            Action::Free {
                points, min, max, ..
            } => {
                let pts = select_points(s, &Selection { points, min, max });
                s.set_fixed(&pts, false)?;
                format!("freed {} control points", pts.len())
            }
            Action::Extrude {
                face, near, factor, ..
            } => {
                let f = match (face, near) {
                    (Some(f), _) => f,
                    (None, Some(x)) => s.boundary_face_near(&vec3(x)).unwrap_or(0),
                    (None, None) => unreachable!("validated"),
                };
                let t0 = std::time::Instant::now();
                s.extrude(f, factor.unwrap_or(1.0))?;
                format!(
                    "extruded control face {f}: {} data points, rebuilt in {:.1} ms",
                    s.data_points().len(),
                    t0.elapsed().as_secs_f64() * 1e3
                )
            }
            Action::DeleteCell { cell, near, .. } => {
                let c = match (cell, near) {
                    (Some(c), _) => c,
                    (None, Some(x)) => s.cell_near(&vec3(x)).unwrap_or(0),
                    (None, None) => unreachable!("validated"),
                };
                let t0 = std::time::Instant::now();
                s.delete_cell(c)?;
                format!(
                    "deleted control cell {c}: {} data points, rebuilt in {:.1} ms",
                    s.data_points().len(),
                    t0.elapsed().as_secs_f64() * 1e3
                )
            }
            Action::PlasticReset { .. } => {
                let e = s.energy().internal;
                s.plastic_reset();
                format!(
                    "plastic reset (internal energy {e:.4e} -> {:.4e})",
                    s.energy().internal
                )
            }
            Action::Stop { .. } => {
                s.stop();
                "stopped all motion".to_string()
            }
            Action::Material {
                cells,
                density,
                damping,
                edge_stiffness,
                virtual_stiffness,
                anisotropy,
                ..
            } => {
                let values = MaterialValues {
                    density,
                    damping,
                    edge_stiffness,
                    virtual_stiffness,
                    anisotropy,
                };
                s.update_material(cells.as_deref(), |m| values.apply(m))?;
                "material changed".to_string()
            }
            Action::Integrator { integrator, dt, .. } => {
                let mut p = *s.params();
                if let Some(i) = integrator.as_deref().and_then(parse_integrator) {
                    p.integrator = i;
                }
                if let Some(dt) = dt {
                    p.dt = dt;
                }
                s.set_params(p)?;
                format!("integrator {:?}, dt {}", p.integrator, p.dt)
            }
        })
    }
}

fn select_points(s: &DynamicSolid, sel: &Selection) -> Vec<usize> {
    match (&sel.points, sel.min.zip(sel.max)) {
        (Some(p), _) => p.clone(),
        (None, Some((lo, hi))) => {
            s.control_points_where(|x| (0..3).all(|a| x[a] >= lo[a] && x[a] <= hi[a]))
        }
        _ => Vec::new(),
    }
}
