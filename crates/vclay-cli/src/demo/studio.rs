//! Demo step of the studio (issue 16): the interactive studio cannot run inside a batch demo,
//! so the page shows the screenshot that `bench/check_studio.sh` takes of it (the studio on the
//! fig07 cube under Xvfb with Mesa's software OpenGL, after a rope drag), committed as
//! `docs/studio.png`, and says how to start it.

use anyhow::{Context, Result};
use std::path::Path;

use super::StepOutput;

/// The screenshot of `bench/check_studio.sh`, embedded.
const SHOT: &[u8] = include_bytes!("../../../../docs/studio.png");

/// Writes `studio.png` into `out`.
pub fn screenshot(out: &Path) -> Result<StepOutput> {
    let path = out.join("studio.png");
    std::fs::write(&path, SHOT).with_context(|| format!("cannot write {}", path.display()))?;
    Ok((
        "the interactive studio (`vclay studio FILE`; build it with `cargo build --release -p vclay-studio`) on the fig07 cube after a rope drag: a screenshot taken under Xvfb with Mesa's software OpenGL by bench/check_studio.sh".into(),
        vec!["studio.png".into()],
    ))
}
