//! Issue 18: the `dnurbs-triangular` kind (d-nurbs.txt section 4.4; Fig 8 rounding scenarios):
//! scenarios parse and step, the model exports a triangular NURBS file that reads back, session
//! files restore it bit for bit, and bad keys are located.
use crate::common;
use common::example;
use std::path::Path;

use vclay_session::scenario::Scenario;

#[test]
fn edge_rounding_scenario_steps_exports_and_restores() {
    // The whole-triangle rule keeps this debug-mode test fast; the shipped scenario uses the
    // default (subdivided) quadrature.
    let text = example("fig08a_edge_rounding.toml").replace(
        "rounding = \"edge\"",
        "rounding = \"edge\"\nquadrature = \"whole\"\nquadrature_points = 4",
    );
    let mut sc = Scenario::parse(&text, "edge.toml", "edge", Path::new(".")).unwrap();
    for _ in 0..3 {
        sc.session.step().unwrap();
    }
    let dir = tempfile::tempdir().unwrap();
    let model = sc.session.model(None).unwrap();
    assert!(
        model.summary().contains("21 control points"),
        "{}",
        model.summary()
    );
    let out = dir.path().join("edge.json");
    model.export(&out).unwrap();
    let back = vclay_io::triangular::read_triangular(&out).unwrap();
    assert_eq!(back.surface.control_points().len(), 21);
    for (a, b) in back
        .surface
        .control_points()
        .iter()
        .zip(model.control_points())
    {
        assert_eq!(a, &b);
    }
    // Session file: save, load, step both, same state bit for bit.
    let saved = model.save().unwrap();
    let mut loaded =
        vclay_session::models::load(vclay_session::ModelKind::DnurbsTriangular, &saved).unwrap();
    let mut original = model.clone_model();
    original.step().unwrap();
    loaded.step().unwrap();
    assert_eq!(original.control_points(), loaded.control_points());
}

/// Issue 28: `rounding = "sharp-corner"` (the corner's exactly sharp start on its own domain,
/// `RoundingKind::SharpCorner`) builds its 114 control points and steps; its scenario is
/// `fig08b_sharp_corner_rounding.toml`.
#[test]
fn sharp_corner_scenario_builds_and_steps() {
    let text = example("fig08b_sharp_corner_rounding.toml").replace(
        "rounding = \"sharp-corner\"",
        "rounding = \"sharp-corner\"\nquadrature = \"whole\"\nquadrature_points = 4",
    );
    let mut sc = Scenario::parse(&text, "corner.toml", "corner", Path::new(".")).unwrap();
    for _ in 0..2 {
        sc.session.step().unwrap();
    }
    let model = sc.session.model(None).unwrap();
    assert!(
        model.summary().contains("114 control points"),
        "{}",
        model.summary()
    );
}

#[test]
fn bad_keys_are_located() {
    let edge = "rounding = \"edge\"";
    common::refused_variants(
        "fig08a_edge_rounding.toml",
        &[
            (edge, "rounding = \"vertex\"", "rounding"),
            (
                edge,
                "rounding = \"edge\"\nquadrature = \"exact\"",
                "quadrature",
            ),
            (
                "preset = \"Edge rounding\"",
                "preset = \"Edge sanding\"",
                "preset",
            ),
        ],
    );
}
