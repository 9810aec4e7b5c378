#![no_main]
//! Fuzz target `obj` (issue 17): any input gives `Ok` or `Err`, never a panic, abort or hang.

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = vclay_io::decode_mesh(data, vclay_io::MeshFormat::Obj, "fuzz.obj");
});
