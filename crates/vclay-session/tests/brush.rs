//! The region force's falloff (a sculpting brush's profile, `vclay_solids::Falloff`) through the
//! session layer: a smooth brush dents the centre deeper than the paper's equal shares; an unknown falloff is refused naming the key; session files keep it.
use crate::common;
use common::assert_same;

use vclay_session::{Command, Edit, Session, file};

const CUBE: &str = r#"
[model]
kind = "subdivision-solid"
points = [4, 4, 4]
level = 1
[simulation]
dt = 0.002
steps = 10
"#;

fn cube() -> Session {
    common::scenario(CUBE)
}

fn push(falloff: Option<&str>) -> Edit {
    Edit::RegionForce {
        name: Some("push".into()),
        center: [0.5, 0.5, 1.0],
        radius: 0.45,
        force: [0.0, 0.0, -20.0],
        until: None,
        falloff: falloff.map(str::to_string),
    }
}

/// Sinking of the top data point nearest the brush centre and of one near its rim.
fn dents(falloff: Option<&str>) -> (f64, f64) {
    let mut s = cube();
    let d0 = s.model(None).unwrap().data_points();
    s.apply(Command::new(push(falloff))).unwrap();
    s.run(60).unwrap();
    let d = s.model(None).unwrap().data_points();
    let near = |x: f64, y: f64| {
        (0..d0.len())
            .min_by(|&a, &b| {
                let da = (d0[a].x - x).powi(2) + (d0[a].y - y).powi(2) + (d0[a].z - 1.0).powi(2);
                let db = (d0[b].x - x).powi(2) + (d0[b].y - y).powi(2) + (d0[b].z - 1.0).powi(2);
                da.total_cmp(&db)
            })
            .unwrap()
    };
    let (c, r) = (near(0.5, 0.5), near(0.5 + 0.35, 0.5));
    (d0[c].z - d[c].z, d0[r].z - d[r].z)
}

#[test]
fn a_smooth_brush_dents_the_centre_deeper_than_equal_shares() {
    let (c_equal, r_equal) = dents(None);
    let (c_smooth, r_smooth) = dents(Some("smooth"));
    assert!(c_equal > 0.0 && r_equal > 0.0, "{c_equal} {r_equal}");
    assert!(
        c_smooth > c_equal,
        "centre: smooth {c_smooth}, equal {c_equal}"
    );
    // Nothing is fixed: the same total force moves both cubes alike; the dent's depth (centre
    // below rim) is what the profile shapes.
    assert!(
        c_smooth - r_smooth > 1.2 * (c_equal - r_equal),
        "dent: smooth {c_smooth} - {r_smooth}, equal {c_equal} - {r_equal}"
    );
    // The same total force: "constant" is the default.
    assert_eq!(dents(Some("constant")), (c_equal, r_equal));
}

#[test]
fn an_unknown_falloff_is_refused_and_files_keep_a_known_one() {
    let mut s = cube();
    let e = s
        .apply(Command::new(push(Some("gaussian"))))
        .unwrap_err()
        .to_string();
    assert!(e.contains("falloff") && e.contains("smooth"), "{e}");
    s.apply(Command::new(push(Some("sharp")))).unwrap();
    s.run(5).unwrap();
    let text = common::session_text(&s);
    assert!(text.contains("\"falloff\":\"sharp\""));
    let (mut back, _) = file::parse(&text, "b.session").unwrap();
    common::continue_alike(&mut s, &mut back, 5, "continued with a sharp brush");
    let bad = text.replace("\"falloff\":\"sharp\"", "\"falloff\":\"soft\"");
    let e = file::parse(&bad, "b.session").unwrap_err().to_string();
    assert!(e.contains("unknown falloff \"soft\""), "{e}");
}

/// Highest data point of the model.
fn top(s: &Session) -> f64 {
    common::top_z(&s.model(None).unwrap().data_points())
}

