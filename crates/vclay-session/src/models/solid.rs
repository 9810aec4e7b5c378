//! Dynamic solids in a session: [`SolidModel`] wraps `vclay_solids::DynamicSolid` (B-spline
//! solids, `subdivision-solids-journal.txt` section 4.1, eq 3, and MacCracken-Joy subdivision
//! solids, section 4.2, eq 4: data points `d = A p` moved by eq 10).
//!
//! Undo: tool edits, stop, direct point moves, parameter and material changes restore a
//! [`SolidState`] snapshot (plus the old parameters and material field); fix/free apply the
//! exact inverse (free exactly the points that the fix fixed) and restore the state; topology
//! edits (extrude, delete cell) and the plastic reset keep a full copy of the model.

use std::path::Path;

use serde::{Deserialize, Serialize};
use vclay_core::{TriMesh, Vec3};
use vclay_lattice::{
    BoundaryRule, EdgeId, Features, Lattice, SubdivisionRules, VertexId, formats, gallery,
    primitives,
};
use vclay_solids::{
    DataNumbering, DynamicSolid, Falloff, Integrator, Material, MaterialField, SolidParams,
    SolidRest, SolidSource, SolidState, SolidsError, Tool, ToolId,
};
use vclay_spline::{KnotVector, NurbsVolume};

use super::{SpecError, misrouted};
use crate::command::{Edit, V3};
use crate::command::{MaterialRequest, RopeRequest};
use crate::error::SessionError;
use crate::model::Done;
use crate::model::{
    Element, Energy, FieldSpec, Hit, LineRole, LineSet, Model, ModelKind, Param, Ray, StepReport,
    extension, unsupported_export,
};
use crate::tools::{CursorPath, ToolHost, ToolTable, a3, field_tool, v3};

/// Default rope stiffness of the solids.
pub const DEFAULT_ROPE_STIFFNESS: f64 = 50.0;
/// Default `[simulation] duration` of a solid scenario (s).
pub const DEFAULT_DURATION: f64 = 1.0;

/// A dynamic solid with its named tools.
#[derive(Clone, Debug)]
pub struct SolidModel {
    solid: DynamicSolid,
    tools: ToolTable,
    revision: u64,
}

#[derive(Clone, Debug)]
pub(crate) struct SolidSnap {
    state: SolidState,
    tools: ToolTable,
    params: SolidParams,
    material: MaterialField,
    /// Rest control and data points: plastic flow moves them while the clay steps, so undoing
    /// a pull puts them back too (docs/sculpting.md).
    rest: (Vec<Vec3>, Vec<Vec3>),
}

/// The painted material a solid's display mesh can be coloured by (journal section 4.3's
/// per-cell material; `Model::display_field`).
const SOLID_FIELDS: [FieldSpec; 4] = [
    FieldSpec {
        name: "edge-stiffness",
        unit: "force/length",
        help: "modulus of the edge springs",
    },
    FieldSpec {
        name: "virtual-stiffness",
        unit: "force/length",
        help: "modulus of the virtual springs",
    },
    FieldSpec {
        name: "density",
        unit: "mass/volume",
        help: "mass per unit volume",
    },
    FieldSpec {
        name: "damping",
        unit: "1/s x density",
        help: "damping per unit volume",
    },
];

fn kernel(e: SolidsError) -> SessionError {
    SessionError::from(e)
}

fn cmd(reason: impl std::fmt::Display) -> SessionError {
    SessionError::command("", "", reason)
}

impl SolidModel {
    /// Wraps a solid (no tools).
    pub fn new(solid: DynamicSolid) -> Self {
        Self {
            solid,
            tools: ToolTable::default(),
            revision: 1,
        }
    }

    /// The solid.
    pub fn solid(&self) -> &DynamicSolid {
        &self.solid
    }

    /// The named tools.
    pub fn tools(&self) -> &ToolTable {
        &self.tools
    }

    fn is_subdivision(&self) -> bool {
        matches!(self.solid.source(), SolidSource::Subdivision { .. })
    }

    fn add_tool(&mut self, tool: Tool) -> Result<usize, SessionError> {
        self.solid
            .add_tool(tool)
            .map(|id| id.0)
            .map_err(SessionError::command_from)
    }

    /// [`Edit::RegionForce`]: a force on the data points within `radius` of `center`.
    fn region_force(&mut self, edit: &Edit) -> Result<String, SessionError> {
        let Edit::RegionForce {
            name,
            center,
            radius,
            force,
            until,
            falloff,
        } = edit
        else {
            return Err(misrouted());
        };
        // The name was checked by `Edit::validate`.
        let falloff = falloff
            .as_deref()
            .and_then(Falloff::from_name)
            .unwrap_or_default();
        let id = self
            .solid
            .add_region_force_with(v3(*center), *radius, v3(*force), falloff)
            .map_err(SessionError::command_from)?
            .0;
        let label = self
            .tools
            .label(name.as_deref(), "region", id)
            .map_err(|e| {
                let _ = self.solid.remove_tool(ToolId(id));
                cmd(e)
            })?;
        self.tools.track(&label, "region-force", id, None, *until);
        let n = match self.solid.tool(ToolId(id)) {
            Some(Tool::RegionForce { points, .. }) => points.len(),
            _ => 0,
        };
        Ok(format!("region force `{label}` on {n} data points"))
    }

    /// [`Edit::Fix`] and [`Edit::Free`], undone by their exact inverse.
    fn fix_or_free(&mut self, edit: &Edit) -> Result<Done, SessionError> {
        let t0 = std::time::Instant::now();
        let r = crate::tools::fix_or_free(&mut self.solid, edit)?;
        let st = self.solid.stats();
        let message = if matches!(edit, Edit::Fix { .. }) {
            format!(
                "fixed {} control points ({} of {} data points and {} springs remain active; rebuilt in {:.1} ms)",
                r.selected.len(),
                st.active_data_points,
                st.data_points,
                st.active_springs,
                t0.elapsed().as_secs_f64() * 1e3
            )
        } else {
            format!("freed {} control points", r.selected.len())
        };
        Ok(Done::Inverse(message, r.inverse))
    }

    /// [`Edit::Material`]: the solid material of some control cells (`cells`, or those whose
    /// centre lies in `min`..`max`) or of all.
    fn set_material(&mut self, edit: &Edit) -> Result<String, SessionError> {
        let r = MaterialRequest::of(edit).ok_or_else(misrouted)?;
        if r.dnurbs_given() {
            return Err(cmd(
                "`mu`, `gamma`, `alpha`, `beta` are D-NURBS materials; solids take density, damping, edge_stiffness, virtual_stiffness, anisotropy",
            ));
        }
        let list: Option<Vec<usize>> = match (&r.cells, &r.min, &r.max) {
            (Some(c), _, _) => Some(c.clone()),
            (None, Some(lo), Some(hi)) => Some(self.cells_in_box(lo, hi)),
            _ => None,
        };
        let values = Values(r.solid, r.anisotropy);
        self.solid
            .update_material(list.as_deref(), |m| values.apply(m))
            .map_err(SessionError::command_from)?;
        Ok(match &list {
            Some(l) => format!("material changed in {} control cells", l.len()),
            None => "material changed".to_string(),
        })
    }

    /// A topology edit (extrude a face, delete a cell: `what` does it and names what it did),
    /// undone by a full copy of the model.
    fn rebuild(
        &mut self,
        what: impl FnOnce(&mut DynamicSolid) -> Result<String, SessionError>,
    ) -> Result<Done, SessionError> {
        let full = self.clone();
        let t0 = std::time::Instant::now();
        let done = what(&mut self.solid)?;
        let message = format!(
            "{done}: {} data points, rebuilt in {:.1} ms",
            self.solid.data_points().len(),
            t0.elapsed().as_secs_f64() * 1e3
        );
        Ok(Done::Model(message, Box::new(full)))
    }

    /// The control face (`key` = `"face"`, for an extrusion) or cell (`"cell"`, to delete)
    /// that an edit names by its index or by a point `near` it.
    fn element(
        &self,
        key: &str,
        index: Option<usize>,
        near: Option<&V3>,
    ) -> Result<usize, SessionError> {
        match (index, near) {
            (Some(i), _) => Ok(i),
            (None, Some(x)) if key == "face" => self
                .solid
                .boundary_face_near(&v3(*x))
                .ok_or_else(|| cmd("only subdivision solids can be extruded")),
            (None, Some(x)) => self
                .solid
                .cell_near(&v3(*x))
                .ok_or_else(|| cmd("only subdivision solids can be trimmed")),
            (None, None) => Err(cmd(format!("give `{key}` or `near`"))),
        }
    }

