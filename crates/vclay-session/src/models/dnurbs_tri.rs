//! The `dnurbs-triangular` model kind: a triangular D-NURBS (`d-nurbs.txt` section 4.4) in the
//! generalized engine (control points and weights dynamic), either one of the Fig 8 rounding
//! models with their far-boundary constraints (section 7.3) or a triangular NURBS file
//! (`"type": "triangular-nurbs"`, `docs/formats.md`).
//!
//! Scenario keys (`[model]`): `rounding = "edge" | "corner" | "bevel"` or `file = "x.json"`
//! (one of the two); `quadrature = "subdivided" | "whole"` (default subdivided: cut along knot
//! lines, exact for the piecewise-polynomial basis) and `quadrature_points` (points per
//! direction per cell; default: the degree + 1, or 6 for `whole`); `tessellation` (domain
//! triangle subdivision of the display mesh, default [`DEFAULT_TESSELLATION`]).
//! `[material]`: `preset` (a Table 1 row; default the rounding's row, or "Corner rounding"
//! for files), overrides `mu`, `gamma`, `alpha = [a11, a22]`, `beta = [b11, b12, b22]`,
//! `reference = "absolute" | "rest"` (default absolute for rounding, rest for files) and
//! `weight_penalty` (default the rounding penalty for rounding, 0 for files).
//! `[simulation]`: `dt` (default the preset's).
//!
//! Edits: `set dt`, `set weight_penalty`; other tools (ropes, forces, fixing) are not offered
//! for this kind yet and are refused with a message.
//!
//! The model is [`GeneralizedModel`] over `GeneralizedDnurbs<TriangularGeometry>`; this file
//! holds what is the kind's own ([`Triangular`]): its keys, how the surface is built, the
//! Bezier-pattern control net, the triangular NURBS export and the saved settings.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use vclay_core::{TriMesh, Vec3};
use vclay_dynamics::dnurbs::generalized::GeneralizedGeometry;
use vclay_dynamics::dnurbs::rounding::{ROUNDING_WEIGHT_PENALTY, RoundingKind, RoundingModel};
use vclay_dynamics::dnurbs::{
    Constraint, GeneralizedDnurbs, TriangleQuadrature, TriangularGeometry,
};

use super::generalized::{
    GeneralizedKind, GeneralizedModel, check_material_and_dt, constant_material,
    generalized_accessors, reference, table_one,
};
use super::saved::SavedState;
use super::{SpecError, keyword};
use crate::command::Edit;
use crate::error::SessionError;
use crate::model::{Done, LineRole, LineSet, ModelKind, Param};
use vclay_dynamics::dnurbs::generalized::GeneralizedState;

/// Default display tessellation level (`level^2` triangles per domain triangle).
pub const DEFAULT_TESSELLATION: usize = 6;

/// Where the surface came from (kept in session files).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
enum Source {
    /// A Fig 8 rounding model.
    Rounding(String),
    /// A triangular NURBS file's JSON (embedded, so that the session stands alone).
    File(serde_json::Value),
}

/// Settings that rebuild the model (with the source).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Settings {
    source: Source,
    subdivided: bool,
    points: Option<usize>,
    tessellation: usize,
    mu: f64,
    gamma: f64,
    alpha: [f64; 2],
    beta: [f64; 3],
    absolute: bool,
    weight_penalty: f64,
    dt: f64,
}

/// The `dnurbs-triangular` kind's part of [`GeneralizedModel`]: its engine and settings.
#[derive(Clone, Debug)]
pub struct Triangular {
    engine: Engine,
    settings: Settings,
}

type Engine = GeneralizedDnurbs<TriangularGeometry>;

/// A triangular D-NURBS model (see the [module docs](self)).
pub type TriangularModel = GeneralizedModel<Triangular>;

fn model_err(e: impl std::fmt::Display) -> SessionError {
    SessionError::model(e)
}

