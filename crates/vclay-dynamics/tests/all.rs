//! Every integration test of `vclay-dynamics` in one test binary: each file of `tests/` is a
//! module here (Cargo.toml: `autotests = false`), so the suite links one binary instead of
//! 6 and its tests share the cores. Run one file with `cargo test -p vclay-dynamics --test all
//! FILE::`.

mod common;

mod dnurbs;
mod fitting;
mod generalized;
mod patches;
mod quadrature;
mod triangular;

vclay_core::every_test_file_is_listed!();
