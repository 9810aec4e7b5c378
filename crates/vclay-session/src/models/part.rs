//! The `cad-part` kind (issue 30): a CAD part of trimmed faces (a STEP B-rep, or a model JSON
//! with `"shells"`) in which one face is a D-NURBS surface that the designer sculpts, the other
//! faces staying as they are.
//!
//! **What.** The part is the file's entities and trimmed shells ([`vclay_io::trimmed`]). The
//! chosen face's surface becomes a `dnurbs-surface` ([`DnurbsModel`], weights held:
//! `d-nurbs.txt` eq 18 with the control points as the only unknowns, on the frozen-weight
//! engine of footnote 2 unless `engine = "generalized"`, see [`DEFAULT_ENGINE`]): refined
//! exactly first ([`refine_for_sculpting`]: degree at least 3, `refine` control points per
//! direction), so a plane's bilinear patch gets interior control points to move. Every edit of
//! a D-NURBS surface (rope, force, fix, free, ...) acts on it through the session layer's tools.
//! The face's trim loops are its pcurves, in the surface's parameter space: they move with it.
//!
//! **The boundary.** With `boundary = "fixed"` (the default) the control points whose basis
//! functions are not zero on the face's pcurves ([`boundary_control_points`]) are fixed when the
//! model is built, so the face's edges, and with them the closed solid, stay exactly as they
//! were (the part's other faces are never touched). Freeing them (`free`, or
//! `boundary = "free"`) lets the edges move: the edges' 3D curves are then recomputed from the
//! pcurves on the new surface ([`with_face_surface`]) for the display and mesh exports, and
//! the neighbours' sides of those edges no longer meet them. [`PartModel::gaps`] measures this;
//! exporting the part as a B-rep (STEP, IGES, model JSON) while a gap exceeds the tolerance
//! `TRIM_RTOL x size` is refused with an error that names the edge, the neighbouring face
//! and the gap (no file is written; meshes are still written).
//!
//! **Choosing the face.** The face sculpted at the start is `face` (by default the largest);
//! [`Edit::SculptFace`] (a click on another face: [`Model::pick`] names the face the ray meets
//! first) puts the current face's shape into the part and builds the chosen face the same
//! way, with the part's keys; the clock and revision run on, undo restores the whole model.
//!
//! **Limitations.** One face is sculpted at a time. Picks on the sculpted face outside its
//! trimming loops are refused. The display mesh is the whole part re-tessellated
//! ([`vclay_io::trimmed::tessellate_shell`], [`DISPLAY_SAMPLES`]) at each revision, and a pick
//! of another face re-tessellates it too.

use std::path::{Path, PathBuf};

use vclay_core::TriMesh;
use vclay_io::brep::Shell;
use vclay_io::model::{Entity, NamedEntity};
use vclay_io::trimmed::TRIM_RTOL;
use vclay_io::trimmed::sculpt::{
    EdgeGap, boundary_control_points, face_edge_gaps, refine_for_sculpting, with_face_surface,
};
use vclay_spline::{NurbsSurface, ParametricCurve, ParametricSurface};

use super::SpecError;
use super::dnurbs::{self, DnurbsModel};
use crate::command::Edit;
use crate::describe::ToolSpec;
use crate::error::SessionError;
use crate::model::{
    Applied, Element, Energy, Hit, LineRole, LineSet, Model, ModelKind, Param, Ray, Snapshot,
    StepReport, Undo, extension, unsupported_export,
};

/// The densities tried, in order, for the sculpted face's refined surface when `refine` is not
/// given (control points per direction): the first at which at least [`MIN_FREE_SHARE`] of the
/// control points are free with the boundary fixed, else the last. A face whose trims cross
/// many basis supports (a plate's face with a hole) gets the finer ones.
pub const AUTO_REFINE: [usize; 4] = [24, 32, 48, 64];
/// The share of free control points [`AUTO_REFINE`] asks for.
pub const MIN_FREE_SHARE: f64 = 0.5;
/// Time step of a part whose `[simulation]` and material preset give none (the model files').
pub const DEFAULT_DT: f64 = crate::open::MODEL_FILE_DT;
/// Edge spacing `size / DISPLAY_SAMPLES` of the display mesh.
pub const DISPLAY_SAMPLES: usize = 32;
/// A rope or force given by position is refused when its point is on another face and farther
/// than `AIM_RTOL x size` from the sculpted face (the display mesh's chords are within
/// `size / DISPLAY_SAMPLES` of the faces, so this is twice a chord's spacing).
pub const AIM_RTOL: f64 = 2.0 / DISPLAY_SAMPLES as f64;