impl TriangularModel {
    fn build(settings: Settings) -> Result<Self, String> {
        let quadrature = if settings.subdivided {
            TriangleQuadrature::Subdivided {
                points: settings.points,
            }
        } else {
            TriangleQuadrature::Whole {
                points: settings.points.unwrap_or(6),
            }
        };
        let material =
            constant_material(settings.mu, settings.gamma, &settings.alpha, &settings.beta);
        let (surface, constraints, fixed): (_, Vec<Constraint>, Vec<usize>) = match &settings.source
        {
            Source::Rounding(name) => {
                let kind = RoundingKind::parse(name).ok_or_else(|| {
                    format!("rounding {name:?}: expected edge, corner, sharp-corner or bevel")
                })?;
                let r = RoundingModel::new(kind).map_err(|e| e.to_string())?;
                let fixed = r.fixed_coordinates();
                (r.surface, r.constraints, fixed)
            }
            Source::File(v) => {
                let text = serde_json::to_string(v).map_err(|e| e.to_string())?;
                let t = vclay_io::triangular::parse_triangular(&text).map_err(|e| e.to_string())?;
                (t.surface, Vec::new(), Vec::new())
            }
        };
        let geometry = TriangularGeometry::new(surface).with_quadrature(quadrature);
        let size = geometry.scale();
        let mut engine = GeneralizedDnurbs::new(geometry, material).map_err(|e| e.to_string())?;
        engine.set_elastic_reference(reference(settings.absolute));
        engine
            .set_weight_penalty(settings.weight_penalty)
            .map_err(|e| e.to_string())?;
        // The rounding's far boundary: its held coordinates (RoundingModel::fixed_coordinates).
        for i in fixed {
            engine
                .set_fixed_coordinate(i, true)
                .map_err(|e| e.to_string())?;
        }
        for c in constraints {
            engine.add_constraint(c).map_err(|e| e.to_string())?;
        }
        Ok(Self::new(Triangular { engine, settings }, size, 0))
    }

    /// Builds the model from its scenario tables.
    pub fn from_keys(spec: &TriangularSpec, base: &Path) -> Result<Self, SpecError> {
        let (m, mat, sim) = (&spec.model, &spec.material, &spec.simulation);
        let (source, rounding) = match (&m.rounding, &m.file) {
            (Some(r), None) => {
                let kind = RoundingKind::parse(r).ok_or_else(|| {
                    SpecError::new(
                        "model",
                        "rounding",
                        format!("{r:?}: expected edge, corner, sharp-corner or bevel"),
                    )
                })?;
                (Source::Rounding(r.to_ascii_lowercase()), Some(kind))
            }
            (None, Some(f)) => {
                let path = if f.is_absolute() {
                    f.clone()
                } else {
                    base.join(f)
                };
                let text = std::fs::read_to_string(&path).map_err(|e| {
                    SpecError::new(
                        "model",
                        "file",
                        format!("cannot read {}: {e}", path.display()),
                    )
                })?;
                // Validate now so that the error names the file.
                vclay_io::triangular::parse_triangular(&text).map_err(|e| {
                    SpecError::new("model", "file", format!("{}: {e}", path.display()))
                })?;
                let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| {
                    SpecError::new("model", "file", format!("{}: {e}", path.display()))
                })?;
                (Source::File(v), None)
            }
            _ => {
                return Err(SpecError::new(
                    "model",
                    "rounding",
                    "give exactly one of rounding = \"edge\" | \"corner\" | \"sharp-corner\" | \"bevel\" and file = \"surface.json\"",
                ));
            }
        };
        let preset_name = mat.preset.clone().unwrap_or_else(|| {
            rounding
                .map(|k| k.preset().name)
                .unwrap_or("Corner rounding")
                .to_string()
        });
        let preset = table_one(&preset_name)?;
        let subdivided = keyword(
            "model",
            "quadrature",
            m.quadrature.as_deref(),
            &[("subdivided", true), ("whole", false)],
        )?
        .unwrap_or(true);
        if let Some(k) = m.quadrature_points
            && !(1..=20).contains(&k)
        {
            return Err(SpecError::new(
                "model",
                "quadrature_points",
                format!("{k}: must be 1 to 20"),
            ));
        }
        let tessellation = m.tessellation.unwrap_or(DEFAULT_TESSELLATION);
        if !(1..=64).contains(&tessellation) {
            return Err(SpecError::new(
                "model",
                "tessellation",
                format!("{tessellation}: must be 1 to 64"),
            ));
        }
        let absolute = keyword(
            "material",
            "reference",
            mat.reference.as_deref(),
            &[("absolute", true), ("rest", false)],
        )?
        .unwrap_or(rounding.is_some());
        let settings = Settings {
            source,
            subdivided,
            points: m.quadrature_points,
            tessellation,
            mu: mat.mu.unwrap_or(preset.mu),
            gamma: mat.gamma.unwrap_or(preset.gamma),
            alpha: mat.alpha.unwrap_or(preset.alpha),
            beta: mat.beta.unwrap_or(preset.beta),
            absolute,
            weight_penalty: mat.weight_penalty.unwrap_or(if rounding.is_some() {
                ROUNDING_WEIGHT_PENALTY
            } else {
                0.0
            }),
            dt: sim.dt.unwrap_or(preset.dt),
        };
        check_material_and_dt(
            &[
                ("mu", settings.mu),
                ("gamma", settings.gamma),
                ("weight_penalty", settings.weight_penalty),
            ],
            settings.dt,
        )?;
        Self::build(settings).map_err(|e| SpecError::new("model", "kind", e))
    }

    /// Rebuilds a saved model.
    pub fn load(v: &serde_json::Value) -> Result<Self, SessionError> {
        let saved: Saved = serde_json::from_value(v.clone()).map_err(SessionError::kernel)?;
        Self::build(saved.settings)
            .map_err(model_err)?
            .with_state(saved.state.into())
    }
}

