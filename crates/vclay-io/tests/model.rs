//! The JSON model format: all three entity types, the three top-level forms, exact round trips,
//! and every error path with its location.

use vclay_core::Vec3;
use vclay_io::IoError;
use vclay_io::model::{
    Entity, NamedEntity, parse_model, parse_named_model, read_model, read_named_model, to_json,
    to_json_string, write_model, write_named_model,
};
use vclay_spline::{NurbsCurve, NurbsSurface, NurbsVolume};

const CURVE: &str = r#"{
  "type": "nurbs-curve", "name": "arc", "degree": 2,
  "knots": [0, 0, 0, 1, 1, 1],
  "control_points": [[1, 0, 0], [1, 1, 0], [0, 1, 0]],
  "weights": [1, 0.7071067811865476, 1]
}"#;

const SURFACE: &str = r#"{
  "type": "nurbs-surface", "degree": [1, 2],
  "knots": [[0, 0, 1, 1], [0, 0, 0, 1, 1, 1]],
  "control_points": [
    [[0, 0, 0], [0, 1, 0.5], [0, 2, 0]],
    [[1, 0, 0], [1, 1, 0.5], [1, 2, 0]]
  ],
  "weights": [[1, 2, 1], [1, 2, 1]]
}"#;

const VOLUME: &str = r#"{
  "type": "nurbs-volume", "degree": [1, 1, 1],
  "knots": [[0, 0, 1, 1], [0, 0, 1, 1], [0, 0, 1, 1]],
  "control_points": [
    [[[0, 0, 0], [0, 0, 1]], [[0, 1, 0], [0, 1, 1]]],
    [[[1, 0, 0], [1, 0, 1]], [[1, 1, 0], [1, 1, 1]]]
  ]
}"#;

fn all_three() -> String {
    format!("{{\"entities\": [{CURVE}, {SURFACE}, {VOLUME}]}}")
}

fn err(text: &str) -> String {
    parse_model(text).unwrap_err().to_string()
}

/// Asserts that `text` fails with a message containing every piece.
fn assert_err(text: &str, pieces: &[&str]) {
    let msg = err(text);
    for p in pieces {
        assert!(msg.contains(p), "message {msg:?} lacks {p:?}");
    }
}

#[test]
fn file_with_all_three_entity_types() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("model.json");
    std::fs::write(&path, all_three()).unwrap();
    let named = read_named_model(&path).unwrap();
    assert_eq!(named.len(), 3);
    assert_eq!(named[0].name.as_deref(), Some("arc"));
    assert_eq!(named[1].name, None);
    let dims: Vec<usize> = named.iter().map(|e| e.entity.param_dims()).collect();
    assert_eq!(dims, [1, 2, 3]);
    let types: Vec<&str> = named.iter().map(|e| e.entity.type_name()).collect();
    assert_eq!(types, ["nurbs-curve", "nurbs-surface", "nurbs-volume"]);

    let Entity::Surface(s) = &named[1].entity else {
        panic!("not a surface")
    };
    // Nesting: the first index runs along u.
    assert_eq!(s.dims(), [2, 3]);
    assert_eq!(s.degree(), [1, 2]);
    assert_eq!(s.control_point(1, 2), Vec3::new(1.0, 2.0, 0.0));
    assert_eq!(s.weights()[1], 2.0);
    let Entity::Volume(v) = &named[2].entity else {
        panic!("not a volume")
    };
    assert_eq!(v.control_point(1, 0, 1), Vec3::new(1.0, 0.0, 1.0));
    assert!(
        v.weights().iter().all(|&w| w == 1.0),
        "weights default to 1"
    );

    let plain = read_model(&path).unwrap();
    assert_eq!(plain.len(), 3);
    assert_eq!(plain[2], named[2].entity);
}

#[test]
fn three_top_level_forms_agree() {
    let single = parse_model(SURFACE).unwrap();
    let array = parse_model(&format!("[{SURFACE}]")).unwrap();
    let object = parse_model(&format!("{{\"entities\": [{SURFACE}]}}")).unwrap();
    assert_eq!(single, array);
    assert_eq!(single, object);
}

