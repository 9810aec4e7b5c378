//! Session files written by main before the typed session layer (issue 26) still load and
//! continue bit for bit as that build continued them (`tests/data/main-2026-12-02/README.md`).
//!
//! The two scenarios that are not shipped examples:
//! - `ffd`: `[model] kind = "ffd"`, `primitive = "bottle"`, `control = [4, 4, 5]`, one
//!   `ffd-move` of `[0, 0, 1]` to `[0.1, 0, 1.1]` at t = 0;
//! - `pde`: `[model] kind = "pde-surface"`, `builtin = "glass"`, `dt = 0.05`, one `pde-local`
//!   `bump` over u = [0.2, 0.6], v = [0.5, 2.0] with p = [0.1, 0, 0.2] at t = 0.

#[allow(dead_code)]
use crate::common;

use std::path::Path;

use vclay_session::file;

const NAMES: [&str; 9] = [
    "fig07_rope_cube",
    "bspline_rope",
    "fig9a_swung_egg",
    "fig06_curve_fit",
    "fig7b_saddle_fit",
    "fig08a_edge_rounding",
    "fig_patches_g1",
    "ffd",
    "pde",
];

#[test]
fn sessions_saved_by_the_old_main_load_and_continue_exactly() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/main-2026-12-02");
    for name in NAMES {
        let (mut session, run) = file::load(&dir.join(format!("{name}.session")))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(run.is_some(), "{name}: the saved run information");
        session.run(3).unwrap_or_else(|e| panic!("{name}: {e}"));
        let now = file::to_value(&session, None).unwrap();
        let text = std::fs::read_to_string(dir.join(format!("{name}.continued.session"))).unwrap();
        let then: serde_json::Value = serde_json::from_str(&text).unwrap();
        if let Some(d) = common::first_difference(&now["models"], &then["models"]) {
            panic!("{name}: {d}");
        }
    }
}

#[test]
fn old_sessions_open_through_the_one_way_in() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/main-2026-12-02");
    for name in NAMES {
        let o = vclay_session::open(&dir.join(format!("{name}.session")))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(o.kind, vclay_session::FileKind::Session, "{name}");
        assert!(o.run.is_some(), "{name}");
    }
}
