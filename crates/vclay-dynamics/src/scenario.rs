//! TOML scenario files for D-NURBS (`vclay run`): `[model] kind = "dnurbs-curve"`,
//! `"dnurbs-surface"` or `"dnurbs-swung"`. `docs/formats.md` ("D-NURBS scenarios") documents every
//! key; `crates/vclay-dynamics/examples/scenarios/` holds examples.
//!
//! All D-NURBS scenarios run on [`GeneralizedDnurbs`]: `weights = "dynamic"` simulates control
//! points and weights, `weights = "frozen"` holds every weight (footnote 2 of `d-nurbs.txt`; the
//! result equals the frozen-weight engine's, see `tests/generalized.rs`).
//!
//! Errors name the file, the line and the key: syntax and type errors come from the `toml`
//! parser with its location, checks after parsing give the line of the entry they belong to.

use crate::dnurbs::{
    Constraint, Density, ElasticReference, Force, GeneralizedDnurbs, GeneralizedGeometry,
    Integrator, Material, Preset, RationalGeometry, SwungGeometry, Target,
};
use crate::error::DynamicsError;
use serde::Deserialize;
use std::fmt::Write as _;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use toml::Spanned;
use vclay_core::Vec3;
use vclay_io::model::Entity;
use vclay_spline::{NurbsCurve, NurbsSurface};

/// The model kinds this module runs.
pub const DNURBS_KINDS: [&str; 3] = ["dnurbs-curve", "dnurbs-surface", "dnurbs-swung"];

