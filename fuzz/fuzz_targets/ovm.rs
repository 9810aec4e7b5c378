#![no_main]
//! Fuzz target `ovm` (issue 17): any input gives `Ok` or `Err`, never a panic, abort or hang.

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = vclay_lattice::formats::ovm::parse(&String::from_utf8_lossy(data), "fuzz.ovm");
});
