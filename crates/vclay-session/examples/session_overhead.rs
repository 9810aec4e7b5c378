//! What the session layer adds to a step, as a count that does not depend on the machine's
//! load: run under `valgrind --tool=callgrind` (instructions, not seconds) with
//! `session_overhead bare|session|dnurbs-bare|dnurbs-session STEPS`, twice with two step counts; the difference of the
//! totals divided by the difference of the steps is the cost of one step. The 4^3 cube at
//! level 2, pulled by a rope, on the calling thread only (`Parallelism::Sequential`: callgrind
//! runs threads one at a time, and spinning helpers would count); the 64x64 frozen-weight
//! D-NURBS sheet of `vclay bench --physics`.
//!
//! ```sh
//! cargo build --release -p vclay-session --example session_overhead
//! for m in bare session; do for n in 100 300; do
//!   valgrind --tool=callgrind --callgrind-out-file=/dev/null \
//!     target/release/examples/session_overhead $m $n 2>&1 | grep refs; done; done
//! ```

use vclay_core::Parallelism;
use vclay_dynamics::Integrator;
use vclay_dynamics::dnurbs::benchmarks as dn;
use vclay_session::Session;
use vclay_session::models::dnurbs::DnurbsModel;
use vclay_session::models::solid::SolidModel;
use vclay_solids::{SolidParams, benchmarks as so};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let (mode, steps) = match args.as_slice() {
        [_, m, n] => (m.as_str(), n.parse::<u64>()?),
        _ => return Err("usage: session_overhead bare|session STEPS".into()),
    };
    let params = SolidParams {
        parallelism: Parallelism::Sequential,
        ..SolidParams::default()
    };
    let mut cube = so::cube(2, params)?;
    so::pull(&mut cube)?;
    match mode {
        "bare" => {
            for _ in 0..steps {
                cube.step()?;
            }
        }
        "session" => {
            let mut s = Session::with_model("cube", Box::new(SolidModel::new(cube)))?;
            s.run(steps)?;
        }
        "dnurbs-bare" => {
            let mut d = dn::frozen_sheet(64)?;
            for _ in 0..steps {
                d.step(Integrator::Implicit { dt: dn::DT })?;
            }
        }
        "dnurbs-session" => {
            let m = DnurbsModel::frozen_surface(dn::frozen_sheet(64)?, dn::DT)?;
            let mut s = Session::with_model("sheet", Box::new(m))?;
            s.run(steps)?;
        }
        other => return Err(format!("unknown mode {other}").into()),
    }
    Ok(())
}
