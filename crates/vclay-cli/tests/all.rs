//! Every integration test of `vclay-cli` in one test binary: each file of `tests/` is a
//! module here (Cargo.toml: `autotests = false`), so the suite links one binary instead of
//! 16 and its tests share the cores. Run one file with `cargo test -p vclay-cli --test all
//! FILE::`.

mod clay;
mod cli;
mod convert_brep;
mod eval_lattice;
mod everyday;
mod ffd;
mod fit;
mod hostile;
mod manual;
mod progress;
mod render_convert;
mod render_scenario;
mod run;
mod step_trimmed;
mod subdivide;
mod vtu_input;

vclay_core::every_test_file_is_listed!();
