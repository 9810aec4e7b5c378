//! Scenario files: parsing, error locations, and a small run with every output.

use std::path::Path;

use vclay_solids::SolidsError;
use vclay_solids::scenario::{Scenario, model_kind};

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

/// Parses `text` and returns the error (file `t.toml`).
fn error_of(text: &str) -> (usize, String) {
    match Scenario::parse(text, "t.toml", Path::new(".")) {
        Err(SolidsError::Scenario {
            file,
            line,
            message,
        }) => {
            assert_eq!(file, "t.toml");
            (line, message)
        }
        Err(e) => panic!("not a located scenario error: {e}"),
        Ok(_) => panic!("accepted a bad scenario"),
    }
}

/// The values of the data array `name` of a `.vtu` text.
fn data_array(xml: &str, name: &str) -> Vec<f64> {
    let at = xml
        .find(&format!("Name=\"{name}\""))
        .unwrap_or_else(|| panic!("no array {name}"));
    let start = at + xml[at..].find('>').unwrap() + 1;
    let end = start + xml[start..].find("</DataArray>").unwrap();
    xml[start..end]
        .split_whitespace()
        .map(|t| t.parse().unwrap())
        .collect()
}

/// Replaces the first occurrence of `from` in SMALL.
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
    let mut sc = Scenario::parse(SMALL, "small.toml", Path::new(".")).unwrap();
    sc.output.dir = dir.path().join("out");
    assert_eq!(sc.steps, 12);
    let mut calls = 0;
    let summary = sc.run(&mut |_| calls += 1).unwrap();
    assert_eq!(summary.steps, 12);
    assert_eq!(calls, 12);
    assert!(summary.final_energy.is_finite());
    assert!(summary.max_step_ms >= summary.mean_step_ms);
    // The extrusion happened: two control cells, 12 control points.
    assert_eq!(summary.stats.control_points, 12);
    let out = dir.path().join("out");
    for f in [
        "frame_000000.obj",
        "frame_000005.vtu",
        "frame_000012.obj",
        "energy.csv",
        "final.ovm",
    ] {
        assert!(
            out.join(f).exists(),
            "{f} missing; wrote {:?}",
            summary.files
        );
    }
    let csv = std::fs::read_to_string(out.join("energy.csv")).unwrap();
    assert_eq!(csv.lines().count(), 13, "{csv}");
    // The surface frames hold the same boundary surface: as many vertices and triangles in
    // the PLY header as in the OBJ, three STL vertices per triangle.
    for step in [0, 5, 10, 12] {
        let read = |ext: &str| std::fs::read_to_string(out.join(format!("frame_{step:06}.{ext}")));
        let obj = read("obj").unwrap();
        let count = |prefix: &str| obj.lines().filter(|l| l.starts_with(prefix)).count();
        let (nv, nf) = (count("v "), count("f "));
        assert!(nv > 0 && nf > 0);
        let ply = read("ply").unwrap();
        assert!(
            ply.contains(&format!("element vertex {nv}\n")),
            "{ply:.200}"
        );
        assert!(ply.contains(&format!("element face {nf}\n")), "{ply:.200}");
        let stl = read("stl").unwrap();
        assert_eq!(stl.matches("facet normal").count(), nf);
        assert_eq!(stl.matches("vertex ").count(), 3 * nf);
        assert!(read("vtu").unwrap().contains("<UnstructuredGrid>"));
    }
    // The VTU frames carry point data: no displacement at the start, the unit cube's mass,
    // motion later; one value (or vector) per point.
    let vtu0 = std::fs::read_to_string(out.join("frame_000000.vtu")).unwrap();
    let points = |xml: &str| -> usize {
        let at = xml.find("NumberOfPoints=\"").unwrap() + 16;
        xml[at..].split('"').next().unwrap().parse().unwrap()
    };
    let n0 = points(&vtu0);
    let disp = data_array(&vtu0, "displacement");
    assert_eq!(disp.len(), 3 * n0);
    assert!(
        disp.iter().all(|x| x.abs() < 1e-12),
        "displacement at step 0"
    );
    let mass = data_array(&vtu0, "mass");
    assert_eq!(mass.len(), n0);
    assert!((mass.iter().sum::<f64>() - 1.0).abs() < 1e-9);
    assert_eq!(data_array(&vtu0, "spring_force").len(), 3 * n0);
    let vtu12 = std::fs::read_to_string(out.join("frame_000012.vtu")).unwrap();
    let n12 = points(&vtu12);
    let vel = data_array(&vtu12, "velocity");
    assert_eq!(vel.len(), 3 * n12);
    assert!(
        vel.iter().any(|x| x.abs() > 1e-6),
        "the rope moved the solid"
    );
    let l = vclay_lattice::formats::ovm::read(&out.join("final.ovm")).unwrap();
    assert_eq!(l.num_cells(), 2);
    assert!(summary.log.iter().any(|l| l.contains("plastic reset")));
}

