//! Opening things: the start page's built-in models and `vclay studio FILE`.
//!
//! Every path goes through the session layer: built-in models are small scenarios parsed by
//! [`Scenario::parse`]; a scenario `.toml` is read by [`Scenario::from_file`] (its timeline is
//! scheduled and plays when the simulation runs); a session file (`.session`, or JSON whose
//! `format` is `vclay-session`) by [`vclay_session::file::load`]; an `.ovm` lattice becomes a
//! subdivision solid, a model `.json` a D-NURBS surface, curve or B-spline solid (the first
//! kind its entity fits), a mesh (`.obj`, `.stl`, `.ply`) an FFD lattice around it: each as a
//! one-model scenario with `file`/`mesh` set. Errors are the session layer's located messages,
//! the same text `vclay run` prints.

use std::path::Path;

use vclay_session::Session;
use vclay_session::scenario::Scenario;

/// A built-in model of the start page.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Builtin {
    /// Short name (also the session's file stem).
    pub name: &'static str,
    /// One line for the start page.
    pub title: &'static str,
    /// The scenario text.
    pub scenario: &'static str,
}

/// The start page's models.
pub const BUILTINS: [Builtin; 6] = [
    Builtin {
        name: "cube",
        title: "4^3 subdivision cube (rope, extrude, delete cell)",
        scenario: "[model]\nkind = \"subdivision-solid\"\nprimitive = \"box\"\npoints = [4, 4, 4]\n\
                   level = 2\nboundary = \"sharp\"\n\n[material]\ndensity = 1.0\ndamping = 2.0\n\
                   edge_stiffness = 100.0\nvirtual_stiffness = 50.0\n\n[simulation]\n\
                   integrator = \"symplectic\"\ndt = 0.002\n",
    },
    Builtin {
        name: "egg",
        title: "Swung D-NURBS egg (Egg sculpting material)",
        scenario: "[model]\nkind = \"dnurbs-swung\"\nprimitive = \"sphere\"\n\n[material]\n\
                   preset = \"Egg sculpting\"\n\n[simulation]\ndt = 0.01\n",
    },
    Builtin {
        name: "torus",
        title: "Swung D-NURBS torus (the demo's torus)",
        scenario: "[model]\nkind = \"dnurbs-swung\"\nprimitive = \"torus\"\n\n[simulation]\n\
                   dt = 0.01\n",
    },
    Builtin {
        name: "sheet",
        title: "32 x 32 D-NURBS sheet",
        scenario: "[model]\nkind = \"dnurbs-surface\"\nsize = [32, 32]\ndegree = [3, 3]\n\
                   engine = \"frozen\"\n\n[simulation]\ndt = 0.01\n",
    },
    Builtin {
        name: "bottle",
        title: "FFD bottle (direct manipulation)",
        scenario: "[model]\nkind = \"ffd\"\nprimitive = \"bottle\"\ncontrol = [4, 4, 5]\n\n\
                   [simulation]\ndt = 0.05\n",
    },
    Builtin {
        name: "glass",
        title: "PDE glass (boundary constants, time)",
        scenario: "[model]\nkind = \"pde-surface\"\nbuiltin = \"glass\"\n\n[simulation]\n\
                   dt = 0.05\n",
    },
];

/// Builds the session of a built-in model.
pub fn builtin(b: &Builtin) -> Result<Session, String> {
    Scenario::parse(b.scenario, b.name, b.name, Path::new("."))
        .map(|s| s.session)
        .map_err(|e| e.to_string())
}

/// The built-in named `name`.
pub fn builtin_named(name: &str) -> Option<&'static Builtin> {
    BUILTINS.iter().find(|b| b.name == name)
}

/// A scenario text for one model of `kind` read from `path` through `key`.
fn file_scenario(kind: &str, key: &str, path: &Path, extra: &str) -> String {
    let quoted = toml::Value::String(path.display().to_string()).to_string();
    format!("[model]\nkind = \"{kind}\"\n{key} = {quoted}\n{extra}")
}

fn parse_text(text: &str, path: &Path) -> Result<Session, String> {
    let base = path.parent().unwrap_or(Path::new("."));
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_else(|| "model".into());
    Scenario::parse(text, &path.display().to_string(), &stem, base)
        .map(|s| s.session)
        .map_err(|e| e.to_string())
}

/// Whether `path` holds a session file (by extension, or JSON with the session `format`).
pub fn is_session_file(path: &Path) -> bool {
    match vclay_session::model::extension(path).as_str() {
        "session" => true,
        "json" => std::fs::read_to_string(path)
            .ok()
            .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
            .and_then(|v| v.get("format").and_then(|f| f.as_str()).map(str::to_string))
            .is_some_and(|f| f == vclay_session::file::FORMAT),
        _ => false,
    }
}

