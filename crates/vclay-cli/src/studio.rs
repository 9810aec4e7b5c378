//! `vclay studio [ARGS]`: starts the interactive studio, the separate `vclay-studio` binary
//! (crates/vclay-studio), so this command line never links the GUI. The binary is looked up
//! next to the `vclay` executable, then on `PATH`.

use std::path::PathBuf;
use std::process::Command;

use anyhow::{Context, bail};

/// The `vclay-studio` executable's name on this platform.
fn exe_name() -> String {
    format!("vclay-studio{}", std::env::consts::EXE_SUFFIX)
}

/// Where `vclay-studio` is: beside the running `vclay`, else on `PATH`.
pub fn find() -> Option<PathBuf> {
    let name = exe_name();
    if let Some(dir) = std::env::current_exe()
        .ok()
        .and_then(|p| p.parent().map(PathBuf::from))
    {
        let p = dir.join(&name);
        if p.is_file() {
            return Some(p);
        }
    }
    std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|d| d.join(&name))
            .find(|p| p.is_file())
    })
}

/// Runs the studio with `args` and waits for it; its exit status becomes ours.
pub fn run(args: &[String]) -> anyhow::Result<()> {
    let Some(exe) = find() else {
        bail!(
            "the studio is a separate binary, `vclay-studio`, and it was found neither next to \
             this `vclay` nor on PATH; build it with `cargo build --release -p vclay-studio` \
             (it lands beside `vclay` in target/release)"
        );
    };
    let status = Command::new(&exe)
        .args(args)
        .status()
        .with_context(|| format!("cannot start {}", exe.display()))?;
    if !status.success() {
        bail!("{} exited with {status}", exe.display());
    }
    Ok(())
}
