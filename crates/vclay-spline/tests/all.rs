//! Every integration test of `vclay-spline` in one test binary: each file of `tests/` is a
//! module here (Cargo.toml: `autotests = false`), so the suite links one binary instead of
//! 7 and its tests share the cores. Run one file with `cargo test -p vclay-spline --test all
//! FILE::`.

mod common;

mod curve;
mod jacobian;
mod properties;
mod refine;
mod surface;
mod tessellate;
mod triangular;

vclay_core::every_test_file_is_listed!();