/// Opens `path` as a session (see the [module docs](self)); the error is the located message
/// the command line prints.
pub fn open(path: &Path) -> Result<Session, String> {
    if !path.exists() {
        return Err(format!("{}: no such file", path.display()));
    }
    let ext = vclay_session::model::extension(path);
    if is_session_file(path) {
        return vclay_session::file::load(path)
            .map(|(s, _)| s)
            .map_err(|e| e.to_string());
    }
    let abs = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    match ext.as_str() {
        "toml" => Scenario::from_file(path)
            .map(|s| s.session)
            .map_err(|e| e.to_string()),
        "ovm" => parse_text(
            &file_scenario(
                "subdivision-solid",
                "file",
                &abs,
                "level = 2\n\n[simulation]\ndt = 0.002\n",
            ),
            path,
        ),
        "obj" | "stl" | "ply" | "glb" => parse_text(&file_scenario("ffd", "mesh", &abs, ""), path),
        // Model files, CAD exchange files included (their first entity that is a surface,
        // curve or volume becomes the model).
        "json" | "step" | "stp" | "igs" | "iges" => {
            let mut first = None;
            // D-NURBS need a time step (no preset names one); solids have a default.
            for (kind, extra) in [
                ("dnurbs-surface", "\n[simulation]\ndt = 0.01\n"),
                ("dnurbs-curve", "\n[simulation]\ndt = 0.01\n"),
                ("bspline-solid", ""),
            ] {
                match parse_text(&file_scenario(kind, "file", &abs, extra), path) {
                    Ok(s) => return Ok(s),
                    Err(e) => {
                        first.get_or_insert(e);
                    }
                }
            }
            Err(first.unwrap_or_default())
        }
        other => Err(format!(
            "{}: cannot open .{other} files; the studio opens scenarios (.toml), sessions \
             (.session), lattices (.ovm), model files (.json, .step, .stp, .igs, .iges) and \
             meshes (.obj, .stl, .ply, .glb)",
            path.display()
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_opens_and_displays() {
        for b in &BUILTINS {
            let s = builtin(b).unwrap_or_else(|e| panic!("{}: {e}", b.name));
            let m = s.model(None).unwrap();
            let mesh = m.display_mesh().unwrap();
            assert!(!mesh.triangles.is_empty(), "{}: empty mesh", b.name);
            assert_eq!(mesh.normals.len(), mesh.positions.len(), "{}", b.name);
        }
    }

    #[test]
    fn unreadable_files_are_located_errors() {
        let dir = std::env::temp_dir().join(format!("vclay-studio-load-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let missing = dir.join("missing.toml");
        assert!(open(&missing).unwrap_err().contains("missing.toml"));
        let odd = dir.join("x.xyz");
        std::fs::write(&odd, "1").unwrap();
        assert!(open(&odd).unwrap_err().contains("cannot open .xyz"));
        let ovm = dir.join("bad.ovm");
        std::fs::write(&ovm, "not a lattice").unwrap();
        let e = open(&ovm).unwrap_err();
        assert!(e.contains("bad.ovm"), "{e}");
    }

    #[test]
    fn model_files_open_as_dnurbs_models() {
        // A model JSON written by vclay (a sheet), then the CAD files of vclay-io's tests.
        let dir = std::env::temp_dir().join(format!("vclay-studio-json-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let json = dir.join("sheet.json");
        std::fs::write(
            &json,
            r#"{"entities": [{"type": "nurbs-surface", "degree": [1, 2],
                "knots": [[0, 0, 1, 1], [0, 0, 0, 1, 1, 1]],
                "control_points": [[[0, 0, 0], [0, 1, 0.5], [0, 2, 0]],
                                   [[1, 0, 0], [1, 1, 0.5], [1, 2, 0]]],
                "weights": [[1, 2, 1], [1, 2, 1]]}]}"#,
        )
        .unwrap();
        let s = open(&json).unwrap_or_else(|e| panic!("sheet.json: {e}"));
        assert_eq!(
            s.model(None).unwrap().kind(),
            vclay_session::ModelKind::DnurbsSurface
        );
        let cad = Path::new(env!("CARGO_MANIFEST_DIR")).join("../vclay-io/tests/data/cad");
        for f in ["rational_surface.step", "rational_surface.igs"] {
            let s = open(&cad.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
            let m = s.model(None).unwrap();
            assert_eq!(m.kind(), vclay_session::ModelKind::DnurbsSurface, "{f}");
            assert!(!m.display_mesh().unwrap().triangles.is_empty(), "{f}");
        }
    }
}
