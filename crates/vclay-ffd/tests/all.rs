//! Every integration test of `vclay-ffd` in one test binary: each file of `tests/` is a
//! module here (Cargo.toml: `autotests = false`), so the suite links one binary instead of
//! 6 and its tests share the cores. Run one file with `cargo test -p vclay-ffd --test all
//! FILE::`.

mod common;

mod decomposition;
mod embedded_mesh;
mod lattice;
mod manipulation;
mod multi_point;
mod weights;

vclay_core::every_test_file_is_listed!();
