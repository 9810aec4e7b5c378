//! Every integration test of `vclay-lattice` in one test binary: each file of `tests/` is a
//! module here (Cargo.toml: `autotests = false`), so the suite links one binary instead of
//! 14 and its tests share the cores. Run one file with `cargo test -p vclay-lattice --test all
//! FILE::`.

mod common;

mod boundary_rules;
mod bspline;
mod compact;
mod counts;
mod edit;
mod formats;
mod from_mesh;
mod gallery;
mod lattice;
mod limit;
mod limit_surface;
mod operator;
mod primitives;
mod renumber;
mod tensor;
mod vtu_read;

vclay_core::every_test_file_is_listed!();
