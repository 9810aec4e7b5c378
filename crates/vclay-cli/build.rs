//! No build step: the script exists so that `[build-dependencies]` can ask for the features of
//! `syn` that the Python module's dependencies use (feature unification, see Cargo.toml).

fn main() {
    println!("cargo::rerun-if-changed=build.rs");
}
