//! The one scenario format: parsing, error locations, a small run with every output, the
//! shipped examples, and a B-spline solid saved by one run and read by the next.

use std::path::Path;

use vclay_session::SessionError;
use vclay_session::scenario::{Scenario, model_kind};

const SMALL: &str = r#"
[model]
kind = "subdivision-solid"
primitive = "box"
points = [2, 2, 2]
level = 1

[material]
damping = 3.0

[[material.cells]]
cells = [0]
edge_stiffness = 150.0

[simulation]
integrator = "implicit"
dt = 0.01
steps = 12

[[timeline]]
action = "rope"
name = "r"
at = 0.0
from = [1.0, 1.0, 1.0]
to = [1.3, 1.0, 1.0]
until = 0.05

[[timeline]]
action = "fix"
at = 0.02
points = [0, 1]

[[timeline]]
action = "plastic-reset"
at = 0.08

[[timeline]]
action = "release"
at = 0.08
name = "r"

[[timeline]]
action = "extrude"
at = 0.1
face = 0

[output]
frames = ["obj", "vtu", "ply", "stl"]
every = 5
final = "final.ovm"
csv = "energy.csv"
"#;

fn parse(text: &str, base: &Path) -> Result<Scenario, SessionError> {
    Scenario::parse(text, "t.toml", "t", base)
}

/// Parses `text` and returns the error's line, key and message (file `t.toml`).
fn error_of(text: &str) -> (usize, String, String) {
    match parse(text, Path::new(".")) {
        Err(SessionError::File {
            file,
            line,
            key,
            what,
        }) => {
            assert_eq!(file, "t.toml");
            (line, key, what)
        }
        Err(e) => panic!("not a located scenario error: {e}"),
        Ok(_) => panic!("accepted a bad scenario"),
    }
}

fn small_with(from: &str, to: &str) -> String {
    assert!(SMALL.contains(from), "{from}");
    SMALL.replacen(from, to, 1)
}

fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

#[test]
fn small_scenario_runs_and_writes_every_output() {
    let dir = tempfile::tempdir().unwrap();
    let mut sc = parse(SMALL, Path::new(".")).unwrap();
    assert_eq!(sc.steps, 12);
    assert_eq!(sc.name, "t");
    let steps = sc.steps;
    let s = vclay_session::run::run(&mut sc.session, steps, dir.path(), &sc.output, &mut |_| {})
        .unwrap();
    assert_eq!(s.steps, 12);
    // Frames at steps 0, 5, 10 and 12, in four formats.
    assert_eq!(s.frames.len(), 16, "{:?}", s.frames);
    for f in [
        "frame_000000.obj",
        "frame_000005.vtu",
        "frame_000010.ply",
        "frame_000012.stl",
    ] {
        assert!(dir.path().join(f).exists(), "{f}");
    }
    let csv = std::fs::read_to_string(dir.path().join("energy.csv")).unwrap();
    assert_eq!(csv.lines().count(), 13);
    assert!(csv.starts_with("step,model,time,kinetic,elastic,tools,total,step_ms,iterations"));
    // Every timeline action ran, in order, and the log says so.
    assert_eq!(s.log.len(), 5, "{:?}", s.log);
    assert!(s.log[0].contains("rope `r` attached"));
    assert!(s.log[1].contains("fixed 2 control points"));
    assert!(s.log[4].contains("extruded control face 0"));
    // The extrusion added a cell: 12 control points.
    let l = vclay_lattice::formats::ovm::read(&dir.path().join("final.ovm")).unwrap();
    assert_eq!(l.num_cells(), 2);
    assert_eq!(l.num_points(), 12);
    // The command log holds what was applied.
    assert_eq!(sc.session.log().len(), 5);
    assert!(sc.session.schedule().is_empty());
}

/// A bad variant of the small scenario: what it has, what replaces it, the error's key if it
/// names one, the text of the line it must point at, words the message must hold.
type ErrorCase = (
    &'static str,
    &'static str,
    Option<&'static str>,
    &'static str,
    &'static [&'static str],
);

#[test]
fn errors_name_line_and_key() {
    // (what the small scenario has, what replaces it, the error's key if it names one, the
    // text of the line it must point at, words the message must hold)
    let cases: [ErrorCase; 9] = [
        // Unknown key (typo) in a timeline entry.
        (
            "points = [0, 1]",
            "pointz = [0, 1]",
            Some("pointz"),
            "pointz = [0, 1]",
            &[],
        ),
        // Wrong type.
        ("dt = 0.01", "dt = \"fast\"", None, "dt = \"fast\"", &[]),
        // Out of range value, checked after parsing.
        ("dt = 0.01", "dt = -0.01", Some("dt"), "dt = -0.01", &[]),
        // Material out of range.
        (
            "edge_stiffness = 150.0",
            "edge_stiffness = -5.0",
            Some("edge_stiffness"),
            "",
            &[],
        ),
        // A cell that does not exist.
        ("cells = [0]", "cells = [7]", None, "cells = [7]", &[]),
        // Time order.
        (
            "until = 0.05",
            "until = -1.0",
            Some("until"),
            "until = -1.0",
            &[],
        ),
        // Unknown action.
        (
            "action = \"fix\"",
            "action = \"glue\"",
            None,
            "\"glue\"",
            &["glue"],
        ),
        // Unknown kind.
        (
            "kind = \"subdivision-solid\"",
            "kind = \"dnurbs-blob\"",
            None,
            "dnurbs-blob",
            &["dnurbs-blob", "pde-surface"],
        ),
        // Level too high.
        ("level = 1", "level = 9", None, "level = 9", &[]),
    ];
    for (from, to, key, at, words) in cases {
        let t = small_with(from, to);
        let (line, k, msg) = error_of(&t);
        if let Some(key) = key {
            assert_eq!(k, key, "{msg}");
        }
        if at.is_empty() {
            assert!(line > 0, "{msg}");
        } else {
            assert_eq!(line, line_of(&t, at), "{msg}");
        }
        for w in words {
            assert!(msg.contains(w), "{w}: {msg}");
        }
    }
}

