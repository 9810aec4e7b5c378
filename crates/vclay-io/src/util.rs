//! Atomic file writes.

use crate::error::IoError;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Writes the text that `render` makes from the file's name (exchange formats record it in
/// their headers) to `path`, atomically; a render error names the file.
pub(crate) fn write_named_text(
    path: &Path,
    render: impl FnOnce(&str) -> Result<String, IoError>,
) -> Result<(), IoError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let text = render(&name).map_err(|e| e.in_file(path))?;
    write_atomic(path, |w| w.write_all(text.as_bytes()))
}

/// Prefix of the temporary files of [`write_atomic`] and [`stage`]: `.vclay-tmp-PID-XXXXXX` in
/// the target's folder (PID the writing process's id).
pub const TEMP_PREFIX: &str = ".vclay-tmp-";

/// Age after which a temporary file of ours ([`TEMP_PREFIX`]) is taken for the leftover of a
/// killed write even when its process id is in use (or cannot be checked: not Linux): one hour,
/// far longer than any write takes.
pub const STALE_TEMP_AGE: std::time::Duration = std::time::Duration::from_secs(3600);

/// Writes a file through `fill`, atomically: the bytes go to a temporary file in the target's
/// directory, which is flushed, synced and renamed over `path` only when everything succeeded. A
/// failed write leaves any existing file untouched and removes the temporary file.
///
/// A missing target folder is created (as `mkdir -p` does). Temporary files of earlier,
/// killed writes in that folder are removed: those named [`TEMP_PREFIX`]`PID-*` whose process
/// no longer runs (Linux: no `/proc/PID`), or older than [`STALE_TEMP_AGE`].
pub fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), IoError> {
    stage(path, fill)?.commit()
}

/// A file written completely to a temporary file beside its target, not yet renamed over it.
/// [`Staged::commit`] renames it; dropping it uncommitted removes the temporary file. Stage
/// every file of a command that writes several, then commit them all, so that a failure while
/// writing any of them leaves none written.
#[derive(Debug)]
pub struct Staged {
    tmp: tempfile::NamedTempFile,
    path: PathBuf,
}

impl Staged {
    /// The target path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Renames the temporary file over the target.
    pub fn commit(self) -> Result<(), IoError> {
        let path = self.path;
        self.tmp
            .persist(&path)
            .map_err(|e| IoError::file(&path, e.error))?;
        Ok(())
    }
}

/// Writes `path`'s bytes through `fill` into a synced temporary file in its folder (created if
/// missing) and returns it uncommitted; see [`write_atomic`].
pub fn stage(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<Staged, IoError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let err = |e| IoError::file(path, e);
    if !dir.is_dir() {
        std::fs::create_dir_all(dir).map_err(err)?;
    }
    remove_stale_temps(dir);
    let mut builder = tempfile::Builder::new();
    let prefix = format!("{TEMP_PREFIX}{}-", std::process::id());
    builder.prefix(&prefix);
    // Temporary files are private (0600) by default; the result should get the permissions an
    // ordinary new file gets (0666 less the umask), or keep those of the file it replaces.
    #[cfg(unix)]
    let perms = match std::fs::metadata(path) {
        Ok(m) => m.permissions(),
        Err(_) => std::os::unix::fs::PermissionsExt::from_mode(0o666),
    };
    #[cfg(unix)]
    builder.permissions(perms);
    // tempfile's error names its random temporary file; the user knows only the target.
    let mut tmp = builder
        .tempfile_in(dir)
        .map_err(|e| err(std::io::Error::new(e.kind(), unwritable(dir, e.kind()))))?;
    {
        let mut w = std::io::BufWriter::new(tmp.as_file_mut());
        fill(&mut w).map_err(err)?;
        w.flush().map_err(err)?;
    }
    tmp.as_file().sync_all().map_err(err)?;
    Ok(Staged {
        tmp,
        path: path.to_path_buf(),
    })
}

/// Why a file could not be created in `dir`, in words, without the temporary file's name.
fn unwritable(dir: &Path, kind: std::io::ErrorKind) -> String {
    format!(
        "cannot create a file in the folder {} ({kind})",
        dir.display()
    )
}

/// Removes our temporary files of dead processes or older than [`STALE_TEMP_AGE`] from `dir`
/// (best effort: errors are ignored; a folder that cannot be listed is left alone).
fn remove_stale_temps(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let now = std::time::SystemTime::now();
    for entry in entries.flatten() {
        let name = entry.file_name();
        let name = name.to_string_lossy();
        let Some(rest) = name.strip_prefix(TEMP_PREFIX) else {
            continue;
        };
        let pid = rest.split('-').next().and_then(|p| p.parse::<u32>().ok());
        let Some(meta) = entry.metadata().ok().filter(|m| m.is_file()) else {
            continue;
        };
        let old = meta
            .modified()
            .ok()
            .and_then(|t| now.duration_since(t).ok())
            .is_some_and(|age| age > STALE_TEMP_AGE);
        let dead = pid.is_some_and(|p| p != std::process::id() && process_gone(p));
        if old || dead {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// Whether no process `pid` runs (Linux: `/proc/PID` is absent; elsewhere unknown: `false`).
fn process_gone(pid: u32) -> bool {
    let proc_root = Path::new("/proc/self");
    cfg!(target_os = "linux") && proc_root.exists() && !Path::new(&format!("/proc/{pid}")).exists()
}
