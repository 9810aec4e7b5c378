//! Support for the workspace's own test suites (not a part of the modelling API).
//!
//! Each crate builds its integration tests as one binary, `tests/all.rs`, with
//! `autotests = false` in its `Cargo.toml`: one link instead of one per file, and the tests of
//! every file share the cores. A file in `tests/` that `all.rs` does not name as a module is
//! then silently not built; [`every_test_file_is_listed!`](crate::every_test_file_is_listed)
//! adds the test that catches it.

use std::path::Path;

/// Panics, naming the file, when a `.rs` file in `tests_dir` other than `all.rs` is not declared
/// as `mod STEM;` (on a line of its own) in `all_rs`, the text of `tests/all.rs`.
pub fn assert_every_test_file_listed(tests_dir: &Path, all_rs: &str) {
    let entries = std::fs::read_dir(tests_dir)
        .unwrap_or_else(|e| panic!("cannot list {}: {e}", tests_dir.display()));
    for entry in entries {
        let path = entry.expect("a readable directory entry").path();
        let (Some(stem), Some("rs")) = (
            path.file_stem().and_then(|s| s.to_str()),
            path.extension().and_then(|s| s.to_str()),
        ) else {
            continue;
        };
        let declared = all_rs.lines().any(|l| l.trim() == format!("mod {stem};"));
        assert!(
            stem == "all" || declared,
            "tests/{stem}.rs is not a module of tests/all.rs: add `mod {stem};` there"
        );
    }
}

/// Adds to a crate's `tests/all.rs` the test that fails while a file of `tests/` is not one of
/// its modules (see [`assert_every_test_file_listed`]). Call it once, in `tests/all.rs`.
#[macro_export]
macro_rules! every_test_file_is_listed {
    () => {
        /// A new file in `tests/` is not built unless it is listed above: this fails until it is.
        #[test]
        fn every_test_file_is_a_module_of_this_binary() {
            $crate::testing::assert_every_test_file_listed(
                &::std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests"),
                include_str!("all.rs"),
            );
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unlisted_file_is_named() {
        let dir = std::env::temp_dir().join(format!("vclay-testing-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("all.rs"), "").unwrap();
        std::fs::write(dir.join("alpha.rs"), "").unwrap();
        std::fs::write(dir.join("notes.txt"), "").unwrap();
        assert_every_test_file_listed(&dir, "mod alpha;\n");
        let missed =
            std::panic::catch_unwind(|| assert_every_test_file_listed(&dir, "mod alphabet;\n"));
        std::fs::remove_dir_all(&dir).unwrap();
        let msg = *missed.unwrap_err().downcast::<String>().unwrap();
        assert!(msg.contains("tests/alpha.rs"), "{msg}");
    }
}