    /// [`Edit::PlasticReset`]: the current shape becomes the rest shape; undone by a full copy.
    fn plastic_reset(&mut self) -> Done {
        let full = self.clone();
        let e = self.solid.energy().internal;
        self.solid.plastic_reset();
        let message = format!(
            "plastic reset (internal energy {e:.4e} -> {:.4e})",
            self.solid.energy().internal
        );
        Done::Model(message, Box::new(full))
    }

    /// [`Edit::MovePoint`]: control point `index` to `to`, at rest.
    fn move_point(&mut self, index: usize, to: &V3) -> Result<String, SessionError> {
        let n = self.solid.control_points().len();
        if index >= n {
            return Err(cmd(format!(
                "control point {index} does not exist (there are {n})"
            )));
        }
        let mut st = self.solid.state();
        st.control_points[index] = v3(*to);
        st.velocities[index] = Vec3::zeros();
        st.data_points = self
            .solid
            .map_to_data(&st.control_points)
            .map_err(SessionError::command_from)?;
        self.solid
            .set_state(&st)
            .map_err(SessionError::command_from)?;
        Ok(format!("moved control point {index} to {to:?}"))
    }

    /// [`Edit::Integrator`]: the integrator of eq 10 and the time step.
    fn set_integrator(
        &mut self,
        integrator: Option<&str>,
        dt: Option<f64>,
    ) -> Result<String, SessionError> {
        let mut p = *self.solid.params();
        if let Some(i) = integrator {
            p.integrator = parse_integrator(i).ok_or_else(|| {
                cmd(format!(
                    "unknown integrator \"{i}\"; expected \"explicit\", \"symplectic\" or \"implicit\""
                ))
            })?;
        }
        if let Some(dt) = dt {
            p.dt = dt;
        }
        self.solid
            .set_params(p)
            .map_err(SessionError::command_from)?;
        Ok(format!("integrator {:?}, dt {}", p.integrator, p.dt))
    }

    fn cells_in_box(&self, lo: &V3, hi: &V3) -> Vec<usize> {
        let p = self.solid.control_points();
        match self.solid.source() {
            SolidSource::Subdivision { control, .. } => (0..control.num_cells())
                .filter(|&c| {
                    let vs = control.cell_vertices(vclay_lattice::CellId::new(c));
                    let ctr = vs.iter().map(|v| p[v.index()]).sum::<Vec3>() / vs.len() as f64;
                    (0..3).all(|a| ctr[a] >= lo[a] && ctr[a] <= hi[a])
                })
                .collect(),
            SolidSource::BSpline { knots, .. } => {
                let dims = knots.each_ref().map(KnotVector::control_points);
                let cells = dims.map(|d| d.saturating_sub(1).max(1));
                let mut out = Vec::new();
                for i in 0..cells[0] {
                    for j in 0..cells[1] {
                        for k in 0..cells[2] {
                            let mut ctr = Vec3::zeros();
                            let mut cnt = 0.0;
                            for (a, b, c) in [
                                (0, 0, 0),
                                (1, 0, 0),
                                (0, 1, 0),
                                (0, 0, 1),
                                (1, 1, 0),
                                (1, 0, 1),
                                (0, 1, 1),
                                (1, 1, 1),
                            ] {
                                let (ii, jj, kk) = (
                                    (i + a).min(dims[0] - 1),
                                    (j + b).min(dims[1] - 1),
                                    (k + c).min(dims[2] - 1),
                                );
                                ctr += p[(ii * dims[1] + jj) * dims[2] + kk];
                                cnt += 1.0;
                            }
                            ctr /= cnt;
                            if (0..3).all(|a| ctr[a] >= lo[a] && ctr[a] <= hi[a]) {
                                out.push((i * cells[1] + j) * cells[2] + k);
                            }
                        }
                    }
                }
                out
            }
        }
    }

