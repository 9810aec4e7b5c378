//! The desktop's own file dialogs: the studio asks the program the desktop ships for them
//! (`zenity` on GNOME and most GTK desktops, `kdialog` on KDE, AppleScript's `choose file` on
//! macOS) and reads the chosen path from its output, on a thread of its own so the window keeps
//! drawing. Where none exists (a bare X server, CI, Windows for now) the studio's typed-path
//! dialog is used, as it is when the program fails to start.
//!
//! Why programs and not the `rfd` crate: rfd's portal backend adds 86 crates to the build (zbus,
//! an async runtime, ICU through `url`; measured with `cargo add` on 2026-12-02) and its GTK
//! backend needs GTK's development files at build time; either would cost CI minutes or its
//! clean-machine build. The programs give the same system dialogs where a desktop is present.
//! Set `VCLAY_NO_NATIVE_DIALOGS=1` to always type paths.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::mpsc::{Receiver, channel};

/// What the dialog is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Purpose {
    /// Choose an existing file to open.
    Open,
    /// Choose where to save (the program asks before overwriting).
    Save,
}

/// How a chooser program is asked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flavor {
    /// `zenity --file-selection` (GNOME, GTK desktops).
    Zenity,
    /// `kdialog --getopenfilename` / `--getsavefilename` (KDE).
    Kdialog,
    /// `osascript` with AppleScript's `choose file` / `choose file name` (macOS).
    AppleScript,
}

/// A file-chooser program (see the [module docs](self)).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Chooser {
    /// The program.
    pub program: PathBuf,
    /// How it is asked.
    pub flavor: Flavor,
}

/// What a chooser answered: a path, `None` when the person cancelled, or why it failed (the
/// studio then shows its typed-path dialog).
pub type Answer = Result<Option<PathBuf>, String>;

impl Chooser {
    /// The desktop's chooser: `None` when `VCLAY_NO_NATIVE_DIALOGS` is set, when there is no
    /// display (Linux: neither `DISPLAY` nor `WAYLAND_DISPLAY`), or when no known program is on
    /// the `PATH`.
    pub fn find() -> Option<Self> {
        if std::env::var_os("VCLAY_NO_NATIVE_DIALOGS").is_some_and(|v| !v.is_empty()) {
            return None;
        }
        if cfg!(target_os = "macos") {
            return on_path("osascript").map(|program| Chooser {
                program,
                flavor: Flavor::AppleScript,
            });
        }
        if std::env::var_os("DISPLAY").is_none() && std::env::var_os("WAYLAND_DISPLAY").is_none() {
            return None;
        }
        // KDE's own dialog on KDE, else zenity, else kdialog.
        let kde = std::env::var("XDG_CURRENT_DESKTOP").is_ok_and(|d| d.contains("KDE"));
        let order = if kde {
            [("kdialog", Flavor::Kdialog), ("zenity", Flavor::Zenity)]
        } else {
            [("zenity", Flavor::Zenity), ("kdialog", Flavor::Kdialog)]
        };
        order
            .into_iter()
            .find_map(|(name, flavor)| on_path(name).map(|program| Chooser { program, flavor }))
    }

    /// The command line that asks for a file (`start`: the suggested file or folder).
    pub fn command(&self, purpose: Purpose, title: &str, start: &Path) -> Command {
        let mut c = Command::new(&self.program);
        match (self.flavor, purpose) {
            (Flavor::Zenity, p) => {
                c.arg("--file-selection").arg(format!("--title={title}"));
                if p == Purpose::Save {
                    c.arg("--save").arg("--confirm-overwrite");
                }
                if !start.as_os_str().is_empty() {
                    c.arg(format!("--filename={}", start.display()));
                }
            }
            (Flavor::Kdialog, p) => {
                c.arg(if p == Purpose::Save {
                    "--getsavefilename"
                } else {
                    "--getopenfilename"
                });
                c.arg(start).arg("--title").arg(title);
            }
            (Flavor::AppleScript, p) => {
                let title = title.replace(['"', '\\'], "");
                let script = if p == Purpose::Save {
                    let name = start
                        .file_name()
                        .map(|n| n.to_string_lossy().replace(['"', '\\'], ""))
                        .unwrap_or_default();
                    format!(
                        "POSIX path of (choose file name with prompt \"{title}\" default name \"{name}\")"
                    )
                } else {
                    format!("POSIX path of (choose file with prompt \"{title}\")")
                };
                c.arg("-e").arg(script);
            }
        }
        c
    }

    /// Asks on a thread; the answer arrives on the returned channel.
    pub fn ask(&self, purpose: Purpose, title: &str, start: &Path) -> Receiver<Answer> {
        let (tx, rx) = channel();
        let mut command = self.command(purpose, title, start);
        let name = self.program.display().to_string();
        std::thread::spawn(move || {
            let answer = match command.output() {
                Err(e) => Err(format!("{name} did not start: {e}")),
                Ok(out) => parse_answer(out.status.code(), &out.stdout, &out.stderr, &name),
            };
            let _ = tx.send(answer);
        });
        rx
    }
}

/// Reads a chooser's exit code and output: exit 0 with a path is the choice, exit 1 (every
/// supported program's "cancelled") is `None`, anything else is a failure with its message.
pub fn parse_answer(code: Option<i32>, stdout: &[u8], stderr: &[u8], program: &str) -> Answer {
    let text = String::from_utf8_lossy(stdout);
    let path = text.trim_end_matches(['\n', '\r']);
    match code {
        Some(0) if !path.is_empty() => Ok(Some(PathBuf::from(path))),
        Some(0) | Some(1) => Ok(None),
        _ => {
            let why = String::from_utf8_lossy(stderr);
            let why = why.lines().next().unwrap_or("no message").trim();
            Err(format!(
                "{program} failed ({}): {why}",
                code.map_or("killed".into(), |c| format!("exit {c}"))
            ))
        }
    }
}

/// `name` found in a folder of the `PATH`.
fn on_path(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join(name))
        .find(|p| p.is_file())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn answers_are_read_as_choice_cancel_or_failure() {
        assert_eq!(
            parse_answer(Some(0), b"/tmp/a b.session\n", b"", "zenity"),
            Ok(Some(PathBuf::from("/tmp/a b.session")))
        );
        assert_eq!(parse_answer(Some(1), b"", b"", "zenity"), Ok(None));
        let e = parse_answer(Some(255), b"", b"cannot open display\n", "zenity").unwrap_err();
        assert!(
            e.contains("exit 255") && e.contains("cannot open display"),
            "{e}"
        );
    }

    #[test]
    fn each_flavor_asks_for_the_purpose() {
        let args = |flavor, purpose| {
            let c = Chooser {
                program: "x".into(),
                flavor,
            }
            .command(purpose, "Save session as", Path::new("/w/cube.session"));
            c.get_args()
                .map(|a| a.to_string_lossy().into_owned())
                .collect::<Vec<_>>()
        };
        let z = args(Flavor::Zenity, Purpose::Save);
        assert!(z.contains(&"--save".to_string()) && z.contains(&"--confirm-overwrite".into()));
        assert!(z.contains(&"--filename=/w/cube.session".to_string()));
        assert!(!args(Flavor::Zenity, Purpose::Open).contains(&"--save".to_string()));
        assert_eq!(args(Flavor::Kdialog, Purpose::Open)[0], "--getopenfilename");
        assert!(
            args(Flavor::AppleScript, Purpose::Save)[1].contains("default name \"cube.session\"")
        );
    }
}
