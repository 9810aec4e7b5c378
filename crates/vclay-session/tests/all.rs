//! Every integration test of `vclay-session` in one test binary: each file of `tests/` is a
//! module here (Cargo.toml: `autotests = false`), so the suite links one binary instead of
//! 20 and its tests share the cores. Run one file with `cargo test -p vclay-session --test all
//! FILE::`.

mod common;

mod brush;
mod cad_part;
mod describe;
mod dnurbs;
mod dnurbs_issue18;
mod dnurbs_patches;
mod dnurbs_triangular;
mod energy;
mod examples;
mod ffd;
mod hostile;
mod open;
mod paper_figures;
mod pde;
mod pde_issue22;
mod plasticity;
mod saved_by_old_main;
mod scenario;
mod selection;
mod session;
mod solid;
mod step_brep_import;

vclay_core::every_test_file_is_listed!();
