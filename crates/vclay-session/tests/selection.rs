//! One fix/free selection rule for every kind (issue 26; the studio's fix brush of issue 27,
//! item 2): a brush (`near` + `radius`) and `near` select by current position, a `min`/`max`
//! box by rest position.

use crate::common;

use vclay_session::{Command, Edit, Session};

fn session(kind: &str) -> Session {
    let text = match kind {
        "solid" => {
            "[model]\nkind = \"subdivision-solid\"\nprimitive = \"box\"\npoints = [3, 3, 3]\nlevel = 1\n"
        }
        _ => "[model]\nkind = \"dnurbs-surface\"\nsize = [4, 4]\n[simulation]\ndt = 0.01\n",
    };
    common::scenario(text)
}

fn fix(
    near: Option<[f64; 3]>,
    radius: Option<f64>,
    min: Option<[f64; 3]>,
    max: Option<[f64; 3]>,
) -> Edit {
    Edit::Fix(vclay_session::Selection {
        points: None,
        min,
        max,
        near,
        radius,
    })
}

fn count(message: &str) -> usize {
    message
        .split_whitespace()
        .nth(1)
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("{message}"))
}

#[test]
fn brushes_select_where_points_are_boxes_where_they_rested() {
    for kind in ["solid", "dnurbs"] {
        let mut s = session(kind);
        let p0 = s.model(None).unwrap().control_points()[0];
        let far = [p0.x + 10.0, p0.y + 10.0, p0.z + 10.0];
        s.apply(Command::new(Edit::MovePoint { index: 0, to: far }))
            .unwrap();
        // A brush at the moved point takes it (and nothing else: the others are 10 away).
        let m = s
            .apply(Command::new(fix(Some(far), Some(0.5), None, None)))
            .unwrap();
        assert_eq!(count(&m), 1, "{kind}: {m}");
        // A brush where it rested takes nothing there.
        let at = [p0.x, p0.y, p0.z];
        s.undo().unwrap();
        let m = s
            .apply(Command::new(fix(Some(at), Some(1e-6), None, None)))
            .unwrap();
        assert_eq!(count(&m), 0, "{kind}: {m}");
        // A box around the rest position still names it (the file format's rule).
        let lo = [p0.x - 1e-6, p0.y - 1e-6, p0.z - 1e-6];
        let hi = [p0.x + 1e-6, p0.y + 1e-6, p0.z + 1e-6];
        let m = s
            .apply(Command::new(fix(None, None, Some(lo), Some(hi))))
            .unwrap();
        assert_eq!(count(&m), 1, "{kind}: {m}");
    }
}

#[test]
fn a_radius_needs_near_and_is_not_negative() {
    let mut s = session("dnurbs");
    let e = s
        .apply(Command::new(fix(
            None,
            Some(1.0),
            Some([0.0; 3]),
            Some([1.0; 3]),
        )))
        .unwrap_err()
        .to_string();
    assert!(e.contains("`radius` goes with `near`"), "{e}");
    let e = s
        .apply(Command::new(fix(Some([0.0; 3]), Some(-1.0), None, None)))
        .unwrap_err()
        .to_string();
    assert!(e.contains("radius"), "{e}");
}
