#![no_main]
//! Fuzz target `pde_spec` (issue 17): any input gives `Ok` or `Err`, never a panic, abort or hang.

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let _ = vclay_pde::PdeModel::from_json(&text, "fuzz.json");
    let _ = vclay_pde::PdeModel::from_toml(&text, "fuzz.toml");
});
