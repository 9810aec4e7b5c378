//! `vclay completions SHELL` and `vclay man [COMMAND]`: shell completion scripts
//! (`clap_complete`) and roff man pages (`clap_mangen`) generated from the clap definitions, so
//! they never disagree with `--help`. Both print to stdout.

use anyhow::{Context, Result, bail};
use clap::CommandFactory;
use std::io::Write;

/// Prints the completion script of `shell` for `vclay`.
pub(crate) fn completions(shell: clap_complete::Shell) -> Result<()> {
    let mut cmd = crate::Cli::command();
    let mut out = Vec::new();
    clap_complete::generate(shell, &mut cmd, "vclay", &mut out);
    write_stdout(&out)
}

/// Prints the man page of `vclay`, or of its subcommand `command` (named `vclay-COMMAND`).
pub(crate) fn man(command: Option<&str>) -> Result<()> {
    let mut cmd = crate::Cli::command();
    cmd.build();
    let page = match command {
        None => cmd,
        Some(name) => {
            let Some(sub) = cmd.find_subcommand(name) else {
                let names: Vec<_> = cmd
                    .get_subcommands()
                    .map(|s| s.get_name().to_string())
                    .collect();
                bail!(
                    "vclay man: no subcommand \"{name}\" (one of {})",
                    names.join(", ")
                );
            };
            // After `build`, a subcommand's display name is `vclay-NAME`: the page's title.
            sub.clone()
        }
    };
    let mut out = Vec::new();
    clap_mangen::Man::new(page)
        .render(&mut out)
        .context("cannot render the man page")?;
    write_stdout(&out)
}

fn write_stdout(bytes: &[u8]) -> Result<()> {
    let mut stdout = std::io::stdout().lock();
    stdout.write_all(bytes)?;
    stdout.flush()?;
    Ok(())
}