fn awkward_entities() -> Vec<Entity> {
    let third = 1.0 / 3.0;
    let curve = NurbsCurve::new(
        3,
        vec![0.0, 0.0, 0.0, 0.0, 0.1, third, 1.0, 1.0, 1.0, 1.0],
        (0..6)
            .map(|i| Vec3::new(0.1 * i as f64, 1e-300 * i as f64, -7.123456789012345e12))
            .collect(),
        Some(vec![1.0, 0.3, 2.5, third, 1e-9, 1.0]),
    )
    .unwrap();
    let pts: Vec<Vec<Vec3>> = (0..3)
        .map(|i| {
            (0..4)
                .map(|j| Vec3::new(i as f64 * 0.7, j as f64 / 7.0, (i * j) as f64 * 1e20))
                .collect()
        })
        .collect();
    let surface = NurbsSurface::new(
        [2, 3],
        [
            vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            vec![0.0, 0.0, 0.0, 0.0, 2.0, 2.0, 2.0, 2.0],
        ],
        pts,
        None,
    )
    .unwrap();
    let volume = NurbsVolume::box_lattice(
        [2, 1, 3],
        [3, 2, 4],
        Vec3::new(-1.0, 0.1, 0.2),
        Vec3::new(1.0, 0.3, std::f64::consts::PI),
    )
    .unwrap();
    vec![curve.into(), surface.into(), volume.into()]
}

#[test]
fn round_trip_is_bit_exact() {
    let model = awkward_entities();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.json");
    write_model(&path, &model).unwrap();
    let back = read_model(&path).unwrap();
    assert_eq!(back, model);
    // In memory too, and through the Value.
    assert_eq!(parse_model(&to_json_string(&model)).unwrap(), model);
    assert_eq!(parse_model(&to_json(&model).to_string()).unwrap(), model);
    // Overwriting an existing file works.
    write_model(&path, &model[..1]).unwrap();
    assert_eq!(read_model(&path).unwrap(), model[..1]);
}

#[test]
fn written_file_is_readable_json_with_one_point_per_line() {
    let text = to_json_string(&parse_model(SURFACE).unwrap());
    assert!(text.contains("\"type\": \"nurbs-surface\""), "{text}");
    assert!(text.contains("[0.0, 1.0, 0.5]"), "{text}");
    // Type first, then degree, as in the documentation.
    assert!(text.find("\"type\"").unwrap() < text.find("\"degree\"").unwrap());
    // Unit weights are omitted, others kept.
    let curve = parse_model(VOLUME).unwrap();
    assert!(!to_json_string(&curve).contains("weights"));
    assert!(text.contains("weights"));
}

