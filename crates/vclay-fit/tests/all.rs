//! Every integration test of `vclay-fit` in one test binary: each file of `tests/` is a
//! module here (Cargo.toml: `autotests = false`), so the suite links one binary instead of
//! 2 and its tests share the cores. Run one file with `cargo test -p vclay-fit --test all
//! FILE::`.

mod common;

mod energy;
mod fit;

vclay_core::every_test_file_is_listed!();
