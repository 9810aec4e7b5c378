//! Hostile input (issue 17): random byte mutations of valid files given to the readers of the
//! session layer and the lattice format it loads (scenario TOML through `Scenario::parse`,
//! session files through `file::parse`, OpenVolumeMesh `.ovm` through
//! `vclay_lattice::formats::ovm::parse`) give an `Ok` or an `Err`, never a panic, and each
//! within a bounded time. Seeded; a few seconds in all in a debug build. The mutation helpers
//! are those of `crates/vclay-io/tests/hostile.rs`. Longer, coverage-guided runs: `fuzz/`
//! (docs/limits.md).

use crate::common;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use std::path::Path;
use std::time::{Duration, Instant};
use vclay_session::file;
use vclay_session::scenario::Scenario;

/// Cases per reader.
const CASES: u32 = 4000;
/// Longest time one case may take (a reader that trusts a mutated count would take far
/// longer, or abort).
const CASE_LIMIT: Duration = Duration::from_secs(2);

/// One edit: (kind, position, byte).
type Edit = (u8, usize, u8);

/// Bytes worth inserting: JSON and number syntax, separators, and any byte.
fn byte() -> impl Strategy<Value = u8> {
    prop_oneof![
        3 => prop::sample::select(b"0123456789-+.eE[]{}\",: \n\t/x".to_vec()),
        1 => any::<u8>(),
    ]
}

fn edits() -> impl Strategy<Value = Vec<Edit>> {
    prop::collection::vec((0u8..5, any::<usize>(), byte()), 1..6)
}

/// Applies `edits` to `seed`: replace, insert or delete a byte, truncate, or repeat a slice
/// (which makes keys, lines and elements appear twice).
fn mutate(seed: &[u8], edits: &[Edit]) -> Vec<u8> {
    let mut b = seed.to_vec();
    for &(kind, pos, x) in edits {
        let n = b.len();
        match kind {
            0 if n > 0 => b[pos % n] = x,
            1 => b.insert(pos % (n + 1), x),
            2 if n > 0 => {
                b.remove(pos % n);
            }
            3 => b.truncate(pos % (n + 1)),
            4 if n > 0 => {
                let start = pos % n;
                let end = (start + 1 + x as usize).min(n);
                let slice = b[start..end].to_vec();
                b.splice(end..end, slice);
            }
            _ => {}
        }
    }
    b
}

/// Runs `read` on mutations of every seed (it says whether the input was accepted); fails on a
/// panic or a slow case.
fn hostile(name: &str, seeds: &[Vec<u8>], read: impl Fn(&[u8]) -> bool) {
    let config = Config {
        cases: CASES,
        failure_persistence: None,
        ..Config::default()
    };
    let rng = TestRng::deterministic_rng(RngAlgorithm::ChaCha);
    let mut runner = TestRunner::new_with_rng(config, rng);
    let strategy = (0..seeds.len(), edits());
    let started = Instant::now();
    let accepted = std::cell::Cell::new(0);
    let result = runner.run(&strategy, |(s, e)| {
        let bytes = mutate(&seeds[s], &e);
        let t = Instant::now();
        if read(&bytes) {
            accepted.set(accepted.get() + 1);
        }
        prop_assert!(
            t.elapsed() < CASE_LIMIT,
            "{name}: {:?} for {:?}",
            t.elapsed(),
            String::from_utf8_lossy(&bytes)
        );
        Ok(())
    });
    if let Err(e) = result {
        panic!("{name}: {e}");
    }
    eprintln!(
        "{name}: {CASES} cases ({} accepted) in {:.2?}",
        accepted.get(),
        started.elapsed()
    );
}

fn text(b: &[u8]) -> std::borrow::Cow<'_, str> {
    String::from_utf8_lossy(b)
}

fn parse_scenario(text: &str) -> Result<Scenario, vclay_session::SessionError> {
    Scenario::parse(text, "hostile.toml", "hostile", Path::new("."))
}

#[test]
fn scenario_toml() {
    hostile("scenario TOML", &[common::two_kinds().into()], |b| {
        parse_scenario(&text(b)).is_ok()
    });
}

#[test]
fn session_files() {
    let mut sc = parse_scenario(&common::two_kinds()).unwrap();
    sc.session.run(3).unwrap();
    let seed = serde_json::to_vec(&file::to_value(&sc.session, None).unwrap()).unwrap();
    hostile("session file", &[seed], |b| {
        file::parse(&text(b), "hostile.session").is_ok()
    });
}

#[test]
fn ovm_lattices() {
    use vclay_core::Vec3;
    let cube = vclay_lattice::primitives::box_lattice(
        [3, 3, 2],
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 0.5),
    );
    let seed = vclay_lattice::formats::ovm::to_string(&cube).into_bytes();
    hostile("OVM", &[seed], |b| {
        vclay_lattice::formats::ovm::parse(&text(b), "hostile.ovm").is_ok()
    });
}
