//! Energies that add up (issue 32 item 8): a D-NURBS with a rope or data points reports the
//! energy stored in their springs as `tools` (it was 0.0), `1/2 k |s(u0) - d0|^2` for a rope.

use crate::common;

use vclay_session::{Command, Edit};

const SHEET: &str = r#"
[model]
kind = "dnurbs-surface"
size = [6, 6]
[simulation]
dt = 0.01
steps = 10
"#;

#[test]
fn a_dnurbs_rope_and_data_points_store_spring_energy() {
    let mut s = common::scenario(SHEET);
    assert_eq!(
        s.model(None).unwrap().energy().tools,
        0.0,
        "no tools, no energy"
    );
    common::apply_json(
        &mut s,
        serde_json::json!({"action": "rope", "name": "r", "from": [0.5, 0.5, 0.0],
                           "to": [0.5, 0.5, 0.4], "stiffness": 10.0}),
    );
    s.run(1).unwrap();
    let e = s.model(None).unwrap().energy();
    // After a step the cursor is 0.4 above where the sheet's point was: about
    // 1/2 10 0.4^2 = 0.8, a little less as the point has begun to rise.
    assert!(e.tools > 0.6 && e.tools <= 0.8 + 1e-12, "{e:?}");
    s.run(20).unwrap();
    let later = s.model(None).unwrap().energy();
    assert!(
        later.tools > 0.0 && later.tools < e.tools,
        "the sheet rose: {later:?}"
    );
    assert!(later.total() >= later.kinetic + later.elastic);
    s.apply(Command::new(Edit::Release { name: "r".into() }))
        .unwrap();
    let data: Edit = serde_json::from_value(serde_json::json!({
        "action": "data", "points": [[0.5, 0.5, 0.2]], "stiffness": 4.0
    }))
    .unwrap();
    s.apply(Command::new(data)).unwrap();
    let d = s.model(None).unwrap().energy().tools;
    assert!(d > 0.0 && d.is_finite(), "{d}");
}
