//! Atomic file writes.

use crate::error::IoError;
use std::io::Write;
use std::path::Path;

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

/// Writes a file through `fill`, atomically: the bytes go to a temporary file in the target's
/// directory, which is flushed, synced and renamed over `path` only when everything succeeded. A
/// failed write leaves any existing file untouched and removes the temporary file.
pub fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), IoError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let err = |e| IoError::file(path, e);
    let mut builder = tempfile::Builder::new();
    builder.prefix(".vclay-tmp-");
    // Temporary files are private (0600) by default; the result should get the permissions an
    // ordinary new file gets (0666 less the umask), or keep those of the file it replaces.
    #[cfg(unix)]
    let perms = match std::fs::metadata(path) {
        Ok(m) => m.permissions(),
        Err(_) => std::os::unix::fs::PermissionsExt::from_mode(0o666),
    };
    #[cfg(unix)]
    builder.permissions(perms);
    let mut tmp = builder.tempfile_in(dir).map_err(err)?;
    {
        let mut w = std::io::BufWriter::new(tmp.as_file_mut());
        fill(&mut w).map_err(err)?;
        w.flush().map_err(err)?;
    }
    tmp.as_file().sync_all().map_err(err)?;
    tmp.persist(path).map_err(|e| err(e.error))?;
    Ok(())
}
