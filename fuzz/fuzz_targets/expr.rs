#![no_main]
//! Fuzz target `expr` (issue 17): any input gives `Ok` or `Err`, never a panic, abort or hang.

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Ok(e) = vclay_pde::Expr::parse(&text) {
        let _ = e.eval(0.5, 0.25, 0.125);
        for x in [vclay_pde::Var::U, vclay_pde::Var::V, vclay_pde::Var::T] {
            let _ = e.try_derivative(x);
        }
    }
});