#[test]
fn errors_name_line_and_key() {
    // Unknown key (typo) in a timeline entry.
    let t = small_with("at = 0.02", "att = 0.02");
    let (line, msg) = error_of(&t);
    assert!(msg.contains("att"), "{msg}");
    assert!(
        line > 0 && line <= line_of(&t, "att = 0.02"),
        "line {line}: {msg}"
    );
    // Wrong type.
    let t = small_with("dt = 0.01", "dt = \"fast\"");
    let (line, msg) = error_of(&t);
    assert_eq!(line, line_of(&t, "dt = \"fast\""), "{msg}");
    // Out of range value, checked after parsing.
    let t = small_with("dt = 0.01", "dt = -0.01");
    let (line, msg) = error_of(&t);
    assert_eq!(line, line_of(&t, "dt = -0.01"), "{msg}");
    assert!(msg.contains("dt"), "{msg}");
    // Material out of range.
    let t = small_with("edge_stiffness = 150.0", "edge_stiffness = -5.0");
    let (line, msg) = error_of(&t);
    assert_eq!(line, line_of(&t, "edge_stiffness = -5.0"), "{msg}");
    assert!(msg.contains("edge_stiffness"), "{msg}");
    // A cell that does not exist.
    let t = small_with("cells = [0]", "cells = [7]");
    let (line, msg) = error_of(&t);
    assert_eq!(line, line_of(&t, "cells = [7]"), "{msg}");
    // A control point that does not exist.
    let t = small_with("points = [0, 1]", "points = [0, 99]");
    let (line, msg) = error_of(&t);
    assert_eq!(line, line_of(&t, "points = [0, 99]"), "{msg}");
    assert!(msg.contains("99"), "{msg}");
    // Time order.
    let t = small_with("until = 0.05", "until = -1.0");
    let (line, msg) = error_of(&t);
    assert_eq!(line, line_of(&t, "until = -1.0"), "{msg}");
    // Unknown action.
    let t = small_with("action = \"fix\"", "action = \"glue\"");
    let (line, msg) = error_of(&t);
    assert!(msg.contains("glue"), "{msg}");
    assert!(line > 0);
    // Unknown kind.
    let t = small_with("kind = \"subdivision-solid\"", "kind = \"dnurbs-blob\"");
    let (line, msg) = error_of(&t);
    assert_eq!(line, line_of(&t, "dnurbs-blob"), "{msg}");
    assert!(msg.contains("dnurbs-blob"), "{msg}");
    // Level too high.
    let t = small_with("level = 1", "level = 9");
    let (line, msg) = error_of(&t);
    assert_eq!(line, line_of(&t, "level = 9"), "{msg}");
    // Key of the other kind.
    let t = small_with("level = 1", "level = 1\nsamples = [4, 4, 4]");
    let (line, msg) = error_of(&t);
    assert_eq!(line, line_of(&t, "samples ="), "{msg}");
    // Syntax error.
    let t = small_with("steps = 12", "steps = = 12");
    let (line, _) = error_of(&t);
    assert_eq!(line, line_of(&t, "steps = = 12"));
    // Frame formats: unknown, and listed twice.
    let t = small_with(
        "frames = [\"obj\", \"vtu\", \"ply\", \"stl\"]",
        "frames = [\"off\"]",
    );
    let (line, msg) = error_of(&t);
    assert_eq!(line, line_of(&t, "frames = "), "{msg}");
    assert!(msg.contains("\"off\"") && msg.contains("\"ply\""), "{msg}");
    let t = small_with(
        "frames = [\"obj\", \"vtu\", \"ply\", \"stl\"]",
        "frames = [\"ply\", \"ply\"]",
    );
    let (line, msg) = error_of(&t);
    assert_eq!(line, line_of(&t, "frames = "), "{msg}");
    assert!(msg.contains("twice"), "{msg}");
    // Final model extension.
    let t = small_with("final = \"final.ovm\"", "final = \"final.obj\"");
    let (line, msg) = error_of(&t);
    assert_eq!(line, line_of(&t, "final.obj"), "{msg}");
}

