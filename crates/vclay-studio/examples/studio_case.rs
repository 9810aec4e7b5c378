//! One case of the studio's frame-time benchmark (`vclay-studio --bench`) alone, for
//! profiling (`perf record` sees only that model): `studio_case [INDEX] [FRAMES]`, `INDEX`
//! into `vclay_studio::bench::CASES` (default 4, the 32 x 32 D-NURBS sheet with dynamic
//! weights and the default block-Schur solve, issue 27), `FRAMES` default 100. Prints the
//! case's mean frame, CPU, step and display times.
fn main() {
    let mut args = std::env::args().skip(1);
    let i: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(4);
    let frames: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(100);
    let Some(case) = vclay_studio::bench::CASES.get(i) else {
        eprintln!(
            "studio_case: no case {i} (0..{})",
            vclay_studio::bench::CASES.len()
        );
        std::process::exit(2);
    };
    match vclay_studio::bench::run(case, frames) {
        Ok(r) => println!(
            "{}: frame {:.2} ms, CPU {:.2} ms/frame, steps {:.2} ms, display {:.2} ms",
            r.name, r.frame_ms, r.cpu_ms, r.step_ms, r.display_ms
        ),
        Err(e) => {
            eprintln!("studio_case: {e}");
            std::process::exit(1);
        }
    }
}
