//! One way in: [`open`] recognizes every file vclay reads, by its content first and its
//! extension only where the content does not decide, and either opens it as a [`Session`] or
//! says in one line what the file is and which command takes it.
//!
//! | file (recognized by) | opens as |
//! | --- | --- |
//! | scenario (TOML with a `[model]` table) | its models and scheduled timeline, with its run length and outputs |
//! | session (JSON whose `format` is `vclay-session`) | the saved session, bit for bit |
//! | model JSON (`entities`), STEP (`ISO-10303-21`), IGES (column 73 `S`) | a part with a closed trimmed shell (a solid) as a `cad-part` whose largest face is sculpted; else the first surface as a `dnurbs-surface` (else the first curve as a `dnurbs-curve`, else the first volume as a `bspline-solid`) |
//! | triangular model JSON (`"type": "triangular-nurbs"`) | a `dnurbs-triangular` |
//! | PDE spec JSON (`patches`, `trial_terms`) | a `pde-surface` |
//! | lattice (`OVM ASCII`, VTK `UnstructuredGrid`) | a level-2 `subdivision-solid` |
//! | mesh (OBJ, PLY with faces, STL, glTF binary) | an `ffd` lattice around it |
//! | point cloud (`x y z` lines, PLY without faces) | not a session: `vclay fit` |
//! | geomdl JSON (`shape`) | not a session: `vclay convert` to a model file first |
//!
//! Every model is built from a typed [`ModelSpec`] (no scenario text is written): the same
//! values a scenario's `[model]` table would give, with the defaults named below
//! ([`MODEL_FILE_DT`], [`LATTICE_DT`], [`LATTICE_LEVEL`]).
//!
//! Limitations: a file whose content and extension disagree (an OBJ mesh named `.txt`) is
//! recognized, but the readers below pick their format by extension, so such a file is refused
//! with a message that says to rename it.

use std::path::{Path, PathBuf};

use crate::error::SessionError;
use crate::file::{self, RunInfo};
use crate::model::extension;
use crate::models::{self, ModelSpec};
use crate::scenario::{DEFAULT_FRAME_EVERY, OutputSpec, Scenario};
use crate::session::Session;

/// Time step of a D-NURBS opened from a model file (no preset names one; a B-spline solid
/// takes the solids' default).
pub const MODEL_FILE_DT: f64 = 0.01;
/// Time step of a subdivision solid opened from a lattice file (the studio's cube's).
pub const LATTICE_DT: f64 = 0.002;
/// Subdivision level of a solid opened from a lattice file.
pub const LATTICE_LEVEL: usize = 2;
/// Bytes read to recognize a file.
const SNIFF_BYTES: usize = 4096;

/// What a file is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileKind {
    /// A scenario (TOML).
    Scenario,
    /// A saved session (JSON).
    Session,
    /// A vclay model file (JSON `entities`).
    ModelJson,
    /// A triangular D-NURBS model file (JSON).
    Triangular,
    /// A PDE surface spec (JSON).
    PdeSpec,
    /// A geomdl document (JSON `shape`).
    Geomdl,
    /// A STEP exchange file.
    Step,
    /// An IGES exchange file.
    Iges,
    /// A lattice (OpenVolumeMesh `.ovm` or VTK `.vtu`).
    Lattice,
    /// A surface mesh (OBJ, PLY, STL, glTF binary).
    Mesh,
    /// A point cloud (`x y z` text, or PLY without faces).
    PointCloud,
}

impl FileKind {
    /// Every kind, in the order [`openable`] and messages list them.
    pub const ALL: [FileKind; 11] = [
        FileKind::Scenario,
        FileKind::Session,
        FileKind::Step,
        FileKind::Iges,
        FileKind::ModelJson,
        FileKind::Triangular,
        FileKind::PdeSpec,
        FileKind::Lattice,
        FileKind::Mesh,
        FileKind::PointCloud,
        FileKind::Geomdl,
    ];

