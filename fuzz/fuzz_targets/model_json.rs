#![no_main]
//! Fuzz target `model_json` (issue 17): any input gives `Ok` or `Err`, never a panic, abort or hang.

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = vclay_io::parse_model(&String::from_utf8_lossy(data));
});
