//! Every integration test of `vclay-studio` in one test binary: each file of `tests/` is a
//! module here (Cargo.toml: `autotests = false`), so the suite links one binary instead of
//! 6 and its tests share the cores. Run one file with `cargo test -p vclay-studio --test all
//! FILE::`.

mod common;

mod brush;
mod cad_part;
mod colour;
mod defects;
mod energy;
mod native_dialogs;
mod sculpt;
mod studio;

vclay_core::every_test_file_is_listed!();