    /// The extensions the readers take for such a file (they choose their format by
    /// extension; a recognized file with another one is refused with these named). A session
    /// and a scenario are recognized by content whatever their name; the first extension is
    /// the one vclay writes.
    pub fn extensions(self) -> &'static [&'static str] {
        match self {
            FileKind::Scenario => &["toml"],
            FileKind::Session => &["session"],
            FileKind::ModelJson | FileKind::Triangular | FileKind::PdeSpec | FileKind::Geomdl => {
                &["json"]
            }
            FileKind::Step => &["step", "stp", "p21"],
            FileKind::Iges => &["igs", "iges"],
            FileKind::Lattice => &["ovm", "vtu"],
            FileKind::Mesh => &["obj", "ply", "stl", "glb"],
            FileKind::PointCloud => &["xyz"],
        }
    }

    /// Whether [`open`] opens such a file as a session (a point cloud and a geomdl document
    /// go to other commands: [`FileKind::commands`]).
    pub fn opens(self) -> bool {
        !matches!(self, FileKind::PointCloud | FileKind::Geomdl)
    }

    /// One phrase for messages ("a PDE surface spec").
    pub fn describe(self) -> &'static str {
        match self {
            FileKind::Scenario => "a vclay scenario",
            FileKind::Session => "a vclay session",
            FileKind::ModelJson => "a vclay model file",
            FileKind::Triangular => "a triangular D-NURBS model file",
            FileKind::PdeSpec => "a PDE surface spec",
            FileKind::Geomdl => "a geomdl JSON document",
            FileKind::Step => "a STEP file",
            FileKind::Iges => "an IGES file",
            FileKind::Lattice => "a volume lattice",
            FileKind::Mesh => "a surface mesh",
            FileKind::PointCloud => "a point cloud",
        }
    }

    /// The commands that take such a file (for messages).
    pub fn commands(self) -> &'static str {
        match self {
            FileKind::Scenario | FileKind::Session => "`vclay run FILE`, `vclay studio FILE`",
            FileKind::ModelJson | FileKind::Step | FileKind::Iges => {
                "`vclay eval`, `vclay convert`, `vclay render`, `vclay studio FILE`"
            }
            FileKind::Triangular => "`vclay studio FILE`, `vclay run FILE`",
            FileKind::PdeSpec => "`vclay pde FILE`, `vclay studio FILE`",
            FileKind::Geomdl => "`vclay convert FILE model.json` (then any command)",
            FileKind::Lattice => "`vclay subdivide`, `vclay studio FILE`",
            FileKind::Mesh => "`vclay ffd`, `vclay clay`, `vclay studio FILE`",
            FileKind::PointCloud => "`vclay fit FILE --out surface.json`",
        }
    }
}

/// What [`open`] opens, in one phrase for front ends (a start page, an Open dialog): every
/// kind that [`FileKind::opens`], with its extensions; kinds with the same extensions share
/// them ("a vclay model file, a triangular D-NURBS model file or a PDE surface spec (.json)").
pub fn openable() -> String {
    list_kinds(FileKind::ALL.iter().copied().filter(|k| k.opens()))
}

/// `kinds` with their extensions, grouped where consecutive kinds share them, joined with
/// commas and a final "or".
fn list_kinds(kinds: impl Iterator<Item = FileKind>) -> String {
    let mut groups: Vec<(Vec<&str>, &[&str])> = Vec::new();
    for k in kinds {
        match groups.last_mut() {
            Some((names, ext)) if *ext == k.extensions() => names.push(k.describe()),
            _ => groups.push((vec![k.describe()], k.extensions())),
        }
    }
    let phrases: Vec<String> = groups
        .iter()
        .map(|(names, ext)| {
            let names = join_or(names.iter().map(|n| n.to_string()).collect());
            format!("{names} (.{})", ext.join(", ."))
        })
        .collect();
    join_or(phrases)
}

/// "a, b or c".
fn join_or(mut items: Vec<String>) -> String {
    match items.pop() {
        Some(last) if !items.is_empty() => format!("{} or {last}", items.join(", ")),
        Some(last) => last,
        None => String::new(),
    }
}

/// A file opened as a session.
#[derive(Debug)]
pub struct Opened {
    /// The session.
    pub session: Session,
    /// What the file was.
    pub kind: FileKind,
    /// The run a scenario or a saved run describes (name, end step, outputs); `None` for a
    /// model file or a session saved without one.
    pub run: Option<RunInfo>,
    /// The name for outputs and saved files (the scenario's `name`, else the file stem).
    pub name: String,
}

impl Opened {
    /// The run information, or a default one: outputs every [`DEFAULT_FRAME_EVERY`] steps,
    /// no run length (end step = the first model's current step).
    pub fn run_info(&self) -> RunInfo {
        self.run.clone().unwrap_or_else(|| RunInfo {
            name: self.name.clone(),
            end_step: self.session.model(None).map_or(0, |m| m.steps()),
            output: OutputSpec {
                every: DEFAULT_FRAME_EVERY,
                ..OutputSpec::default()
            },
        })
    }
}

