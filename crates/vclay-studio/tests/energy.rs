//! The readout of the energies under the plot (issue 27's frame loop): while a simulation runs,
//! frames evaluate the models' energies at most every `ENERGY_REFRESH` (a D-NURBS with dynamic
//! weights pays about a third of a step for it) and reuse the last values in between; paused,
//! every frame evaluates them.

use std::time::Duration;
use vclay_session::Energy;
use vclay_studio::worker::{ENERGY_REFRESH, EnergyClock, model_views};

#[test]
fn running_frames_reuse_the_energies_within_the_refresh_interval() {
    let mut clock = EnergyClock::default();
    // Nothing evaluated yet: evaluate, running or not.
    assert!(clock.reuse(true).is_none());
    assert!(clock.reuse(false).is_none());
    let e = Energy {
        kinetic: 1.0,
        elastic: 2.0,
        tools: 3.0,
    };
    clock.evaluated(e);
    assert_eq!(clock.reuse(true).map(|x| x.elastic), Some(2.0));
    // Paused: always evaluated (a frame is built only when something changed).
    assert!(clock.reuse(false).is_none());
    std::thread::sleep(ENERGY_REFRESH + Duration::from_millis(20));
    assert!(clock.reuse(true).is_none());
}

#[test]
fn model_views_report_known_energies_or_evaluate_them() {
    let scenario = r#"
[model]
kind = "dnurbs-surface"
primitive = "sheet"
size = [5, 5]
degree = [2, 2]
weights = "dynamic"
[material]
preset = "Hemisphere fitting"
"#;
    let session =
        vclay_session::scenario::Scenario::parse(scenario, "t", "t", std::path::Path::new("."))
            .unwrap()
            .session;
    let known = Energy {
        kinetic: 7.0,
        elastic: 8.0,
        tools: 9.0,
    };
    let (models, e) = model_views(&session, None, Some(known));
    assert_eq!(models.len(), 1);
    assert_eq!((e.kinetic, e.elastic, e.tools), (7.0, 8.0, 9.0));
    let (_, e) = model_views(&session, None, None);
    let m = session.model(None).unwrap().energy();
    assert_eq!(
        (e.kinetic, e.elastic, e.tools),
        (m.kinetic, m.elastic, m.tools)
    );
}
