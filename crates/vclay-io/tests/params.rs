//! Parameter lists for `vclay eval`: arities 1 to 3, bare numbers for curves, and errors that
//! name the tuple.

use vclay_io::params::{parse_params, read_params};

fn err(text: &str, dims: usize) -> String {
    parse_params(text, dims).unwrap_err().to_string()
}

#[test]
fn tuples_of_each_arity() {
    assert_eq!(
        parse_params("[[0], [0.5], [1]]", 1).unwrap(),
        [[0.0], [0.5], [1.0]]
    );
    assert_eq!(
        parse_params("[[0, 1], [0.25, 0.75]]", 2).unwrap(),
        [[0.0, 1.0], [0.25, 0.75]]
    );
    assert_eq!(
        parse_params("[[0.1, 0.2, 0.3]]", 3).unwrap(),
        [[0.1, 0.2, 0.3]]
    );
    assert!(parse_params("[]", 2).unwrap().is_empty());
}

#[test]
fn bare_numbers_for_curves() {
    assert_eq!(
        parse_params("[0, [0.5], 1e-3]", 1).unwrap(),
        [[0.0], [0.5], [1e-3]]
    );
    assert_eq!(parse_params("0.25", 1).unwrap(), [[0.25]]);
    let msg = err("0.25", 2);
    assert!(
        msg.contains("parameters: expected an array of parameter tuples [u, v], found a number"),
        "{msg}"
    );
    let msg = err("[[0.1, 0.2], 0.3]", 2);
    assert!(
        msg.contains("parameter tuple 1: expected 2 numbers [u, v], found a number"),
        "{msg}"
    );
}

#[test]
fn errors_name_the_tuple() {
    let msg = err("[[0.1, 0.2], [0.3, 0.4], [0.5]]", 2);
    assert!(
        msg.contains("parameter tuple 2: expected 2 numbers [u, v], found an array of 1 element"),
        "{msg}"
    );
    let msg = err("[[0.1, 0.2, 0.3], [0.1, 0.2, 0.3, 0.4]]", 3);
    assert!(
        msg.contains("parameter tuple 1: expected 3 numbers [u, v, w]"),
        "{msg}"
    );
    let msg = err("[[0.1, \"x\"]]", 2);
    assert!(
        msg.contains("parameter tuple 0:") && msg.contains("found a string"),
        "{msg}"
    );
    let msg = err("[[0.1, 0.2]]", 1);
    assert!(
        msg.contains("parameter tuple 0: expected 1 number [u]"),
        "{msg}"
    );
    let msg = err("{\"u\": 1}", 1);
    assert!(msg.contains("parameters: expected an array"), "{msg}");
    let msg = err("[[0.1], [null]]", 1);
    assert!(
        msg.contains("parameter tuple 1:") && msg.contains("null"),
        "{msg}"
    );
}

#[test]
fn syntax_errors_and_bad_dims() {
    let msg = err("[\n[0.1, 0.2],\n[0.3 0.4]\n]", 2);
    assert!(msg.contains("line 3, column 6: invalid JSON"), "{msg}");
    // An overflowing literal is a JSON error, not an infinity.
    assert!(parse_params("[1e400]", 1).is_err());
    let msg = err("[]", 4);
    assert!(msg.contains("only 1, 2 or 3"), "{msg}");
    assert!(parse_params("[]", 0).is_err());
}

#[test]
fn read_params_names_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("uv.json");
    std::fs::write(&path, "[[0.5, 0.5], [0.5]]").unwrap();
    let msg = read_params(&path, 2).unwrap_err().to_string();
    assert!(msg.contains("uv.json: parameter tuple 1"), "{msg}");
    std::fs::write(&path, "[[0.5, 0.5]]").unwrap();
    assert_eq!(read_params(&path, 2).unwrap(), [[0.5, 0.5]]);
    let msg = read_params(dir.path().join("none.json"), 2)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("none.json"), "{msg}");
}
