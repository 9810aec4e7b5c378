//! Every integration test of `vclay-io` in one test binary: each file of `tests/` is a
//! module here (Cargo.toml: `autotests = false`), so the suite links one binary instead of
//! 6 and its tests share the cores. Run one file with `cargo test -p vclay-io --test all
//! FILE::`.

mod cad_brep;
mod cad_read;
mod hostile;
mod iges_trims;
mod mesh;
mod model;
mod params;
mod trimmed;

vclay_core::every_test_file_is_listed!();