/// The formats a part exports.
const FORMATS: [&str; 7] = ["step", "igs", "json", "obj", "stl", "ply", "glb"];

/// The typed spec of a `cad-part` ([`super::ModelSpec`]): its `[model]` keys, and the
/// `[material]` and `[simulation]` keys of a `dnurbs-surface`.
pub type PartSpec = super::KindSpec<ModelKeys, dnurbs::MaterialKeys, dnurbs::SimKeys>;

scenario_keys! {
    /// The `[model]` keys of a `cad-part`.
    pub struct ModelKeys {
        /// STEP B-rep or model JSON with `"shells"` (required).
        pub file: Option<PathBuf>,
        /// Shell index (default 0).
        pub shell: Option<usize>,
        /// Face index in the shell (default: the largest face).
        pub face: Option<usize>,
        /// `[nu, nv]`: control points of the refined face (default: chosen by [`AUTO_REFINE`]).
        pub refine: Option<Vec<usize>>,
        /// `"fixed"` (default) or `"free"`.
        pub boundary: Option<String>,
        /// The face's D-NURBS engine: `"frozen"` (default; [`DEFAULT_ENGINE`]) or
        /// `"generalized"` (constraints, quadrature and solver choices).
        pub engine: Option<String>,
    }
}

/// The sculpted face's engine when the part gives none: the frozen-weight engine
/// (`d-nurbs.txt` footnote 2). A part's weights are held anyway, so its matrices are constant
/// and factored once: a step of the cut sphere's 24 x 24 face took 0.32 ms against 8.4 ms on
/// the generalized engine, of the plate's 48 x 48 face 1.6-1.8 ms against 44.5 ms (`vclay run`,
/// docs/performance.md, session 23), and the two engines' control points agree to 1e-10 after
/// 30 steps of a pull. The generalized engine, which reassembles and refactors every step, is
/// kept for constraints (`engine = "generalized"`).
pub const DEFAULT_ENGINE: &str = "frozen";

/// A CAD part with one face sculpted as a D-NURBS surface (see the [module docs](self)).
#[derive(Clone, Debug)]
pub struct PartModel {
    /// The sculpted face's surface.
    face: DnurbsModel,
    /// The part's entities as read (the sculpted face's entity is replaced on export).
    entities: Vec<NamedEntity>,
    /// The part's shells as read.
    shells: Vec<Shell>,
    /// The shell and face sculpted.
    shell: usize,
    face_index: usize,
    /// The entity of the sculpted face's surface.
    entity: usize,
    /// The control points fixed as the face's boundary when built.
    boundary: Vec<usize>,
    /// Diagonal of the part's vertices' bounding box.
    size: f64,
    /// The keys the part was built with (refine, boundary, material, simulation): a face
    /// chosen later ([`Edit::SculptFace`]) is built with the same.
    spec: PartSpec,
    /// Time, steps and revisions of the faces sculpted before this one, so that the part's
    /// clock and revision run on across a change of face.
    before: Offsets,
}

/// Time, steps and revisions spent on faces sculpted before the current one.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
struct Offsets {
    time: f64,
    steps: u64,
    revision: u64,
}

/// The error of a `[model]` key.
fn key_err(key: &str, what: impl std::fmt::Display) -> SpecError {
    SpecError::new("model", key, what)
}

