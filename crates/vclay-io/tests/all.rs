//! Every integration test of `vclay-io` in one test binary: each file of `tests/` is a
//! module here (Cargo.toml: `autotests = false`), so the suite links one binary instead of
//! 6 and its tests share the cores. Run one file with `cargo test -p vclay-io --test all
//! FILE::`.

mod cad_brep;
mod cad_read;
mod hostile;
mod mesh;
mod model;
mod params;
mod trimmed;

/// A new file in `tests/` is not built unless it is listed above: this fails until it is.
#[test]
fn every_test_file_is_a_module_of_this_binary() {
    let listed = include_str!("all.rs");
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let (Some(stem), Some("rs")) = (
            path.file_stem().and_then(|s| s.to_str()),
            path.extension().and_then(|s| s.to_str()),
        ) else {
            continue;
        };
        assert!(
            stem == "all" || listed.contains(&format!("\nmod {stem};\n")),
            "tests/{stem}.rs is not a module of tests/all.rs: add `mod {stem};` there"
        );
    }
}
