//! The readout of the energies under the plot (issue 27's frame loop): while a simulation runs,
//! frames evaluate the models' energies at most every `ENERGY_REFRESH`, and at most every
//! `ENERGY_COST_RATIO` times what the last evaluating frame took (a D-NURBS with dynamic
//! weights pays about a third of a step for it), and reuse the last values in between; paused,
//! every frame evaluates them.

use std::time::Duration;
use vclay_session::Energy;
use vclay_studio::worker::{ENERGY_COST_RATIO, ENERGY_REFRESH, EnergyClock, model_views};

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
fn an_expensive_evaluation_waits_in_proportion_to_its_cost() {
    let mut clock = EnergyClock::default();
    let e = Energy {
        kinetic: 1.0,
        elastic: 2.0,
        tools: 3.0,
    };
    // A frame that took 10 ms: the next evaluation waits 20 x 10 = 200 ms, past the 100 ms.
    let took = Duration::from_millis(10);
    assert!(took * ENERGY_COST_RATIO > ENERGY_REFRESH + Duration::from_millis(60));
    clock.evaluated_in(e, took);
    std::thread::sleep(ENERGY_REFRESH + Duration::from_millis(20));
    assert!(clock.reuse(true).is_some(), "still within 20 x its cost");
    assert!(clock.reuse(false).is_none(), "paused: always evaluated");
    std::thread::sleep(took * ENERGY_COST_RATIO - ENERGY_REFRESH);
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