/// A face's area estimated from its loops' pcurves: the parameter-space area inside the outer
/// loop minus the holes (shoelace over 32 samples per pcurve) times `|S_u x S_v|` at the
/// middle of the parameter box.
fn face_area(f: &vclay_io::brep::Face) -> f64 {
    let mut area = 0.0;
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for l in f.loops() {
        let pts = f.loop_polygon(l, 32);
        let n = pts.len();
        let mut a = 0.0;
        for i in 0..n {
            let (p, q) = (pts[i], pts[(i + 1) % n]);
            a += p[0] * q[1] - q[0] * p[1];
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        area += 0.5 * a;
    }
    if !lo[0].is_finite() {
        return 0.0;
    }
    let (u, v) = (0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]));
    let jac = f
        .surface
        .derivatives(u, v, 1)
        .ok()
        .map_or(0.0, |d| d[1][0].cross(&d[0][1]).norm());
    area.abs() * jac
}

impl PartModel {
    /// Whether the parameters `(u, v)` of the sculpted face lie inside its trimming loops
    /// (even-odd rule over the outer loop and the holes, each pcurve sampled at 32 points; the
    /// refined face keeps the original parameters, so the pcurves apply as read). A face
    /// without pcurves (a whole surface) contains every parameter.
    fn inside_trims(&self, [u, v]: [f64; 2]) -> bool {
        let face = &self.shells[self.shell].faces[self.face_index];
        if face.pcurves.is_empty() {
            return true;
        }
        let mut inside = false;
        for l in face.loops() {
            let poly = face.loop_polygon(l, 33);
            let n = poly.len();
            for i in 0..n {
                let (a, b) = (poly[i], poly[(i + 1) % n]);
                if (a[1] > v) != (b[1] > v) {
                    let x = a[0] + (v - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                    if u < x {
                        inside = !inside;
                    }
                }
            }
        }
        inside
    }

    /// Builds a part from a scenario's (or a front end's) keys; relative files resolve against
    /// `base`. Errors name the key.
    pub fn from_keys(spec: &PartSpec, base: &Path) -> Result<Self, SpecError> {
        let m = &spec.model;
        let file = m
            .file
            .as_ref()
            .ok_or_else(|| key_err("file", "missing: a cad-part needs `file`"))?;
        let path = base.join(file);
        let import =
            vclay_io::model::import_model(&path).map_err(|e| key_err("file", e.to_string()))?;
        if import.shells.is_empty() {
            return Err(key_err(
                "file",
                format!(
                    "{} has no trimmed B-rep (STEP faces, or \"shells\" in a model file): open its surfaces as a dnurbs-surface",
                    path.display()
                ),
            ));
        }
        Self::build(spec, import.entities, import.shells, Offsets::default())
    }

    /// Builds the part of `entities` and `shells` with the face that `spec` chooses sculpted.
    fn build(
        spec: &PartSpec,
        entities: Vec<NamedEntity>,
        shells: Vec<Shell>,
        before: Offsets,
    ) -> Result<Self, SpecError> {
        let m = &spec.model;
        let shell = m.shell.unwrap_or(0);
        let sh = shells.get(shell).ok_or_else(|| {
            key_err(
                "shell",
                format!("shell {shell} out of range ({} shells)", shells.len()),
            )
        })?;
        let face_index = match m.face {
            Some(f) if f < sh.faces.len() => f,
            Some(f) => {
                return Err(key_err(
                    "face",
                    format!(
                        "face {f} out of range (shell {shell} has {} faces)",
                        sh.faces.len()
                    ),
                ));
            }
            None => {
                (0..sh.faces.len())
                    .map(|i| (i, face_area(&sh.faces[i])))
                    .fold((0, f64::NEG_INFINITY), |b, x| if x.1 > b.1 { x } else { b })
                    .0
            }
        };
        let face = &sh.faces[face_index];
        let entity = face.entity.ok_or_else(|| {
            key_err(
                "face",
                format!("face {face_index} refers to no surface entity"),
            )
        })?;
        let fixed = super::keyword(
            "model",
            "boundary",
            m.boundary.as_deref(),
            &[("fixed", true), ("free", false)],
        )?
        .unwrap_or(true);
        let densities: Vec<[usize; 2]> = match m.refine.as_deref() {
            None if fixed => AUTO_REFINE.iter().map(|&n| [n, n]).collect(),
            None => vec![[AUTO_REFINE[0]; 2]],
            Some(&[a, b]) => vec![[a, b]],
            Some(_) => return Err(key_err("refine", "expected [nu, nv]")),
        };
        let (mut refined, mut boundary) = (None, Vec::new());
        for d in densities {
            let r = refine_for_sculpting(&face.surface, d).map_err(|e| key_err("refine", e))?;
            boundary = if fixed {
                boundary_control_points(face, &r).map_err(|e| key_err("face", e))?
            } else {
                Vec::new()
            };
            let n = r.control_points().len();
            refined = Some(r);
            if (n - boundary.len()) as f64 >= MIN_FREE_SHARE * n as f64 {
                break;
            }
        }
        let refined = refined.expect("at least one density");
        let [nu, nv] = refined.dims();
        if boundary.len() == nu * nv {
            return Err(key_err(
                "refine",
                format!(
                    "every one of the {nu} x {nv} control points of face {face_index} acts on its edges, so none could move with the boundary fixed: give more (e.g. refine = [{0}, {0}])",
                    2 * nu.max(nv)
                ),
            ));
        }
        let mut simulation = spec.simulation.clone();
        if simulation.dt.is_none() && spec.material.preset.is_none() {
            simulation.dt = Some(DEFAULT_DT);
        }
        let inner = dnurbs::DnurbsSpec {
            model: dnurbs::ModelKeys {
                surface: Some(refined),
                weights: Some("frozen".into()),
                engine: Some(m.engine.clone().unwrap_or_else(|| DEFAULT_ENGINE.into())),
                fix: boundary.clone(),
                ..Default::default()
            },
            material: spec.material.clone(),
            simulation,
        };
        let face_model = DnurbsModel::from_keys(ModelKind::DnurbsSurface, &inner, Path::new(""))?;
        Ok(Self::assemble(
            face_model,
            (entities, shells),
            [shell, face_index, entity],
            boundary,
            spec.clone(),
            before,
        ))
    }

    /// The part from its pieces: the sculpted face's model, the part, where the face is
    /// (`[shell, face index, surface entity]`), its held boundary control points, the keys
    /// it was built with and the offsets of faces sculpted before.
    fn assemble(
        face: DnurbsModel,
        (entities, shells): (Vec<NamedEntity>, Vec<Shell>),
        [shell, face_index, entity]: [usize; 3],
        boundary: Vec<usize>,
        spec: PartSpec,
        before: Offsets,
    ) -> Self {
        let size = part_size(&shells);
        Self {
            face,
            entities,
            shells,
            shell,
            face_index,
            entity,
            boundary,
            size,
            spec,
            before,
        }
    }

    /// Every shell of the part now, meshed crack-free (closed shells closed by index: what
    /// mesh exports write), with each triangle's face numbered across the shells.
    fn crack_free_mesh(&self) -> Result<(TriMesh, Vec<u32>), SessionError> {
        let (_, shells) = self.part()?;
        let mut out = TriMesh::new();
        let mut parts = Vec::new();
        let mut first_face = 0;
        for sh in &shells {
            let (m, faces) = vclay_io::trimmed::tessellate_shell_faces(sh, DISPLAY_SAMPLES)
                .map_err(SessionError::model)?;
            out.append(&m);
            parts.extend(faces.iter().map(|f| first_face + f));
            first_face += sh.faces.len() as u32;
        }
        Ok((out, parts))
    }

    /// The sculpted shell now, meshed, with the face of each triangle
    /// ([`vclay_io::trimmed::tessellate_shell_faces`]).
    fn part_faces(&self) -> Result<(TriMesh, Vec<u32>), SessionError> {
        let (_, shells) = self.part()?;
        vclay_io::trimmed::tessellate_shell_faces(&shells[self.shell], DISPLAY_SAMPLES)
            .map_err(SessionError::model)
    }

    /// The face of the sculpted shell nearest `p`, and how far `p` is from the sculpted face
    /// (over the part's display mesh).
    fn face_near(&self, p: vclay_core::Vec3) -> Result<(usize, f64), SessionError> {
        let (mesh, faces) = self.part_faces()?;
        let nearest = mesh
            .closest_triangle(p)
            .map(|(t, _)| faces[t] as usize)
            .ok_or_else(|| SessionError::model("the part has no faces to choose from"))?;
        let own = mesh
            .triangles
            .iter()
            .zip(&faces)
            .filter(|(_, f)| **f as usize == self.face_index)
            .map(|(t, _)| {
                let c = |k: usize| mesh.positions[t[k] as usize];
                (vclay_core::mesh::closest_on_triangle(p, [c(0), c(1), c(2)]) - p).norm()
            })
            .fold(f64::INFINITY, f64::min);
        Ok((nearest, own))
    }

    /// Refuses a rope or force aimed (by position, not by a surface parameter) at a face that
    /// is not the sculpted one: the D-NURBS tool would take the sculpted face's nearest
    /// point, which may lie across the part.
    fn check_aim(&self, edit: &Edit) -> Result<(), SessionError> {
        let at = match edit {
            Edit::Rope {
                from, param: None, ..
            } => *from,
            Edit::Force {
                near: Some(p),
                param: None,
                ..
            } => *p,
            _ => return Ok(()),
        };
        let (nearest, own) = self.face_near(vclay_core::Vec3::new(at[0], at[1], at[2]))?;
        if nearest != self.face_index && own > AIM_RTOL * self.size {
            return Err(SessionError::model(format!(
                "{} at {at:?} is on face {nearest}, not on the sculpted face {} (it is {own:.3e} away): choose face {nearest} first (`sculpt-face`, the studio's Face tool)",
                edit.action(),
                self.face_index,
            )));
        }
        Ok(())
    }

    /// [`Edit::SculptFace`]: the current face's shape goes into the part, and `face` (or the
    /// face nearest `near`) becomes the sculpted one, built with the part's keys; the clock
    /// runs on. Undone by the whole model as it was.
    fn sculpt_face(
        &mut self,
        face: Option<usize>,
        near: Option<[f64; 3]>,
    ) -> Result<Applied, SessionError> {
        let f = match (face, near) {
            (Some(f), _) => f,
            (None, Some(p)) => self.face_near(vclay_core::Vec3::new(p[0], p[1], p[2]))?.0,
            (None, None) => return Err(SessionError::model("sculpt-face: give `face` or `near`")),
        };
        let old = self.face_index;
        if f == old {
            return Err(SessionError::model(format!(
                "face {f} is already the sculpted face"
            )));
        }
        let (entities, shells) = self.part()?;
        let mut spec = self.spec.clone();
        spec.model.shell = Some(self.shell);
        spec.model.face = Some(f);
        let before = Offsets {
            time: self.time(),
            steps: self.steps(),
            revision: self.revision() + 1,
        };
        let next = Self::build(&spec, entities, shells, before)
            .map_err(|e| SessionError::model(format!("sculpt-face: `{}`: {}", e.key, e.what)))?;
        let prev = std::mem::replace(self, next);
        Ok(Applied {
            message: format!(
                "face {f} is sculpted now ({} boundary control points fixed); face {old} keeps its shape",
                self.boundary.len()
            ),
            undo: Undo::Model(Box::new(prev)),
        })
    }

    /// The sculpted face: `(shell, face)` indices in the part.
    pub fn face(&self) -> (usize, usize) {
        (self.shell, self.face_index)
    }

    /// The control points fixed as the face's boundary when the model was built (empty with
    /// `boundary = "free"`).
    pub fn boundary(&self) -> &[usize] {
        &self.boundary
    }

    /// The tolerance within which the sculpted face's edges still meet their neighbours:
    /// `TRIM_RTOL x size` (the reader's, [`vclay_io::trimmed::validate_shell`]).
    pub fn tolerance(&self) -> f64 {
        TRIM_RTOL * self.size
    }

    /// The sculpted face's surface now.
    pub fn surface(&self) -> Result<NurbsSurface, SessionError> {
        self.face
            .current_surface()?
            .ok_or_else(|| SessionError::model("the sculpted face has no surface"))
    }

    /// How far each edge of the sculpted face moved and how far it is from the neighbouring
    /// face's side ([`EdgeGap`]).
    pub fn gaps(&self) -> Result<Vec<EdgeGap>, SessionError> {
        face_edge_gaps(&self.shells[self.shell], self.face_index, &self.surface()?)
            .map_err(SessionError::model)
    }

    /// The part now: its entities (the face's surface the sculpted one) and shells (the face's
    /// moved edges recomputed, [`with_face_surface`]).
    pub fn part(&self) -> Result<(Vec<NamedEntity>, Vec<Shell>), SessionError> {
        let s = self.surface()?;
        let mut entities = self.entities.clone();
        entities[self.entity].entity = Entity::Surface(s.clone());
        let mut shells = self.shells.clone();
        shells[self.shell] = with_face_surface(
            &self.shells[self.shell],
            self.face_index,
            &s,
            self.tolerance(),
        )
        .map_err(SessionError::model)?;
        Ok((entities, shells))
    }

    /// Rebuilds a part saved by [`Model::save`].
    pub fn load(v: &serde_json::Value) -> Result<Self, SessionError> {
        let field = |k: &str| {
            v.get(k)
                .ok_or_else(|| SessionError::model(format!("saved cad-part: no \"{k}\"")))
        };
        let index = |k: &str| -> Result<usize, SessionError> {
            field(k)?.as_u64().map(|x| x as usize).ok_or_else(|| {
                SessionError::model(format!("saved cad-part: \"{k}\" is not an index"))
            })
        };
        let (entities, shells) = vclay_io::model::trimmed_model_of_value(field("part")?)
            .map_err(|e| SessionError::model(format!("saved cad-part: part: {e}")))?;
        let (shell, face_index) = (index("shell")?, index("face")?);
        let entity = shells
            .get(shell)
            .and_then(|s| s.faces.get(face_index))
            .and_then(|f| f.entity)
            .filter(|&e| e < entities.len())
            .ok_or_else(|| {
                SessionError::model(format!(
                    "saved cad-part: shell {shell} face {face_index} is not a face of the part"
                ))
            })?;
        let boundary: Vec<usize> = serde_json::from_value(field("boundary")?.clone())
            .map_err(|e| SessionError::model(format!("saved cad-part: boundary: {e}")))?;
        let face = DnurbsModel::load(ModelKind::DnurbsSurface, field("dnurbs")?)?;
        // Files written before faces could be changed have neither: the default keys, and no
        // faces sculpted before.
        let optional = |k: &str| v.get(k).filter(|x| !x.is_null()).cloned();
        let spec: PartSpec = match optional("spec") {
            Some(x) => serde_json::from_value(x)
                .map_err(|e| SessionError::model(format!("saved cad-part: spec: {e}")))?,
            None => PartSpec::default(),
        };
        let before: Offsets = match optional("before") {
            Some(x) => serde_json::from_value(x)
                .map_err(|e| SessionError::model(format!("saved cad-part: before: {e}")))?,
            None => Offsets::default(),
        };
        Ok(Self::assemble(
            face,
            (entities, shells),
            [shell, face_index, entity],
            boundary,
            spec,
            before,
        ))
    }

    /// The largest gap over the tolerance, as an error for exporting `path` as a B-rep.
    fn check_closed(&self, path: &Path) -> Result<(), SessionError> {
        let tol = self.tolerance();
        let worst = self
            .gaps()?
            .into_iter()
            .filter(|g| g.gap > tol)
            .max_by(|a, b| a.gap.total_cmp(&b.gap));
        match worst {
            None => Ok(()),
            Some(g) => Err(SessionError::io(
                path,
                format!(
                    "not written: the sculpted face's boundary moved, its edge {} is up to {:.3e} from {} (tolerance {tol:.3e}), so the faces no longer close; fix the face's boundary control points (`boundary = \"fixed\"`, the default) or export a mesh (.obj, .stl, .ply, .glb)",
                    g.edge,
                    g.gap,
                    match g.neighbour {
                        Some(n) => format!("face {n}'s side"),
                        None => "where it was".into(),
                    }
                ),
            )),
        }
    }
}

/// The diagonal of the bounding box of the shells' vertices.
fn part_size(shells: &[Shell]) -> f64 {
    super::generalized::bbox_diagonal(
        shells
            .iter()
            .flat_map(|s| s.vertices.iter().map(|v| &v.point)),
    )
}

impl Model for PartModel {
    fn kind(&self) -> ModelKind {
        ModelKind::CadPart
    }