#[test]
fn the_smooth_brush_flattens_a_sculpted_bump_through_the_physics() {
    // A bump pulled up from the top and kept (plastic reset), then smoothed where it is.
    let mut s = cube();
    let rope: Edit = serde_json::from_value(serde_json::json!({
        "action": "rope", "name": "r", "from": [0.5, 0.5, 1.0], "to": [0.5, 0.5, 1.5],
        "stiffness": 300.0
    }))
    .unwrap();
    s.apply(Command::new(Edit::Fix(vclay_session::Selection::rest_box(
        [-0.1, -0.1, -0.1],
        [1.1, 1.1, 0.1],
    ))))
    .unwrap();
    s.apply(Command::new(rope)).unwrap();
    s.run(300).unwrap();
    s.apply(Command::new(Edit::Release { name: "r".into() }))
        .unwrap();
    s.apply(Command::new(Edit::Stop)).unwrap();
    s.apply(Command::new(Edit::PlasticReset)).unwrap();
    s.run(50).unwrap();
    let bump = top(&s);
    assert!(bump > 1.1, "the bump: {bump}");
    let before = file::to_value(&s, None).unwrap();
    let smooth = Edit::Smooth {
        near: [0.5, 0.5, bump],
        radius: 0.5,
        strength: Some(1.0),
    };
    let msg = s.apply(Command::new(smooth.clone())).unwrap();
    assert!(msg.contains("smoothed the rest shape at"), "{msg}");
    s.run(400).unwrap();
    let smoothed = top(&s);
    assert!(
        smoothed < bump - 0.3 * (bump - 1.0),
        "the clay settled lower: {smoothed} from {bump}"
    );
    // Undo puts the rest shape back (the stroke and the steps after it).
    s.undo().unwrap();
    let now = file::to_value(&s, None).unwrap();
    assert_same(
        &now["models"][0]["state"]["rest"],
        &before["models"][0]["state"]["rest"],
        "undo of the smooth brush",
    );
    let e = s
        .apply(Command::new(Edit::Smooth {
            near: [0.5, 0.5, 1.0],
            radius: 0.2,
            strength: Some(1.5),
        }))
        .unwrap_err()
        .to_string();
    assert!(e.contains("strength"), "{e}");
}

/// Highest control point of the model.
fn top_control(s: &Session) -> f64 {
    common::top_z(&s.model(None).unwrap().control_points())
}

/// On both D-NURBS engines: the frozen-weight one keeps its rest shape as control points
/// (`K p_rest`), so it takes the smooth brush too (session 23; it used to refuse).
#[test]
fn the_smooth_brush_fairs_a_dnurbs_bump_on_both_engines() {
    for engine in ["generalized", "frozen"] {
        let text = format!(
            "[model]\nkind = \"dnurbs-surface\"\nsize = [8, 8]\nengine = \"{engine}\"\n\
             [simulation]\ndt = 0.01\nsteps = 10\n"
        );
        let mut s = common::scenario(&text);
        // The sheet's border held, so the rope raises a bump instead of lifting the sheet.
        for (lo, hi) in [
            ([-0.1, -0.1, -1.0], [1.1, 0.05, 1.0]),
            ([-0.1, 0.95, -1.0], [1.1, 1.1, 1.0]),
            ([-0.1, -0.1, -1.0], [0.05, 1.1, 1.0]),
            ([0.95, -0.1, -1.0], [1.1, 1.1, 1.0]),
        ] {
            s.apply(Command::new(Edit::Fix(vclay_session::Selection::rest_box(
                lo, hi,
            ))))
            .unwrap();
        }
        common::apply_json(
            &mut s,
            serde_json::json!({"action": "rope", "name": "r", "from": [0.5, 0.5, 0.0],
                               "to": [0.5, 0.5, 0.5], "stiffness": 200.0}),
        );
        s.run(60).unwrap();
        for e in [
            Edit::Release { name: "r".into() },
            Edit::Stop,
            Edit::PlasticReset,
        ] {
            s.apply(Command::new(e)).unwrap();
        }
        let bump = top_control(&s);
        assert!(bump > 0.1, "{engine}: the bump: {bump}");
        // Left alone, the reset bump stays.
        s.run(20).unwrap();
        let kept = top_control(&s);
        assert!(
            (kept - bump).abs() < 1e-6,
            "{engine}: the bump moved to {kept} from {bump}"
        );
        let msg = s
            .apply(Command::new(Edit::Smooth {
                near: [0.5, 0.5, bump],
                radius: 0.4,
                strength: Some(1.0),
            }))
            .unwrap();
        assert!(
            msg.contains("smoothed the rest shape at"),
            "{engine}: {msg}"
        );
        s.run(100).unwrap();
        let after = top_control(&s);
        assert!(
            after < 0.8 * bump,
            "{engine}: the surface settled lower: {after} from {bump}"
        );
        // Undo gives the shape and rest shape from before the smoothing back: the bump stays.
        s.undo().unwrap();
        s.run(100).unwrap();
        let again = top_control(&s);
        assert!(
            (again - bump).abs() < 0.05 * bump,
            "{engine}: after undoing the smoothing {again}, the bump was {bump}"
        );
    }
}