impl GeneralizedKind for Triangular {
    type Engine = Engine;
    /// The time step and the weight penalty.
    type State = (f64, f64);
    const EDITS_REDRAW: bool = false;
    const MESH_NAME: &'static str = "triangular-dnurbs";
    fn kind(&self) -> ModelKind {
        ModelKind::DnurbsTriangular
    }
    generalized_accessors!(engine, settings.dt);
    fn exports(&self) -> &'static [&'static str] {
        &["json", "obj", "ply", "stl", "glb"]
    }
    fn take(&self) -> (f64, f64) {
        (self.settings.dt, self.settings.weight_penalty)
    }
    fn put(&mut self, s: &(f64, f64)) -> Result<(), SessionError> {
        (self.settings.dt, self.settings.weight_penalty) = *s;
        Ok(())
    }
    fn summary(&self) -> String {
        let engine = &self.engine;
        let s = engine.geometry().surface();
        format!(
            "dnurbs-triangular ({}): degree {}, {} domain triangles, {} control points, {} constraints",
            match &self.settings.source {
                Source::Rounding(r) => format!("{r} rounding"),
                Source::File(_) => "file".to_string(),
            },
            s.basis().degree(),
            s.basis().domain().triangles().len(),
            s.control_points().len(),
            engine.constraints().len()
        )
    }
    fn mesh(&self) -> Result<TriMesh, SessionError> {
        let mut mesh = TriMesh::new();
        self.engine
            .geometry()
            .surface()
            .tessellate(self.settings.tessellation, &mut mesh)
            .map_err(SessionError::kernel)?;
        Ok(mesh)
    }
    fn display_lines(&self, _size: f64) -> Vec<LineSet> {
        let engine = &self.engine;
        // The control net: the points of each domain triangle's functions joined in the
        // Bezier pattern (markers when the net is shared), and the constraint points.
        let g = engine.geometry();
        let pts = g.control_points();
        let mut net = LineSet::new(LineRole::ControlNet);
        let basis = g.surface().basis();
        let n = basis.degree();
        let map = g.surface().control_map();
        let per = (n + 1) * (n + 2) / 2;
        let betas = vclay_spline::triangular::multi_indices(n);
        let idx = |b: [usize; 3]| betas.iter().position(|x| *x == b);
        for t in 0..basis.domain().triangles().len() {
            for (k, b) in betas.iter().enumerate() {
                let here = pts[map[t * per + k]];
                for next in [
                    [b[0].wrapping_sub(1), b[1] + 1, b[2]],
                    [b[0].wrapping_sub(1), b[1], b[2] + 1],
                    [b[0], b[1].wrapping_sub(1), b[2] + 1],
                ] {
                    if let Some(j) = (next.iter().all(|&x| x <= n)).then(|| idx(next)).flatten() {
                        net.segment(here, pts[map[t * per + j]]);
                    }
                }
            }
        }
        let mut cons = LineSet::new(LineRole::Constraints);
        for c in engine.constraints() {
            if let Constraint::Point { target, .. } = c {
                cons.points.push(*target);
            }
        }
        vec![net, cons]
    }
    fn control_points(&self) -> Vec<Vec3> {
        self.engine.geometry().control_points().to_vec()
    }
    fn more_params(&self) -> Vec<Param> {
        vec![Param::new(
            "weight_penalty",
            self.settings.weight_penalty,
            0.0,
            1000.0,
            "penalty c/2 sum (w - w0)^2 holding the weights near their initial values",
        )]
    }
    fn edit(
        &mut self,
        edit: &Edit,
        _before: &(GeneralizedState, (f64, f64)),
    ) -> Result<Done, SessionError> {
        match edit {
            Edit::Set { name, value } if name == "weight_penalty" => {
                self.engine
                    .set_weight_penalty(*value)
                    .map_err(SessionError::kernel)?;
                self.settings.weight_penalty = *value;
                Ok(Done::State(format!("weight_penalty = {value}")))
            }
            other => Err(SessionError::command(
                "",
                "",
                format!(
                    "a dnurbs-triangular model takes `set dt` and `set weight_penalty` only, not {other:?}"
                ),
            )),
        }
    }
    fn write(&self, ext: &str, path: &Path) -> Option<Result<(), SessionError>> {
        (ext == "json").then(|| {
            vclay_io::triangular::write_triangular(path, self.engine.geometry().surface(), None)
                .map_err(|e| SessionError::io(path, e))
        })
    }
    fn save(&self, _size: f64) -> Result<serde_json::Value, SessionError> {
        serde_json::to_value(Saved {
            settings: self.settings.clone(),
            state: SavedState::from(&self.engine.state()),
        })
        .map_err(SessionError::kernel)
    }
}

/// The typed spec of a triangular D-NURBS ([`super::ModelSpec`]).
pub type TriangularSpec = super::KindSpec<ModelKeys, MaterialKeys, SimKeys>;

scenario_keys! {
    /// The `[model]` keys of a `dnurbs-triangular` model.
    pub struct ModelKeys {
        pub rounding: Option<String>,
        pub file: Option<PathBuf>,
        pub quadrature: Option<String>,
        pub quadrature_points: Option<usize>,
        pub tessellation: Option<usize>,
    }
}

scenario_keys! {
    /// The `[material]` keys of a `dnurbs-triangular` model.
    pub struct MaterialKeys {
        pub preset: Option<String>,
        pub mu: Option<f64>,
        pub gamma: Option<f64>,
        pub alpha: Option<[f64; 2]>,
        pub beta: Option<[f64; 3]>,
        pub reference: Option<String>,
        pub weight_penalty: Option<f64>,
    }
}

/// The `[simulation]` keys of this kind: only the clock's step `dt` (absent: the preset's).
pub type SimKeys = super::ClockKeys;

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Saved {
    settings: Settings,
    state: SavedState,
}