    /// The kind's tools that the sculpted face takes (its engine's: no `constraint` on the
    /// frozen-weight one), and `sculpt-face`.
    fn tools(&self) -> Vec<ToolSpec> {
        let face: Vec<&str> = Model::tools(&self.face).iter().map(|t| t.action).collect();
        crate::describe::tools_for(ModelKind::CadPart)
            .into_iter()
            .filter(|t| t.action == "sculpt-face" || face.contains(&t.action))
            .collect()
    }

    fn summary(&self) -> String {
        let faces: usize = self.shells.iter().map(|s| s.faces.len()).sum();
        let mut s = format!(
            "{} faces, face {} of shell {} sculpted ({} boundary control points fixed): {}",
            faces,
            self.face_index,
            self.shell,
            self.boundary.len(),
            self.face.summary()
        );
        if let Ok(g) = self.gaps() {
            let worst = g.iter().map(|g| g.gap).fold(0.0, f64::max);
            if worst > self.tolerance() {
                s.push_str(&format!(
                    "; the boundary moved: its edges are up to {worst:.3e} from the neighbouring faces (the part is no longer closed)"
                ));
            }
        }
        s
    }

    crate::model::clock_methods!(self =>
        self.before.time + self.face.time(),
        self.face.dt(),
        self.before.steps + self.face.steps());

