#![no_main]
//! Fuzz target `params` (issue 17): any input gives `Ok` or `Err`, never a panic, abort or hang.

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    for dims in 1..=3 {
        let _ = vclay_io::parse_params(&text, dims);
    }
});
