//! Issue 22 through the session layer: the Fourier-series and pseudospectral solvers
//! (`dynamic-pde-surfaces.txt` eq 19-23), the aircraft of Fig 9 and the constants of Figs 5-6
//! (`docs/pde-figures.md`) driven by `pde-set`, with exact undo, redo and reload.

use std::path::Path;

use crate::common;
use common::{positions, saved_text as saved};
use vclay_core::Vec3;
use vclay_session::{Command, Edit, Model, ModelKind, Session};

fn build(model: &str, base: &Path) -> Box<dyn Model> {
    common::try_build(ModelKind::PdeSurface, model, None, Some("dt = 0.25"), base)
        .unwrap_or_else(|e| panic!("builds: {e:?}"))
}

/// A session of one PDE model `name` whose spec is `spec` (written to a file in `dir`),
/// sampled on a `grid`.
fn spec_session(dir: &Path, name: &str, spec: &str, grid: [usize; 2]) -> Session {
    let file = format!("{name}.json");
    std::fs::write(dir.join(&file), spec).unwrap();
    let keys =
        format!("kind = \"pde-surface\"\nname = \"{name}\"\nspec = \"{file}\"\ngrid = {grid:?}");
    Session::with_model(name, build(&keys, dir)).unwrap()
}

fn set(s: &mut Session, name: &str, value: f64) {
    s.apply(Command::new(Edit::PdeSet {
        name: name.into(),
        value,
    }))
    .unwrap_or_else(|e| panic!("pde-set {name}: {e}"));
}

/// `pde-set name value` through [`common::round_trip`], which must move the surface; the
/// display mesh before and after.
fn round_trip(s: &mut Session, name: &str, value: f64) -> (Vec<Vec3>, Vec<Vec3>) {
    let edit = Edit::PdeSet {
        name: name.into(),
        value,
    };
    let (before, after) = common::round_trip(s, edit);
    assert_ne!(before.1, after.1, "{name} = {value} changed nothing");
    (before.1, after.1)
}

fn workspace() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
}

#[test]
fn spectral_solvers_drive_undo_and_reload() {
    let dir = tempfile::tempdir().unwrap();
    let text = vclay_pde::builtin::SECTION3.replacen(
        "\"trial_terms\": 7,",
        "\"trial_terms\": 7, \"solver\": \"pseudospectral\", \"fourier_terms\": 5,",
        1,
    );
    assert!(text.contains("pseudospectral"));
    let mut s = spec_session(dir.path(), "s", &text, [8, 16]);
    round_trip(&mut s, "e", 0.05);
    // The saved model keeps the solver and reloads bit for bit.
    let text = saved(&s);
    assert!(text.contains("pseudospectral"), "{text}");
    common::reloaded(&s, "s");
}

#[test]
fn aircraft_flaps_with_time_and_constants() {
    let m = build(
        "kind = \"pde-surface\"\nname = \"a\"\nspec = \"examples/pde/aircraft.json\"\ngrid = [6, 24]",
        workspace(),
    );
    let mut s = Session::with_model("a", m).unwrap();
    let top = |s: &Session| positions(s).iter().map(|p| p.z).fold(f64::MIN, f64::max);
    let tip = |s: &Session| {
        positions(s)
            .iter()
            .filter(|p| p.y > 6.9)
            .map(|p| p.z)
            .fold(f64::MIN, f64::max)
    };
    assert!(tip(&s).abs() < 1e-12, "wing tip at z = 0 at t = 0");
    s.run(4).unwrap();
    assert!((s.model(None).unwrap().time() - 1.0).abs() < 1e-12);
    assert!(
        (tip(&s) - 0.8).abs() < 1e-9,
        "flap * t at t = 1: {}",
        tip(&s)
    );
    round_trip(&mut s, "flap", 1.5);
    assert!((tip(&s) - 1.5).abs() < 1e-9);
    let fin = top(&s);
    round_trip(&mut s, "fin", 3.0);
    assert!(top(&s) > fin + 0.5, "a taller fin");
}

#[test]
fn figure_5_and_6_constants_are_sliders() {
    // d0 is a named constant of fig5a; rho and eta are not, unless a spec names them (here as
    // parameters "dens" and "damp"). More damping makes the vase more convex (docs/pde-figures.md).
    let dir = tempfile::tempdir().unwrap();
    let text = vclay_pde::builtin::FIG5A
        .replacen("\"rho\": 1,", "\"rho\": \"dens\",", 1)
        .replacen("\"eta\": 1,", "\"eta\": \"damp\",", 1)
        .replacen("\"d0\": -1.3", "\"d0\": -1.3, \"dens\": 1, \"damp\": 1", 1);
    assert!(text.contains("\"damp\": 1"), "{text}");
    let mut s = spec_session(dir.path(), "v", &text, [9, 8]);
    set(&mut s, "t", 0.5);
    // Radius of the middle row (u = 0.5 is the fifth of nine rows).
    let mid = |p: &[Vec3]| p[4 * 8..5 * 8].iter().map(|q| q.x.hypot(q.y)).sum::<f64>() / 8.0;
    let (b, a) = round_trip(&mut s, "damp", 9.0);
    assert!(mid(&a) > mid(&b), "damping: more convex");
    let (b, a) = round_trip(&mut s, "d0", -9.0);
    assert!(mid(&a) < mid(&b), "larger |d0|: more concave");
}