#[test]
fn kind_is_read_for_dispatch() {
    assert_eq!(model_kind(SMALL).unwrap(), "subdivision-solid");
    assert_eq!(model_kind("[model]\nkin = 1\n"), None);
}

#[test]
fn shipped_scenarios_parse() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/scenarios");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let text = std::fs::read_to_string(&path).unwrap();
            assert!(text.starts_with("# "), "{path:?} needs a header comment");
            let sc =
                Scenario::from_file(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert!(sc.steps > 0);
            n += 1;
        }
    }
    assert!(n >= 8, "found {n} scenarios");
}

const BSPLINE: &str = r#"
[model]
kind = "bspline-solid"
control = [4, 4, 5]
samples = [5, 5, 6]

[simulation]
dt = 0.002
steps = 10

[[timeline]]
action = "rope"
at = 0.0
from = [1.0, 1.0, 1.0]
to = [1.3, 1.2, 1.1]

[output]
final = "final.json"
"#;

#[test]
fn a_bspline_solid_saved_by_one_run_is_the_model_of_the_next() {
    let dir = tempfile::tempdir().unwrap();
    let mut first = parse(BSPLINE, dir.path()).unwrap();
    let initial = first.session.model(None).unwrap().save().unwrap();
    vclay_session::run::run(
        &mut first.session,
        10,
        dir.path(),
        &first.output,
        &mut |_| {},
    )
    .unwrap();
    let saved = match &vclay_io::model::read_model(dir.path().join("final.json")).unwrap()[..] {
        [vclay_io::Entity::Volume(v)] => v.control_points().to_vec(),
        other => panic!("final.json holds {} entities, not one volume", other.len()),
    };
    assert_ne!(initial, first.session.model(None).unwrap().save().unwrap());
    let next = BSPLINE
        .replace("control = [4, 4, 5]\n", "file = \"final.json\"\n")
        .replace("samples = [5, 5, 6]", "samples = [4, 4, 5]");
    let second = parse(&next, dir.path()).unwrap();
    let m = second.session.model(None).unwrap();
    assert!(
        m.summary().starts_with("80 control points") || m.summary().contains("80 data points"),
        "{}",
        m.summary()
    );
    let st: serde_json::Value = m.save().unwrap();
    let cps: Vec<[f64; 3]> = serde_json::from_value(st["state"]["control_points"].clone()).unwrap();
    assert_eq!(cps.len(), saved.len());
    for (a, b) in cps.iter().zip(&saved) {
        assert_eq!(*a, [b.x, b.y, b.z]);
    }
    // Keys that describe a primitive do not go with `file`.
    let t = next.replace(
        "samples = [4, 4, 5]",
        "samples = [4, 4, 5]\ndegree = [2, 2, 2]",
    );
    match parse(&t, dir.path()) {
        Err(SessionError::File { key, line, .. }) => {
            assert_eq!(key, "degree");
            assert_eq!(line, line_of(&t, "degree ="));
        }
        other => panic!("{other:?}"),
    }
    let t = next.replace("final.json\"", "missing.json\"");
    match parse(&t, dir.path()) {
        Err(SessionError::File { key, .. }) => assert_eq!(key, "file"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn sizes_are_checked_before_anything_is_built() {
    // A level-6 solid of the 4^3 cube: about 7 million data cells, refused with the estimate.
    let t = small_with(
        "points = [2, 2, 2]\nlevel = 1",
        "points = [4, 4, 4]\nlevel = 6",
    );
    let (line, key, msg) = error_of(&t);
    assert_eq!(key, "level", "{msg}");
    assert_eq!(line, line_of(&t, "level = 6"));
    assert!(msg.contains("GB"), "{msg}");
    // A B-spline control net of 10^9 points; samples past the bound.
    let b = "[model]\nkind = \"bspline-solid\"\ncontrol = [1000, 1000, 1000]\n";
    let (_, key, _) = error_of(b);
    assert_eq!(key, "control");
    let b = "[model]\nkind = \"bspline-solid\"\ncontrol = [100, 100, 100]\n";
    let (_, key, msg) = error_of(b);
    assert_eq!(key, "control", "{msg}");
    let b = "[model]\nkind = \"bspline-solid\"\nsamples = [9223372036854775807, 6, 6]\n";
    let (_, key, _) = error_of(b);
    assert_eq!(key, "samples");
    // Run length from a tiny time step or a huge duration.
    let t = small_with("steps = 12", "duration = 1e308");
    let (_, key, msg) = error_of(&t);
    assert_eq!(key, "duration", "{msg}");
    let t = small_with("dt = 0.01\nsteps = 12", "dt = 1e-300\nduration = 1.0");
    let (_, key, _) = error_of(&t);
    assert_eq!(key, "duration");
    // Two outputs naming one file.
    let t = small_with("csv = \"energy.csv\"", "csv = \"final.ovm\"");
    let (_, _, msg) = error_of(&t);
    assert!(msg.contains("two outputs"), "{msg}");
    // NaN positions and too many data points are refused where they are written.
    let t = small_with("from = [1.0, 1.0, 1.0]", "from = [nan, 1.0, 1.0]");
    let (line, key, _) = error_of(&t);
    assert_eq!((line, key.as_str()), (line_of(&t, "nan"), "from"));
}