fn not_a_session(path: &Path, kind: FileKind, why: &str) -> SessionError {
    SessionError::NotASession {
        path: path.display().to_string(),
        what: format!("{}{why}", kind.describe()),
        commands: kind.commands().to_string(),
    }
}

/// Recognizes the file at `path` by its content (see the [module docs](self)).
pub fn identify(path: &Path) -> Result<FileKind, SessionError> {
    use std::io::Read as _;
    let mut f = std::fs::File::open(path).map_err(|e| SessionError::io(path, e))?;
    let mut head = Vec::with_capacity(SNIFF_BYTES);
    f.by_ref()
        .take(SNIFF_BYTES as u64)
        .read_to_end(&mut head)
        .map_err(|e| SessionError::io(path, e))?;
    let len = f.metadata().map_or(0, |m| m.len());
    identify_bytes(path, &head, len)
}

/// [`identify`] on the first bytes `head` of a file of `len` bytes named `path`.
pub fn identify_bytes(path: &Path, head: &[u8], len: u64) -> Result<FileKind, SessionError> {
    let ext = extension(path);
    if head.starts_with(b"glTF") {
        return Ok(FileKind::Mesh);
    }
    // Binary STL: an 80-byte header, a triangle count, 50 bytes a triangle.
    if head.len() >= 84 && !head.starts_with(b"solid") {
        let n = u32::from_le_bytes([head[80], head[81], head[82], head[83]]) as u64;
        if 84 + 50 * n == len {
            return Ok(FileKind::Mesh);
        }
    }
    let text = String::from_utf8_lossy(head);
    let t = text.trim_start_matches('\u{feff}').trim_start();
    if t.starts_with("ISO-10303-21") {
        return Ok(FileKind::Step);
    }
    if t.starts_with("OVM ASCII") || t.starts_with("OVM BINARY") {
        return Ok(FileKind::Lattice);
    }
    if t.starts_with("<?xml") || t.starts_with("<VTKFile") {
        if t.contains("UnstructuredGrid") {
            return Ok(FileKind::Lattice);
        }
        return Err(SessionError::io(
            path,
            "an XML file that is not a VTK unstructured grid (.vtu)",
        ));
    }
    if let Some(ply) = t.strip_prefix("ply") {
        let faces = ply
            .lines()
            .take_while(|l| l.trim() != "end_header")
            .any(|l| l.starts_with("element face") && l.trim() != "element face 0");
        return Ok(if faces {
            FileKind::Mesh
        } else {
            FileKind::PointCloud
        });
    }
    if t.starts_with("solid") && (t.contains("facet") || ext == "stl") {
        return Ok(FileKind::Mesh);
    }
    let first = text.lines().next().unwrap_or("");
    if first.len() >= 73 && first.as_bytes()[72] == b'S' {
        return Ok(FileKind::Iges);
    }
    if t.starts_with('{') {
        return identify_json(path);
    }
    // A JSON list of entities, or a TOML table header.
    if t.starts_with('[')
        && let Ok(kind) = identify_json(path)
    {
        return Ok(kind);
    }
    if looks_like_obj(t) {
        return Ok(FileKind::Mesh);
    }
    if looks_like_xyz(t) {
        return Ok(FileKind::PointCloud);
    }
    if ext == "toml" || looks_like_toml(t) {
        return Ok(FileKind::Scenario);
    }
    // A JSON file by its name that is not JSON (a damaged or truncated save): say so.
    if matches!(ext.as_str(), "session" | "json") {
        return identify_json(path);
    }
    Err(SessionError::io(
        path,
        format!(
            "not a file vclay reads: {}",
            list_kinds(FileKind::ALL.iter().copied())
        ),
    ))
}

fn looks_like_obj(t: &str) -> bool {
    let mut vertices = 0;
    for l in t.lines().map(str::trim).filter(|l| !l.is_empty()) {
        match l.split_whitespace().next().unwrap_or("") {
            "v" => vertices += 1,
            "#" | "vn" | "vt" | "f" | "o" | "g" | "s" | "mtllib" | "usemtl" | "l" => {}
            w if w.starts_with('#') => {}
            _ => return false,
        }
    }
    vertices > 0
}

