//! Opening things: the start page's built-in models and `vclay studio FILE`.
//!
//! Every path goes through the session layer: built-in models are typed
//! [`ModelSpec`] values built directly (no scenario text); a file of any kind vclay reads is
//! opened by [`vclay_session::open`], which recognizes it by content (scenario, session, model
//! JSON, PDE spec, triangular model, STEP, IGES, lattice, mesh) or says in one line what it is and
//! which command takes it. Errors are the session layer's located messages, the same text
//! `vclay run` prints.

use std::path::Path;

use vclay_session::models::{self, KindSpec, ModelSpec};
use vclay_session::{Opened, Session};

/// A built-in model of the start page.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Builtin {
    /// Short name (also the session's file stem).
    pub name: &'static str,
    /// One line for the start page.
    pub title: &'static str,
}

/// The start page's models.
pub const BUILTINS: [Builtin; 6] = [
    Builtin {
        name: "cube",
        title: "4^3 subdivision cube (rope, extrude, delete cell)",
    },
    Builtin {
        name: "egg",
        title: "Swung D-NURBS egg (Egg sculpting material)",
    },
    Builtin {
        name: "torus",
        title: "Swung D-NURBS torus (the demo's torus)",
    },
    Builtin {
        name: "sheet",
        title: "32 x 32 D-NURBS sheet",
    },
    Builtin {
        name: "bottle",
        title: "FFD bottle (direct manipulation)",
    },
    Builtin {
        name: "glass",
        title: "PDE glass (boundary constants, time)",
    },
];

/// A swung D-NURBS primitive with a time step (and a material preset).
fn swung(primitive: &str, preset: Option<&str>, dt: f64) -> ModelSpec {
    ModelSpec::DnurbsSwung(KindSpec {
        model: models::dnurbs::ModelKeys {
            primitive: Some(primitive.into()),
            ..Default::default()
        },
        material: models::dnurbs::MaterialKeys {
            preset: preset.map(str::to_string),
            ..Default::default()
        },
        simulation: models::dnurbs::SimKeys {
            dt: Some(dt),
            ..Default::default()
        },
    })
}

impl Builtin {
    /// The model as a typed spec.
    pub fn spec(&self) -> ModelSpec {
        match self.name {
            "cube" => ModelSpec::SubdivisionSolid(KindSpec {
                model: models::solid::ModelKeys {
                    primitive: Some("box".into()),
                    points: Some([4, 4, 4]),
                    level: Some(2),
                    boundary: Some("sharp".into()),
                    ..Default::default()
                },
                material: models::solid::MaterialKeys {
                    density: Some(1.0),
                    damping: Some(2.0),
                    edge_stiffness: Some(100.0),
                    virtual_stiffness: Some(50.0),
                    ..Default::default()
                },
                simulation: models::solid::SimKeys {
                    integrator: Some("symplectic".into()),
                    dt: Some(0.002),
                    ..Default::default()
                },
            }),
            "egg" => swung("sphere", Some("Egg sculpting"), 0.01),
            "torus" => swung("torus", None, 0.01),
            "sheet" => ModelSpec::DnurbsSurface(KindSpec {
                model: models::dnurbs::ModelKeys {
                    size: Some(vec![32, 32]),
                    degree: Some(vec![3, 3]),
                    engine: Some("frozen".into()),
                    ..Default::default()
                },
                simulation: models::dnurbs::SimKeys {
                    dt: Some(0.01),
                    ..Default::default()
                },
                ..Default::default()
            }),
            "bottle" => ModelSpec::Ffd(KindSpec {
                model: models::ffd::ModelKeys {
                    primitive: Some("bottle".into()),
                    control: Some(models::ffd::OneOrThree::Three([4, 4, 5])),
                    ..Default::default()
                },
                simulation: models::ClockKeys { dt: Some(0.05) },
                ..Default::default()
            }),
            _ => ModelSpec::PdeSurface(KindSpec {
                model: models::pde::ModelKeys {
                    builtin: Some("glass".into()),
                    ..Default::default()
                },
                simulation: models::ClockKeys { dt: Some(0.05) },
                ..Default::default()
            }),
        }
    }
}

/// Builds the session of a built-in model.
pub fn builtin(b: &Builtin) -> Result<Session, String> {
    let spec = b.spec();
    let model = spec
        .build(Path::new("."))
        .map_err(|e| format!("{}: {}: {}", b.name, e.key, e.what))?;
    Session::with_model(spec.kind().name(), model).map_err(|e| e.to_string())
}

/// The built-in named `name`.
pub fn builtin_named(name: &str) -> Option<&'static Builtin> {
    BUILTINS.iter().find(|b| b.name == name)
}

/// Whether `path` holds a saved session (recognized by content, [`vclay_session::open::identify`]).
pub fn is_session_file(path: &Path) -> bool {
    matches!(
        vclay_session::open::identify(path),
        Ok(vclay_session::FileKind::Session)
    )
}

/// Opens `path` with [`vclay_session::open`]; the error is the one-line message the command
/// line prints.
pub fn open(path: &Path) -> Result<Opened, String> {
    vclay_session::open(path).map_err(|e| e.to_string())
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
        std::fs::write(&odd, "0 0 0\n1 0 0\n0 1 0\n").unwrap();
        let e = open(&odd).unwrap_err();
        assert!(e.contains("point cloud") && e.contains("vclay fit"), "{e}");
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
        let s = open(&json)
            .unwrap_or_else(|e| panic!("sheet.json: {e}"))
            .session;
        assert_eq!(s.model(None).unwrap().kind().name(), "dnurbs-surface");
        let cad = Path::new(env!("CARGO_MANIFEST_DIR")).join("../vclay-io/tests/data/cad");
        for f in ["rational_surface.step", "rational_surface.igs"] {
            let s = open(&cad.join(f))
                .unwrap_or_else(|e| panic!("{f}: {e}"))
                .session;
            let m = s.model(None).unwrap();
            assert_eq!(m.kind().name(), "dnurbs-surface", "{f}");
            assert!(!m.display_mesh().unwrap().triangles.is_empty(), "{f}");
        }
    }
}