    fn set_param(&mut self, name: &str, value: f64) -> Result<String, SessionError> {
        let mut p = *self.solid.params();
        match name {
            "dt" => p.dt = value,
            "divergence_factor" => p.divergence_factor = value,
            "cg_tolerance" => p.cg_tolerance = value,
            "cg_max_iterations" => {
                if !(value >= 1.0 && value.fract() == 0.0 && value <= 1e9) {
                    return Err(cmd(format!(
                        "cg_max_iterations = {value}: a whole number from 1 to 1e9"
                    )));
                }
                p.cg_max_iterations = value as usize;
            }
            "density" | "damping" | "edge_stiffness" | "virtual_stiffness" => {
                let f = |m: &mut Material| match name {
                    "density" => m.density = value,
                    "damping" => m.damping = value,
                    "edge_stiffness" => m.edge_stiffness = value,
                    _ => m.virtual_stiffness = value,
                };
                self.solid
                    .update_material(None, f)
                    .map_err(SessionError::command_from)?;
                return Ok(format!("{name} = {value} in every cell"));
            }
            _ => {
                return Err(cmd(format!(
                    "no parameter `{name}`; a solid has {}",
                    self.params()
                        .iter()
                        .map(|p| p.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            }
        }
        self.solid
            .set_params(p)
            .map_err(SessionError::command_from)?;
        Ok(format!("{name} = {value}"))
    }

    fn boundary_mesh(&self) -> TriMesh {
        self.boundary_mesh_and_points().0
    }

    /// The boundary mesh and, per mesh vertex, its data point.
    fn boundary_mesh_and_points(&self) -> (TriMesh, Vec<u32>) {
        let (off, verts) = self.solid.boundary_loops();
        let d = self.solid.data_points();
        let mut map = vec![u32::MAX; d.len()];
        let mut points = Vec::new();
        let mut mesh = TriMesh::new();
        for k in 0..off.len().saturating_sub(1) {
            let lp = &verts[off[k] as usize..off[k + 1] as usize];
            let ids: Vec<u32> = lp
                .iter()
                .map(|&v| {
                    if map[v as usize] == u32::MAX {
                        map[v as usize] = mesh.positions.len() as u32;
                        mesh.positions.push(d[v as usize]);
                        points.push(v);
                    }
                    map[v as usize]
                })
                .collect();
            for j in 1..ids.len().saturating_sub(1) {
                mesh.triangles.push([ids[0], ids[j], ids[j + 1]]);
            }
        }
        mesh.compute_normals();
        (mesh, points)
    }

    fn control_net(&self) -> LineSet {
        let mut set = LineSet::new(LineRole::ControlNet);
        let p = self.solid.control_points();
        match self.solid.source() {
            SolidSource::Subdivision { control, .. } => {
                set.points = p.to_vec();
                for e in 0..control.num_edges() {
                    let [a, b] = control.edge_vertices(EdgeId::new(e));
                    set.segments.push([a.0, b.0]);
                }
            }
            SolidSource::BSpline { knots, .. } => {
                let dims = knots.each_ref().map(KnotVector::control_points);
                set = LineSet::grid(set.role.unwrap_or(LineRole::ControlNet), p.to_vec(), dims);
            }
        }
        set
    }

    /// Builds a solid from a scenario's `[model]`, `[material]` and `[simulation]` tables.
    pub fn from_keys(kind: ModelKind, spec: &SolidSpec, base: &Path) -> Result<Self, SpecError> {
        let m = &spec.model;
        let (source, p) = build_source(kind, m, base)?;
        let mut field = MaterialField::uniform(Material::default(), source.control_cells());
        let mut metric: Option<f64> = None;
        {
            let mk = &spec.material;
            let merr = |e: SolidsError, cells: bool| match e {
                SolidsError::InvalidParameter {
                    name,
                    value,
                    expected,
                } => SpecError::new(
                    "material",
                    name.split('[').next().unwrap_or(&name),
                    format!("{value} is invalid: {expected}"),
                ),
                SolidsError::NoSuchElement { index, count, .. } => SpecError::new(
                    "material",
                    if cells { "cells" } else { "material" },
                    format!("control cell {index} does not exist (there are {count})"),
                ),
                e => SpecError::new("material", "material", e),
            };
            let uniform = mk.values();
            field
                .update(None, |x| uniform.apply(x))
                .map_err(|e| merr(e, false))?;
            match mk.energy.as_deref() {
                None | Some("springs") => {
                    if mk.metric_stiffness.is_some() {
                        return Err(SpecError::new(
                            "material",
                            "metric_stiffness",
                            "needs `energy = \"metric-tensor\"`",
                        ));
                    }
                }
                Some("metric-tensor") => {
                    metric = Some(
                        mk.metric_stiffness
                            .unwrap_or(vclay_solids::metric::DEFAULT_METRIC_STIFFNESS),
                    )
                }
                Some(o) => {
                    return Err(SpecError::new(
                        "material",
                        "energy",
                        format!(
                            "unknown energy \"{o}\"; expected \"springs\" or \"metric-tensor\""
                        ),
                    ));
                }
            }
            for c in &mk.cells {
                field
                    .update(Some(&c.cells), |x| c.values().apply(x))
                    .map_err(|e| merr(e, true))?;
            }
        }
        let sim = &spec.simulation;
        let mut params = SolidParams::default();
        if let Some(i) = &sim.integrator {
            params.integrator = parse_integrator(i).ok_or_else(|| {
                SpecError::new("simulation", "integrator", format!("unknown integrator \"{i}\"; expected \"explicit\", \"symplectic\" or \"implicit\""))
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
            } => SpecError::new(
                "simulation",
                &name,
                format!("{value} is invalid: {expected}"),
            ),
            e => SpecError::new("simulation", "simulation", e),
        })?;
        let mut solid = DynamicSolid::with_material(source, p, field, params).map_err(|e| {
            let key = match &e {
                SolidsError::InvalidParameter { name, .. } if name.starts_with("samples") => {
                    "samples"
                }
                _ => "kind",
            };
            SpecError::new("model", key, e)
        })?;
        if metric.is_some() {
            solid.use_metric_energy(metric).map_err(|e| match e {
                SolidsError::InvalidParameter {
                    name,
                    value,
                    expected,
                } => SpecError::new("material", &name, format!("{value} is invalid: {expected}")),
                e => SpecError::new("material", "energy", e),
            })?;
        }
        Ok(Self::new(solid))
    }

    /// Rebuilds a model saved by [`Model::save`].
    pub fn load(v: &serde_json::Value) -> Result<Self, SessionError> {
        let s: Saved = serde_json::from_value(v.clone()).map_err(SessionError::kernel)?;
        let source = match &s.source {
            SavedSource::Subdivision {
                lattice,
                creases,
                corners,
                boundary,
                levels,
            } => {
                let control = formats::ovm::parse(lattice, "session lattice")
                    .map_err(SessionError::kernel)?;
                let mut features = Features::none(&control);
                for &e in creases {
                    features
                        .tag_crease(EdgeId::new(e))
                        .map_err(SessionError::kernel)?;
                }
                for &c in corners {
                    features
                        .tag_corner(VertexId::new(c))
                        .map_err(SessionError::kernel)?;
                }
                SolidSource::Subdivision {
                    control,
                    features,
                    rules: SubdivisionRules::new(parse_boundary(boundary).ok_or_else(|| {
                        SessionError::model(format!("unknown boundary rule \"{boundary}\""))
                    })?),
                    levels: *levels,
                }
            }
            SavedSource::Bspline {
                knots,
                degrees,
                weights,
                samples,
            } => SolidSource::BSpline {
                knots: super::saved::knot_vectors(knots, degrees)?,
                weights: weights.clone(),
                samples: *samples,
            },
        };
        let material =
            MaterialField::from_cells(s.material.iter().map(|m| m.to_material()).collect())
                .map_err(SessionError::kernel)?;
        let params = SolidParams {
            integrator: parse_integrator(&s.params.integrator).ok_or_else(|| {
                SessionError::model(format!("unknown integrator \"{}\"", s.params.integrator))
            })?,
            dt: s.params.dt,
            divergence_factor: s.params.divergence_factor,
            cg_tolerance: s.params.cg_tolerance,
            cg_max_iterations: s.params.cg_max_iterations,
            ..SolidParams::default()
        };
        let rest = SolidRest {
            control_points: s.rest.control_points.iter().map(|a| v3(*a)).collect(),
            data_points: s.rest.data_points.iter().map(|a| v3(*a)).collect(),
            physics_data_points: s.rest.physics_data_points.iter().map(|a| v3(*a)).collect(),
            fixed: s.rest.fixed.clone(),
            metric_stiffness: s.rest.metric_stiffness,
            energy_scale: s.rest.energy_scale,
        };
        let state = SolidState {
            control_points: s.state.control_points.iter().map(|a| v3(*a)).collect(),
            velocities: s.state.velocities.iter().map(|a| v3(*a)).collect(),
            data_points: s.state.data_points.iter().map(|a| v3(*a)).collect(),
            tools: s
                .state
                .tools
                .iter()
                .map(|t| t.as_ref().map(SavedTool::to_tool))
                .collect(),
            time: s.state.time,
            steps: s.state.steps,
            tool_energy_seen: s.state.tool_energy_seen,
        };
        let numbering = match s.numbering.as_deref() {
            None => DataNumbering::Locality,
            Some(name) => DataNumbering::from_name(name).ok_or_else(|| {
                SessionError::model(format!(
                    "unknown data-point numbering \"{name}\" (\"locality\" or \"grid\")"
                ))
            })?,
        };
        let solid =
            DynamicSolid::from_parts_numbered(source, material, params, &rest, &state, numbering)
                .map_err(SessionError::kernel)?;
        for t in &s.tools.tools {
            if solid.tool(ToolId(t.handle)).is_none() {
                return Err(SessionError::model(format!(
                    "tool `{}` refers to kernel tool {} which does not exist",
                    t.name, t.handle
                )));
            }
        }
        Ok(Self {
            solid,
            tools: s.tools,
            revision: 1,
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

fn integrator_name(i: Integrator) -> &'static str {
    match i {
        Integrator::Explicit => "explicit",
        Integrator::SymplecticEuler => "symplectic",
        Integrator::ImplicitEuler => "implicit",
    }
}

fn parse_boundary(s: &str) -> Option<BoundaryRule> {
    match s {
        "sharp" => Some(BoundaryRule::Sharp),
        "smooth" => Some(BoundaryRule::Smooth),
        "interior" => Some(BoundaryRule::Interior),
        _ => None,
    }
}

fn boundary_name(b: BoundaryRule) -> &'static str {
    match b {
        BoundaryRule::Sharp => "sharp",
        BoundaryRule::Smooth => "smooth",
        BoundaryRule::Interior => "interior",
    }
}

/// The control lattice of a solid for the shared fix/free tool.
impl crate::tools::ControlNet for vclay_solids::DynamicSolid {
    fn current_points(&self) -> Vec<Vec3> {
        self.control_points().to_vec()
    }
    fn rest_points(&self) -> Vec<Vec3> {
        self.rest_control_points().to_vec()
    }
    fn is_fixed(&self, i: usize) -> bool {
        vclay_solids::DynamicSolid::is_fixed(self, i)
    }
    fn set_fixed(&mut self, ids: &[usize], fix: bool) -> Result<(), SessionError> {
        vclay_solids::DynamicSolid::set_fixed(self, ids, fix).map_err(SessionError::command_from)
    }
}

/// A solid's tools for the shared rope, force and release edits: a handle is the kernel's tool
/// id.
impl ToolHost for SolidModel {
    type Field = Tool;
    crate::tools::tool_table!(tools);
    fn attach_rope(
        &mut self,
        r: &RopeRequest,
    ) -> Result<(usize, Option<CursorPath>, String), SessionError> {
        if r.param.is_some() || r.kernel.is_some() {
            return Err(cmd("`param` and `kernel` are for D-NURBS models"));
        }
        let id = self
            .solid
            .attach_rope(
                v3(r.from),
                r.stiffness.unwrap_or(DEFAULT_ROPE_STIFFNESS),
                r.length.unwrap_or(0.0),
            )
            .map_err(SessionError::command_from)?
            .0;
        let Some(Tool::Rope { point, .. }) = self.solid.tool(ToolId(id)) else {
            unreachable!("just added a rope")
        };
        let start = r.start.unwrap_or(self.solid.time());
        let path = match r.velocity {
            Some(velocity) => CursorPath::Velocity {
                from: r.from,
                velocity,
            },
            None => CursorPath::Linear {
                from: r.from,
                to: r.to.unwrap_or(r.from),
                start,
                end: r.until.unwrap_or(start),
            },
        };
        Ok((id, Some(path), format!("to data point {point}")))
    }
    fn attach_force(&mut self, edit: &Edit) -> Result<(usize, String), SessionError> {
        let Edit::Force { near, force, .. } = edit else {
            return Err(misrouted());
        };
        let Some(near) = near else {
            return Err(cmd("solids take `near`, not `param`"));
        };
        let point = vclay_solids::tools::nearest(self.solid.data_points(), &v3(*near)).unwrap_or(0);
        let id = self.add_tool(Tool::PointForce {
            point,
            force: v3(*force),
        })?;
        Ok((id, format!("on data point {point}")))
    }
    fn attach_field(&mut self, field: Tool) -> Result<usize, SessionError> {
        self.add_tool(field)
    }
    fn replace_field(&mut self, handle: usize, field: Tool) -> Result<usize, SessionError> {
        let id = self.add_tool(field)?;
        let _ = self.solid.remove_tool(ToolId(handle));
        Ok(id)
    }
    fn move_cursor(&mut self, handle: usize, to: V3) -> Result<(), SessionError> {
        self.solid
            .move_cursor(ToolId(handle), v3(to))
            .map_err(SessionError::command_from)
    }
    fn detach(&mut self, handle: usize) {
        let _ = self.solid.remove_tool(ToolId(handle));
    }
}

impl crate::model::Stateful for SolidModel {
    type State = SolidSnap;
    fn take_state(&self) -> SolidSnap {
        SolidSnap {
            state: self.solid.state(),
            tools: self.tools.clone(),
            params: *self.solid.params(),
            material: self.solid.material().clone(),
            rest: {
                let (c, d) = self.solid.rest_shape();
                (c.to_vec(), d.to_vec())
            },
        }
    }
    fn put_state(&mut self, s: &SolidSnap) -> Result<(), SessionError> {
        if self.solid.material() != &s.material {
            self.solid
                .set_material(s.material.clone())
                .map_err(kernel)?;
        }
        self.solid.set_params(s.params).map_err(kernel)?;
        self.solid.set_state(&s.state).map_err(kernel)?;
        self.solid
            .set_rest_shape(&s.rest.0, &s.rest.1)
            .map_err(kernel)?;
        self.tools = s.tools.clone();
        Ok(())
    }
    fn revision_mut(&mut self) -> &mut u64 {
        &mut self.revision
    }
    fn edit(&mut self, edit: &Edit, _before: &SolidSnap) -> Result<Done, SessionError> {
        Ok(match edit {
            _ if crate::tools::is_tool_edit(edit) => {
                Done::State(crate::tools::tool_edit(self, edit)?)
            }
            Edit::RegionForce { .. } => Done::State(self.region_force(edit)?),
            Edit::Gravity { name, g, until } => {
                let gravity = Tool::Gravity { g: v3(*g) };
                Done::State(field_tool(self, name, "gravity", gravity, *until)?)
            }
            Edit::Inflate {
                name,
                pressure,
                until,
            } => {
                let inflation = Tool::Inflation {
                    pressure: *pressure,
                };
                Done::State(field_tool(self, name, "inflate", inflation, *until)?)
            }
            Edit::Fix { .. } | Edit::Free { .. } => self.fix_or_free(edit)?,
            Edit::Material { .. } => Done::State(self.set_material(edit)?),
            Edit::Extrude { face, near, factor } => {
                let f = self.element("face", *face, near.as_ref())?;
                self.rebuild(|s| {
                    let factor = factor.unwrap_or(1.0);
                    s.extrude(f, factor).map_err(SessionError::command_from)?;
                    Ok(format!("extruded control face {f}"))
                })?
            }
            Edit::DeleteCell { cell, near } => {
                let c = self.element("cell", *cell, near.as_ref())?;
                self.rebuild(|s| {
                    s.delete_cell(c).map_err(SessionError::command_from)?;
                    Ok(format!("deleted control cell {c}"))
                })?
            }
            Edit::Smooth { .. } => Done::State(self.smooth(edit)?),
            Edit::PlasticReset => self.plastic_reset(),
            Edit::Stop => {
                self.solid.stop();
                Done::State("stopped all motion".to_string())
            }
            Edit::MovePoint { index, to } => Done::State(self.move_point(*index, to)?),
            Edit::SetWeight { .. } => {
                return Err(cmd(
                    "the weights of a dynamic solid are frozen (journal section 4.1: c = B q with fixed weights)",
                ));
            }
            Edit::Set { name, value } => Done::State(self.set_param(name, *value)?),
            Edit::Integrator { integrator, dt } => {
                Done::State(self.set_integrator(integrator.as_deref(), *dt)?)
            }
            _ => return Err(super::not_taken(edit, self.kind(), "")),
        })
    }
}

impl Model for SolidModel {
    fn kind(&self) -> ModelKind {
        if self.is_subdivision() {
            ModelKind::SubdivisionSolid
        } else {
            ModelKind::BsplineSolid
        }
    }

    fn summary(&self) -> String {
        let st = self.solid.stats();
        format!(
            "{} control points ({} free), {} data points ({} active), {} springs ({} active)",
            st.control_points,
            st.free_control_points,
            st.data_points,
            st.active_data_points,
            st.edge_springs + st.virtual_springs,
            st.active_springs
        )
    }

    crate::model::clock_methods!(self => self.solid.time(), self.solid.params().dt, self.solid.steps());

    fn step(&mut self) -> Result<StepReport, SessionError> {
        let t = self.solid.time();
        let due = self.tools.due(t, self.solid.params().dt);
        for e in &due.expired {
            let _ = self.solid.remove_tool(ToolId(e.handle));
        }
        for (h, c) in &due.cursors {
            self.solid.move_cursor(ToolId(*h), *c).map_err(kernel)?;
        }
        self.revision += 1;
        let r = self.solid.step().map_err(kernel)?;
        Ok(StepReport {
            time: self.solid.time(),
            energy: Energy {
                kinetic: r.energy.kinetic,
                elastic: r.energy.internal,
                tools: r.energy.tools,
            },
            iterations: r.cg_iterations,
            seconds: r.seconds,
        })
    }

    fn display_fields(&self) -> Vec<FieldSpec> {
        SOLID_FIELDS.to_vec()
    }

    fn display_field(&self, name: &str) -> Option<Vec<f64>> {
        let f: fn(&Material) -> f64 = match name {
            "edge-stiffness" => |m| m.edge_stiffness,
            "virtual-stiffness" => |m| m.virtual_stiffness,
            "density" => |m| m.density,
            "damping" => |m| m.damping,
            _ => return None,
        };
        let per_point = self.solid.data_point_material(f);
        let (_, points) = self.boundary_mesh_and_points();
        Some(points.iter().map(|&i| per_point[i as usize]).collect())
    }

    fn plastic_flow(&mut self, fraction: f64, yield_distance: f64) -> Result<usize, SessionError> {
        self.solid
            .plastic_flow(fraction, yield_distance)
            .map_err(kernel)
    }

    fn energy(&self) -> Energy {
        let e = self.solid.energy();
        Energy {
            kinetic: e.kinetic,
            elastic: e.internal,
            tools: e.tools,
        }
    }

    fn size(&self) -> f64 {
        let mut lo = Vec3::repeat(f64::INFINITY);
        let mut hi = Vec3::repeat(f64::NEG_INFINITY);
        for p in self.solid.rest_control_points() {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        (hi - lo).norm().max(f64::MIN_POSITIVE)
    }

    fn revision(&self) -> u64 {
        self.revision
    }

    fn display_mesh(&self) -> Result<TriMesh, SessionError> {
        Ok(self.boundary_mesh())
    }

    fn display_lines(&self) -> Vec<LineSet> {
        let mut out = vec![self.control_net()];
        let p = self.solid.control_points();
        out.push(LineSet::markers(LineRole::Fixed, p, |i| {
            self.solid.is_fixed(i)
        }));
        let d = self.solid.data_points();
        if d.len() <= 20_000 {
            let mut dp = LineSet::new(LineRole::DataPoints);
            dp.points = d.to_vec();
            out.push(dp);
        }
        let mut ropes = LineSet::new(LineRole::Ropes);
        let mut forces = LineSet::new(LineRole::Forces);
        let size = self.size();
        for t in &self.tools.tools {
            match self.solid.tool(ToolId(t.handle)) {
                Some(Tool::Rope { point, cursor, .. }) => ropes.segment(d[*point], *cursor),
                Some(Tool::PointForce { point, force }) => {
                    let n = force.norm();
                    if n > 0.0 {
                        forces.segment(d[*point], d[*point] + force / n * (0.2 * size));
                    }
                }
                Some(Tool::RegionForce { center, force, .. }) => {
                    let n = force.norm();
                    if n > 0.0 {
                        forces.segment(*center, center + force / n * (0.2 * size));
                    }
                }
                _ => {}
            }
        }
        out.push(ropes);
        out.push(forces);
        out
    }

    fn pick(&self, ray: &Ray, tolerance: f64) -> Option<Hit> {
        let cp = crate::pick::control_point(ray, self.solid.control_points(), tolerance);
        let mesh = self.boundary_mesh();
        let surf = crate::pick::ray_mesh(ray, &mesh).map(|(s, _, _)| {
            let x = ray.origin + ray.direction * s;
            let dp = vclay_solids::tools::nearest(self.solid.data_points(), &x).unwrap_or(0);
            Hit {
                distance: s,
                point: x,
                element: Element::DataPoint { index: dp },
                extra: [
                    self.solid
                        .boundary_face_near(&x)
                        .map(|index| Element::Face { index }),
                    self.solid
                        .cell_near(&x)
                        .map(|index| Element::Cell { index }),
                ],
            }
        });
        match (cp, surf) {
            // A control point in front of (or just behind) the surface wins.
            (Some(c), Some(s)) if c.distance <= s.distance + tolerance => Some(c),
            (c, s) => s.or(c),
        }
    }

    fn params(&self) -> Vec<Param> {
        let p = self.solid.params();
        let m = self.solid.material().cell(0);
        let par = Param::new;
        vec![
            par("dt", p.dt, 1e-5, 0.05, "time step (s)"),
            par(
                "density",
                m.density,
                0.01,
                100.0,
                "mass per volume (cell 0 shown; set applies to every cell)",
            ),
            par("damping", m.damping, 0.0, 100.0, "damping per volume"),
            par(
                "edge_stiffness",
                m.edge_stiffness,
                0.0,
                10_000.0,
                "edge spring modulus",
            ),
            par(
                "virtual_stiffness",
                m.virtual_stiffness,
                0.0,
                10_000.0,
                "virtual spring modulus",
            ),
            par(
                "divergence_factor",
                p.divergence_factor,
                1.0,
                1e9,
                "divergence bound / spring energy scale",
            ),
            par(
                "cg_tolerance",
                p.cg_tolerance,
                1e-14,
                1e-2,
                "implicit: CG relative residual",
            ),
            par(
                "cg_max_iterations",
                p.cg_max_iterations as f64,
                1.0,
                10_000.0,
                "implicit: CG iteration cap",
            ),
        ]
    }

    crate::model::stateful_methods!();

    fn export(&self, path: &Path) -> Result<(), SessionError> {
        let ext = extension(path);
        let io = |e: &dyn std::fmt::Display| SessionError::io(path, e);
        match (ext.as_str(), self.solid.source()) {
            ("ovm", SolidSource::Subdivision { .. }) => {
                let l = self.solid.control_lattice().expect("subdivision solid");
                formats::ovm::write(&l, path).map_err(|e| io(&e))
            }
            ("json", SolidSource::BSpline { knots, weights, .. }) => {
                let vol = NurbsVolume::from_flat(
                    knots.clone(),
                    self.solid.control_points().to_vec(),
                    weights.clone(),
                )
                .map_err(|e| io(&e))?;
                vclay_io::write_model(path, &[vclay_io::Entity::Volume(vol)]).map_err(|e| io(&e))
            }
            ("step" | "stp" | "igs" | "iges", source) => {
                // A solid B-rep (issue 20): a B-spline solid's six boundary faces, or the
                // bicubic patches of a subdivision solid's boundary limit surface, joined into
                // one closed shell.
                let entities: Vec<vclay_io::NamedEntity> = match source {
                    SolidSource::BSpline { knots, weights, .. } => {
                        let vol = NurbsVolume::from_flat(
                            knots.clone(),
                            self.solid.control_points().to_vec(),
                            weights.clone(),
                        )
                        .map_err(|e| io(&e))?;
                        vec![vclay_io::Entity::Volume(vol).into()]
                    }
                    SolidSource::Subdivision {
                        features, rules, ..
                    } => {
                        let l = self
                            .solid
                            .control_lattice()
                            .ok_or_else(|| io(&"no control lattice"))?;
                        vclay_lattice::boundary_patches(
                            &l,
                            features,
                            *rules,
                            vclay_lattice::limit_surface::DEFAULT_PATCH_SAMPLE_LEVELS,
                        )
                        .map_err(|e| io(&e))?
                        .patches
                        .into_iter()
                        .map(|s| vclay_io::Entity::Surface(s).into())
                        .collect()
                    }
                };
                if matches!(ext.as_str(), "igs" | "iges") {
                    let layout = vclay_io::iges::IgesLayout::JoinedBrep;
                    vclay_io::iges::write_iges_as(path, &entities, layout)
                } else {
                    let layout = vclay_io::step::StepLayout::JoinedBrep;
                    vclay_io::step::write_step_as(path, &entities, layout)
                }
                .map_err(|e| io(&e))
            }
            ("obj" | "ply" | "stl", _) => {
                let mesh = vclay_lattice::boundary_mesh(&self.solid.data_lattice_copy());
                match ext.as_str() {
                    "obj" => formats::surface::write_obj(&mesh, path),
                    "ply" => formats::surface::write_ply(&mesh, path),
                    _ => formats::surface::write_stl(&mesh, path),
                }
                .map_err(|e| io(&e))
            }
            ("glb", _) => vclay_io::gltf::write_glb(
                path,
                &[vclay_io::gltf::GlbMesh::new(
                    self.kind().name(),
                    self.boundary_mesh(),
                )],
            )
            .map_err(|e| io(&e)),
            ("vtu", _) => {
                use vclay_lattice::formats::vtu::PointData;
                let s = &self.solid;
                let rest = s.map_to_data(s.rest_control_points()).map_err(|e| io(&e))?;
                let disp: Vec<Vec3> = s
                    .data_points()
                    .iter()
                    .zip(&rest)
                    .map(|(d, r)| d - r)
                    .collect();
                let vel = s.map_to_data(s.velocities()).map_err(|e| io(&e))?;
                let force = (!s.uses_metric_energy()).then(|| s.internal_forces());
                let mass = s.masses().to_vec();
                let mut data = vec![
                    PointData::Vectors("displacement", &disp),
                    PointData::Vectors("velocity", &vel),
                ];
                if let Some(f) = &force {
                    data.push(PointData::Vectors("spring_force", f));
                }
                data.push(PointData::Scalars("mass", &mass));
                formats::vtu::write_with_point_data(&s.data_lattice_copy(), &data, path)
                    .map_err(|e| io(&e))
            }
            _ => Err(unsupported_export(
                self.kind(),
                path,
                &self.export_formats(),
            )),
        }
    }

    fn control_points(&self) -> Vec<Vec3> {
        self.solid.control_points().to_vec()
    }

    fn data_points(&self) -> Vec<Vec3> {
        self.solid.data_points().to_vec()
    }

    fn export_formats(&self) -> Vec<&'static str> {
        if self.is_subdivision() {
            vec!["ovm", "obj", "ply", "stl", "vtu", "glb", "step", "igs"]
        } else {
            vec!["json", "obj", "ply", "stl", "vtu", "glb", "step", "igs"]
        }
    }

    fn save(&self) -> Result<serde_json::Value, SessionError> {
        let s = &self.solid;
        let source = match s.source() {
            SolidSource::Subdivision {
                control,
                features,
                rules,
                levels,
            } => SavedSource::Subdivision {
                lattice: formats::ovm::to_string(control),
                creases: features.creases().map(|e| e.index()).collect(),
                corners: features.corners().map(|v| v.index()).collect(),
                boundary: boundary_name(rules.boundary).to_string(),
                levels: *levels,
            },
            SolidSource::BSpline {
                knots,
                weights,
                samples,
            } => SavedSource::Bspline {
                knots: knots.each_ref().map(|k| k.as_slice().to_vec()),
                degrees: knots.each_ref().map(KnotVector::degree),
                weights: weights.clone(),
                samples: *samples,
            },
        };
        let p = s.params();
        let rest = s.rest();
        let st = s.state();
        let arr = |v: &[Vec3]| v.iter().map(a3).collect::<Vec<_>>();
        let saved = Saved {
            source,
            numbering: (s.data_numbering() != DataNumbering::Locality)
                .then(|| s.data_numbering().name().to_string()),
            material: s
                .material()
                .cells()
                .iter()
                .map(SavedMaterial::from)
                .collect(),
            params: SavedParams {
                integrator: integrator_name(p.integrator).into(),
                dt: p.dt,
                divergence_factor: p.divergence_factor,
                cg_tolerance: p.cg_tolerance,
                cg_max_iterations: p.cg_max_iterations,
            },
            rest: SavedRest {
                control_points: arr(&rest.control_points),
                data_points: arr(&rest.data_points),
                physics_data_points: arr(&rest.physics_data_points),
                fixed: rest.fixed,
                metric_stiffness: rest.metric_stiffness,
                energy_scale: rest.energy_scale,
            },
            state: SavedState {
                control_points: arr(&st.control_points),
                velocities: arr(&st.velocities),
                data_points: arr(&st.data_points),
                tools: st
                    .tools
                    .iter()
                    .map(|t| t.as_ref().map(SavedTool::from))
                    .collect(),
                time: st.time,
                steps: st.steps,
                tool_energy_seen: st.tool_energy_seen,
            },
            tools: self.tools.clone(),
        };
        serde_json::to_value(saved).map_err(SessionError::kernel)
    }
}

// ---------------------------------------------------------------------------------------
// Scenario keys
// ---------------------------------------------------------------------------------------

scenario_keys! {
    /// The `[model]` keys of a `subdivision-solid` or `bspline-solid` model.
    pub struct ModelKeys {
        pub primitive: Option<String>,
        pub file: Option<std::path::PathBuf>,
        pub entity: Option<usize>,
        pub points: Option<[usize; 3]>,
        pub min: Option<V3>,
        pub max: Option<V3>,
        pub radius: Option<f64>,
        pub height: Option<f64>,
        pub level: Option<usize>,
        pub boundary: Option<String>,
        pub control: Option<[usize; 3]>,
        pub degree: Option<[usize; 3]>,
        pub samples: Option<[usize; 3]>,
        /// Cells of the lattice built from a mesh `file`.
        pub cells: Option<usize>,
    }
}

/// The solid material values that a `[material]` table, a `[[material.cells]]` entry or a
/// `material` edit gives: `[density, damping, edge_stiffness, virtual_stiffness]` and the
/// `anisotropy` (journal section 4.3); absent values stay as they are.
#[derive(Clone, Copy, Debug, Default)]
struct Values([Option<f64>; 4], Option<V3>);

impl Values {
    fn apply(&self, m: &mut Material) {
        let moduli = [
            &mut m.density,
            &mut m.damping,
            &mut m.edge_stiffness,
            &mut m.virtual_stiffness,
        ];
        for (slot, value) in moduli.into_iter().zip(self.0) {
            if let Some(x) = value {
                *slot = x;
            }
        }
        if let Some(x) = self.1 {
            m.anisotropy = x;
        }
    }
}

/// Declares a key struct of a solid that gives the solid material values (`density`,
/// `damping`, `edge_stiffness`, `virtual_stiffness`, `anisotropy`: journal section 4.3) besides
/// its own keys, and its `values()`. Each field is the key of the same name in
/// `docs/formats.md` section 8 (absent: the documented default).
macro_rules! material_keys {
    ($(#[$meta:meta])* pub struct $name:ident { $($own:tt)* }) => {
        $(#[$meta])*
        #[allow(missing_docs)]
        #[derive(Debug, Default, Deserialize, Clone, PartialEq, Serialize)]
        #[serde(deny_unknown_fields)]
        pub struct $name {
            pub density: Option<f64>,
            pub damping: Option<f64>,
            pub edge_stiffness: Option<f64>,
            pub virtual_stiffness: Option<f64>,
            pub anisotropy: Option<V3>,
            $($own)*
        }

        impl $name {
            /// The material values given.
            fn values(&self) -> Values {
                let moduli = [
                    self.density,
                    self.damping,
                    self.edge_stiffness,
                    self.virtual_stiffness,
                ];
                Values(moduli, self.anisotropy)
            }
        }
    };
}

material_keys! {
    /// The entry keys of a `[[material.cells]]` entry of a `subdivision-solid` or
    /// `bspline-solid` model as a typed value.
    pub struct CellKeys {
        pub cells: Vec<usize>,
    }
}

material_keys! {
    /// The `[material]` keys of a `subdivision-solid` or `bspline-solid` model as a typed
    /// value.
    pub struct MaterialKeys {
        pub energy: Option<String>,
        pub metric_stiffness: Option<f64>,
        #[serde(default)]
        pub cells: Vec<CellKeys>,
    }
}

scenario_keys! {
    /// The `[simulation]` keys of a `subdivision-solid` or `bspline-solid` model.
    pub struct SimKeys {
        pub integrator: Option<String>,
        pub dt: Option<f64>,
        pub divergence_factor: Option<f64>,
        pub cg_tolerance: Option<f64>,
        pub cg_max_iterations: Option<usize>,
    }
}

/// The typed spec of a solid ([`super::ModelSpec`]).
pub type SolidSpec = super::KindSpec<ModelKeys, MaterialKeys, SimKeys>;

fn build_source(
    kind: ModelKind,
    m: &ModelKeys,
    base: &Path,
) -> Result<(SolidSource, Vec<Vec3>), SpecError> {
    let err = |key: &str, what: String| SpecError::new("model", key, what);
    let min = v3(m.min.unwrap_or([0.0; 3]));
    let max = v3(m.max.unwrap_or([1.0; 3]));
    for (k, v) in [("min", &min), ("max", &max)] {
        if !v.iter().all(|c| c.is_finite()) {
            return Err(err(k, "coordinates must be finite".into()));
        }
    }
    if (0..3).any(|a| max[a] <= min[a]) {
        return Err(err("max", "must exceed `min` along every axis".into()));
    }
    // The keys of the other solid kind (`cells` is also clay's, from a mesh file).
    let mesh_cells = m.cells.is_some() && !m.file.as_deref().is_some_and(is_mesh);
    let foreign = match kind {
        ModelKind::SubdivisionSolid => vec![
            ("control", m.control.is_some()),
            ("degree", m.degree.is_some()),
            ("samples", m.samples.is_some()),
            ("entity", m.entity.is_some()),
            ("cells", mesh_cells),
        ],
        ModelKind::BsplineSolid => vec![
            ("cells", m.cells.is_some()),
            ("primitive", m.primitive.is_some()),
            ("level", m.level.is_some()),
            ("boundary", m.boundary.is_some()),
            ("points", m.points.is_some()),
            ("radius", m.radius.is_some()),
            ("height", m.height.is_some()),
        ],
        _ => return Err(err("kind", format!("{kind} is not a solid"))),
    };
    first_given(&foreign, format!("is not a key of kind \"{kind}\""))?;
    if kind == ModelKind::SubdivisionSolid {
        subdivision_source(m, base, min, max)
    } else {
        bspline_source(m, base, min, max)
    }
}

/// An error naming the first of `keys` given (`what`: why it may not be).
fn first_given(keys: &[(&str, bool)], what: impl std::fmt::Display) -> Result<(), SpecError> {
    match keys.iter().find(|k| k.1) {
        Some((key, _)) => Err(SpecError::new("model", key, what)),
        None => Ok(()),
    }
}

/// An error naming the first of `keys` given: primitive keys with a model read from `file`.
fn from_file_only(keys: &[(&str, bool)]) -> Result<(), SpecError> {
    first_given(
        keys,
        "describes a primitive; it does not apply to a model read from `file`",
    )
}

/// `f` resolved against `base` unless it is absolute.
fn resolve_in(base: &Path, f: &Path) -> std::path::PathBuf {
    if f.is_absolute() {
        f.to_path_buf()
    } else {
        base.join(f)
    }
}

/// The control lattice of a `subdivision-solid`: a primitive, a lattice file or clay from a
/// mesh file.
fn subdivision_source(
    m: &ModelKeys,
    base: &Path,
    min: Vec3,
    max: Vec3,
) -> Result<(SolidSource, Vec<Vec3>), SpecError> {
    let err = |key: &str, what: String| SpecError::new("model", key, what);
    let resolve = |f: &Path| resolve_in(base, f);
    if m.file.is_some() {
        from_file_only(&[
            ("points", m.points.is_some()),
            ("min", m.min.is_some()),
            ("max", m.max.is_some()),
            ("radius", m.radius.is_some()),
            ("height", m.height.is_some()),
        ])?;
    }
    let lattice: Lattice = match (&m.primitive, &m.file) {
        (Some(_), Some(_)) => {
            return Err(err(
                "file",
                "give either `primitive` or `file`, not both".into(),
            ));
        }
        (None, Some(f)) if is_mesh(f) => {
            // Any closed mesh becomes clay: a hexahedral lattice of about `cells`
            // cells whose level-`level` boundary is fitted to it
            // (`vclay_lattice::lattice_from_mesh`, issue 19).
            let mesh = super::ffd::read_any_mesh(&resolve(f)).map_err(|e| err("file", e))?;
            let params = vclay_lattice::ClayParams {
                cells: m.cells.unwrap_or(DEFAULT_MESH_CELLS),
                levels: m
                    .level
                    .unwrap_or(2)
                    .min(vclay_lattice::from_mesh::MAX_LEVELS),
                boundary: parse_boundary(m.boundary.as_deref().unwrap_or("smooth"))
                    .filter(|b| *b != BoundaryRule::Interior)
                    .unwrap_or(BoundaryRule::Smooth),
                ..Default::default()
            };
            let clay = vclay_lattice::lattice_from_mesh(&mesh, &params).map_err(|e| {
                let key = match &e {
                    vclay_lattice::ClayError::Parameter { .. } => "cells",
                    _ => "file",
                };
                err(key, format!("{}: {e}", f.display()))
            })?;
            clay.solid.control().clone()
        }
        (None, Some(f)) if extension(f) == "vtu" => {
            formats::vtu::read(&resolve(f)).map_err(|e| err("file", e.to_string()))?
        }
        (None, Some(f)) => {
            formats::ovm::read(&resolve(f)).map_err(|e| err("file", e.to_string()))?
        }
        (prim, None) => build_primitive(prim.as_deref().unwrap_or("box"), m, min, max)?,
    };
    let level = m.level.unwrap_or(2);
    if level > vclay_solids::model::MAX_LEVEL {
        return Err(err(
            "level",
            format!(
                "{level} is above the maximum {}",
                vclay_solids::model::MAX_LEVEL
            ),
        ));
    }
    // Memory: every level multiplies the cells by about 8 (hexahedra; other cells by
    // their vertex count); the dynamic solid keeps the hierarchy, springs and per-step
    // arrays (about BYTES_PER_DATA_CELL per finest cell).
    let cells = lattice.num_cells() as f64 * 8f64.powi(level as i32);
    let bytes = cells * BYTES_PER_DATA_CELL;
    if bytes > MAX_SOLID_BYTES as f64 {
        return Err(err(
            "level",
            format!(
                "level {level} of this lattice makes about {cells:.3e} data cells, an \
                 estimated {:.1} GB; the limit is {:.1} GB (a lower level, or fewer \
                 control cells)",
                bytes / 1e9,
                MAX_SOLID_BYTES as f64 / 1e9
            ),
        ));
    }
    let boundary = parse_boundary(m.boundary.as_deref().unwrap_or("sharp")).ok_or_else(|| {
        err(
            "boundary",
            format!(
                "unknown rule \"{}\"; expected \"sharp\", \"smooth\" or \"interior\"",
                m.boundary.as_deref().unwrap_or("")
            ),
        )
    })?;
    Ok(SolidSource::subdivision(lattice, boundary, level))
}

/// The control net of a `bspline-solid`: a box lattice or a volume of a model file.
fn bspline_source(
    m: &ModelKeys,
    base: &Path,
    min: Vec3,
    max: Vec3,
) -> Result<(SolidSource, Vec<Vec3>), SpecError> {
    let err = |key: &str, what: String| SpecError::new("model", key, what);
    let resolve = |f: &Path| resolve_in(base, f);
    let samples = m.samples.unwrap_or([10; 3]);
    for (a, &n) in samples.iter().enumerate() {
        if n < 2 {
            return Err(err(
                "samples",
                format!("{n} samples along axis {a}; at least 2 needed"),
            ));
        }
        if n > MAX_SAMPLES {
            return Err(err(
                "samples",
                format!("{n} samples along axis {a}; at most {MAX_SAMPLES}"),
            ));
        }
    }
    if samples.iter().product::<usize>() > MAX_SAMPLE_POINTS {
        return Err(err(
            "samples",
            format!(
                "{samples:?} makes {} data points; at most {MAX_SAMPLE_POINTS}",
                samples.iter().product::<usize>()
            ),
        ));
    }
    if let Some(f) = &m.file {
        from_file_only(&[
            ("control", m.control.is_some()),
            ("degree", m.degree.is_some()),
            ("min", m.min.is_some()),
            ("max", m.max.is_some()),
        ])?;
        let path = resolve(f);
        let idx = m.entity.unwrap_or(0);
        let entities =
            vclay_io::model::read_model(&path).map_err(|e| err("file", e.to_string()))?;
        let count = entities.len();
        let vol = match entities.into_iter().nth(idx) {
            Some(vclay_io::Entity::Volume(v)) => v,
            Some(other) => {
                return Err(err(
                    "entity",
                    format!(
                        "entity {idx} of {} is a {}, not a nurbs-volume",
                        path.display(),
                        other.type_name()
                    ),
                ));
            }
            None => {
                return Err(err(
                    "entity",
                    format!(
                        "{} has {count} entities; there is no entity {idx}",
                        path.display()
                    ),
                ));
            }
        };
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
        return Err(err(
            "entity",
            "selects an entity of `file`; give `file`".into(),
        ));
    }
    let control = m.control.unwrap_or([4; 3]);
    let degree = m.degree.unwrap_or([3; 3]);
    if let Some(a) = (0..3).find(|&a| control[a] > 256) {
        return Err(err(
            "control",
            format!("{} control points along axis {a}; at most 256", control[a]),
        ));
    }
    let total: usize = control.iter().product();
    if total > MAX_CONTROL_POINTS {
        return Err(err(
            "control",
            format!("{control:?} makes {total} control points; at most {MAX_CONTROL_POINTS}"),
        ));
    }
    let mut knots = Vec::with_capacity(3);
    for a in 0..3 {
        knots.push(
            KnotVector::clamped_uniform(degree[a], control[a])
                .map_err(|e| err("control", format!("axis {a}: {e}")))?,
        );
    }
    let knots: [KnotVector; 3] = knots.try_into().expect("three axes");
    let vol = NurbsVolume::box_lattice(degree, control, min, max)
        .map_err(|e| err("control", e.to_string()))?;
    Ok((
        SolidSource::BSpline {
            knots,
            weights: vec![1.0; vol.control_points().len()],
            samples,
        },
        vol.control_points().to_vec(),
    ))
}

/// Default `cells` of a subdivision solid built from a mesh `file` (500 cells at level 2 are
/// 32,000 data cells: interactive on two cores).
pub const DEFAULT_MESH_CELLS: usize = 500;

/// Whether `f` names a mesh file (built into a lattice) rather than a lattice `.ovm`.
fn is_mesh(f: &Path) -> bool {
    matches!(extension(f).as_str(), "obj" | "stl" | "ply" | "glb")
}

/// Estimated bytes a dynamic subdivision solid holds per finest-level cell (about 850 bytes per
/// data point in the per-step structures, measured, plus the subdivision hierarchy while it is
/// built; `vclay_lattice::command::BYTES_PER_CELL` measures the hierarchy alone at 760).
pub const BYTES_PER_DATA_CELL: f64 = 2000.0;
/// Largest estimated memory of one dynamic solid built from a scenario (4 GB, a laptop).
pub const MAX_SOLID_BYTES: u64 = 4_000_000_000;
/// Most control points of a B-spline solid (the mass matrix is factored once; 100,000 control
/// points take minutes).
pub const MAX_CONTROL_POINTS: usize = 100_000;

/// Most samples of a B-spline solid along one direction.
pub const MAX_SAMPLES: usize = 1024;
/// Most data points of a B-spline solid (`m0 m1 m2`).
pub const MAX_SAMPLE_POINTS: usize = 4_000_000;

fn build_primitive(name: &str, m: &ModelKeys, min: Vec3, max: Vec3) -> Result<Lattice, SpecError> {
    let err = |key: &str, what: String| SpecError::new("model", key, what);
    let size = (max - min).min();
    let r = m.radius.unwrap_or(0.5 * size);
    let h = m.height.unwrap_or(size);
    if !(r.is_finite() && r > 0.0) {
        return Err(err("radius", format!("{r} must be positive")));
    }
    if !(h.is_finite() && h > 0.0) {
        return Err(err("height", format!("{h} must be positive")));
    }
    let canonical = vclay_lattice::command::canonical_primitive(name).unwrap_or(name);
    Ok(match canonical {
        "box" => {
            let n = m.points.unwrap_or([4; 3]);
            if let Some(a) = (0..3).find(|&a| n[a] < 2 || n[a] > 64) {
                return Err(err(
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
        // Issue 19: the papers' galleries and the tetrahedron with holes (split into convex
        // cells, so that no cell folds), sized by the box.
        "tetrahedron-with-holes" => {
            primitives::tetrahedron_with_holes_split(size, primitives::DEFAULT_SPLIT_HOLE)
        }
        "soccer-player" => gallery::soccer_player(h),
        "cactus" => gallery::cactus(h),
        "spiked-object" => gallery::spiked_object(size / 3.0),
        "holed-object" => gallery::holed_object(size / 9.0),
        other => {
            return Err(err(
                "primitive",
                format!(
                    "unknown primitive \"{other}\"; expected one of {}",
                    vclay_lattice::command::primitive_names()
                ),
            ));
        }
    })
}

// ---------------------------------------------------------------------------------------
// Session file form
// ---------------------------------------------------------------------------------------

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Saved {
    source: SavedSource,
    /// How the data points (and the tools' data-point ids) of `rest` and `state` are
    /// numbered ([`DataNumbering::name`]); absent: `"locality"`, the numbering of every file
    /// written before issue 31's grid numbering and of every solid that does not use it, so
    /// those files are unchanged. Loading moves them into the numbering of this build.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    numbering: Option<String>,
    material: Vec<SavedMaterial>,
    params: SavedParams,
    rest: SavedRest,
    state: SavedState,
    tools: ToolTable,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
enum SavedSource {
    Subdivision {
        lattice: String,
        creases: Vec<usize>,
        corners: Vec<usize>,
        boundary: String,
        levels: usize,
    },
    Bspline {
        knots: [Vec<f64>; 3],
        degrees: [usize; 3],
        weights: Vec<f64>,
        samples: [usize; 3],
    },
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SavedMaterial {
    density: f64,
    damping: f64,
    edge_stiffness: f64,
    virtual_stiffness: f64,
    anisotropy: V3,
}

impl From<&Material> for SavedMaterial {
    fn from(m: &Material) -> Self {
        Self {
            density: m.density,
            damping: m.damping,
            edge_stiffness: m.edge_stiffness,
            virtual_stiffness: m.virtual_stiffness,
            anisotropy: m.anisotropy,
        }
    }
}

impl SavedMaterial {
    fn to_material(&self) -> Material {
        Material {
            density: self.density,
            damping: self.damping,
            edge_stiffness: self.edge_stiffness,
            virtual_stiffness: self.virtual_stiffness,
            anisotropy: self.anisotropy,
        }
    }
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SavedParams {
    integrator: String,
    dt: f64,
    divergence_factor: f64,
    cg_tolerance: f64,
    cg_max_iterations: usize,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SavedRest {
    control_points: Vec<V3>,
    data_points: Vec<V3>,
    physics_data_points: Vec<V3>,
    fixed: Vec<bool>,
    metric_stiffness: Option<f64>,
    energy_scale: f64,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SavedState {
    control_points: Vec<V3>,
    velocities: Vec<V3>,
    data_points: Vec<V3>,
    tools: Vec<Option<SavedTool>>,
    time: f64,
    steps: u64,
    tool_energy_seen: f64,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
enum SavedTool {
    Rope {
        point: usize,
        cursor: V3,
        stiffness: f64,
        length: f64,
    },
    PointForce {
        point: usize,
        force: V3,
    },
    RegionForce {
        points: Vec<usize>,
        force: V3,
        center: V3,
        radius: f64,
        /// Brush profile (absent: constant, equal shares).
        #[serde(
            default,
            skip_serializing_if = "Option::is_none",
            deserialize_with = "known_falloff"
        )]
        falloff: Option<String>,
        /// The profile's weight per point (absent: equal shares).
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        weights: Vec<f64>,
    },
    Gravity {
        g: V3,
    },
    Inflation {
        pressure: f64,
    },
}

impl From<&Tool> for SavedTool {
    fn from(t: &Tool) -> Self {
        match t {
            Tool::Rope {
                point,
                cursor,
                stiffness,
                length,
            } => SavedTool::Rope {
                point: *point,
                cursor: a3(cursor),
                stiffness: *stiffness,
                length: *length,
            },
            Tool::PointForce { point, force } => SavedTool::PointForce {
                point: *point,
                force: a3(force),
            },
            Tool::RegionForce {
                points,
                force,
                center,
                radius,
                falloff,
                weights,
            } => SavedTool::RegionForce {
                points: points.clone(),
                force: a3(force),
                center: a3(center),
                radius: *radius,
                falloff: (*falloff != Falloff::Constant).then(|| falloff.name().to_string()),
                weights: weights.clone(),
            },
            Tool::Gravity { g } => SavedTool::Gravity { g: a3(g) },
            Tool::Inflation { pressure } => SavedTool::Inflation {
                pressure: *pressure,
            },
        }
    }
}

/// A falloff name of a saved region force, checked when the file is read.
fn known_falloff<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<String>, D::Error> {
    let name = Option::<String>::deserialize(d)?;
    match &name {
        Some(n) if Falloff::from_name(n).is_none() => Err(serde::de::Error::custom(format!(
            "unknown falloff \"{n}\"; expected one of {}",
            Falloff::ALL.map(Falloff::name).join(", ")
        ))),
        _ => Ok(name),
    }
}

impl SavedTool {
    fn to_tool(&self) -> Tool {
        match self {
            SavedTool::Rope {
                point,
                cursor,
                stiffness,
                length,
            } => Tool::Rope {
                point: *point,
                cursor: v3(*cursor),
                stiffness: *stiffness,
                length: *length,
            },
            SavedTool::PointForce { point, force } => Tool::PointForce {
                point: *point,
                force: v3(*force),
            },
            SavedTool::RegionForce {
                points,
                force,
                center,
                radius,
                falloff,
                weights,
            } => Tool::RegionForce {
                points: points.clone(),
                force: v3(*force),
                center: v3(*center),
                radius: *radius,
                // Checked when the file is read (`known_falloff`).
                falloff: falloff
                    .as_deref()
                    .and_then(Falloff::from_name)
                    .unwrap_or_default(),
                weights: weights.clone(),
            },
            SavedTool::Gravity { g } => Tool::Gravity { g: v3(*g) },
            SavedTool::Inflation { pressure } => Tool::Inflation {
                pressure: *pressure,
            },
        }
    }
}

impl SolidModel {
    /// [`Edit::Smooth`]: one umbrella step of the rest control points under the brush
    /// (`crate::smooth`); the springs' rest lengths follow (`A p0`, eq 3) and the clay settles
    /// towards the smoothed rest shape as it steps. Undone with the state, rest shape included.
    fn smooth(&mut self, edit: &Edit) -> Result<String, SessionError> {
        let (smoothed, n) = crate::smooth::smoothed_rest(&self.solid, self.control_net(), edit)?;
        self.solid
            .set_rest_control_points(&smoothed)
            .map_err(kernel)?;
        Ok(crate::smooth::message(n))
    }
}
