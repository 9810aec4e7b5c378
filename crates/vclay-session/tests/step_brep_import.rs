//! Issue 20: a scenario's `[model] file` opens a STEP B-rep written by OpenCASCADE, and the
//! elementary surface of its face (here a torus, converted exactly to a rational NURBS) becomes
//! a D-NURBS surface that steps without diverging.
use std::path::Path;

use vclay_session::scenario::Scenario;

#[test]
fn scenario_opens_an_elementary_step_surface() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../vclay-io/tests/data/cad");
    let text = "[model]\nkind = \"dnurbs-surface\"\nfile = \"brep_torus.step\"\n\
                weights = \"dynamic\"\n\n[material]\npreset = \"Hemisphere fitting\"\n\n[simulation]\nsteps = 3\n";
    let mut sc = Scenario::parse(text, "torus.toml", "torus", &data).unwrap();
    for _ in 0..3 {
        sc.session.step().unwrap_or_else(|e| panic!("{e}"));
    }
    let summary = sc.session.model(None).unwrap().summary();
    // The torus: 9 x 9 = 81 control points of the rational quadratic circle in both directions.
    assert!(summary.contains("81 control points"), "{summary}");
}