fn looks_like_xyz(t: &str) -> bool {
    let mut rows = 0;
    // The last line of the sniffed bytes may be cut.
    let lines: Vec<&str> = t.lines().collect();
    for l in lines.iter().take(lines.len().saturating_sub(1).max(1)) {
        let l = l.trim();
        if l.is_empty() || l.starts_with('#') || l.starts_with("//") {
            continue;
        }
        let n = l
            .split(|c: char| c.is_whitespace() || c == ',' || c == ';')
            .filter(|w| !w.is_empty())
            .map(|w| w.parse::<f64>().is_ok())
            .collect::<Vec<_>>();
        if n.len() < 3 || !n.iter().all(|&ok| ok) {
            return false;
        }
        rows += 1;
    }
    rows > 0
}

fn looks_like_toml(t: &str) -> bool {
    t.lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
        .is_some_and(|l| l.starts_with('[') || l.contains(" = "))
}

/// A JSON file's kind from its top-level keys.
fn identify_json(path: &Path) -> Result<FileKind, SessionError> {
    let text = std::fs::read_to_string(path).map_err(|e| SessionError::io(path, e))?;
    let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| {
        let what = if path.extension().is_some_and(|x| x == "session") {
            "a .session file is JSON (docs/formats.md section 10); this one is damaged or \
             not a session"
        } else {
            "invalid JSON"
        };
        SessionError::io(path, format!("line {}: {what}: {e}", e.line().max(1)))
    })?;
    let has = |k: &str| v.get(k).is_some();
    let entity_type = |v: &serde_json::Value| {
        v.get("type")
            .and_then(|t| t.as_str())
            .is_some_and(|t| t.starts_with("nurbs-"))
    };
    if let Some(list) = v.as_array() {
        return if !list.is_empty() && list.iter().all(entity_type) {
            Ok(FileKind::ModelJson)
        } else {
            Err(SessionError::io(
                path,
                "a JSON list that is not a list of model entities",
            ))
        };
    }
    Ok(match v.get("format").and_then(|f| f.as_str()) {
        Some(file::FORMAT) => FileKind::Session,
        Some(other) => {
            return Err(SessionError::io(
                path,
                format!(
                    "JSON of format \"{other}\": not a file vclay reads (a session has \"format\": \"{}\")",
                    file::FORMAT
                ),
            ));
        }
        None if has("entities") || entity_type(&v) => FileKind::ModelJson,
        None if v.get("type").and_then(|t| t.as_str()) == Some("triangular-nurbs") => {
            FileKind::Triangular
        }
        None if has("patches") || has("trial_terms") => FileKind::PdeSpec,
        None if has("shape") => FileKind::Geomdl,
        None => {
            return Err(SessionError::io(
                path,
                "JSON that is not a vclay session (\"format\"), model file (\"entities\"), \
                 triangular model (\"type\"), PDE spec (\"patches\") or geomdl document \
                 (\"shape\")",
            ));
        }
    })
}

/// Opens the file at `path` as a session (see the [module docs](self)); a file that is not a
/// session (a point cloud, a geomdl document) is a [`SessionError::NotASession`] naming the
/// commands that take it.
pub fn open(path: &Path) -> Result<Opened, SessionError> {
    if !path.exists() {
        return Err(SessionError::io(path, "no such file"));
    }
    let kind = identify(path)?;
    let stem = path
        .file_stem()
        .map_or("model".into(), |s| s.to_string_lossy().to_string());
    let abs = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    let with_model = |spec: ModelSpec| -> Result<Opened, SessionError> {
        let session = session_of(&spec, path, &abs)?;
        Ok(Opened {
            session,
            kind,
            run: None,
            name: stem.clone(),
        })
    };
    match kind {
        FileKind::Scenario => {
            let sc = Scenario::from_file(path)?;
            let start = sc.session.model(None)?.steps();
            Ok(Opened {
                run: Some(RunInfo {
                    name: sc.name.clone(),
                    end_step: start + sc.steps,
                    output: sc.output,
                }),
                name: sc.name,
                session: sc.session,
                kind,
            })
        }
        FileKind::Session => {
            let (session, run) = file::load(path)?;
            Ok(Opened {
                name: run.as_ref().map_or(stem.clone(), |r| r.name.clone()),
                session,
                kind,
                run,
            })
        }
        FileKind::ModelJson | FileKind::Step | FileKind::Iges => {
            let allowed = [FileKind::ModelJson, FileKind::Step, FileKind::Iges]
                .iter()
                .flat_map(|k| k.extensions().iter().copied())
                .collect::<Vec<_>>();
            check_extension(path, kind, &allowed)?;
            with_model(model_file_spec(&abs)?)
        }
        FileKind::Triangular => with_model(ModelSpec::DnurbsTriangular(
            models::KindSpec::of_model(models::dnurbs_tri::ModelKeys {
                file: Some(abs.clone()),
                ..Default::default()
            }),
        )),
        FileKind::PdeSpec => with_model(ModelSpec::PdeSurface(models::KindSpec::of_model(
            models::pde::ModelKeys {
                spec: Some(abs.clone()),
                ..Default::default()
            },
        ))),
        FileKind::Lattice => {
            check_extension(path, kind, kind.extensions())?;
            let spec = models::KindSpec::of_model(models::solid::ModelKeys {
                file: Some(abs.clone()),
                level: Some(LATTICE_LEVEL),
                ..Default::default()
            });
            with_model(ModelSpec::SubdivisionSolid(spec.with_simulation(
                models::solid::SimKeys {
                    dt: Some(LATTICE_DT),
                    ..Default::default()
                },
            )))
        }
        FileKind::Mesh => {
            check_extension(path, kind, kind.extensions())?;
            with_model(ModelSpec::Ffd(models::KindSpec::of_model(
                models::ffd::ModelKeys {
                    mesh: Some(abs.clone()),
                    ..Default::default()
                },
            )))
        }
        FileKind::PointCloud => Err(not_a_session(path, kind, "")),
        FileKind::Geomdl => Err(not_a_session(path, kind, "")),
    }
}