/// An error in a scenario file, with its place.
#[derive(Debug, thiserror::Error)]
#[error("{file}:{line}: {key}: {what}")]
pub struct ScenarioError {
    /// File name as given.
    pub file: String,
    /// 1-based line.
    pub line: usize,
    /// The key or table at fault.
    pub key: String,
    /// What is wrong.
    pub what: String,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    model: Spanned<ModelSpec>,
    #[serde(default)]
    material: Option<Spanned<MaterialSpec>>,
    simulation: Spanned<SimulationSpec>,
    #[serde(default)]
    force: Vec<Spanned<ForceSpec>>,
    #[serde(default)]
    constraint: Vec<Spanned<ConstraintSpec>>,
    #[serde(default)]
    output: Option<OutputSpec>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelSpec {
    kind: String,
    #[serde(default)]
    primitive: Option<String>,
    #[serde(default)]
    file: Option<PathBuf>,
    #[serde(default)]
    entity: Option<usize>,
    #[serde(default)]
    size: Option<Vec<usize>>,
    #[serde(default)]
    degree: Option<Vec<usize>>,
    #[serde(default)]
    extent: Option<f64>,
    #[serde(default)]
    weights: Option<String>,
    #[serde(default)]
    fix: Vec<usize>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialSpec {
    #[serde(default)]
    preset: Option<String>,
    #[serde(default)]
    mu: Option<f64>,
    #[serde(default)]
    gamma: Option<f64>,
    #[serde(default)]
    alpha: Option<f64>,
    #[serde(default)]
    beta: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SimulationSpec {
    #[serde(default)]
    dt: Option<f64>,
    steps: usize,
    #[serde(default)]
    reference: Option<String>,
    #[serde(default)]
    weight_penalty: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
enum ForceSpec {
    Spring {
        param: [f64; 2],
        target: [f64; 3],
        #[serde(default)]
        velocity: Option<[f64; 3]>,
        stiffness: Option<f64>,
        #[serde(default)]
        kernel: Option<f64>,
    },
    Point {
        param: [f64; 2],
        force: [f64; 3],
    },
    Gravity {
        g: [f64; 3],
    },
    Inflation {
        pressure: f64,
    },
    Data {
        points: Vec<[f64; 3]>,
        stiffness: Option<f64>,
    },
}

#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
enum ConstraintSpec {
    Point { param: [f64; 2], target: [f64; 3] },
    Normal { param: [f64; 2], normal: [f64; 3] },
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct OutputSpec {
    #[serde(default)]
    dir: Option<PathBuf>,
    #[serde(default)]
    every: Option<usize>,
    #[serde(default)]
    grid: Option<[usize; 2]>,
}

/// What a run did.
#[derive(Debug, Clone)]
pub struct DnurbsRunSummary {
    /// Steps taken.
    pub steps: usize,
    /// Mean and largest wall time per step in milliseconds.
    pub mean_step_ms: f64,
    /// Largest step time.
    pub max_step_ms: f64,
    /// Elastic plus kinetic energy after the last step.
    pub final_energy: f64,
    /// Largest constraint violation at the end.
    pub constraint_violation: f64,
    /// RMS distance of the data points at the end (0 without data).
    pub data_rms: f64,
    /// Files written.
    pub files: Vec<PathBuf>,
}

enum Model {
    Rational(GeneralizedDnurbs<RationalGeometry>, bool),
    Swung(GeneralizedDnurbs<SwungGeometry>),
}

/// A parsed D-NURBS scenario, ready to run.
pub struct DnurbsScenario {
    model: Model,
    dt: f64,
    /// Steps to run.
    pub steps: usize,
    /// Output folder.
    pub out_dir: PathBuf,
    /// Write a frame (`frame_NNNNNN.obj`) every this many steps (0: never).
    pub every: usize,
    grid: [usize; 2],
    /// Short description of the model.
    pub description: String,
}

impl std::fmt::Debug for DnurbsScenario {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "DnurbsScenario({})", self.description)
    }
}

struct Src<'a> {
    file: &'a str,
    text: &'a str,
}

impl Src<'_> {
    fn err(&self, span: &Range<usize>, key: &str, what: impl Into<String>) -> ScenarioError {
        ScenarioError {
            file: self.file.into(),
            line: vclay_core::text::key_line(self.text, span, key),
            key: key.into(),
            what: what.into(),
        }
    }
    fn dyn_err(&self, span: &Range<usize>, key: &str, e: DynamicsError) -> ScenarioError {
        self.err(span, key, e.to_string())
    }
}

fn v3(a: [f64; 3]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

impl DnurbsScenario {
    /// Parses a scenario; `base` resolves relative paths.
    pub fn parse(text: &str, name: &str, base: &Path) -> Result<Self, ScenarioError> {
        let src = Src { file: name, text };
        let f: File = toml::from_str(text).map_err(|e| {
            let span = e.span().unwrap_or(0..0);
            src.err(&span, "syntax", e.message().to_string())
        })?;
        let mspan = f.model.span();
        let m = f.model.into_inner();
        let kind = m.kind.as_str();
        if !DNURBS_KINDS.contains(&kind) {
            return Err(src.err(
                &mspan,
                "kind",
                format!("unknown model kind \"{kind}\"; this runner reads {DNURBS_KINDS:?}"),
            ));
        }
        // Material.
        let surface = kind != "dnurbs-curve";
        let (material, preset) = match &f.material {
            None => (
                if surface {
                    Material::surface(1.0, 2.0, 1.0, 0.1)
                } else {
                    Material::curve(1.0, 2.0, 1.0, 0.1)
                },
                None,
            ),
            Some(ms) => {
                let span = ms.span();
                let ms = ms.get_ref();
                let preset = match &ms.preset {
                    Some(p) => Some(Preset::by_name(p).ok_or_else(|| {
                        src.err(&span, "preset", format!("no Table 1 preset named \"{p}\""))
                    })?),
                    None => None,
                };
                let mut mat = match (preset, surface) {
                    (Some(p), true) => p.surface_material(),
                    (Some(p), false) => p.curve_material(),
                    (None, true) => Material::surface(1.0, 2.0, 1.0, 0.1),
                    (None, false) => Material::curve(1.0, 2.0, 1.0, 0.1),
                };
                for (key, v) in [
                    ("mu", ms.mu),
                    ("gamma", ms.gamma),
                    ("alpha", ms.alpha),
                    ("beta", ms.beta),
                ] {
                    if let Some(v) = v {
                        if !(v.is_finite() && v >= 0.0) {
                            return Err(src.err(
                                &span,
                                key,
                                format!("{v} must be finite and non-negative"),
                            ));
                        }
                        let d = Density::Constant(v);
                        match key {
                            "mu" => mat.mu = d,
                            "gamma" => mat.gamma = d,
                            "alpha" => mat.alpha.iter_mut().for_each(|a| *a = d.clone()),
                            _ => mat.beta.iter_mut().for_each(|b| *b = d.clone()),
                        }
                    }
                }
                (mat, preset)
            }
        };
        // Simulation.
        let sspan = f.simulation.span();
        let sim = f.simulation.into_inner();
        let dt = sim
            .dt
            .or(preset.map(|p| p.dt))
            .ok_or_else(|| src.err(&sspan, "dt", "missing (give dt or a material preset)"))?;
        if !(dt.is_finite() && dt > 0.0) {
            return Err(src.err(&sspan, "dt", format!("{dt} must be positive")));
        }
        if sim.steps == 0 {
            return Err(src.err(&sspan, "steps", "must be at least 1"));
        }
        let reference = match sim.reference.as_deref() {
            None | Some("rest") => ElasticReference::RestShape,
            Some("absolute") => ElasticReference::Absolute,
            Some(o) => {
                return Err(src.err(
                    &sspan,
                    "reference",
                    format!("\"{o}\": expected \"rest\" or \"absolute\""),
                ));
            }
        };
        let default_k = preset.map(|p| p.k).filter(|k| *k > 0.0);
        // Forces and constraints.
        let mut forces = Vec::new();
        for fs in &f.force {
            let span = fs.span();
            let k = |s: Option<f64>| -> Result<f64, ScenarioError> {
                let k = s.or(default_k).ok_or_else(|| {
                    src.err(
                        &span,
                        "stiffness",
                        "missing (give stiffness or a preset with k)",
                    )
                })?;
                if !(k.is_finite() && k > 0.0) {
                    return Err(src.err(&span, "stiffness", format!("{k} must be positive")));
                }
                Ok(k)
            };
            match fs.get_ref() {
                ForceSpec::Spring {
                    param,
                    target,
                    velocity,
                    stiffness,
                    kernel,
                } => {
                    let t0 = v3(*target);
                    let target = match velocity {
                        Some(vel) => {
                            let vel = v3(*vel);
                            Target::Moving(Arc::new(move |t| t0 + vel * t))
                        }
                        None => Target::Fixed(t0),
                    };
                    if let Some(s) = kernel
                        && !(s.is_finite() && *s > 0.0)
                    {
                        return Err(src.err(&span, "kernel", format!("{s} must be positive")));
                    }
                    forces.push(Force::Spring {
                        param: *param,
                        target,
                        stiffness: k(*stiffness)?,
                        kernel: *kernel,
                    });
                }
                ForceSpec::Point { param, force } => forces.push(Force::Point {
                    param: *param,
                    force: v3(*force),
                }),
                ForceSpec::Gravity { g } => forces.push(Force::Gravity(v3(*g))),
                ForceSpec::Inflation { pressure } => {
                    if !surface {
                        return Err(src.err(&span, "inflation", "needs a surface"));
                    }
                    forces.push(Force::Inflation(*pressure))
                }
                ForceSpec::Data { points, stiffness } => {
                    let k = k(*stiffness)?;
                    if points.is_empty() {
                        return Err(src.err(&span, "points", "no data points"));
                    }
                    for p in points {
                        forces.push(Force::DataPoint {
                            point: v3(*p),
                            stiffness: k,
                        });
                    }
                }
            }
        }
        let constraints: Vec<(Range<usize>, Constraint)> = f
            .constraint
            .iter()
            .map(|c| {
                (
                    c.span(),
                    match c.get_ref() {
                        ConstraintSpec::Point { param, target } => Constraint::Point {
                            param: *param,
                            target: v3(*target),
                        },
                        ConstraintSpec::Normal { param, normal } => Constraint::Normal {
                            param: *param,
                            normal: v3(*normal),
                        },
                    },
                )
            })
            .collect();
        // Model.
        let dynamic_weights = match m.weights.as_deref() {
            None | Some("dynamic") => true,
            Some("frozen") => false,
            Some(o) => {
                return Err(src.err(
                    &mspan,
                    "weights",
                    format!("\"{o}\": expected \"dynamic\" or \"frozen\""),
                ));
            }
        };
        let out = f.output.unwrap_or_default();
        let out_dir = base.join(out.dir.unwrap_or_else(|| PathBuf::from("vclay-run")));
        let every = out.every.unwrap_or(0);
        let grid = out.grid.unwrap_or([32, 32]);
        let penalty = sim.weight_penalty.unwrap_or(0.0);
        let mut description = String::new();
        let model = if kind == "dnurbs-swung" {
            let g = match m.primitive.as_deref() {
                Some("sphere") => SwungGeometry::sphere(m.extent.unwrap_or(1.0)),
                Some("torus") => SwungGeometry::torus(
                    2.0 * m.extent.unwrap_or(1.0),
                    0.5 * m.extent.unwrap_or(1.0),
                ),
                Some("hat") => SwungGeometry::hat(),
                Some("wine-glass") => SwungGeometry::wine_glass(),
                Some(o) => return Err(src.err(
                    &mspan,
                    "primitive",
                    format!(
                        "unknown swung primitive \"{o}\"; expected sphere, torus, hat or wine-glass"
                    ),
                )),
                None => {
                    return Err(src.err(
                        &mspan,
                        "primitive",
                        "missing (sphere, torus, hat or wine-glass)",
                    ));
                }
            }
            .map_err(|e| src.dyn_err(&mspan, "primitive", e))?;
            let _ = write!(
                description,
                "swung {} ({} coordinates)",
                m.primitive.as_deref().unwrap_or(""),
                g.coordinates().len()
            );
            let mut d = GeneralizedDnurbs::new(g, material)
                .map_err(|e| src.dyn_err(&mspan, "material", e))?;
            setup(
                &src,
                &mut d,
                reference,
                penalty,
                &forces,
                &constraints,
                &m.fix,
                dynamic_weights,
                &mspan,
            )?;
            Model::Swung(d)
        } else {
            let g = if let Some(file) = &m.file {
                let path = base.join(file);
                let ents = vclay_io::model::read_model(&path)
                    .map_err(|e| src.err(&mspan, "file", e.to_string()))?;
                let idx = m.entity.unwrap_or(0);
                let e = ents.into_iter().nth(idx).ok_or_else(|| {
                    src.err(&mspan, "entity", format!("the file has no entity {idx}"))
                })?;
                match (e, surface) {
                    (Entity::Curve(c), false) => RationalGeometry::from_curve(&c),
                    (Entity::Surface(s), true) => RationalGeometry::from_surface(&s),
                    _ => {
                        return Err(src.err(
                            &mspan,
                            "entity",
                            format!(
                                "entity {idx} is not a {}",
                                if surface {
                                    "nurbs-surface"
                                } else {
                                    "nurbs-curve"
                                }
                            ),
                        ));
                    }
                }
            } else {
                let extent = m.extent.unwrap_or(2.0);
                match (m.primitive.as_deref(), surface) {
                    (Some("sheet") | None, true) => {
                        let size = m.size.clone().unwrap_or(vec![8, 8]);
                        let deg = m.degree.clone().unwrap_or(vec![3, 3]);
                        if size.len() != 2 || deg.len() != 2 {
                            return Err(src.err(
                                &mspan,
                                "size",
                                "a sheet needs size = [nu, nv] and degree = [p, q]",
                            ));
                        }
                        let mut pts = Vec::new();
                        for i in 0..size[0] {
                            for j in 0..size[1] {
                                pts.push(Vec3::new(
                                    extent * (i as f64 / (size[0].max(2) - 1) as f64 - 0.5),
                                    extent * (j as f64 / (size[1].max(2) - 1) as f64 - 0.5),
                                    0.0,
                                ));
                            }
                        }
                        let s = NurbsSurface::clamped_uniform(
                            [deg[0], deg[1]],
                            [size[0], size[1]],
                            pts,
                        )
                        .map_err(|e| src.err(&mspan, "size", e.to_string()))?;
                        RationalGeometry::from_surface(&s)
                    }
                    (Some("circle"), false) => RationalGeometry::from_curve(
                        &NurbsCurve::circle(Vec3::zeros(), Vec3::x(), Vec3::y(), 0.5 * extent)
                            .map_err(|e| src.err(&mspan, "primitive", e.to_string()))?,
                    ),
                    (Some("line") | None, false) => {
                        let n = m
                            .size
                            .as_ref()
                            .and_then(|s| s.first().copied())
                            .unwrap_or(8);
                        let deg = m
                            .degree
                            .as_ref()
                            .and_then(|s| s.first().copied())
                            .unwrap_or(3);
                        let pts = (0..n)
                            .map(|i| {
                                Vec3::new(
                                    extent * (i as f64 / (n.max(2) - 1) as f64 - 0.5),
                                    0.0,
                                    0.0,
                                )
                            })
                            .collect();
                        RationalGeometry::from_curve(
                            &NurbsCurve::clamped_uniform(deg, pts)
                                .map_err(|e| src.err(&mspan, "size", e.to_string()))?,
                        )
                    }
                    (Some(o), _) => {
                        return Err(src.err(
                            &mspan,
                            "primitive",
                            format!(
                                "unknown primitive \"{o}\" for {kind}; expected {}",
                                if surface { "sheet" } else { "line or circle" }
                            ),
                        ));
                    }
                }
            };
            let _ = write!(
                description,
                "{kind} ({} coordinates, weights {})",
                g.coordinates().len(),
                if dynamic_weights { "dynamic" } else { "frozen" }
            );
            let mut d = GeneralizedDnurbs::new(g, material)
                .map_err(|e| src.dyn_err(&mspan, "material", e))?;
            setup(
                &src,
                &mut d,
                reference,
                penalty,
                &forces,
                &constraints,
                &m.fix,
                dynamic_weights,
                &mspan,
            )?;
            Model::Rational(d, surface)
        };
        Ok(Self {
            model,
            dt,
            steps: sim.steps,
            out_dir,
            every,
            grid,
            description,
        })
    }

    /// Reads and parses a scenario file.
    pub fn from_file(path: &Path) -> Result<Self, ScenarioError> {
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| ScenarioError {
            file: name.clone(),
            line: 0,
            key: "file".into(),
            what: e.to_string(),
        })?;
        Self::parse(&text, &name, path.parent().unwrap_or(Path::new(".")))
    }

    /// Runs the scenario, calling `progress(step, steps, energy)` after each step; writes the final
    /// model (`final.json`), its mesh (`final.obj`), frames every `[output] every` steps and
    /// `energy.csv`.
    pub fn run(
        &mut self,
        progress: &mut dyn FnMut(usize, usize, f64),
    ) -> Result<DnurbsRunSummary, DynamicsError> {
        std::fs::create_dir_all(&self.out_dir).map_err(|e| DynamicsError::Output {
            what: format!("cannot create {}: {e}", self.out_dir.display()),
        })?;
        let mut csv =
            String::from("step,time,elastic_energy,kinetic_energy,cg_iterations,step_ms\n");
        let mut times = Vec::with_capacity(self.steps);
        let mut files = Vec::new();
        let mut energy = 0.0;
        for k in 0..self.steps {
            let t0 = std::time::Instant::now();
            let r = match &mut self.model {
                Model::Rational(d, _) => d.step(Integrator::Implicit { dt: self.dt })?,
                Model::Swung(d) => d.step(Integrator::Implicit { dt: self.dt })?,
            };
            let ms = t0.elapsed().as_secs_f64() * 1e3;
            times.push(ms);
            energy = r.elastic_energy + r.kinetic_energy;
            let _ = writeln!(
                csv,
                "{},{},{},{},{},{ms}",
                k + 1,
                r.time,
                r.elastic_energy,
                r.kinetic_energy,
                r.solver.iterations
            );
            if self.every > 0 && (k + 1) % self.every == 0 {
                let p = self.out_dir.join(format!("frame_{:06}.obj", k + 1));
                self.write_mesh(&p)?;
                files.push(p);
            }
            progress(k + 1, self.steps, energy);
        }
        let p = self.out_dir.join("energy.csv");
        vclay_io::write_atomic(&p, |w| w.write_all(csv.as_bytes())).map_err(io_err)?;
        files.push(p);
        let p = self.out_dir.join("final.obj");
        self.write_mesh(&p)?;
        files.push(p);
        let p = self.out_dir.join("final.json");
        self.write_model(&p)?;
        files.push(p);
        let (cv, data) = match &self.model {
            Model::Rational(d, _) => (d.constraint_violations()?, d.data_distances()?),
            Model::Swung(d) => (d.constraint_violations()?, d.data_distances()?),
        };
        let rms = if data.is_empty() {
            0.0
        } else {
            (data.iter().map(|x| x * x).sum::<f64>() / data.len() as f64).sqrt()
        };
        Ok(DnurbsRunSummary {
            steps: self.steps,
            mean_step_ms: times.iter().sum::<f64>() / times.len().max(1) as f64,
            max_step_ms: times.iter().cloned().fold(0.0, f64::max),
            final_energy: energy,
            constraint_violation: cv.into_iter().fold(0.0, f64::max),
            data_rms: rms,
            files,
        })
    }

    fn surface(&self) -> Result<Option<NurbsSurface>, DynamicsError> {
        Ok(match &self.model {
            Model::Rational(d, true) => Some(d.geometry().to_surface()?),
            Model::Rational(_, false) => None,
            Model::Swung(d) => Some(d.geometry().to_surface()?),
        })
    }

    fn write_mesh(&self, path: &Path) -> Result<(), DynamicsError> {
        let mut mesh = vclay_core::TriMesh::new();
        match self.surface()? {
            Some(s) => vclay_spline::tessellate_surface(&s, self.grid, &mut mesh)?,
            None => {
                // A curve as a thin tube-free polyline mesh is not meaningful; write its points
                // as degenerate triangles is wrong too, so curves get an OBJ polyline.
                if let Model::Rational(d, false) = &self.model {
                    let c = d.geometry().to_curve()?;
                    let dom = vclay_spline::ParametricCurve::domain(&c);
                    let mut text = String::from("# vclay D-NURBS curve\n");
                    let n = self.grid[0].max(2) * 4;
                    for i in 0..=n {
                        let p = vclay_spline::ParametricCurve::point(
                            &c,
                            dom.min + dom.length() * i as f64 / n as f64,
                        )?;
                        let _ = writeln!(text, "v {} {} {}", p.x, p.y, p.z);
                    }
                    text.push('l');
                    for i in 1..=n + 1 {
                        let _ = write!(text, " {i}");
                    }
                    text.push('\n');
                    return vclay_io::write_atomic(path, |w| w.write_all(text.as_bytes()))
                        .map_err(io_err);
                }
            }
        }
        vclay_io::mesh::write_mesh(path, &mesh).map_err(io_err)
    }

    fn write_model(&self, path: &Path) -> Result<(), DynamicsError> {
        let entity = match (&self.model, self.surface()?) {
            (_, Some(s)) => Entity::Surface(s),
            (Model::Rational(d, false), None) => Entity::Curve(d.geometry().to_curve()?),
            _ => unreachable!("every model is a curve or a surface"),
        };
        vclay_io::model::write_model(path, &[entity]).map_err(io_err)
    }
}

#[allow(clippy::too_many_arguments)]
fn setup<G: GeneralizedGeometry>(
    src: &Src<'_>,
    d: &mut GeneralizedDnurbs<G>,
    reference: ElasticReference,
    penalty: f64,
    forces: &[Force],
    constraints: &[(Range<usize>, Constraint)],
    fix: &[usize],
    dynamic_weights: bool,
    mspan: &Range<usize>,
) -> Result<(), ScenarioError> {
    d.set_elastic_reference(reference);
    d.set_weight_penalty(penalty)
        .map_err(|e| src.dyn_err(mspan, "weight_penalty", e))?;
    *d.forces_mut() = forces.to_vec();
    for (span, c) in constraints {
        d.add_constraint(c.clone())
            .map_err(|e| src.dyn_err(span, "constraint", e))?;
    }
    if !dynamic_weights {
        for i in d.geometry().weight_coordinates() {
            d.set_fixed_coordinate(i, true)
                .map_err(|e| src.dyn_err(mspan, "weights", e))?;
        }
    }
    let groups = d.geometry().coordinate_groups();
    for &cp in fix {
        // Control point indices count the geometry's coordinate groups (x, y, z, w each).
        let g = groups
            .iter()
            .filter(|g| g.len() == 4)
            .nth(cp)
            .cloned()
            .ok_or_else(|| src.err(mspan, "fix", format!("control point {cp} does not exist")))?;
        for i in g.start..g.start + 3 {
            d.set_fixed_coordinate(i, true)
                .map_err(|e| src.dyn_err(mspan, "fix", e))?;
        }
    }
    Ok(())
}

fn io_err(e: vclay_io::IoError) -> DynamicsError {
    DynamicsError::Output {
        what: e.to_string(),
    }
}