#[test]
fn names_round_trip() {
    let named = parse_named_model(&all_three()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("named.json");
    write_named_model(&path, &named).unwrap();
    assert_eq!(read_named_model(&path).unwrap(), named);
    let plain: NamedEntity = named[1].entity.clone().into();
    assert_eq!(plain.name, None);
}

#[test]
fn syntax_errors_give_line_and_column() {
    let text = "{\n  \"type\": \"nurbs-curve\",\n  \"degree\": 2,,\n}";
    assert_err(text, &["line 3, column 15", "invalid JSON"]);
    assert_err("", &["line 1", "invalid JSON"]);
    assert_err("[1, 2", &["invalid JSON", "line 1"]);
}

#[test]
fn structural_errors_give_json_path() {
    let bad_point = SURFACE.replace("[0, 1, 0.5]", "\"oops\"");
    assert_err(
        &bad_point,
        &["entities[0].control_points[0][1]: expected an array of 3 numbers, found a string"],
    );
    let two_coords = SURFACE.replace("[1, 2, 0]", "[1, 2]");
    assert_err(
        &two_coords,
        &[
            "entities[0].control_points[1][2]: expected an array of 3 numbers, found an array of 2 elements",
        ],
    );
    let bad_coord = format!("[{VOLUME}, {}]", CURVE.replace("[1, 1, 0]", "[1, true, 0]"));
    assert_err(
        &bad_coord,
        &["entities[1].control_points[1][1]: expected a number, found a boolean"],
    );
    let bad_knots = format!(
        "[{CURVE}, {}]",
        SURFACE.replace("[[0, 0, 1, 1], [0,", "[\"u\", [0,")
    );
    assert_err(
        &bad_knots,
        &["entities[1].knots[0]: expected an array of numbers, found a string"],
    );
    let bad_knot = CURVE.replace("[0, 0, 0, 1, 1, 1]", "[0, 0, null, 1, 1, 1]");
    assert_err(
        &bad_knot,
        &["entities[0].knots[2]: expected a number, found null"],
    );
    let one_knot_vector = SURFACE.replace("[[0, 0, 1, 1], [0, 0, 0, 1, 1, 1]]", "[[0, 0, 1, 1]]");
    assert_err(
        &one_knot_vector,
        &["entities[0].knots: expected an array of 2 knot vectors"],
    );
    let bad_degree = SURFACE.replace("[1, 2]", "2");
    assert_err(
        &bad_degree,
        &["entities[0].degree: expected an array of 2 non-negative integers, found a number (2)"],
    );
    let neg_degree = CURVE.replace("\"degree\": 2", "\"degree\": -1");
    assert_err(
        &neg_degree,
        &["entities[0].degree: expected a non-negative integer"],
    );
    let bad_weight = VOLUME.replace(
        "]\n  ]\n}",
        "]\n  ], \"weights\": [[[1, 1], [1, 1]], [[1, 1], [1, \"x\"]]]\n}",
    );
    assert_err(
        &bad_weight,
        &["entities[0].weights[1][1][1]: expected a number, found a string"],
    );
    let bad_name = CURVE.replace("\"arc\"", "3");
    assert_err(&bad_name, &["entities[0].name: expected a string"]);
}

#[test]
fn missing_unknown_and_mistyped_fields() {
    assert_err(
        &CURVE.replace("\"knots\"", "\"knotz\""),
        &[
            "entities[0]: unknown field \"knotz\" (allowed: type, name, degree, knots, control_points, weights)",
        ],
    );
    assert_err(
        r#"{"type": "nurbs-curve", "degree": 1, "control_points": []}"#,
        &["entities[0]: missing field \"knots\""],
    );
    assert_err(
        r#"[{"degree": 1}]"#,
        &[
            "entities[0]: missing field \"type\"",
            "nurbs-curve",
            "nurbs-volume",
        ],
    );
    assert_err(
        &format!("[{CURVE}, {}]", CURVE.replace("nurbs-curve", "nurbs-blob")),
        &[
            "entities[1].type: unknown entity type \"nurbs-blob\"",
            "\"nurbs-curve\", \"nurbs-surface\", \"nurbs-volume\"",
        ],
    );
    assert_err(
        r#"{"type": 7}"#,
        &["entities[0].type: expected a string, found a number (7)"],
    );
    assert_err(
        "[3]",
        &["entities[0]: expected an entity object, found a number"],
    );
    assert_err(
        r#"{"entities": {}}"#,
        &["entities: expected an array of entities, found an object"],
    );
    assert_err(r#"{"entities": [], "x": 1}"#, &["unknown field \"x\""]);
    assert_err(r#"{"shape": 1}"#, &["top level: expected an entity object"]);
    assert_err("\"curve\"", &["top level", "found a string"]);
    assert!(matches!(parse_model("[]"), Err(IoError::EmptyModel)));
    assert_err(r#"{"entities": []}"#, &["no entities"]);
}

#[test]
fn semantic_errors_name_entity_and_type() {
    // 4 + 3 + 1 = 8 knots expected along u for a 4 x 3 net of degree 3: give 9.
    let text = r#"[{"type": "nurbs-curve", "degree": 1, "knots": [0, 0, 1, 1],
        "control_points": [[0,0,0],[1,0,0]]},
        {"type": "nurbs-surface", "degree": [3, 1],
        "knots": [[0, 0, 0, 0, 0.5, 1, 1, 1, 1], [0, 0, 0.5, 1, 1]],
        "control_points": [[[0,0,0],[0,1,0],[0,2,0]], [[1,0,0],[1,1,0],[1,2,0]],
                           [[2,0,0],[2,1,0],[2,2,0]], [[3,0,0],[3,1,0],[3,2,0]]]}]"#;
    assert_err(
        text,
        &["entity 1 (nurbs-surface): knot vector along u: 9 knots given, expected 8"],
    );
    let decreasing = CURVE.replace("[0, 0, 0, 1, 1, 1]", "[0, 0, 0.5, 0.2, 1, 1]");
    assert_err(
        &decreasing,
        &["entity 0 (nurbs-curve): knot vector along u: knots decrease at index 3"],
    );
    let zero_weight = CURVE.replace("0.7071067811865476", "0");
    assert_err(&zero_weight, &["entity 0 (nurbs-curve): weight [1] is 0"]);
    let ragged = SURFACE.replace(
        "[[1, 0, 0], [1, 1, 0.5], [1, 2, 0]]",
        "[[1, 0, 0], [1, 1, 0.5]]",
    );
    assert_err(
        &ragged,
        &[
            "entity 0 (nurbs-surface):",
            "control_points[1]",
            "found 2, expected 3",
        ],
    );
    let ragged_weights = SURFACE.replace("[[1, 2, 1], [1, 2, 1]]", "[[1, 2, 1], [1, 2]]");
    assert_err(&ragged_weights, &["entity 0 (nurbs-surface):", "weights"]);
    let bad_v = VOLUME.replace(
        "[[0, 0, 1, 1], [0, 0, 1, 1], [0, 0, 1, 1]]",
        "[[0, 0, 1, 1], [0, 0, 1, 1], [0, 1, 1]]",
    );
    assert_err(
        &bad_v,
        &["entity 0 (nurbs-volume): knot vector along w: 3 knots given, expected 4"],
    );
}

#[test]
fn file_errors_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nowhere.json");
    let msg = read_model(&missing).unwrap_err().to_string();
    assert!(msg.contains("nowhere.json"), "{msg}");

    let bad = dir.path().join("bad.json");
    std::fs::write(&bad, "[\n  {\"type\": \"nurbs-curve\"\n]").unwrap();
    let msg = read_model(&bad).unwrap_err().to_string();
    assert!(
        msg.contains("bad.json: line 3, column 1: invalid JSON"),
        "{msg}"
    );

    let shape = dir.path().join("shape.json");
    std::fs::write(&shape, CURVE.replace("\"arc\"", "[]")).unwrap();
    let msg = read_model(&shape).unwrap_err().to_string();
    assert!(msg.contains("shape.json: entities[0].name"), "{msg}");

    // A missing folder is created (issue 17); a folder that is a file is an error naming it.
    let model = parse_model(CURVE).unwrap();
    let target = dir.path().join("no_such_dir").join("out.json");
    write_model(&target, &model).unwrap();
    assert_eq!(read_model(&target).unwrap(), model);
    let target = bad.join("out.json");
    let msg = write_model(&target, &model).unwrap_err().to_string();
    assert!(msg.contains("out.json"), "{msg}");
}

#[test]
fn no_panic_on_odd_but_valid_json() {
    for text in [
        "null",
        "{}",
        "[[]]",
        r#"{"type": "nurbs-surface", "degree": [1, 1], "knots": [[], []], "control_points": []}"#,
        r#"{"type": "nurbs-surface", "degree": [1, 1], "knots": [[0,0,1,1], [0,0,1,1]], "control_points": [[], []]}"#,
        r#"{"type": "nurbs-volume", "degree": [1, 1, 1], "knots": [[], [], []], "control_points": [[[]]]}"#,
        r#"{"type": "nurbs-curve", "degree": 1e30, "knots": [], "control_points": []}"#,
        r#"{"type": "nurbs-curve", "degree": 99, "knots": [0, 1], "control_points": [[0,0,0]]}"#,
        r#"{"type": "nurbs-curve", "degree": 1, "knots": [0, 0, 1, 1], "control_points": [[0,0,0],[1,1,1e999]]}"#,
    ] {
        assert!(parse_model(text).is_err(), "{text}");
    }
}

/// Issue 17: `"degree": 2, "degree": 3` read as degree 3 (serde_json keeps the last key).
#[test]
fn duplicate_keys_are_errors_naming_key_and_place() {
    let dup = CURVE.replace("\"degree\": 2,", "\"degree\": 2, \"degree\": 3,");
    let e = parse_model(&dup).unwrap_err();
    assert!(
        matches!(&e, IoError::DuplicateKey { key, path, line: 2, .. } if key == "degree" && path == "top level"),
        "{e:?}"
    );
    assert_err(
        &dup,
        &[
            "line 2, column",
            "duplicate key \"degree\" in the object at top level",
        ],
    );
    // Deeper: the path of the object that holds the key twice.
    let text = format!(
        "{{\"entities\": [{CURVE}, {}]}}",
        SURFACE.replace("\"type\"", "\"knots\": [], \"type\"")
    );
    assert_err(
        &text,
        &["duplicate key \"knots\" in the object at entities[1]"],
    );
    // In every reader that goes through the JSON parser: geomdl and parameter lists too.
    let geomdl = r#"{"shape": {"type": "curve", "type": "surface", "data": []}}"#;
    let msg = vclay_io::geomdl::parse_geomdl(geomdl)
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("duplicate key \"type\" in the object at shape"),
        "{msg}"
    );
    // Equal keys in different objects are fine.
    assert!(parse_model(&all_three()).is_ok());
}