/// A one-model session built from `spec` (errors name the file given by the user).
fn session_of(spec: &ModelSpec, path: &Path, abs: &Path) -> Result<Session, SessionError> {
    let base = abs.parent().unwrap_or(Path::new("."));
    let model = spec.build(base).map_err(|e| SessionError::File {
        file: path.display().to_string(),
        line: 0,
        key: e.key.clone(),
        what: e
            .what
            .replace(&abs.display().to_string(), &path.display().to_string()),
    })?;
    Session::with_model(spec.kind().name(), model)
}

/// The readers choose their format by extension: a recognized file with another extension is
/// refused with the extension to use.
fn check_extension(path: &Path, kind: FileKind, allowed: &[&str]) -> Result<(), SessionError> {
    let ext = extension(path);
    if allowed.contains(&ext.as_str()) {
        return Ok(());
    }
    Err(SessionError::io(
        path,
        format!(
            "holds {} but its extension .{ext} is not one of .{}; rename it",
            kind.describe(),
            allowed.join(", .")
        ),
    ))
}

/// The spec of a model file: a `cad-part` when it holds a closed trimmed shell (a solid),
/// else its first surface (else curve, else volume).
fn model_file_spec(abs: &Path) -> Result<ModelSpec, SessionError> {
    let import = vclay_io::model::import_model(abs).map_err(|e| SessionError::io(abs, e))?;
    if let Some(shell) = import.shells.iter().position(|s| s.closed) {
        return Ok(ModelSpec::CadPart(models::KindSpec::of_model(
            models::part::ModelKeys {
                file: Some(PathBuf::from(abs)),
                shell: Some(shell),
                ..Default::default()
            },
        )));
    }
    let entities: Vec<_> = import.entities.into_iter().map(|e| e.entity).collect();
    let first = |dims: usize| entities.iter().position(|e| e.param_dims() == dims);
    let dnurbs = |entity: usize| {
        models::KindSpec::of_model(models::dnurbs::ModelKeys {
            file: Some(PathBuf::from(abs)),
            entity: Some(entity),
            ..Default::default()
        })
        .with_simulation(models::dnurbs::SimKeys {
            dt: Some(MODEL_FILE_DT),
            ..Default::default()
        })
    };
    if let Some(i) = first(2) {
        return Ok(ModelSpec::DnurbsSurface(dnurbs(i)));
    }
    if let Some(i) = first(1) {
        return Ok(ModelSpec::DnurbsCurve(dnurbs(i)));
    }
    if let Some(i) = first(3) {
        return Ok(ModelSpec::BsplineSolid(models::KindSpec::of_model(
            models::solid::ModelKeys {
                file: Some(PathBuf::from(abs)),
                entity: Some(i),
                ..Default::default()
            },
        )));
    }
    Err(SessionError::io(
        abs,
        "the file holds no curve, surface or volume",
    ))
}