#[test]
fn kind_is_read_for_dispatch() {
    assert_eq!(model_kind(SMALL, "s").unwrap(), "subdivision-solid");
    let e = model_kind("[model]\nkin = 1\n", "s").unwrap_err();
    assert!(e.to_string().contains("kind"), "{e}");
}

#[test]
fn shipped_scenarios_parse() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/scenarios");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let text = std::fs::read_to_string(&path).unwrap();
            assert!(
                text.starts_with("# Reproduces") || text.starts_with("# "),
                "{path:?} needs a header"
            );
            let sc =
                Scenario::from_file(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert!(sc.steps > 0);
            n += 1;
        }
    }
    assert!(n >= 5, "found {n} scenarios");
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
    let mut first = Scenario::parse(BSPLINE, "first.toml", dir.path()).unwrap();
    first.output.dir = dir.path().to_path_buf();
    let initial = first.solid.control_points().to_vec();
    first.run(&mut |_| {}).unwrap();
    let saved = match &vclay_io::model::read_model(dir.path().join("final.json")).unwrap()[..] {
        [vclay_io::Entity::Volume(v)] => v.control_points().to_vec(),
        other => panic!("final.json holds {} entities, not one volume", other.len()),
    };
    assert!(
        saved.iter().zip(&initial).any(|(a, b)| a != b),
        "the rope moved the solid"
    );
    // The next scenario reads `final.json` (relative to its own folder) and keeps the
    // control points, the knots (5 control points along w) and the sampling it asks for.
    let next = BSPLINE
        .replace("control = [4, 4, 5]\n", "file = \"final.json\"\n")
        .replace("samples = [5, 5, 6]", "samples = [4, 4, 5]");
    let second = Scenario::parse(&next, "next.toml", dir.path()).unwrap();
    assert_eq!(second.solid.control_points(), &saved[..]);
    assert_eq!(second.solid.data_points().len(), 80);
    // Keys that describe a primitive do not go with `file`; a missing entity, a file that
    // does not exist.
    let parse = |text: &str| match Scenario::parse(text, "t.toml", dir.path()) {
        Err(SolidsError::Scenario { line, message, .. }) => (line, message),
        other => panic!("accepted or unlocated: {other:?}"),
    };
    let t = next.replace(
        "samples = [4, 4, 5]",
        "samples = [4, 4, 5]\ndegree = [2, 2, 2]",
    );
    let (line, msg) = parse(&t);
    assert_eq!(line, line_of(&t, "degree ="), "{msg}");
    assert!(msg.contains("file"), "{msg}");
    let t = next.replace("samples = [4, 4, 5]", "samples = [4, 4, 5]\nentity = 3");
    let (line, msg) = parse(&t);
    assert_eq!(line, line_of(&t, "entity ="), "{msg}");
    assert!(msg.contains("no entity 3"), "{msg}");
    let t = next.replace("final.json\"\n", "missing.json\"\n");
    let (line, msg) = parse(&t);
    assert_eq!(line, line_of(&t, "missing.json"), "{msg}");
    // Fewer samples than control points along an axis (5 along w) cannot determine them.
    let t = next.replace("samples = [4, 4, 5]", "samples = [6, 6, 4]");
    let (line, msg) = parse(&t);
    assert_eq!(line, line_of(&t, "samples ="), "{msg}");
    assert!(
        msg.contains("samples[2]") && msg.contains("at least 5"),
        "{msg}"
    );
    // `entity` without `file`.
    let t = BSPLINE.replace("samples = [5, 5, 6]", "samples = [5, 5, 6]\nentity = 0");
    let (line, msg) = parse(&t);
    assert_eq!(line, line_of(&t, "entity ="), "{msg}");
}