/// Issue 17: a megabyte-long key or type was quoted whole in the message.
#[test]
fn long_tokens_are_quoted_cut() {
    let long = "x".repeat(100_000);
    for text in [
        CURVE.replace("\"name\"", &format!("\"{long}\"")),
        CURVE.replace("\"nurbs-curve\"", &format!("\"{long}\"")),
        format!("{{\"entities\": [{CURVE}], \"{long}\": 1}}"),
        CURVE.replace(
            "\"degree\": 2,",
            &format!("\"{long}\": 1, \"{long}\": 2, \"degree\": 2,"),
        ),
    ] {
        let msg = err(&text);
        assert!(msg.len() < 400, "{} characters: {}", msg.len(), &msg[..400]);
        assert!(msg.contains("...\" (100000 characters)"), "{msg}");
    }
    // Short tokens are quoted whole, with control characters escaped.
    let msg = err(&CURVE.replace("\"name\"", "\"na\\nme\""));
    assert!(msg.contains("unknown field \"na\\nme\""), "{msg}");
    let msg = err(&CURVE.replace("\"name\"", "\"it's \\\"x\\\"\""));
    assert!(msg.contains(r#"unknown field "it's \"x\"""#), "{msg}");
}

/// Issue 17: `m.json: entity 0 (nurbs-curve): weight [1] is 0 ...` was printed three times by
/// callers that print an error's causes after it. Each message holds its causes' text once, and
/// the text of no clause repeats.
#[test]
fn errors_say_their_message_once() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        CURVE.replace("0.7071067811865476", "0"),
        CURVE.replace("[0, 0, 0, 1, 1, 1]", "[0, 0, 1, 1]"),
        CURVE.replace("\"degree\": 2,", "\"degree\": 2, \"degree\": 2,"),
        CURVE.replace("2,", "{},"),
        "[1, 2".to_string(),
    ];
    for (n, text) in cases.iter().enumerate() {
        let path = dir.path().join(format!("m{n}.json"));
        std::fs::write(&path, text).unwrap();
        let e = read_model(&path).unwrap_err();
        let msg = e.to_string();
        assert_eq!(msg.matches(&format!("m{n}.json")).count(), 1, "{msg}");
        let mut source = std::error::Error::source(&e);
        while let Some(s) = source {
            let inner = s.to_string();
            assert!(
                msg.matches(&inner).count() <= 1,
                "{inner:?} repeats in {msg:?}"
            );
            source = s.source();
        }
        let clauses: Vec<&str> = msg.split(": ").collect();
        for (i, c) in clauses.iter().enumerate() {
            assert!(
                !clauses[i + 1..].contains(c),
                "clause {c:?} repeats in {msg:?}"
            );
        }
    }
}

/// Issue 17: a value of the wrong type names its key (the reader never shows serde's bare
/// `invalid type: map, expected f64`).
#[test]
fn wrong_types_name_the_key() {
    for (text, piece) in [
        (
            CURVE.replace("\"degree\": 2", "\"degree\": {}"),
            "entities[0].degree: expected a non-negative integer, found an object",
        ),
        (
            CURVE.replace("[1, 0, 0]", "[1, {}, 0]"),
            "entities[0].control_points[0][1]: expected a number, found an object",
        ),
        (
            CURVE.replace("[1, 0.7071067811865476, 1]", "{}"),
            "entities[0].weights: expected an array of numbers, found an object",
        ),
        (
            CURVE.replace("\"arc\"", "{}"),
            "entities[0].name: expected a string, found an object",
        ),
    ] {
        let msg = err(&text);
        assert!(msg.contains(piece), "{msg}");
        assert!(!msg.contains("invalid type"), "{msg}");
    }
}
