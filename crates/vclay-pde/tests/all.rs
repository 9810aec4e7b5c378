//! Every integration test of `vclay-pde` in one test binary: each file of `tests/` is a
//! module here (Cargo.toml: `autotests = false`), so the suite links one binary instead of
//! 9 and its tests share the cores. Run one file with `cargo test -p vclay-pde --test all
//! FILE::`.

mod support;

mod aircraft;
mod animation;
mod expr;
mod figs56;
mod patches;
mod residual_check;
mod section3;
mod spec;
mod spectral;
mod trial;

vclay_core::every_test_file_is_listed!();