    fn step(&mut self) -> Result<StepReport, SessionError> {
        self.face.step()
    }

    fn energy(&self) -> Energy {
        self.face.energy()
    }

    fn size(&self) -> f64 {
        self.size
    }

    fn revision(&self) -> u64 {
        self.before.revision + self.face.revision()
    }

    /// The whole part meshed, shaded with sharp edges between faces that meet at an angle
    /// (over [`vclay_core::mesh::CREASE_ANGLE_DEG`]: a box's edges, a hole's rim) and smooth
    /// within each face however coarse its triangles ([`TriMesh::with_creases_between`]).
    fn display_mesh(&self) -> Result<TriMesh, SessionError> {
        let (mesh, parts) = self.crack_free_mesh()?;
        Ok(mesh.with_creases_between(
            vclay_core::mesh::CREASE_ANGLE_DEG.to_radians(),
            Some(&parts),
        ))
    }

    fn display_lines(&self) -> Vec<LineSet> {
        let mut out = self.face.display_lines();
        // The part's edges, as curves.
        if let Ok((_, shells)) = self.part() {
            let mut edges = LineSet::new(LineRole::Curve);
            for e in shells.iter().flat_map(|s| &s.edges) {
                let d = e.curve.domain();
                let pts: Vec<_> = (0..=16)
                    .filter_map(|k| e.curve.point(d.min + d.length() * k as f64 / 16.0).ok())
                    .collect();
                edges.polyline(&pts);
            }
            out.push(edges);
        }
        out
    }

