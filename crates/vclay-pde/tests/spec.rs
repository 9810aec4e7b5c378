//! Spec files: errors name the place (file line/column, field path, expression column), and
//! ill-posed specs say what is missing.

use vclay_pde::expr::ExprErrorKind;
use vclay_pde::{PdeError, PdeModel};

const SECTION3: &str = include_str!("../examples/specs/section3.json");

fn with(from: &str, to: &str) -> Result<PdeModel, PdeError> {
    assert!(SECTION3.contains(from), "{from}");
    PdeModel::from_json(&SECTION3.replacen(from, to, 1), "s3.json")
}

#[test]
fn all_example_specs_compile_and_solve() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/specs");
    let mut n = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "json" || e == "toml") {
            let model = PdeModel::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            model
                .solve(0.5)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            n += 1;
        }
    }
    assert!(n >= 8, "found {n} specs");
}

#[test]
fn toml_and_json_specs_agree() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/specs");
    let a = PdeModel::read(format!("{dir}/vase.json")).unwrap();
    let b = PdeModel::read(format!("{dir}/vase.toml")).unwrap();
    assert_eq!(a.patches, b.patches);
    // TOML errors carry line and column too.
    let text = std::fs::read_to_string(format!("{dir}/vase.toml")).unwrap();
    let bad = text.replace("trial_terms = 7", "trial_terms = 7\nbogus = 1");
    match PdeModel::from_toml(&bad, "vase.toml").unwrap_err() {
        PdeError::Spec { place, message } => {
            let want = bad.lines().position(|l| l.starts_with("bogus")).unwrap() + 1;
            assert_eq!(place, format!("vase.toml:{want}:1"), "{message}");
            assert!(message.contains("bogus"), "{message}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn expression_errors_name_field_and_column() {
    let e = with("a + b*sin(v)", "a + b*sni(v)").unwrap_err();
    match &e {
        PdeError::Expression {
            place,
            error,
            pointer,
        } => {
            assert_eq!(place, "patches[0].x.u0");
            assert_eq!(error.column, 7);
            assert!(matches!(&error.kind, ExprErrorKind::UnknownFunction(n) if n == "sni"));
            assert!(pointer.ends_with("      ^"), "{pointer:?}");
        }
        other => panic!("{other:?}"),
    }
    let msg = e.to_string();
    assert!(
        msg.contains("column 7") && msg.contains("unknown function 'sni'"),
        "{msg}"
    );

    let e = with("h0 - h1*v", "h0 - (h1*v").unwrap_err();
    assert!(
        matches!(&e, PdeError::Expression { place, error, .. }
        if place == "patches[0].z.u0" && error.column == 6 && error.kind == ExprErrorKind::UnclosedParen),
        "{e}"
    );
    let e = with("h0 - h1*v", "h0 - h1*v)").unwrap_err();
    assert!(
        matches!(&e, PdeError::Expression { error, .. }
        if error.column == 10 && error.kind == ExprErrorKind::UnopenedParen),
        "{e}"
    );
    // u in a boundary function of v and t.
    let e = with("r*sin(v)", "r*sin(v) + u").unwrap_err();
    assert!(
        matches!(&e, PdeError::Expression { place, error, .. }
        if place == "patches[0].x.u1" && error.column == 12),
        "{e}"
    );
    // Unknown parameter.
    let e = with("rp*sin(v)", "rq*sin(v)").unwrap_err();
    assert!(e.to_string().contains("unknown name 'rq'"), "{e}");
}

#[test]
fn json_errors_name_line_and_column() {
    let e = with("\"trial_terms\": 7", "\"trial_term\": 7").unwrap_err();
    match e {
        PdeError::Spec { place, message } => {
            assert!(place.starts_with("s3.json:"), "{place}");
            let line: usize = place.split(':').nth(1).unwrap().parse().unwrap();
            let want = SECTION3
                .lines()
                .position(|l| l.contains("\"trial_terms\""))
                .unwrap()
                + 1;
            assert_eq!(line, want);
            assert!(message.contains("unknown field `trial_term`"), "{message}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn invalid_values_are_reported() {
    let e = with("\"trial_terms\": 7", "\"trial_terms\": 3").unwrap_err();
    assert!(
        matches!(&e, PdeError::InvalidValue { place, .. } if place.ends_with("trial_terms")),
        "{e}"
    );
    let e = with("\"v_range\": [0, \"2*pi\"]", "\"v_range\": [1, 1]").unwrap_err();
    assert!(
        matches!(&e, PdeError::InvalidValue { place, .. } if place.ends_with("v_range")),
        "{e}"
    );
    let e = with("\"k\": 3", "\"k\": 3, \"sin\": 2").unwrap_err();
    assert!(
        matches!(&e, PdeError::InvalidValue { place, .. } if place == "params.sin"),
        "{e}"
    );
    let e = with(", \"du1\": \"rp*sin(v)\"", "").unwrap_err();
    assert!(e.to_string().contains("both u1 and du1"), "{e}");
}

#[test]
fn collocation_grid_on_the_zeros_of_a_basic_function_is_reported() {
    // sin(v) with collocation columns at v = pi/2 + k pi would be fine; with v range [0, 2 pi]
    // and one column (v = pi) it vanishes at every collocation point.
    let e = with("\"collocation\": [6, 6]", "\"collocation\": [12, 1]")
        .unwrap()
        .solve(0.0)
        .unwrap_err();
    match e {
        PdeError::RankDeficient {
            basic, component, ..
        } => {
            assert_eq!(component, 'x');
            assert_eq!(basic, "sin(v)");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn too_few_rows_along_u_is_reported() {
    // Two distinct u values cannot fix four trial terms per basic function.
    let e = with("\"collocation\": [6, 6]", "\"collocation\": [2, 40]")
        .unwrap()
        .solve(0.0)
        .unwrap_err();
    assert!(matches!(&e, PdeError::RankDeficient { .. }), "{e}");
    assert!(e.to_string().contains("more collocation points"), "{e}");
}

#[test]
fn a_vanishing_basic_function_is_harmless() {
    // t*sin(v) is identically zero at t = 0 (and rho = eta = 0): its constants are free but
    // do not change the surface, so the solve succeeds.
    let model = with("a + b*sin(v)", "a + b*sin(v) + t*sin(2*v)").unwrap();
    let s0 = model.solve(0.0).unwrap();
    assert!(s0.patches[0].stats.residual_rms.is_finite());
    let s1 = model.solve(1.0).unwrap();
    assert!(s1.patches[0].stats.residual_rms.is_finite());
}

#[test]
fn nan_shape_function_is_reported() {
    let e = with("\"b\": 1,", "\"b\": \"sqrt(-1 - u)\",")
        .unwrap()
        .solve(0.0)
        .unwrap_err();
    assert!(matches!(e, PdeError::NonFinite { .. }), "{e}");
    // A constant that folds to NaN is reported when the spec is read (issue 17).
    let e = with("\"b\": 1,", "\"b\": \"sqrt(-1)\",").unwrap_err();
    assert!(
        e.to_string()
            .contains("shape.b: column 1: this constant part evaluates to NaN"),
        "{e}"
    );
}

/// Issue 17: a value of the wrong type gave serde's bare `invalid type: map, expected f64` or
/// `data did not match any variant of untagged enum Value`, without the key.
#[test]
fn wrong_types_name_the_key() {
    for (from, to, key, what) in [
        (
            "\"a\": 4.763",
            "\"a\": {}",
            "params.a: ",
            "invalid type: map, expected f64",
        ),
        (
            "\"rho\": 0",
            "\"rho\": {}",
            "rho: ",
            "a number or an expression string",
        ),
        (
            "\"trial_terms\": 7",
            "\"trial_terms\": {}",
            "trial_terms: ",
            "invalid type: map",
        ),
        (
            "\"collocation\": [6, 6]",
            "\"collocation\": {}",
            "collocation: ",
            "a point count or a grid",
        ),
        (
            "\"u1\": 0,",
            "\"u1\": {},",
            "patches[0].z.u1: ",
            "a number or an expression string",
        ),
    ] {
        match with(from, to).unwrap_err() {
            PdeError::Spec { place, message } => {
                assert!(place.starts_with("s3.json:"), "{place}");
                assert!(message.starts_with(key), "{message}");
                assert!(message.contains(what), "{message}");
                assert!(!message.contains("untagged enum"), "{message}");
            }
            other => panic!("{other:?}"),
        }
    }
    // TOML names the key as well.
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/specs");
    let text = std::fs::read_to_string(format!("{dir}/vase.toml")).unwrap();
    let bad = text.replace("trial_terms = 7", "trial_terms = {}");
    match PdeModel::from_toml(&bad, "vase.toml").unwrap_err() {
        PdeError::Spec { message, .. } => {
            assert!(message.starts_with("trial_terms: "), "{message}")
        }
        other => panic!("{other:?}"),
    }
}
