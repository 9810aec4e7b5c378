//! `vclay completions SHELL` and `vclay man [COMMAND]` (issue 17): generated from the clap
//! definitions, printed to stdout, naming every subcommand and option.

use std::process::{Command, Output};

fn vclay(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vclay"))
        .args(args)
        .output()
        .expect("vclay runs")
}

fn stdout_of(args: &[&str]) -> String {
    let out = vclay(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.stderr.is_empty(), "{args:?} wrote to stderr");
    String::from_utf8(out.stdout).unwrap()
}

#[test]
fn completions_for_every_shell() {
    for shell in ["bash", "zsh", "fish", "elvish", "powershell"] {
        let text = stdout_of(&["completions", shell]);
        for word in ["vclay", "eval", "subdivide", "max-memory"] {
            assert!(text.contains(word), "{shell} completions lack {word}");
        }
    }
    let out = vclay(&["completions", "tcsh"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(out.stdout.is_empty());
}

#[test]
fn man_pages() {
    let page = stdout_of(&["man"]);
    assert!(page.contains(".TH vclay 1"), "{page}");
    for word in ["eval", "render", "completions", "max\\-memory"] {
        assert!(page.contains(word), "man page lacks {word}");
    }
    let eval = stdout_of(&["man", "eval"]);
    assert!(eval.contains(".TH vclay-eval 1"), "{eval}");
    assert!(eval.contains("\\-\\-derivatives"), "{eval}");
    let out = vclay(&["man", "nope"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(out.stdout.is_empty());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no subcommand \"nope\""));
}