    /// The sculpted face's pick, with surface points outside its trimming loops refused (a
    /// ray through the hole must not attach a rope to the untrimmed surface there); its hits
    /// name the face as `extra[0]`. A ray that meets another face of the part first hits that
    /// face ([`Element::Face`] with its index in the shell: what [`Edit::SculptFace`] takes).
    fn pick(&self, ray: &Ray, tolerance: f64) -> Option<Hit> {
        let own = self.face.pick(ray, tolerance).filter(|h| match h.element {
            Element::SurfacePoint { param } => self.inside_trims(param),
            _ => true,
        });
        let other = self.part_faces().ok().and_then(|(mesh, faces)| {
            crate::pick::ray_mesh(ray, &mesh).map(|(t, tri, _)| (t, faces[tri] as usize))
        });
        let face_hit = |(t, f): (f64, usize)| Hit {
            distance: t,
            point: ray.origin + ray.direction * t,
            element: Element::Face { index: f },
            extra: [None, None],
        };
        // Coincident hits (the sculpted face in the part's mesh) within this distance along
        // the ray go to the sculpted face.
        let slack = 1e-3 * self.size / ray.direction.norm().max(1e-300);
        match (own, other) {
            (Some(h), Some(o)) if o.1 != self.face_index && o.0 < h.distance - slack => {
                Some(face_hit(o))
            }
            (Some(mut h), _) => {
                h.extra[0] = Some(Element::Face {
                    index: self.face_index,
                });
                Some(h)
            }
            (None, Some(o)) if o.1 != self.face_index => Some(face_hit(o)),
            (None, _) => None,
        }
    }

