//! Progress bars (issue 17): drawn on stderr only when it is a terminal and `--quiet` is not
//! given; stdout is the same with and without them.

use std::path::Path;
use std::process::{Command, Output};

/// A spec whose frames all solve the PDE (section III's surface is over the residual warning
/// of issue 28, which would be the only thing on stderr).
const SPEC: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../vclay-pde/examples/specs/fig4a.json"
);

fn vclay(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vclay"))
        .args(args)
        .output()
        .expect("vclay runs")
}

/// Whether stderr shows a bar or spinner being redrawn.
fn has_progress(text: &str) -> bool {
    text.contains('\r') || text.contains("\u{1b}[") || text.contains("] ")
}

#[test]
fn no_progress_when_stderr_is_not_a_terminal() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("frames");
    let out = vclay(&[
        "pde",
        SPEC,
        "--frames",
        "0:1:5",
        "--out-dir",
        out_dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = vclay(&[
        "subdivide",
        "--primitive",
        "box",
        "--levels",
        "3",
        "--stats",
    ]);
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!has_progress(&err), "{err:?}");
}

/// Runs `command` (a shell line) with a pseudo-terminal as stdin, stdout and stderr through
/// util-linux `script`; `None` where `script` is missing.
fn on_terminal(command: &str, dir: &Path) -> Option<String> {
    let out = Command::new("script")
        .current_dir(dir)
        .args(["-qec", command, "/dev/null"])
        .output()
        .ok()?;
    assert!(
        out.status.success(),
        "{command}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    Some(String::from_utf8_lossy(&out.stdout).into_owned())
}

#[test]
fn progress_on_a_terminal_unless_quiet_and_stdout_unchanged() {
    let dir = tempfile::tempdir().unwrap();
    let exe = env!("CARGO_BIN_EXE_vclay");
    let pde = format!("{exe} pde {SPEC} --frames 0:1:5 --out-dir f > pde.json");
    let Some(tty) = on_terminal(&pde, dir.path()) else {
        eprintln!("skipped: no `script` command to give vclay a terminal");
        return;
    };
    assert!(tty.contains("vclay pde: frames ["), "{tty:?}");
    assert!(tty.contains("5/5") || tty.contains("4/5"), "{tty:?}");
    let quiet = on_terminal(
        &format!("{exe} --quiet pde {SPEC} --frames 0:1:5 --out-dir f > q.json"),
        dir.path(),
    )
    .unwrap();
    assert!(!has_progress(&quiet), "{quiet:?}");

    // The spinner of `subdivide` leaves stdout as it is without a terminal.
    on_terminal(
        &format!("{exe} subdivide --primitive box --levels 3 --stats > tty.json"),
        dir.path(),
    )
    .unwrap();
    let piped = vclay(&[
        "subdivide",
        "--primitive",
        "box",
        "--levels",
        "3",
        "--stats",
    ]);
    assert_eq!(
        std::fs::read(dir.path().join("tty.json")).unwrap(),
        piped.stdout
    );
    let frames = |name: &str| {
        let v: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.path().join(name)).unwrap()).unwrap();
        v["frames"].as_array().unwrap().len()
    };
    assert_eq!(frames("pde.json"), 5);
    assert_eq!(frames("q.json"), 5);
}
