//! Models say what they take (issue 26): the tool descriptions, the session's refusal and
//! `docs/formats.md` section 9 agree.

use std::collections::BTreeSet;
use std::path::Path;

use vclay_session::describe::{ACTIONS, actions};
use vclay_session::{Command, Edit, ModelKind, Session};

/// The kinds column of section 9's command table, by action.
fn documented() -> Vec<(String, BTreeSet<String>)> {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/formats.md"),
    )
    .unwrap();
    let start = text.find("## 9. Commands").expect("section 9");
    let table = &text[start..];
    let table = &table[table.find("| action | keys | kinds | effect |").unwrap()..];
    let mut rows = Vec::new();
    for line in table.lines().skip(2) {
        if !line.starts_with("| `") {
            break;
        }
        let cells: Vec<&str> = line.split(" | ").collect();
        let ticked = |s: &str| -> Vec<String> {
            s.split('`')
                .skip(1)
                .step_by(2)
                .map(str::to_string)
                .collect()
        };
        let kinds: BTreeSet<String> = ticked(cells[2]).into_iter().collect();
        for a in ticked(cells[0]).into_iter().filter(|a| a != "trim") {
            rows.push((a, kinds.clone()));
        }
    }
    rows
}

#[test]
fn formats_section_9_lists_what_each_kind_takes() {
    let rows = documented();
    let listed: BTreeSet<&str> = rows.iter().map(|r| r.0.as_str()).collect();
    assert_eq!(
        listed,
        ACTIONS.into_iter().collect(),
        "actions in the table"
    );
    for (action, kinds) in rows {
        let takes: BTreeSet<String> = ModelKind::ALL
            .into_iter()
            .filter(|k| actions(*k).contains(&action.as_str()))
            .map(|k| k.name().to_string())
            .collect();
        assert_eq!(
            kinds, takes,
            "`{action}`: docs/formats.md section 9 vs describe::actions"
        );
    }
}

#[test]
fn an_edit_the_kind_does_not_take_is_refused_before_the_model_and_names_what_it_takes() {
    let text = "[model]\nkind = \"pde-surface\"\nbuiltin = \"glass\"\n";
    let sc = vclay_session::scenario::Scenario::parse(text, "t.toml", "t", Path::new(".")).unwrap();
    let mut s: Session = sc.session;
    let m = s.model(None).unwrap();
    assert!(m.accepts(&Edit::PdeSet {
        name: "t".into(),
        value: 1.0
    }));
    assert!(!m.accepts(&Edit::Stop));
    let tools: Vec<&str> = m.tools().iter().map(|t| t.action).collect();
    assert_eq!(tools, ["pde-set", "pde-local", "release", "set"]);
    let e = s.apply(Command::new(Edit::Stop)).unwrap_err().to_string();
    assert!(
        e.contains("does not take `stop`") && e.contains("pde-set, pde-local, release, set"),
        "{e}"
    );
    // A scenario that schedules such an edit fails when read, at the entry's line.
    let bad = format!("{text}\n[[timeline]]\nat = 1.0\naction = \"stop\"\n");
    let e = vclay_session::scenario::Scenario::parse(&bad, "t.toml", "t", Path::new("."))
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("t.toml:7:") && e.contains("does not take `stop`"),
        "{e}"
    );
}