    fn params(&self) -> Vec<Param> {
        self.face.params()
    }

    fn apply(&mut self, edit: &Edit) -> Result<Applied, SessionError> {
        match edit {
            Edit::SculptFace { face, near } => self.sculpt_face(*face, *near),
            _ => {
                self.check_aim(edit)?;
                self.face.apply(edit)
            }
        }
    }

    fn undo(&mut self, undo: Undo) -> Result<(), SessionError> {
        self.face.undo(undo)
    }

    fn snapshot(&self) -> Snapshot {
        self.face.snapshot()
    }

    fn restore(&mut self, snapshot: &Snapshot) -> Result<(), SessionError> {
        self.face.restore(snapshot)
    }

    fn clone_model(&self) -> Box<dyn Model> {
        Box::new(self.clone())
    }

    fn export(&self, path: &Path) -> Result<(), SessionError> {
        let io = |e: &dyn std::fmt::Display| SessionError::io(path, e);
        let ext = extension(path);
        match ext.as_str() {
            "step" | "igs" | "json" => {
                self.check_closed(path)?;
                let (entities, shells) = self.part()?;
                match ext.as_str() {
                    "step" => vclay_io::step::write_step_trimmed(
                        path,
                        &entities,
                        &shells,
                        vclay_io::step::StepLayout::Brep,
                    ),
                    "igs" => vclay_io::iges::write_iges_trimmed(
                        path,
                        &entities,
                        &shells,
                        vclay_io::iges::IgesLayout::default(),
                    ),
                    _ => vclay_io::model::write_trimmed_model(path, &entities, &shells),
                }
                .map_err(|e| io(&e))
            }
            "obj" | "stl" | "ply" => {
                vclay_io::mesh::write_mesh(path, &self.crack_free_mesh()?.0).map_err(|e| io(&e))
            }
            "glb" => vclay_io::gltf::write_glb(
                path,
                &[vclay_io::gltf::GlbMesh::new(
                    "part",
                    self.crack_free_mesh()?.0,
                )],
            )
            .map_err(|e| io(&e)),
            _ => Err(unsupported_export(self.kind(), path, &FORMATS)),
        }
    }

    fn save(&self) -> Result<serde_json::Value, SessionError> {
        Ok(serde_json::json!({
            "dnurbs": self.face.save()?,
            "part": vclay_io::model::trimmed_to_json(&self.entities, &self.shells),
            "shell": self.shell,
            "face": self.face_index,
            "boundary": self.boundary,
            "spec": self.spec,
            "before": self.before,
        }))
    }

    fn control_points(&self) -> Vec<vclay_core::Vec3> {
        self.face.control_points()
    }

    fn export_formats(&self) -> Vec<&'static str> {
        FORMATS.to_vec()
    }

    fn plastic_flow(&mut self, fraction: f64, yield_distance: f64) -> Result<usize, SessionError> {
        self.face.plastic_flow(fraction, yield_distance)
    }
}
