//! Plastic flow through the session layer (`Session::set_plasticity`, docs/sculpting.md): the
//! rest shape follows a pull, undoing the pull puts the rest shape back, session files keep the
//! setting and continue bit for bit, and kinds without a rest shape refuse it.
use crate::common;
use common::assert_same;

use vclay_session::{Command, Edit, Plasticity, Session, file};

/// [`common::cube_and_sheet`] (3 points) and an FFD `box`, 10 steps.
fn models() -> String {
    common::cube_and_sheet(3)
        + r#"
[[model]]
name = "box"
kind = "ffd"
primitive = "bottle"
control = [4, 4, 5]

[simulation]
steps = 10
"#
}

fn session() -> Session {
    common::scenario(&models())
}

fn rope(model: &str, from: [f64; 3], to: [f64; 3]) -> Command {
    let edit: Edit = serde_json::from_value(serde_json::json!({
        "action": "rope", "name": "r", "from": from, "to": to, "stiffness": 200.0
    }))
    .unwrap();
    Command::to(model, edit)
}

fn rest(s: &Session, model: &str) -> serde_json::Value {
    let v = file::to_value(s, None).unwrap();
    let m = v["models"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["name"] == model)
        .unwrap()
        .clone();
    match m["state"].get("rest") {
        Some(r) => r.clone(),
        None => m["state"].clone(),
    }
}

#[test]
fn the_rest_shape_follows_a_pull_and_undo_puts_it_back() {
    for (model, from, to) in [
        ("cube", [1.0, 1.0, 1.0], [1.4, 1.0, 1.0]),
        ("sheet", [0.5, 0.5, 0.0], [0.5, 0.5, 0.4]),
    ] {
        let mut s = session();
        s.set_plasticity(Some(model), Some(Plasticity::new(20.0, 0.0).unwrap()))
            .unwrap();
        assert!(s.plasticity(Some(model)).is_some());
        let before = rest(&s, model);
        s.begin_group();
        s.apply(rope(model, from, to)).unwrap();
        for _ in 0..40 {
            s.step().unwrap();
        }
        s.apply(Command::to(model, Edit::Release { name: "r".into() }))
            .unwrap();
        s.end_group();
        let after = rest(&s, model);
        assert_ne!(after, before, "{model}: the rest shape flowed");
        s.undo().unwrap();
        assert_same(
            &rest(&s, model),
            &before,
            &format!("{model}: undo of the pull"),
        );
    }
}

#[test]
fn session_files_keep_the_flow_and_continue_bit_for_bit() {
    let mut s = session();
    s.set_plasticity(Some("cube"), Some(Plasticity::new(5.0, 0.01).unwrap()))
        .unwrap();
    s.apply(rope("cube", [1.0, 1.0, 1.0], [1.4, 1.0, 1.0]))
        .unwrap();
    for _ in 0..10 {
        s.step().unwrap();
    }
    let v = file::to_value(&s, None).unwrap();
    assert_eq!(v["models"][0]["plasticity"]["rate"], 5.0);
    assert!(
        v["models"][1].get("plasticity").is_none(),
        "off is not written"
    );
    let text = serde_json::to_string(&v).unwrap();
    let (mut back, _) = file::parse(&text, "x.session").unwrap();
    assert_eq!(back.plasticity(Some("cube")), s.plasticity(Some("cube")));
    common::continue_alike(&mut s, &mut back, 10, "continued after loading");
    // A bad value in a file is refused with its place.
    let bad = text.replace("\"rate\":5.0", "\"rate\":-5.0");
    let e = file::parse(&bad, "x.session").unwrap_err().to_string();
    assert!(
        e.contains("models[0].plasticity") && e.contains("rate"),
        "{e}"
    );
}

#[test]
fn kinds_without_a_rest_shape_refuse_the_flow() {
    let mut s = session();
    let e = s
        .set_plasticity(Some("box"), Some(Plasticity::new(1.0, 0.0).unwrap()))
        .unwrap_err()
        .to_string();
    assert!(e.contains("no plastic flow"), "{e}");
    assert!(s.plasticity(Some("box")).is_none());
    assert!(Plasticity::new(f64::INFINITY, 0.0).is_err());
}
